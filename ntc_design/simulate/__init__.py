"""Simulation layer: Monte Carlo Euler–Maruyama of the noisy SAN and its exact moments."""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..certify.gain import T as T_SYM
from ..certify.gain import parse_gain
from ..design import DESIGN_KEYS, ProtocolDesign, design_topology
from ..errors import InputError, require_positive
from ..model import SwitchingTopology, TimeVaryingTopology, Topology
from .grid import TimeGrid, build_grid
from .moments import Moments, check_moments_size, exact_moments
from .montecarlo import MonteCarloSpec, PartialStats, merge, run, run_chunk
from .system import SCHEMES, ModeSystem, NoiseModel, check_step_size, mode_system

Z95 = 1.959963984540054


class SimulationDiverged(RuntimeError):
    """NaN or overflow: the message names the time and the agent; ``result`` keeps what
    was computed until then."""

    def __init__(self, msg: str, result: SimulationResult):
        super().__init__(msg)
        self.result = result


@dataclass
class SimulationResult:
    labels: tuple
    theta: np.ndarray
    save_times: np.ndarray
    designs: dict[str, ProtocolDesign]
    mc: dict | None  # mean, lo, hi (S, N); mean_state (S, Nd); paths (k, S, Nd); count
    exact: Moments | None
    parameters: dict
    stats: dict
    notes: list[str] = field(default_factory=list)
    failure: dict | None = None
    grid: TimeGrid | None = None

    def summary(self) -> dict:
        lab = [str(a) for a in self.labels]
        out: dict = {
            "parameters": self.parameters,
            "topologies": {k: d.topology.to_dict() for k, d in self.designs.items()},
            "designs": {k: _design_brief(d) for k, d in self.designs.items()},
            "save_times": {
                "count": int(self.save_times.size),
                "first": float(self.save_times[0]),
                "last": float(self.save_times[-1]),
            },
            "run": self.stats,
            "notes": self.notes,
            "failure": self.failure,
        }
        if self.mc is not None:
            out["final_ms_error_mc"] = dict(zip(lab, self.mc["mean"][-1].tolist(), strict=True))
            out["final_ms_error_mc_band"] = {
                a: [lo, hi]
                for a, lo, hi in zip(
                    lab, self.mc["lo"][-1].tolist(), self.mc["hi"][-1].tolist(), strict=True
                )
            }
            out["sample_paths"] = path_spread(self)
        if self.exact is not None:
            out["final_ms_error_exact"] = dict(
                zip(lab, self.exact.ms_error[-1].tolist(), strict=True)
            )
            out["min_ms_error_exact"] = float(np.min(self.exact.ms_error.sum(axis=1)))
        return out


def _design_brief(d: ProtocolDesign) -> dict:
    full = d.to_dict()
    return {k: full[k] for k in DESIGN_KEYS}


def path_spread(res: SimulationResult, late_fraction: float = 0.2) -> dict:
    """How much the stored sample paths still move late in the run: over the last
    ``late_fraction`` of save times, per stored path, max − min of ‖x(t) − 1⊗θ‖, and the
    spread (std across stored paths) of ‖x(T) − 1⊗θ‖ at the final time."""
    paths = res.mc["paths"]
    if paths.size == 0:
        return {"stored": 0}
    err = np.linalg.norm(paths - np.tile(res.theta, len(res.labels)), axis=2)  # (k, S)
    s = err.shape[1]
    late = err[:, int(np.floor((1 - late_fraction) * (s - 1))) :]
    return {
        "stored": int(paths.shape[0]),
        "late_window": [float(res.save_times[-late.shape[1]]), float(res.save_times[-1])],
        "late_fluctuation_max": float(np.max(late.max(axis=1) - late.min(axis=1))),
        "late_fluctuation_mean": float(np.mean(late.max(axis=1) - late.min(axis=1))),
        "final_error_norm_mean": float(err[:, -1].mean()),
        "final_error_norm_spread": float(err[:, -1].std()),
    }


def make_gain(
    gain: str | Callable, field_name: str = "gain"
) -> tuple[Callable[[np.ndarray], np.ndarray], str]:
    """A vectorised c(t) (array in, array of the same shape out) from an expression
    string or a callable, and a label for it."""
    if isinstance(gain, str):
        import sympy as sp

        fn, label = sp.lambdify(T_SYM, parse_gain(gain, field_name), modules="numpy"), gain
    elif callable(gain):
        fn, label = gain, getattr(gain, "__name__", "callable")
    else:
        raise InputError(f"{field_name}: expected an expression in t or a callable")

    def c(t):  # a constant expression returns a scalar: broadcast it
        return np.asarray(fn(np.asarray(t, dtype=float)), dtype=float) * np.ones(np.shape(t))

    return c, label


