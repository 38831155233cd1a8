"""Simulation under weight uncertainty: K realisations drawn from the Loewner set of
:mod:`ntc_design.certify.robust.search`, each run with the nominal protocol, beside the proven
brackets at the same radii (scenario key ``robust: {realizations, radius, seed}``).

**Draws.** Realisation k uses ``SeedSequence(seed, spawn_key=(k,))``: for every edge
E = Q diag(u) Qᵀ with Q Haar-distributed (QR of a Gaussian matrix, signs fixed) and u
uniform on [−ρ_e, ρ_e]^d, so |A'| = F(I + E)F lies in the set. The draws do not depend on
the number of workers or on the other realisations.

**What is recorded.** Per realisation: its exact decay rate min Re λ(L_B(A')), its exact
consensus offset ‖L_B(A')⁻¹u − 1⊗θ‖₂ (the point the protocol converges to), and from the
simulation the Monte Carlo mean state at T (its distance to 1⊗θ) and the final mean-square
error Σ_i E‖x_i(T) − θ‖².
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..certify.robust import (
    abscissa,
    radius_text,
    realised_topology,
    robust,
    uncertain_edges,
)
from ..errors import InputError
from ..model import Topology
from ..present.rows import fmt
from ..protocol import ProtocolDesign, design_topology
from ..simulate import SimulationSpec, simulate

#: Each realisation's exact decay rate and offset need dense L_B(A') up to this Nd.
STUDY_MAX_ND = 600
ROW_KEYS = ("realization", "decay_rate", "offset", "mc_offset_T", "final_ms_error")


@dataclass(frozen=True)
class RobustStudy:
    """The realisations' figures and the proven brackets at the same radii."""

    radius: float
    radii: tuple[float, ...]
    brackets: dict
    rows: tuple[dict, ...]

    def to_dict(self) -> dict:
        """The study as summary.json keeps it.

        Returns
        -------
        dict
            ``radius``, ``realizations``, ``brackets`` (as ``ntc robust`` prints as JSON, without
            the realisations' weights), ``rows`` and the spread of each figure.
        """

        def spread(key: str) -> dict:
            vals = [r[key] for r in self.rows if r[key] is not None]
            return {"min": min(vals), "max": max(vals)} if vals else {"min": None, "max": None}

        return {
            "radius": self.radius,
            "realizations": len(self.rows),
            "brackets": self.brackets,
            "rows": [dict(r) for r in self.rows],
            "spread": {k: spread(k) for k in ROW_KEYS[1:]},
        }

    def csv(self) -> str:
        """One line per realisation (``robust.csv``).

        Returns
        -------
        str
        """
        lines = [",".join(ROW_KEYS)]
        for r in self.rows:
            lines.append(",".join("" if r[k] is None else repr(r[k]) for k in ROW_KEYS))
        return "\n".join(lines) + "\n"


def draw_realisation(top: Topology, radii: np.ndarray, seed: int, k: int) -> Topology:
    """Realisation ``k`` of the set (module docstring).

    Parameters
    ----------
    top : Topology
        The nominal topology.
    radii : numpy.ndarray
        ρ_e per uncertain edge (:class:`ntc_design.certify.robust.search.UncertainEdges` order).
    seed : int
        The study's seed.
    k : int
        The realisation's index.

    Returns
    -------
    Topology
        The same agents and edges with realised weights.
    """
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(k,)))
    ed = uncertain_edges(top)
    d = top.dim
    out = np.empty_like(ed.w)
    for e in range(ed.m):
        q, r = np.linalg.qr(rng.normal(size=(d, d)))
        q = q * np.sign(np.diag(r))  # Haar
        u = rng.uniform(-radii[e], radii[e], size=d)
        lam, v = np.linalg.eigh(ed.w[e])
        f = (v * np.sqrt(np.clip(lam, 0, None))) @ v.T
        a = f @ (np.eye(d) + (q * u) @ q.T) @ f
        out[e] = ed.s[e] * 0.5 * (a + a.T)
    return realised_topology(top, ed, out)


