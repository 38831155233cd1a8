"""What every tuning run checks of its result, whichever the gain: that the written
scenario can be simulated (:func:`stable_stepping`, :func:`checked_spec`) and the
certificate of the tuned design (:func:`certify_tuned`)."""

from __future__ import annotations

import numpy as np

from ..certify import CertifyResult, certify
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
) -> CertifyResult | None:
    """The certificate of the tuned design, or None with a note when none applies.

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
        return certify(
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


__all__ = ["IMPLICIT", "certify_tuned", "checked_spec", "stable_stepping"]
