"""What a tuning run minimises: E Σ_i ‖x_i(T) − θ‖² of a scenario under a candidate gain.

A family of objectives, one class each, chosen by :func:`objective_for` from the
registry :data:`OBJECTIVES` (the first whose ``accepts`` is true, or the one named):

- :class:`DigitalObjective`: the exact moments of the sampled, delayed recursion (a
  scenario with a ``digital`` block);
- :class:`ExactObjective`: the exact moment equations (linear f, Nd up to
  ``MOMENTS_MAX_ND``) of a fixed topology, a switching schedule or a sampled A(t);
- :class:`ExpressionObjective`: the exact moments of a topology given as expressions of t,
  through :func:`ntc_design.simulate.simulate` for each candidate;
- :class:`MonteCarloObjective`: Euler–Maruyama Monte Carlo with common random numbers
  (the same seed, so the same Brownian increments, for every candidate): any f, any size;
  its optimum is statistical and every value carries its 95 % band.

A candidate whose RK4 work would exceed ``MAX_STEPS`` (a stiff start, c(0)·ρ large), or
whose moments overflow, scores +∞ with the reason recorded: it is never the optimum.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..choices import TuneMethod, choices
from ..errors import InputError
from ..gain.schedule import ScheduleGain
from ..model.timevarying import ExpressionTopology
from ..protocol import design_topology
from ..protocol.digital import Digital
from ..simulate import SimulationSpec, simulate
from ..simulate.budget import Estimate, exact_seconds, mc_seconds
from ..simulate.cayley import KAPPA_NOISE, cayley_moments, noise_radius
from ..simulate.digital import DigitalMoments, digital_moments
from ..simulate.moments import KAPPA, MOMENTS_MAX_ND, generator_radius
from ..simulate.options import SaveAt
from ..simulate.prepare import (
    AnyTopology,
    PreparedModes,
    edge_count,
    prepare_modes,
    sampled_grid,
)
from ..simulate.system import mode_system
from .family import PowerGain

#: A gain the objectives evaluate: a power law or a tabulated schedule (both give c(t),
#: ``text`` and ``integrals``).
AnyGain = PowerGain | ScheduleGain

#: RK4's c·h·ρ while searching (accuracy about 1e-6 relative on the paper's networks,
#: against 0.2 for the reported numbers).
SEARCH_KAPPA = 1.0
#: RK4 steps above which a candidate scores +∞ instead of being integrated.
MAX_STEPS = 20_000
#: Crank–Nicolson's c·h per step while searching and for the reported numbers (second
#: order: at the horizon about 1e-3 and 1e-4 relative on the paper's G1, 1e-4 against
#: DOP853 on a stiff 300-agent network), and how much dearer its step is than RK4's (an
#: LU and four solves against four products).
CAYLEY_DS = 0.02
CAYLEY_DS_ACCURATE = 0.004
CAYLEY_COST = 3.0
#: A candidate whose E‖ε‖² exceeds this many times max(E‖ε(0)‖², 1) is stopped and
#: scores +∞ (mean-square unstable: its moments grow without bound).
GROWTH_LIMIT = 1e6


@dataclass(frozen=True)
class Curve:
    """E Σ_i ‖x_i − θ‖² over time, with its 95 % band for Monte Carlo (else None)."""

    t: np.ndarray
    total: np.ndarray
    lo: np.ndarray | None = None
    hi: np.ndarray | None = None

    @property
    def final(self) -> float:
        """The value at the horizon."""
        return float(self.total[-1])

    @property
    def peak(self) -> dict[str, float]:
        """sup_t of the curve over its save times and where: ``{value, t}``."""
        k = int(np.argmax(self.total))
        return {"value": float(self.total[k]), "t": float(self.t[k])}

    def first_below(self, eps: float) -> float | None:
        """The first time the curve reaches ``eps`` (linear between save times), or None.

        Parameters
        ----------
        eps : float
            The tolerance ε.

        Returns
        -------
        float or None
        """
        below = np.nonzero(self.total <= eps)[0]
        if below.size == 0:
            return None
        k = int(below[0])
        if k == 0:
            return float(self.t[0])
        t0, t1, y0, y1 = self.t[k - 1], self.t[k], self.total[k - 1], self.total[k]
        return float(t0 + (t1 - t0) * (y0 - eps) / (y0 - y1))


class Objective:
    """The base of the objectives: ``accepts``, ``value`` (search) and ``curve``
    (reporting)."""

    name = ""
    statistical = False

    @classmethod
    def accepts(cls, topology: AnyTopology, spec: SimulationSpec) -> bool:
        """Whether this objective can evaluate the scenario.

        Parameters
        ----------
        topology : Topology, SwitchingTopology, TimeVaryingTopology or ExpressionTopology
            The network.
        spec : SimulationSpec
            The scenario's options.

        Returns
        -------
        bool
        """
        return cls._accepts(topology, spec)

    @classmethod
    def _accepts(cls, topology: AnyTopology, spec: SimulationSpec) -> bool:
        raise NotImplementedError

    def __init__(self, topology: AnyTopology, spec: SimulationSpec, horizon: float) -> None:
        self.topology, self.spec, self.horizon = topology, spec, float(horizon)
        self.skipped: dict[str, str] = {}  # gain text -> why it scored +∞

    def value(self, gain: AnyGain, delta: float | None = None) -> float:
        """E Σ‖x_i(T) − θ‖² under ``gain`` (and δ), +∞ for a candidate out of reach.

        Parameters
        ----------
        gain : PowerGain
            The candidate.
        delta : float, optional
            An explicit common δ (else the scenario's).

        Returns
        -------
        float
        """
        try:
            # save times every T/40 also bound the step where c·ρ is small (c varies in t)
            v = self.curve(gain, delta, points=41, accurate=False).final
        except (InputError, FloatingPointError, OverflowError) as exc:
            self.skipped[gain.text] = str(exc)
            return math.inf
        if not math.isfinite(v):
            self.skipped[gain.text] = "the moments overflow on [0, T]"
            return math.inf
        return v

    def curve(
        self, gain: AnyGain, delta: float | None = None, points: int = 401, accurate: bool = True
    ) -> Curve:
        """E Σ‖x_i − θ‖² at ``points`` equally spaced times of [0, T].

        Parameters
        ----------
        gain : PowerGain
            The gain.
        delta : float, optional
            An explicit common δ.
        points : int, optional
            Save times.
        accurate : bool, optional
            The reported accuracy (RK4 κ = 0.2) rather than the search's.

        Returns
        -------
        Curve
        """
        return self._curve(gain, delta, points, accurate)

    def _curve(self, gain: AnyGain, delta: float | None, points: int, accurate: bool) -> Curve:
        raise NotImplementedError

    def seconds(self, gain: AnyGain, accurate: bool = False) -> float | None:
        """The estimated time of one evaluation of ``gain`` (capped as the evaluation
        caps its work; a candidate refused before any work costs nothing), for the
        estimate a tuning run makes before it starts.

        Parameters
        ----------
        gain : PowerGain
            The candidate.
        accurate : bool, optional
            The reported accuracy rather than the search's.

        Returns
        -------
        float or None
            Seconds (within a factor of a few), or None when not estimated.
        """
        return None

    def describe(self) -> str:
        """What the objective computes, for the result's ``method``.

        Returns
        -------
        str
        """
        return self.name


class ExactObjective(Objective):
    """Exact moments (:func:`.simulate.moments.exact_moments`) of a fixed topology, a
    switching schedule or a sampled A(t); designs and systems are built once per δ."""

    name = "exact moments"

    @classmethod
    def _accepts(cls, topology: AnyTopology, spec: SimulationSpec) -> bool:
        return (
            not isinstance(topology, ExpressionTopology)
            and spec.noise.linear
            and spec.digital is None
            and topology.n * topology.dim <= MOMENTS_MAX_ND
        )

    def __init__(self, topology: AnyTopology, spec: SimulationSpec, horizon: float) -> None:
        super().__init__(topology, spec, horizon)
        self.spec = spec.replace(T=self.horizon, method="exact")
        self._prepared: dict[float | None, tuple[PreparedModes, float, float, float]] = {}
        self.schemes: set[str] = set()

    def prepared(self, delta: float | None) -> tuple[PreparedModes, float, float, float]:
        """The designs and systems at δ, with the radius bounds ρ_L, ρ_Q (RK4's step,
        :func:`.simulate.moments.generator_radius`) and ρ_G (the Crank–Nicolson step's
        noise bound, :func:`.simulate.cayley.noise_radius`), each the largest over modes.

        Parameters
        ----------
        delta : float or None
            An explicit common δ, or the scenario's.

        Returns
        -------
        (PreparedModes, float, float, float)
        """
        if delta not in self._prepared:
            if len(self._prepared) > 64:  # a δ search visits few values; bound the cache
                self._prepared.clear()
            spec = self.spec if delta is None else self.spec.replace(delta=delta)
            spec = spec.replace(digital=None)  # the designs; a digital objective samples them
            assert not isinstance(self.topology, ExpressionTopology)  # see accepts
            pm = prepare_modes(self.topology, spec, spec.gain if callable(spec.gain) else _one)
            rho = np.array([generator_radius(s) for s in pm.systems])
            rho_g = max(noise_radius(s) for s in pm.systems)
            self._prepared[delta] = (pm, float(rho[:, 0].max()), float(rho[:, 1].max()), rho_g)
        return self._prepared[delta]

    def plan(self, gain: AnyGain, delta: float | None, accurate: bool) -> tuple[str, float]:
        """The cheaper integrator for a candidate and its step count: classical RK4
        (c·h·ρ <= κ: ∫ c (ρ_L + c ρ_Q) dt / κ steps) or Crank–Nicolson (∫ c dt / ds +
        ρ_G ∫ c² dt / κ_G steps, each a few times dearer), from the gain's closed-form
        integrals.

        Parameters
        ----------
        gain : PowerGain
            The candidate.
        delta : float or None
            The δ.
        accurate : bool
            The reported accuracy rather than the search's.

        Returns
        -------
        (str, float)
            ``"rk4"`` or ``"cayley"``, and the estimated steps.
        """
        _, rho_l, rho_q, rho_g = self.prepared(delta)
        i1, i2 = gain.integrals(self.horizon)
        rk4 = (rho_l * i1 + rho_q * i2) / (KAPPA if accurate else SEARCH_KAPPA)
        cay = i1 / (CAYLEY_DS_ACCURATE if accurate else CAYLEY_DS) + rho_g * i2 / KAPPA_NOISE
        return ("cayley", cay) if rk4 > CAYLEY_COST * cay else ("rk4", rk4)

    def seconds(self, gain: AnyGain, accurate: bool = False) -> float | None:
        """The estimated time of one evaluation: its RK4 (or Crank–Nicolson, each step
        ``CAYLEY_COST`` dearer) steps at :func:`.simulate.budget.exact_seconds`; 0 above
        the step cap (it scores +∞ unintegrated).

        Parameters
        ----------
        gain : PowerGain
            The candidate.
        accurate : bool, optional
            The reported accuracy rather than the search's.

        Returns
        -------
        float
        """
        scheme, steps = self.plan(gain, None, accurate)
        if not steps <= MAX_STEPS * (5 if accurate else 1):
            return 0.0
        cost = CAYLEY_COST if scheme == "cayley" else 1.0
        return exact_seconds(steps * cost, self.topology.n * self.topology.dim)

    def _curve(self, gain: AnyGain, delta: float | None, points: int, accurate: bool) -> Curve:
        scheme, steps = self.plan(gain, delta, accurate)
        if steps > MAX_STEPS * (5 if accurate else 1):
            raise InputError(
                f"about {steps:.3g} steps of the moment equations (c(0) = "
                f"{float(gain(np.array([0.0]))[0]):.3g}); too stiff",
                field=gain.text,
            )
        pm = self.prepared(delta)[0]
        t = np.linspace(0.0, self.horizon, points)
        limit = None if accurate else GROWTH_LIMIT * max(float(pm.eps0 @ pm.eps0), 1.0)
        self.schemes.add(scheme)
        with np.errstate(all="ignore"):
            if scheme == "cayley":
                ds = CAYLEY_DS_ACCURATE if accurate else CAYLEY_DS
                m = cayley_moments(pm, gain, t, ds, abort_above=limit)
            else:
                kappa = KAPPA if accurate else SEARCH_KAPPA
                m = pm.moments(gain, t, kappa=kappa, abort_above=limit)
        return Curve(t, m.ms_error.sum(axis=1))

    def describe(self) -> str:
        """What the objective computes: exact moments, and by which integrators.

        Returns
        -------
        str
        """
        names = {"rk4": "RK4", "cayley": "Crank–Nicolson"}
        used = " and ".join(names[k] for k in sorted(self.schemes)) or "RK4"
        return f"exact moments ({used})"


def _one(t):
    return np.ones(np.shape(t))


class DigitalObjective(ExactObjective):
    """The exact moments of the sampled, delayed recursion (:func:`.simulate.digital.
    digital_moments`; the scenario's ``digital`` block): what the digital protocol's
    agents reach at the deadline, with K = ⌊T/h⌋ steps and a partial one to T (the held input), no integration error."""

    name = "exact moments of the sampled recursion"

    @classmethod
    def _accepts(cls, topology: AnyTopology, spec: SimulationSpec) -> bool:
        return (
            not isinstance(topology, ExpressionTopology)
            and spec.noise.linear
            and spec.digital is not None
            and topology.n * topology.dim <= MOMENTS_MAX_ND
        )

    def moments(
        self,
        gain: Callable[[np.ndarray], np.ndarray],
        save_times: np.ndarray,
        digital: Digital | None = None,
        delta: float | None = None,
        abort_above: float | None = None,
    ) -> DigitalMoments:
        """The exact moments of the sampled recursion to T under ``gain`` (what
        :meth:`curve` reduces, and what the period search of ``ntc tune`` evaluates at each
        period: the designs are prepared once, whatever h).

        Parameters
        ----------
        gain : callable
            c(t), vectorised (a candidate, or the scenario's gain).
        save_times : numpy.ndarray
            Where to record (moved to the nearest sample).
        digital : Digital, optional
            The period and delay (default: the scenario's ``digital`` block).
        delta : float, optional
            An explicit common δ (else the scenario's).
        abort_above : float, optional
            A run whose E‖e_k‖² passes this stops (its values +∞).

        Returns
        -------
        DigitalMoments

        Raises
        ------
        InputError
            h > T, or moments too large for memory.
        """
        dg = digital if digital is not None else self.spec.digital
        assert dg is not None  # see accepts
        pm = self.prepared(delta)[0]
        grid = sampled_grid(self.topology, pm, dg, self.horizon, save_times)
        with np.errstate(all="ignore"):
            return digital_moments(pm, grid, gain, dg.delay, abort_above)

    def _curve(self, gain: AnyGain, delta: float | None, points: int, accurate: bool) -> Curve:
        pm = self.prepared(delta)[0]
        limit = None if accurate else GROWTH_LIMIT * max(float(pm.eps0 @ pm.eps0), 1.0)
        save = np.linspace(0, self.horizon, points)
        m = self.moments(gain, save, delta=delta, abort_above=limit)
        return Curve(m.moments.t, m.moments.ms_error.sum(axis=1))

    def describe(self) -> str:
        """What the objective computes.

        Returns
        -------
        str
        """
        dg = self.spec.digital
        assert dg is not None
        return f"{self.name} (h = {dg.period:g}, D = {dg.delay})"


class ExpressionObjective(Objective):
    """Exact moments of a topology given as expressions of t (A(t)), one
    :func:`~ntc_design.simulate.simulate` per candidate (δ(t) is Lemma 1's)."""

    name = "exact moments (A(t))"
    _radius: tuple[float, float] | None = None

    @classmethod
    def _accepts(cls, topology: AnyTopology, spec: SimulationSpec) -> bool:
        return (
            isinstance(topology, ExpressionTopology)
            and spec.noise.linear
            and topology.n * topology.dim <= MOMENTS_MAX_ND
        )

    def radius(self) -> tuple[float, float]:
        """(ρ_L, ρ_Q) of the design at t = 0 (:func:`.simulate.moments.generator_radius`):
        the step-count estimate that keeps a stiff candidate from being integrated.

        Returns
        -------
        (float, float)

        Raises
        ------
        InputError
            The design or the noise does not fit the topology at t = 0.
        """
        if self._radius is None:
            assert isinstance(self.topology, ExpressionTopology)  # see accepts
            at0 = self.topology.at(0.0)
            des = design_topology(at0, self.spec.theta, self.spec.margin, thresholds=False)
            self._radius = generator_radius(mode_system(des, self.spec.noise, "t=0"))
        return self._radius

    def _steps(self, gain: AnyGain) -> float:
        rho_l, rho_q = self.radius()
        i1, i2 = gain.integrals(self.horizon)
        return (rho_l * i1 + rho_q * i2) / KAPPA

    def seconds(self, gain: AnyGain, accurate: bool = False) -> float | None:
        """The estimated time of one evaluation: its steps with A(t) and Lemma 1 made at
        each (:func:`.simulate.budget.exact_seconds`); 0 above the step cap.

        Parameters
        ----------
        gain : PowerGain
            The candidate.
        accurate : bool, optional
            The reported accuracy rather than the search's (a larger step cap).

        Returns
        -------
        float
        """
        steps = self._steps(gain)
        if not steps <= MAX_STEPS * (5 if accurate else 1):
            return 0.0
        top = self.topology
        return exact_seconds(steps, top.n * top.dim, agents_per_step=top.n)

    def _curve(self, gain: AnyGain, delta: float | None, points: int, accurate: bool) -> Curve:
        if delta is not None:
            raise InputError("a topology given as expressions of t takes δ(t)", field="tune_delta")
        steps = self._steps(gain)
        if steps > MAX_STEPS * (5 if accurate else 1):  # the search's cap is ExactObjective's
            raise InputError(
                f"about {steps:.3g} steps at t = 0's radius; too stiff", field=gain.text
            )
        t = np.linspace(0.0, self.horizon, points)
        spec = self.spec.replace(T=self.horizon, gain=gain, method="exact", save=_save_at(t))
        run = simulate(self.topology, spec=spec)
        assert run.exact is not None
        return Curve(run.exact.t, run.exact.ms_error.sum(axis=1))


class MonteCarloObjective(Objective):
    """Euler–Maruyama Monte Carlo with common random numbers: the scenario's seed, paths
    and grid for every candidate, so differences between candidates are not noise of
    the draws. The value is the sample mean; the band is the per-agent 95 % bands added
    (conservative)."""

    name = "Monte Carlo"
    statistical = True

    @classmethod
    def _accepts(cls, topology: AnyTopology, spec: SimulationSpec) -> bool:
        return True

    def describe(self) -> str:
        """What the objective computes: Monte Carlo, its paths and seed, statistical.

        Returns
        -------
        str
        """
        return (
            f"Monte Carlo ({self.spec.mc.paths} paths, seed {self.spec.mc.seed}, common random "
            "numbers): the optimum is statistical"
        )

    def seconds(self, gain: AnyGain, accurate: bool = False) -> float | None:
        """The estimated time of one evaluation: paths × T/dt path-steps at the Monte Carlo
        kernel's rate (:func:`.simulate.budget.mc_seconds`).

        Parameters
        ----------
        gain : PowerGain
            The candidate (the grid is the scenario's: every candidate costs the same).
        accurate : bool, optional
            Unused.

        Returns
        -------
        float
        """
        top, spec, st = self.topology, self.spec, self.spec.stepping
        steps = self.horizon / st.dt
        if st.kind == "intrinsic":  # h = min(ds / c(t), h_max): ∫c dt / ds steps at least
            ds = st.ds if st.ds is not None else st.dt
            h_max = st.h_max if st.h_max is not None else max(1.0, 100 * st.dt)
            steps = max(gain.integrals(self.horizon)[0] / ds, self.horizon / h_max)
        est = Estimate({}, steps, steps * spec.mc.paths)
        edges = edge_count(top) * top.dim**2
        implicit = spec.stepping.scheme == "implicit"
        return mc_seconds(est, top.n * top.dim, edges, spec.mc.workers, implicit)

    def _curve(self, gain: AnyGain, delta: float | None, points: int, accurate: bool) -> Curve:
        t = np.linspace(0.0, self.horizon, points if accurate else 2)
        spec = self.spec.replace(
            T=self.horizon, gain=gain, method="mc", save=_save_at(t), delta=delta
        )
        run = simulate(self.topology, spec=spec)
        mc = run.mc
        assert mc is not None
        return Curve(run.save_times, mc.mean.sum(axis=1), mc.lo.sum(axis=1), mc.hi.sum(axis=1))


def _save_at(t: np.ndarray) -> SaveAt:
    return SaveAt(times=t)


#: The objectives in the order :func:`objective_for` tries them.
OBJECTIVES: dict[str, type[Objective]] = {
    "exact-digital": DigitalObjective,
    "exact": ExactObjective,
    "exact-expression": ExpressionObjective,
    "mc": MonteCarloObjective,
}


def check_method(method: object) -> None:
    """Refuse an objective that is not one of ``auto``, ``exact`` or ``mc``.

    Parameters
    ----------
    method : object
        The method asked for.

    Raises
    ------
    InputError
        One line naming ``method`` (and why ``both`` is not one).
    """
    if method not in choices(TuneMethod):
        # one objective per candidate: simulate's 'both' (the two curves) has no meaning here
        why = " (tuning minimises one objective; both is simulate's)" if method == "both" else ""
        raise InputError(f"expected auto, exact or mc, got {method!r}{why}", field="method")


def objective_for(
    topology: AnyTopology, spec: SimulationSpec, horizon: float, method: TuneMethod = "auto"
) -> Objective:
    """The objective for a scenario: the first of :data:`OBJECTIVES` that accepts it
    (``auto``), exact moments (``exact``) or Monte Carlo (``mc``).

    Parameters
    ----------
    topology : Topology, SwitchingTopology, TimeVaryingTopology or ExpressionTopology
        The network.
    spec : SimulationSpec
        The scenario's options (noise, x(0), seed, paths, ...).
    horizon : float
        T.
    method : {"auto", "exact", "mc"}
        Which to use.

    Returns
    -------
    Objective

    Raises
    ------
    InputError
        ``exact`` for a non-linear f or above the exact moments' size; an unknown method.
    """
    check_method(method)
    if method == "mc":
        return MonteCarloObjective(topology, spec, horizon)
    for key, cls in OBJECTIVES.items():
        if key.startswith("exact") and cls.accepts(topology, spec):
            return cls(topology, spec, horizon)
    if method == "exact":
        why = (
            "f is not linear"
            if not spec.noise.linear
            else f"N·d = {topology.n * topology.dim} is above {MOMENTS_MAX_ND}"
        )
        raise InputError(f"exact moments are not available here ({why}); use mc", field="method")
    return MonteCarloObjective(topology, spec, horizon)
