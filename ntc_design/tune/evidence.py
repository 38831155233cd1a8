"""What every tuning run checks of its result, whichever the gain: that the written
scenario can be simulated (:func:`stable_stepping`, :func:`checked_spec`) and the
certificate of the tuned design (:func:`certify_tuned`)."""

from __future__ import annotations

import math

import numpy as np

from ..certify import CertifyResult, certify
from ..certify.deadline_loss import loss_section
from ..certify.deadline_subject import add_deadline
from ..errors import InputError
from ..gain.schedule import ScheduleGain
from ..model import TimeVaryingTopology
from ..model.timevarying import ExpressionTopology
from ..simulate import SimulationSpec, simulate
from ..simulate.driver import check_stepping
from ..simulate.options import MonteCarlo, SaveAt, Stepping
from ..simulate.prepare import AnyTopology
from .family import PowerGain

#: What the written scenario switches to when its own Euler–Maruyama grid is unstable
#: under the tuned gain (a large c(0) can break the explicit scheme's mean-square limit).
IMPLICIT = {"stepping": "intrinsic", "scheme": "implicit"}


def checked_spec(topology: AnyTopology, spec: SimulationSpec) -> tuple[SimulationSpec, str | None]:
    """``spec`` when its Euler–Maruyama step-size guard passes, else the same spec with
    the drift-implicit scheme on intrinsic steps, and why: at most two evaluations of the
    guard (:func:`ntc_design.simulate.driver.check_stepping`: the spectra once per scheme,
    no path drawn); a topology given as expressions of t, whose guard is its simulator's,
    is probed by a two-path run instead.

    Parameters
    ----------
    topology : Topology, SwitchingTopology, TimeVaryingTopology or ExpressionTopology
        The network.
    spec : SimulationSpec
        A Monte Carlo spec.

    Returns
    -------
    (SimulationSpec, str or None)
        The spec to run, and the explicit guard's refusal when it was switched.

    Raises
    ------
    InputError
        Neither scheme can run the spec.
    """
    probe = MonteCarlo(paths=2, seed=0, workers=1)
    save = SaveAt(times=np.array([0.0, spec.T]))

    def check(s: SimulationSpec) -> None:
        s = s.replace(mc=probe, save=save)
        if check_stepping(topology, s) is None:  # no guard without a run here
            simulate(topology, spec=s)

    try:
        check(spec)
        return spec, None
    except InputError as exc:
        if "unstable" not in str(exc):
            raise
        why = str(exc)
    implicit = spec.replace(
        stepping=Stepping(kind="intrinsic", dt=spec.stepping.dt, scheme="implicit"),
        mc=MonteCarlo(**{**spec.mc.__dict__, "device": "cpu"}),  # sparse LU: on the CPU
    )
    check(implicit)
    return implicit, why


def stable_stepping(
    topology: AnyTopology,
    spec: SimulationSpec,
    tuned: PowerGain | ScheduleGain,
    delta: float | None,
    horizon: float,
    notes: list[str],
) -> dict[str, str]:
    """The scenario keys the written scenario needs for a Monte Carlo check of the tuned
    gain: none when its own stepping passes the guard, else :data:`IMPLICIT` (with a note).

    Parameters
    ----------
    topology : Topology, SwitchingTopology, TimeVaryingTopology or ExpressionTopology
        The network.
    spec : SimulationSpec
        The scenario.
    tuned : PowerGain or ScheduleGain
        The tuned gain.
    delta : float or None
        The tuned δ (None: the scenario's).
    horizon : float
        T.
    notes : list of str
        Where a switch or a failure is said.

    Returns
    -------
    dict of str to str
    """
    if spec.digital is not None:  # the sampled protocol has no stepping to choose
        return {}
    base = spec.replace(
        T=horizon,
        gain=tuned,
        delta=delta if delta is not None else spec.delta,
        method="mc",
    )
    try:
        _, why = checked_spec(topology, base)
    except InputError as exc:
        notes.append(f"the tuned scenario cannot be simulated as written: {exc}")
        return {}
    if why is None:
        return {}
    notes.append(
        "the scenario's explicit Euler–Maruyama step is unstable under the tuned gain "
        f"({why.split(';')[0].removeprefix('dt: ')}); tuned.yaml uses the drift-implicit scheme"
    )
    return dict(IMPLICIT)


