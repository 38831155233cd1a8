"""Euler–Maruyama moments by exact recursion, the Monte Carlo band check against exact
moments, and a scenario file writer."""

import json

import numpy as np

from ntc_design.model.paper import THETA
from ntc_design.simulate import NoiseModel
from ntc_design.simulate.moments import PreparedModes, em_moments
from ntc_design.simulate.system import mode_system
from tests.conftest import ROOT, X0


def em_exact(res, gain=lambda t: 1 / (1 + t)):
    """Exact moments of the Euler–Maruyama recursion on the run's own grid."""
    systems = [mode_system(res.designs[k], NoiseModel()) for k in res.designs]
    return em_moments(PreparedModes.of(systems, X0 - np.tile(THETA, 7)), res.grid, gain).ms_error


def assert_mc_matches_exact(res, max_outside=0.15, max_z=6.0, exact=None):
    """The exact curve lies in the MC 95% band at most save times. Save times share their
    paths (errors are correlated in time) and ‖x_i − θ‖² is heavy-tailed under
    multiplicative noise (the band under-covers now and then), so the test bounds the
    fraction outside, the median standardized error (a bias of one standard error would
    push it above 1) and the worst case."""
    mc, ex = res.mc, (res.exact.ms_error if exact is None else exact)
    half = np.maximum(mc.hi - mc.mean, 1e-12)
    z = np.abs(mc.mean[1:] - ex[1:]) / half[1:] * 1.96
    outside = np.mean((ex[1:] < mc.lo[1:]) | (ex[1:] > mc.hi[1:]))
    assert outside <= max_outside, f"{outside:.0%} of (time, agent) pairs outside the 95% band"
    assert np.median(z) < 1.2, f"median |MC − exact| = {np.median(z):.2f} standard errors"
    assert np.max(z) < max_z, f"max |MC − exact| = {np.max(z):.2f} standard errors"


# --------------------------------------------------------------------------- CLI


def write_scenario(tmp_path, **over):
    doc = {
        "topology": str(ROOT / "examples" / "g1.yaml"),
        "theta": THETA,
        "gain": "1/(1+t)",
        "noise": {"sigma": 0.4, "f": 0.3},
        "initial": {"uniform": [-3, 3], "seed": 1},
        "T": 0.2,
        "dt": 0.001,
        "paths": 40,
        "seed": 0,
        "save_every": 0.05,
        "method": "both",
        "workers": 1,
    }
    doc.update(over)
    p = tmp_path / "sc.yaml"
    p.write_text(json.dumps({k: v for k, v in doc.items() if v is not None}))
    return p
