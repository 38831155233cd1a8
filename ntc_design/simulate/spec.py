"""What to simulate, as a frozen value that checks itself.

A :class:`SimulationSpec` is built either from keyword arguments
(:meth:`SimulationSpec.build`, what ``simulate(topology, theta, T=..., paths=...)`` calls)
or from a scenario document (:meth:`SimulationSpec.from_document`); both go through the
same small option objects, each of which validates itself on construction (the pattern
of diffrax's ``SaveAt``):

- :class:`SaveAt` -- ``every`` (a period) or ``times`` (a list);
- :class:`Stepping` -- ``uniform`` steps ``dt`` or ``intrinsic`` steps ``ds`` in
  s = ∫c dt, capped at ``h_max``;
- :class:`MonteCarlo` -- ``paths``, ``seed``, ``block_size``, ``store_paths``, ``workers``,
  ``rng`` (``xoshiro``: per-path streams drawn in the kernel, :mod:`.rng`; ``numpy``),
  ``device`` (``cpu``, or ``gpu``: :mod:`.gpu`, the same paths on an NVIDIA GPU);
- :class:`UniformInitial` -- x(0) drawn uniformly from [lo, hi] with its own seed;
- the noise (:class:`~ntc_design.simulate.system.NoiseModel`), checked by
  :func:`check_noise`.

The flat keys of a scenario file (:data:`SCENARIO_KEYS`) are defined here and only here.
Checks that need the topology (θ's length, the initial state's size, ``resample``) are
made by the driver (the initial state's through :meth:`SimulationSpec.initial_state`).
θ, x(0), σ and f are bounded by :data:`MAX_MAGNITUDE` (1e100). Every error is one line
naming the field.
"""

from __future__ import annotations

import numbers
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..choices import SimulateMethod, choices
from ..errors import (
    InputError,
    quote,
    require_horizon,
    require_number,
    require_positive,
)
from ..expr.tree import numeric_function
from ..gain.schedule import ScheduleGain, read_schedule, schedule_from_document
from ..protocol.digital import Digital
from .noise import MAX_MAGNITUDE, NoiseModel, noise_from_document
from .options import (
    MonteCarlo,
    SaveAt,
    Stepping,
    UniformInitial,
    check_states,
    check_vector,
)
from .robust_sampling import RobustSampling


def check_noise(noise: NoiseModel) -> NoiseModel:
    """Check σ (finite, >= 0), f (a finite scalar, a finite square matrix or a
    callable) and the per-edge σ (finite, >= 0, keyed by (from, to) labels); every
    number at most :data:`MAX_MAGNITUDE` in magnitude.

    Parameters
    ----------
    noise : NoiseModel
        The noise to check.

    Returns
    -------
    NoiseModel
        The same object.

    Raises
    ------
    InputError
        Naming the field (``noise.sigma``, ``noise.f``, ``noise.sigma_edges``).
    """
    if not isinstance(noise, NoiseModel):
        raise InputError(f"expected a NoiseModel, got {type(noise).__name__}", field="noise")
    require_number("noise.sigma", noise.sigma, minimum=0.0, bound=MAX_MAGNITUDE)
    f = noise.f
    if not callable(f):
        if isinstance(f, bool):
            raise InputError("expected a number or a d×d matrix, got a boolean", field="noise.f")
        if isinstance(f, numbers.Real):
            require_number("noise.f", f, bound=MAX_MAGNITUDE)
        else:
            try:
                arr = np.asarray(f, dtype=float)
            except (TypeError, ValueError):
                raise InputError("expected a number or a d×d matrix", field="noise.f") from None
            except OverflowError:
                raise InputError(
                    "an entry is beyond the float range (about 1.8e308)", field="noise.f"
                ) from None
            if arr.ndim != 2 or arr.shape[0] != arr.shape[1] or arr.size == 0:
                raise InputError(
                    f"expected a number or a square matrix, got shape {arr.shape}", field="noise.f"
                )
            if not np.all(np.isfinite(arr)):
                raise InputError("entries must be finite", field="noise.f")
            if np.any(np.abs(arr) > MAX_MAGNITUDE):
                raise InputError(
                    f"entries must be at most {MAX_MAGNITUDE:g} in magnitude", field="noise.f"
                )
    if not isinstance(noise.sigma_edges, Mapping):
        raise InputError("expected a mapping (from, to) -> σ", field="noise.sigma_edges")
    for key, s in noise.sigma_edges.items():
        if not isinstance(key, tuple) or len(key) != 2:
            raise InputError(f"key {key!r} is not a (from, to) pair", field="noise.sigma_edges")
        require_number(
            f"noise.sigma_edges {quote(key[0])}->{quote(key[1])}",
            s,
            minimum=0.0,
            bound=MAX_MAGNITUDE,
        )
    return noise