def simulate(
    topology: Topology | SwitchingTopology | TimeVaryingTopology,
    theta: Sequence[float],
    *,
    margin: float = 0.1,
    gain: str | Callable = "1/(1+t)",
    noise: NoiseModel | None = None,
    initial: np.ndarray | Sequence | None = None,
    T: float = 10.0,  # noqa: N803 - the paper's name
    dt: float = 1e-3,
    paths: int = 1000,
    seed: int = 0,
    save_every: float | None = 0.1,
    save_times: Sequence[float] | None = None,
    method: str = "both",
    stepping: str = "uniform",
    ds: float | None = None,
    scheme: str = "explicit",
    workers: int = 2,
    block_size: int = 500,
    store_paths: int = 10,
    resample: float | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> SimulationResult:
    """Simulate the SAN with compound noise under the Lemma 1 protocol (re-designed per
    mode for switching files, and every ``resample`` time units for a topology given as
    functions of t), by Monte Carlo Euler–Maruyama (``method`` mc), exact moments (exact,
    linear f only) or both."""
    noise = noise or NoiseModel()
    require_positive("T", T)
    require_positive("dt", dt)
    require_positive("paths", paths, integer=True)
    require_positive("block_size", block_size, integer=True)
    require_positive("workers", workers, integer=True)
    if method not in ("mc", "exact", "both"):
        raise InputError(f"method: must be mc, exact or both, got {method!r}")
    if stepping not in ("uniform", "intrinsic"):
        raise InputError(f"stepping: must be uniform or intrinsic, got {stepping!r}")
    if scheme not in SCHEMES:
        raise InputError(f"scheme: must be explicit or implicit, got {scheme!r}")
    if scheme == "implicit" and stepping != "intrinsic":
        raise InputError(
            "scheme: implicit needs stepping: intrinsic (c·h constant, so (I + c h L_B) is factorised once per mode)"
        )
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise InputError(f"seed: must be a non-negative integer, got {seed!r}")
    if method in ("exact", "both") and noise.linear:
        check_moments_size(topology.n * topology.dim)
    cfun, gain_text = make_gain(gain)
    notes: list[str] = []
    # modes and their segments on [0, T)
    if isinstance(topology, SwitchingTopology):
        names = list(topology.modes)
        designs = {
            k: design_topology(topology.modes[k], theta, margin, thresholds=False) for k in names
        }
        segments = [(a, b, names.index(m)) for a, b, m in topology.segments(T)]
        n, d, labels = topology.n, topology.dim, topology.labels
    elif isinstance(topology, TimeVaryingTopology):
        step = resample if resample is not None else 0.1
        require_positive("resample", step)
        ts = np.arange(0.0, T, step)
        designs = {
            f"t={t:g}": design_topology(topology.at(float(t)), theta, margin, thresholds=False)
            for t in ts
        }
        names = list(designs)
        segments = [(float(t), float(min(t + step, T)), k) for k, t in enumerate(ts)]
        n, d, labels = topology.n, topology.dim, topology.labels
        notes.append(
            f"topology given as functions of t: sampled and re-designed every {step:g} time units"
        )
    else:
        designs = {
            topology.name or "topology": design_topology(topology, theta, margin, thresholds=False)
        }
        names = list(designs)
        segments = [(0.0, float(T), 0)]
        n, d, labels = topology.n, topology.dim, topology.labels
    th = next(iter(designs.values())).theta
    for k, des in designs.items():
        if not des.assumption_holds:
            notes.append(f"mode {k}: Assumption 2 fails (the design is used as Lemma 1 gives it)")
    systems = [mode_system(designs[k], noise, k) for k in names]
    # initial state
    if initial is None:
        x_init = np.zeros(n * d)
        notes.append("initial state: zero")
    else:
        try:
            x_init = np.asarray(initial, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise InputError("initial: expected numbers") from None
        if x_init.size != n * d:
            raise InputError(f"initial: expected N×d = {n}×{d} = {n * d} values, got {x_init.size}")
        if not np.all(np.isfinite(x_init)):
            raise InputError("initial: entries must be finite")
    # save times
    if save_times is not None:
        st = np.asarray(save_times, dtype=float)
        if st.size == 0 or np.any(~np.isfinite(st)) or np.any(st < 0) or np.any(st > T):
            raise InputError(f"save_times: expected times in [0, T={T:g}]")
        st = np.unique(np.concatenate([[0.0], st]))
    else:
        require_positive("save_every", save_every)
        st = np.unique(np.concatenate([np.arange(0.0, T, save_every), [T]]))
    grid = build_grid(
        float(T),
        float(dt),
        st,
        segments,
        gain=cfun,
        intrinsic_ds=(ds or dt) if stepping == "intrinsic" else None,
        h_max=max(1.0, 100 * dt) if stepping == "intrinsic" else None,
    )
    c_grid = cfun(grid.t[:-1])
    if c_grid.shape != grid.t[:-1].shape or not np.all(np.isfinite(c_grid)):
        raise InputError(f"gain: {gain_text!r} is not finite on [0, T]")
    if np.any(c_grid < 0):
        k = int(np.argmax(c_grid < 0))
        raise InputError(
            f"gain: {gain_text!r} is negative at t = {grid.t[k]:.6g}; c(t) must be >= 0"
        )
    # Euler–Maruyama step-size guard (drift eigenvalues and the mean-square noise limit)
    if method != "exact":
        check = check_step_size(systems, grid, c_grid, scheme)
        if check.warning:
            notes.append(check.warning)
            warnings.warn(check.warning, stacklevel=2)
    # noise callable shape check
    if not noise.linear:
        probe = np.zeros((2, systems[0].n_edges, d))
        try:
            outp = np.asarray(noise.f(probe + 1.0))
        except Exception as exc:  # noqa: BLE001 - user code
            raise InputError(
                f"noise.f: calling it on an array of shape {probe.shape} failed ({exc.__class__.__name__})"
            ) from None
        if outp.shape != probe.shape:
            raise InputError(
                f"noise.f: returned shape {outp.shape} for input shape {probe.shape}; it must return the same shape"
            )
    params = {
        "theta": th.tolist(),
        "margin": margin,
        "gain": gain_text,
        "noise": {
            "sigma": noise.sigma,
            "f": noise.f.tolist()
            if isinstance(noise.f, np.ndarray)
            else (noise.f if not callable(noise.f) else "callable"),
            "sigma_edges": {f"{a}->{b}": s for (a, b), s in noise.sigma_edges.items()},
        },
        "initial": x_init.tolist(),
        "T": T,
        "dt": dt,
        "paths": paths,
        "seed": seed,
        "block_size": block_size,
        "method": method,
        "stepping": stepping,
        "ds": ds,
        "scheme": scheme,
        "workers": workers,
        "save_times": int(st.size),
        "modes": names,
    }
    if isinstance(topology, SwitchingTopology):
        params["schedule"] = [{"mode": m, "duration": t} for m, t in topology.schedule]
    stats: dict = {"steps": grid.n_steps, "path_steps": grid.n_steps * paths}
    mc = None
    failure = None
    if method in ("mc", "both"):
        spec = MonteCarloSpec(
            tuple(systems),
            grid,
            cfun,
            th,
            x_init,
            n,
            d,
            paths,
            seed,
            block_size,
            store_paths,
            tuple(labels),
            scheme,
        )
        t0 = time.perf_counter()
        part = run(spec, workers=workers, progress=progress)
        sec = time.perf_counter() - t0
        stats.update({"mc_seconds": sec, "path_steps_per_second": grid.n_steps * paths / sec})
        mc = _mc_summary(part)
        failure = part.failure
    exact = None
    if method in ("exact", "both"):
        if noise.linear:
            t0 = time.perf_counter()
            exact = exact_moments(
                systems, segments, cfun, x_init - np.tile(th, n), grid.save_times, n, d
            )
            stats.update(
                {"exact_seconds": time.perf_counter() - t0, "exact_rk4_steps": exact.steps}
            )
        elif method == "exact":
            raise InputError("method: exact moments need a linear f (a scalar or a matrix)")
        else:
            notes.append("exact moments skipped: f is not linear")
    res = SimulationResult(
        tuple(labels), th, grid.save_times, designs, mc, exact, params, stats, notes, None, grid
    )
    if failure is not None:
        lab = labels[failure["agent"]]
        k = failure["save_index"]
        res = _truncate(res, k)
        res.failure = {**failure, "agent": lab}
        raise SimulationDiverged(
            f"simulation diverged (NaN or overflow) by t = {failure['t']:.6g} at agent {lab} (path {failure['path']}); "
            f"results kept up to t = {res.save_times[-1]:.6g}"
            if res.save_times.size
            else "",
            res,
        )
    return res


def _mc_summary(part: PartialStats) -> dict:
    p = part.count
    mean = part.sq / p
    var = np.maximum(part.sq2 / p - mean**2, 0.0) * (p / max(p - 1, 1))
    half = Z95 * np.sqrt(var / p)
    return {
        "mean": mean,
        "lo": np.maximum(mean - half, 0.0),
        "hi": mean + half,
        "mean_state": part.state / p,
        "paths": part.stored,
        "count": p,
        "valid_saves": part.valid_saves,
    }


def _truncate(res: SimulationResult, k: int) -> SimulationResult:
    if res.mc is not None:
        res.mc = {
            key: (
                v[:k]
                if key in ("mean", "lo", "hi", "mean_state")
                else (v[:, :k] if key == "paths" else v)
            )
            for key, v in res.mc.items()
        }
    if res.exact is not None:
        res.exact = Moments(
            res.exact.t[:k],
            res.exact.mean[:k],
            res.exact.ms_error[:k],
            res.exact.second,
            res.exact.steps,
        )
    res.save_times = res.save_times[:k]
    return res


__all__ = [
    "ModeSystem",
    "Moments",
    "MonteCarloSpec",
    "NoiseModel",
    "SimulationDiverged",
    "SimulationResult",
    "TimeGrid",
    "build_grid",
    "exact_moments",
    "merge",
    "mode_system",
    "run",
    "run_chunk",
    "simulate",
]