def certify_tuned(
    topology: AnyTopology,
    spec: SimulationSpec,
    tuned: PowerGain | ScheduleGain,
    delta: float | None,
    notes: list[str],
    deadline: float | None = None,
) -> CertifyResult | None:
    """The certificate of the tuned design, or None with a note when none applies; with a
    deadline it also carries the proven figures at T (:mod:`ntc_design.certify.deadline`).

    Parameters
    ----------
    topology : Topology, SwitchingTopology, TimeVaryingTopology or ExpressionTopology
        The network.
    spec : SimulationSpec
        The scenario (θ, ΔC, δ, noise).
    tuned : PowerGain or ScheduleGain
        The tuned gain (a schedule is stored in the certificate).
    delta : float or None
        The tuned δ (None: the scenario's).
    notes : list of str
        Where a missing certificate is explained.
    deadline : float, optional
        T: add ``subject.deadline`` and ``results.deadline`` (a note says why not, when
        they cannot be proven within :data:`DEADLINE_SECONDS`).

    Returns
    -------
    CertifyResult or None
    """
    if isinstance(topology, TimeVaryingTopology):
        notes.append("no certificate: a topology given as Python functions of t has none")
        return None
    f = spec.noise.f
    if callable(f):
        if isinstance(topology, ExpressionTopology):
            notes.append("no certificate: a time-varying certificate needs a linear f's bound")
            return None
        f = 0.0  # only the time-varying certificate uses the noise
    f_bound = float(np.linalg.norm(np.atleast_2d(np.asarray(f, dtype=float)), 2))
    try:
        res = certify(
            topology,
            spec.theta,
            spec.margin,
            gain=tuned.text if isinstance(tuned, PowerGain) else tuned,
            delta=delta if delta is not None else spec.delta,
            noise_sigma=spec.noise.sigma,
            noise_f=f_bound if spec.digital is None else spec.noise.f,
            digital=spec.digital,
            sigma_edges={(str(a), str(b)): v for (a, b), v in spec.noise.sigma_edges.items()},
        )
    except InputError as exc:
        notes.append(f"no certificate: {exc}")
        return None
    if deadline is not None and res.verification.valid:
        _add_deadline(res, spec, tuned, deadline, notes)
    return res


def proven_text(cert: CertifyResult | None) -> str:
    """``", proven ≤ B_T"`` (B_T rounded up to 6 significant digits) when the tuned
    certificate carries the deadline figures, else ``""``.

    Parameters
    ----------
    cert : CertifyResult or None
        The tuned design's certificate.

    Returns
    -------
    str
    """
    if cert is None or not cert.verification.valid:
        return ""
    fig = cert.certificate.get("results", {}).get("deadline")
    if not isinstance(fig, dict) or not isinstance(fig.get("ms_error_bound"), (int, float)):
        return ""
    b = float(fig["ms_error_bound"])
    if not (math.isfinite(b) and b > 0):
        return ""
    scale = 10.0 ** (math.floor(math.log10(b)) - 5)
    return f", proven ≤ {math.ceil(b / scale) * scale:.6g}"


#: The tuned certificate's deadline figures are proven when estimated within this (s).
DEADLINE_SECONDS = 120.0


def _add_deadline(res, spec, tuned, deadline: float, notes: list[str]) -> None:
    """The proven figures at the deadline in the tuned certificate (a note when not)."""

    f = np.asarray(spec.noise.f, dtype=float) if not callable(spec.noise.f) else None
    top = res.design.base if hasattr(res.design, "digital") else res.design
    modes = getattr(top, "modes", None)
    first = next(iter(modes.values())) if modes else top
    n, d = first.topology.n, first.topology.dim
    x0, _ = spec.initial_state(n, d)
    dg = spec.digital
    section = {
        "T": float(deadline),
        "period": dg.period if dg is not None else None,
        "delay": dg.delay if dg is not None else 0,
        "gain": tuned.text if isinstance(tuned, PowerGain) else tuned.to_document(),
        "noise": {
            "sigma": float(spec.noise.sigma),
            "f": None if f is None else (float(f) if f.ndim == 0 else f.tolist()),
            "sigma_edges": [
                {"from": str(a), "to": str(b), "sigma": float(v)}
                for (a, b), v in spec.noise.sigma_edges.items()
            ],
        },
        "initial": {"x0": [float(v) for v in x0]},
    }
    if dg is not None and dg.period is not None and not modes:  # its lossy links, if any
        lossy = loss_section(first.topology, dg.loss, dg.policy)
        if lossy is not None:
            section["loss"] = lossy
    try:
        if f is None:
            raise InputError("a linear f(x) = F x is needed", field="f")
        add_deadline(res.certificate, section, DEADLINE_SECONDS)
    except (InputError, KeyError, TypeError) as exc:
        res.certificate["subject"].pop("deadline", None)
        notes.append(f"no proven figures at the deadline: {exc}")


__all__ = [
    "DEADLINE_SECONDS",
    "IMPLICIT",
    "certify_tuned",
    "proven_text",
    "checked_spec",
    "stable_stepping",
]