# The flat keys of a scenario file and of simulate(**options), in one place.
SCENARIO_KEYS = (
    "name",
    "description",
    "topology",
    "theta",
    "margin",
    "delta",
    "gain",
    "noise",
    "initial",
    "T",
    "dt",
    "paths",
    "seed",
    "save_every",
    "save_times",
    "method",
    "stepping",
    "ds",
    "scheme",
    "workers",
    "block_size",
    "store_paths",
    "rng",
    "device",
    "resample",
    "robust",
    "digital",
)
OPTION_KEYS = tuple(k for k in SCENARIO_KEYS if k not in ("name", "description", "topology"))
METHODS = choices(SimulateMethod)
MAX_GAIN_TEXT = 10_000


def _schedule_from_document(doc: Mapping[str, Any], source: str | None) -> ScheduleGain:
    """A scenario's ``gain: {schedule: FILE.csv, tail: EXPRESSION, interpolation: linear}``
    (the file relative to the scenario), or an inline ``{t: [...], c: [...], tail}``."""
    if "schedule" not in doc:
        return schedule_from_document(dict(doc), "gain")
    unknown = sorted(str(k) for k in set(doc) - {"schedule", "tail", "interpolation"})
    if unknown:
        raise InputError(
            "unknown field (known: schedule, tail, interpolation)", field=f"gain.{unknown[0]}"
        )
    for key in ("schedule", "tail", "interpolation"):
        if key in doc and not isinstance(doc[key], str):
            raise InputError(f"expected a string, got {doc[key]!r}", field=f"gain.{key}")
    base = Path(source).parent if source else Path(".")
    return read_schedule(base / doc["schedule"], doc.get("tail"), doc.get("interpolation"))