def robust_study(
    top: Any,
    spec: SimulationSpec,
    progress: Callable[[int, int], None] | None = None,
) -> RobustStudy:
    """Simulate ``spec.robust.realizations`` weight realisations with the nominal protocol
    and compute the proven brackets at the same radii.

    Parameters
    ----------
    top : Topology
        The nominal topology (radii from its ``uncertainty:`` values, else the spec's);
        any other kind is refused.
    spec : SimulationSpec
        The scenario's spec, with ``robust`` set.
    progress : callable(done, total), optional
        Called after each realisation.

    Returns
    -------
    RobustStudy

    Raises
    ------
    InputError
        No ``robust`` in the spec, not one fixed topology, a network above
        :data:`STUDY_MAX_ND`, or a bad option of a realisation's run.
    """
    rs = spec.robust
    if rs is None:
        raise InputError("the scenario has no robust: {realizations, radius, seed}", field="robust")
    if not isinstance(top, Topology):
        raise InputError("weight realisations are drawn for one fixed topology", field="robust")
    if top.nd > STUDY_MAX_ND:
        raise InputError(
            f"Nd = {top.nd} is above {STUDY_MAX_ND}, where each realisation's decay "
            "rate and offset are computed exactly (dense)",
            field="robust",
        )
    nominal = design_topology(top, spec.theta, spec.margin, spec.delta, thresholds=False)
    assert isinstance(nominal, ProtocolDesign)
    ed = uncertain_edges(top)
    radii = ed.radii(top, rs.radius)
    rep = robust(nominal, rs.radius, starts=2)  # sparse decay and margin above the dense size
    doc = rep.to_dict()
    brackets = {
        k: {kk: vv for kk, vv in v.items() if kk not in ("realization", "destabilizing")}
        if isinstance(v, dict)
        else v
        for k, v in doc.items()
    }
    run_spec = dataclasses.replace(spec, robust=None)
    u = nominal.input_vector()
    target = np.tile(nominal.theta, top.n)
    rows = []
    for k in range(rs.realizations):
        real = draw_realisation(top, radii, rs.seed, k)
        proto = dataclasses.replace(nominal, topology=real)
        lap = proto.grounded_laplacian()
        offset = float(np.linalg.norm(np.linalg.solve(lap, u) - target))
        res = simulate(real, run_spec, protocol=proto)
        mc_off = None
        if res.mc is not None and res.mc.mean_state.size:
            mc_off = float(np.linalg.norm(res.mc.mean_state[-1] - target))
        ms = res.exact.ms_error if res.exact is not None else res.mc.mean if res.mc else None
        rows.append(
            {
                "realization": k,
                "decay_rate": abscissa(lap),
                "offset": offset,
                "mc_offset_T": mc_off,
                "final_ms_error": None if ms is None else float(np.sum(ms[-1])),
            }
        )
        if progress is not None:
            progress(k + 1, rs.realizations)
    return RobustStudy(
        float(np.max(radii, initial=0.0)), tuple(radii.tolist()), brackets, tuple(rows)
    )


def study_sentence(study: dict) -> str:
    """What a study shows, in one sentence (the terminal and the HTML report say this).

    Parameters
    ----------
    study : dict
        :meth:`RobustStudy.to_dict` (summary.json's ``robust``).

    Returns
    -------
    str
    """
    rows, b = study["rows"], study.get("brackets") or {}
    lo, hi = _proven_ends(b)
    dec = [r["decay_rate"] for r in rows]
    off = [r["offset"] for r in rows]
    ok_d, ok_o = _respected(rows, b)
    num = functools.partial(fmt, digits=5)
    return (
        f"{len(rows)} weight realisations within {study_radius_text(study)}, nominal protocol: "
        f"decay rate {num(min(dec))}–{num(max(dec))} (proven >= {num(lo)}), consensus offset "
        f"{num(min(off))}–{num(max(off))} (proven <= {num(hi)}); "
        + ("both proven bounds hold" if ok_d and ok_o else "a proven bound is VIOLATED (a bug)")
    )


def study_radius_text(study: dict, short: bool = False) -> str:
    """The study's uncertainty set in words: ``ρ = 0.05``, or the per-edge radii with
    their largest (:func:`ntc_design.certify.robust.search.radius_text`).

    Parameters
    ----------
    study : dict
        :meth:`RobustStudy.to_dict` (summary.json's ``robust``).
    short : bool, optional
        Leave the list of ρ_e out.

    Returns
    -------
    str
    """
    radii = (study.get("brackets") or {}).get("radius")  # a list for per-edge radii
    return radius_text(radii if isinstance(radii, list) else [], study["radius"], short)


def _proven_ends(brackets: dict) -> tuple[float | None, float | None]:
    """The proven lower bound on the decay rate and upper bound on the offset."""
    return (brackets.get("decay") or {}).get("lower"), (brackets.get("offset") or {}).get("upper")


def _respected(rows, brackets: dict) -> tuple[bool, bool]:
    """Whether every row's decay rate and offset respect the proven ends."""
    lo, hi = _proven_ends(brackets)
    return (
        lo is None or all(r["decay_rate"] >= lo for r in rows),
        hi is None or all(r["offset"] <= hi * (1 + 1e-12) for r in rows),
    )


def within_brackets(study: RobustStudy) -> dict[str, bool]:
    """Whether every realisation respects the proven ends (a decay rate at least the
    proven lower bound, an offset at most the proven upper bound).

    Parameters
    ----------
    study : RobustStudy
        The study.

    Returns
    -------
    dict of str to bool
        ``decay`` and ``offset`` (True where no bound was proven).
    """
    ok_d, ok_o = _respected(study.rows, study.brackets)
    return {"decay": ok_d, "offset": ok_o}


__all__ = [
    "ROW_KEYS",
    "STUDY_MAX_ND",
    "RobustStudy",
    "draw_realisation",
    "robust_study",
    "study_radius_text",
    "within_brackets",
]