@dataclass(frozen=True, eq=False)
class SimulationSpec:
    """Everything a simulation needs besides the topology (see the module docstring).

    Attributes
    ----------
    theta : ndarray
        Target consensus state θ (d numbers).
    T : float
        Horizon.
    margin : float
        ΔC > 0 of the Lemma 1 design (δ = C + ΔC).
    delta : float or None
        An explicit common coupling δ > 0 for every mode instead of C + ΔC (what
        ``ntc tune`` writes when it tunes δ); None: Lemma 1's.
    gain : str or callable
        c(t): an expression in t, or a vectorised callable.
    noise : NoiseModel
    initial : ndarray, UniformInitial, mapping or None
        x(0) (N·d numbers), a uniform draw (a :class:`UniformInitial`, or the scenario's
        mapping ``{"uniform": [lo, hi], "seed": S}``), or zero.
    save : SaveAt
    stepping : Stepping
    mc : MonteCarlo
    method : str
        ``mc``, ``exact`` or ``both``.
    resample : float or None
        Re-design period of a topology given as functions of t.
    robust : RobustSampling or None
        Weight realisations to simulate too (``ntc simulate`` runs them after the nominal
        network; :func:`ntc_design.sweep.robust.robust_study`).
    digital : Digital or None
        The sampled protocol (period h, delay D; :mod:`ntc_design.protocol.digital`): the
        recursion is stepped every h instead of the continuous SAN; None: continuous.
    digital_steps : (int, float) or None
        K = ⌊T/h⌋ and the partial step s of the sampled protocol (:meth:`Digital.steps`),
        decided once on construction (None: continuous).
    """

    theta: np.ndarray
    T: float = 10.0  # noqa: N815 - the paper's name
    margin: float = 0.1
    gain: str | Callable = "1/(1+t)"
    delta: float | None = None
    noise: NoiseModel = field(default_factory=NoiseModel)
    initial: np.ndarray | UniformInitial | None = None
    save: SaveAt = field(default_factory=lambda: SaveAt(every=0.1))
    stepping: Stepping = field(default_factory=Stepping)
    mc: MonteCarlo = field(default_factory=MonteCarlo)
    method: SimulateMethod = "both"
    resample: float | None = None
    robust: RobustSampling | None = None
    digital: Digital | None = None
    #: K and s of the sampled protocol to T (:meth:`Digital.steps`), decided once here:
    #: the size check, the grid and the run's summary read them.
    digital_steps: tuple[int, float] | None = field(
        default=None, init=False, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        th = check_vector("theta", self.theta, bound=MAX_MAGNITUDE)
        if th.size == 0:
            raise InputError("expected at least one number", field="theta")
        if not np.any(th):
            raise InputError(
                "must be non-zero (the target of non-trivial consensus)", field="theta"
            )
        object.__setattr__(self, "theta", th)
        object.__setattr__(self, "T", require_horizon("T", self.T))
        require_positive("margin", self.margin)
        if self.delta is not None:
            require_positive("delta", self.delta)
            object.__setattr__(self, "delta", float(self.delta))
        if isinstance(self.gain, str):
            if len(self.gain) > MAX_GAIN_TEXT:
                raise InputError(f"longer than {MAX_GAIN_TEXT} characters", field="gain")

            numeric_function(self.gain, "gain")  # whitelisted, in t; or one line naming gain
        elif not callable(self.gain):
            raise InputError(
                f"expected an expression in t or a callable, got {type(self.gain).__name__}",
                field="gain",
            )
        check_noise(self.noise)
        ini = self.initial
        if isinstance(ini, Mapping):  # the scenario's {uniform: [lo, hi], seed: S}
            object.__setattr__(self, "initial", _initial_from_document(ini))
        elif ini is not None and not isinstance(ini, UniformInitial):
            object.__setattr__(self, "initial", check_states(ini))
        for name, cls in (("save", SaveAt), ("stepping", Stepping), ("mc", MonteCarlo)):
            if not isinstance(getattr(self, name), cls):
                raise InputError(f"expected a {cls.__name__}", field=name)
        if self.save.times is not None and np.any(self.save.times > self.T):
            raise InputError(f"expected times in [0, T={self.T:g}]", field="save_times")
        if self.method not in METHODS:
            raise InputError(f"must be mc, exact or both, got {self.method!r}", field="method")
        if self.resample is not None:
            require_positive("resample", self.resample)
        if self.digital is not None:
            object.__setattr__(self, "digital", Digital.from_document(self.digital))
            if self.stepping.kind != "uniform" or self.stepping.scheme != "explicit":
                raise InputError(
                    "the sampled protocol steps every period h; stepping: intrinsic "
                    "and scheme: implicit do not apply to it",
                    field="digital",
                )
            # h <= T and a bounded number of steps
            object.__setattr__(self, "digital_steps", self.digital.steps(self.T))
        if self.mc.device == "gpu":
            if self.stepping.scheme != "explicit":
                raise InputError("implicit runs on the CPU only (device: cpu)", field="scheme")
            if callable(self.noise.f):
                raise InputError(
                    "a callable f runs on the CPU only (device: gpu compiles a linear f)",
                    field="noise.f",
                )

    # -- constructors -------------------------------------------------------------

    @classmethod
    def build(cls, theta, **options: Any) -> SimulationSpec:
        """A spec from the flat keyword options of :func:`simulate` (the keys of a
        scenario file: T, dt, paths, seed, save_every or save_times, method, stepping,
        ds, workers, block_size, store_paths, resample, margin, delta, gain, noise, initial,
        digital).

        Parameters
        ----------
        theta : sequence of float
            The target consensus state θ ≠ 0.
        **options
            Flat options; unknown names are refused.

        Returns
        -------
        SimulationSpec

        Raises
        ------
        InputError
            For an unknown option or a bad value, naming it.
        """
        unknown = sorted(set(options) - set(OPTION_KEYS))
        if unknown:
            raise InputError(
                f"unknown option (known: {', '.join(sorted(OPTION_KEYS))})", field=unknown[0]
            )
        o = dict(options)
        if "save_times" in o and o["save_times"] is not None:
            if o.get("save_every") is not None:
                raise InputError("give save_every or save_times, not both", field="save_times")
            save = SaveAt(times=o.pop("save_times"))
            o.pop("save_every", None)
        else:
            o.pop("save_times", None)
            every = o.pop("save_every", 0.1)
            save = SaveAt(every=0.1 if every is None else every)
        stepping = Stepping(
            kind=o.pop("stepping", "uniform"),
            dt=o.pop("dt", 1e-3),
            ds=o.pop("ds", None),
            scheme=o.pop("scheme", "explicit"),
        )
        mc = MonteCarlo(
            **{
                k: o.pop(k)
                for k in ("paths", "seed", "block_size", "store_paths", "workers", "rng", "device")
                if k in o
            }
        )
        if o.get("noise") is None:
            o.pop("noise", None)
        return cls(theta=theta, save=save, stepping=stepping, mc=mc, **o)

    @classmethod
    def from_document(cls, doc: Mapping[str, Any], source: str | None = None) -> SimulationSpec:
        """A spec from a scenario document (a parsed YAML/JSON mapping; the ``topology``,
        ``name`` and ``description`` keys are ignored here). ``noise`` is
        ``{sigma, f, sigma_edges: [{from, to, sigma}]}``; ``initial`` a list of N·d
        numbers (or N lists of d, all of one length) or ``{uniform: [lo, hi], seed: S}``.

        Parameters
        ----------
        doc : mapping
            The scenario as read.
        source : str, optional
            The file name that prefixes error messages.

        Returns
        -------
        SimulationSpec

        Raises
        ------
        InputError
            ``SOURCE: FIELD: what is wrong``.
        """
        try:
            return cls._from_document(doc, source)
        except InputError as exc:
            if source:
                raise InputError(f"{exc}", field=source) from None
            raise

    @classmethod
    def _from_document(cls, doc: Mapping[str, Any], source: str | None = None) -> SimulationSpec:
        unknown = sorted(str(k) for k in set(doc) - set(SCENARIO_KEYS))
        if unknown:
            raise InputError(
                f"unknown field (allowed: {', '.join(SCENARIO_KEYS)})", field=quote(unknown[0])
            )
        if "theta" not in doc:
            raise InputError("missing", field="theta")
        o = {k: v for k, v in doc.items() if k in OPTION_KEYS}
        o["noise"] = noise_from_document(doc.get("noise"))
        if o.get("robust") is not None:
            o["robust"] = RobustSampling.from_document(o["robust"])
        if "initial" in o:
            o["initial"] = _initial_from_document(o["initial"])
        if "gain" in o and isinstance(o["gain"], Mapping):
            o["gain"] = _schedule_from_document(o["gain"], source)
        elif "gain" in o and not isinstance(o["gain"], str):
            raise InputError(
                "expected an expression in t (a string) or {schedule: FILE.csv, tail: "
                f"EXPRESSION}}, got {o['gain']!r}",
                field="gain",
            )
        for key in ("method", "stepping", "scheme"):
            if key in o and not isinstance(o[key], str):
                raise InputError(f"expected a string, got {o[key]!r}", field=key)
        for key in ("T", "dt", "ds", "margin", "delta", "save_every", "resample"):
            if key in o and o[key] is not None:
                require_number(key, o[key])
        if o.get("save_times") is not None and o.get("save_every") is not None:
            raise InputError("give save_every or save_times, not both", field="save_times")
        return cls.build(**o)

    def replace(self, **changes: Any) -> SimulationSpec:
        """A copy with some fields changed (checked again).

        Parameters
        ----------
        **changes
            New values of fields of this spec.

        Returns
        -------
        SimulationSpec
            The new spec.

        Raises
        ------
        InputError
            A changed value is bad.
        """
        return replace(self, **changes)

    def initial_state(self, n: int, d: int) -> tuple[np.ndarray, list[str]]:
        """x(0) for a network of ``n`` agents in dimension ``d`` (one check for every
        topology kind).

        Parameters
        ----------
        n, d : int
            Agents and state dimension.

        Returns
        -------
        (numpy.ndarray, list of str)
            x(0) (N·d numbers) and notes (``initial state: zero`` when none is given).

        Raises
        ------
        InputError
            The given states do not have the network's shape: N·d numbers, or N states
            of d numbers each.
        """
        ini = self.initial
        if ini is None:
            return np.zeros(n * d), ["initial state: zero"]
        if isinstance(ini, UniformInitial):
            return ini.draw(n * d), []
        if ini.ndim == 2 and ini.shape != (n, d):
            raise InputError(
                f"expected {n} states of {d} numbers, got {ini.shape[0]} states of {ini.shape[1]}",
                field="initial",
            )
        if ini.size != n * d:
            raise InputError(
                f"expected {n} states of {d} numbers ({n * d} values), got {ini.size}",
                field="initial",
            )
        return np.array(ini, dtype=float).reshape(-1), []

    def options(self) -> dict[str, Any]:
        """The flat options (as :meth:`build` takes them), for summaries and re-runs.

        Returns
        -------
        dict
            θ, ΔC, the gain, T, the stepping, the method, ``resample``, the noise, the
            Monte Carlo options and the save times.
        """
        n = self.noise
        out: dict[str, Any] = {
            "theta": self.theta.tolist(),
            "margin": self.margin,
            "delta": self.delta,
            "gain": (
                self.gain
                if isinstance(self.gain, str)
                else self.gain.to_document()
                if isinstance(self.gain, ScheduleGain)
                else "callable"
            ),
            "T": self.T,
            "dt": self.stepping.dt,
            "stepping": self.stepping.kind,
            "ds": self.stepping.ds,
            "scheme": self.stepping.scheme,
            "method": self.method,
            "resample": self.resample,
            "digital": self.digital.to_dict() if self.digital is not None else None,
            "noise": {
                "sigma": n.sigma,
                "f": np.asarray(n.f).tolist() if not callable(n.f) else "callable",
                "sigma_edges": {f"{a}->{b}": s for (a, b), s in n.sigma_edges.items()},
            },
        }
        out.update({f.name: getattr(self.mc, f.name) for f in fields(self.mc)})
        if self.save.every is not None:
            out["save_every"] = self.save.every
        else:
            out["save_times"] = self.save._listed().tolist()
        return out


def _initial_from_document(doc: Any) -> np.ndarray | UniformInitial | None:
    if doc is None:
        return None
    if isinstance(doc, Mapping):
        if set(doc) != {"uniform", "seed"}:
            raise InputError(
                "expected {uniform: [lo, hi], seed: S} (UniformInitial(lo, hi, seed) in "
                "Python) or a list of states",
                field="initial",
            )
        uni = doc["uniform"]
        if not isinstance(uni, (list, tuple)) or len(uni) != 2:
            raise InputError("expected [lo, hi]", field="initial.uniform")
        return UniformInitial(uni[0], uni[1], doc["seed"])
    if isinstance(doc, list):
        return check_states(doc)
    raise InputError(
        "expected {uniform: [lo, hi], seed: S} (UniformInitial(lo, hi, seed) in "
        "Python) or a list of states",
        field="initial",
    )


__all__ = [
    "METHODS",
    "OPTION_KEYS",
    "RobustSampling",
    "SCENARIO_KEYS",
    "SimulationSpec",
    "check_noise",
]
