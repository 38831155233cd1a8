"""What ``ntc export`` exports: the agents' law (:class:`~ntc_design.protocol.agents.AgentLaw`)
of a certified design, from a scenario or from a certificate.

- A scenario (YAML or JSON, :func:`~ntc_design.simulate.scenario.load_scenario`): its
  ``digital:`` block gives h and D (``period``/``delay`` override it), its gain, noise and θ
  the rest; the design is Lemma 1's, and it is certified first
  (:func:`ntc_design.certify.certify`): refused unless the certificate verifies and a
  theorem is guaranteed.
- A certificate (kinds whose subject has dense modes: ``hurwitz``, ``switching``): verified
  first (:func:`ntc_design.certify.verify`) and refused unless valid; its subject gives the
  topologies (their edge order is the subject's), the informed agents, B_i, δ, x0, θ and
  the schedule. h, D, the gain and the noise come from its subject where it states them
  (``digital: {period, delay}``, ``gain``, ``noise: {sigma, f, sigma_edges}``), else from
  the arguments (``period`` is then required; the gain defaults to 1/(1+t), the noise to
  the paper's σ and f), and the gain must satisfy the conditions of Theorem 1.

Messages name the parameters (``period``, ``delay``, ``gain``) for the values given as
arguments (the command line writes them as its flags), the file's fields for the file's.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..certify import KINDS, certify, verify
from ..certify.dense import DenseContext
from ..certify.fields import vector
from ..certify.format import FORMAT
from ..certify.kinds.digital import DigitalContext, DigitalState
from ..certify.kinds.digital_loss import LossState
from ..choices import LossPolicy
from ..errors import AssumptionWarning, InputError, Option
from ..gain.schedule import ScheduleGain, analyse_any_gain, gain_from_option, schedule_from_document
from ..io.documents import read_document
from ..io.files import parse_scenario
from ..model import SwitchingTopology, Topology
from ..model.paper import F_SCALE, SIGMA
from ..numerics.linalg import RANGE_TEXT, out_of_range
from ..protocol.agents import AgentLaw, agent_law, lossy_law, make_law, mode_law
from ..protocol.digital import Digital, DigitalDesign
from ..protocol.lemma1 import (
    ProtocolDesign,
    SwitchingDesign,
    no_informed_agent_text,
    uninformed_modes,
)
from ..simulate.noise import NoiseModel
from ..simulate.scenario import load_scenario
from ..simulate.spec import SimulationSpec

#: A scenario's horizon when it gives none (the simulator's default).
DEFAULT_T = SimulationSpec.__dataclass_fields__["T"].default


@dataclass(frozen=True)
class ExportOptions:
    """What an export may set over its source, written once: each None keeps the
    scenario's or the certificate's value (a certified value that an option contradicts is
    refused by the reader).

    Attributes
    ----------
    period, delay : float, int or None
        h and D (over a scenario's or a subject's digital block; ``period`` required for a
        continuous certificate).
    gain : str, ScheduleGain or None
        c(t) (a ``.csv`` name is a schedule file).
    sigma, f : float or None
        The noise's σ and f (a continuous certificate's default: the paper's σ = 0.4,
        f = 0.3).
    loss : float or None
        p on every edge.
    policy : {"skip", "rescale", "hold"} or None
        What an agent does with a lost message.

    Examples
    --------
    >>> ExportOptions(period=0.1, delay=1).period
    0.1
    """

    period: float | None = None
    delay: int | None = None
    gain: str | ScheduleGain | None = None
    sigma: float | None = None
    f: float | None = None
    loss: float | None = None
    policy: LossPolicy | None = None


#: No option given: every value is the source's.
NO_OPTIONS = ExportOptions()


@dataclass(frozen=True, eq=False)
class ExportSource:
    """A certified design's agents' law and where it came from.

    Attributes
    ----------
    law : AgentLaw
        What the agents run.
    source : str
        The file.
    kind : str
        ``scenario`` or ``certificate (KIND)``.
    initial : numpy.ndarray
        x(0) for the example input (the scenario's, else zero).
    horizon : float or None
        T (a scenario's), else None.
    notes : tuple of str
        What the reader should know.
    """

    law: AgentLaw
    source: str
    kind: str
    initial: np.ndarray
    horizon: float | None
    notes: tuple[str, ...] = ()


def _digital(
    period: float | None,
    delay: int | None,
    given: Any,
    horizon: float | None,
    where: str,
    loss: float | None = None,
    policy: str | None = None,
) -> Digital:
    """h, D, p and the policy: the arguments over a scenario's ``digital:`` block (read as
    simulate reads it: an unknown field is refused), errors naming the parameter for an
    argument and the block for the file's value."""
    if given is not None and not isinstance(given, dict):
        raise InputError("expected {period: h, delay: D}", field=f"{where}: digital")
    base = dict(given or {})
    if period is not None:
        base["period"] = period
    if delay is not None:
        base["delay"] = delay
    if loss is not None:
        base["loss"] = loss
    if policy is not None:
        base["policy"] = policy
    if "period" not in base:
        raise InputError(
            f"{where} has no digital block (period h, delay D); give ",
            Option("period"),
            field="period",
            option=True,
        )
    try:
        dg = Digital.from_document(base)
        if horizon is not None:
            dg.steps(horizon)
    except InputError as exc:  # a field an argument gave is that parameter, else the file's
        args = {"period": period, "delay": delay, "loss": loss, "policy": policy}
        name = (exc.field or "").removeprefix("digital.")
        if (exc.field or "").startswith("digital.") and args.get(name) is not None:
            raise InputError(*exc.parts, field=name, option=True) from None
        raise InputError(f"{exc}", field=where) from None
    if not math.isfinite(dg.period):
        raise InputError(f"must be a finite number, got {dg.period!r}", field="period", option=True)
    return dg


def _gain_option(gain: str | ScheduleGain | None) -> str | ScheduleGain | None:
    if gain is None or isinstance(gain, ScheduleGain):
        return gain

    return gain_from_option(gain, "gain")


def _check_gain(gain: str | ScheduleGain, where: str) -> None:
    """Refuse a gain whose conditions of Theorem 1 do not hold (or are undetermined)."""
    a = analyse_any_gain(gain)
    if a.mean_square is not True:
        label = gain.text if isinstance(gain, ScheduleGain) else gain
        raise InputError(
            f"c(t) = {label} does not satisfy the gain conditions of Theorem 1 "
            "(continuous and >= 0, ∫c = ∞, c → 0); no theorem would be guaranteed",
            field=where,
        )


def from_scenario(path: str | Path, options: ExportOptions = NO_OPTIONS) -> ExportSource:
    """The agents' law of a scenario's certified Lemma 1 design (on lossy links when its
    ``digital:`` block or its topology's edges give a loss: the ``digital_loss``
    certificate, D = 0 with ``skip`` or ``rescale``).

    Parameters
    ----------
    path : str or Path
        The scenario (YAML or JSON).
    options : ExportOptions, optional
        h and D over the scenario's ``digital:`` block, and the gain, the noise, the loss
        and the policy instead of the scenario's.

    Returns
    -------
    ExportSource

    Raises
    ------
    InputError
        A bad file or value; a topology that is neither fixed nor switching; a design whose
        certificate does not verify or for which no theorem is guaranteed; lossy links
        with ``hold`` its certificate does not prove, a switching set (not proven), or a
        delay the certificate does not prove.
    """
    period, delay, gain, sigma, f = (
        options.period,
        options.delay,
        options.gain,
        options.sigma,
        options.f,
    )
    sc = parse_scenario(path)
    src = sc.source
    given = sc.document.get("digital")
    horizon = sc.document.get("T", DEFAULT_T)
    if isinstance(horizon, bool) or not isinstance(horizon, (int, float)) or not horizon > 0:
        horizon = None  # the scenario's own check names it
    # the options replace the file's block before the scenario is checked (a period of the
    # file's that the option overrides is not refused)
    dg = _digital(period, delay, given, horizon, src, options.loss, options.policy)
    top, spec, _ = load_scenario(path, {"digital": dg}, sc)
    if not isinstance(top, (Topology, SwitchingTopology)):
        raise InputError(
            f"only a fixed topology or a switching set can be exported (got {type(top).__name__})",
            field=f"{src}: topology",
        )
    if uninformed_modes(top):  # said as ntc design says it, not as a failed inequality
        raise InputError(
            f"{no_informed_agent_text(uninformed_modes(top))}; nothing exported", field=src
        )
    g = _gain_option(gain)
    if g is not None:
        spec = spec.replace(gain=g)
    if sigma is not None or f is not None:
        noise = spec.noise
        spec = spec.replace(
            noise=NoiseModel(
                sigma=noise.sigma if sigma is None else _number("sigma", sigma, 0.0),
                f=noise.f if f is None else _number("f", f),
                sigma_edges=noise.sigma_edges,
            )
        )
    if not isinstance(spec.gain, (str, ScheduleGain)):
        raise InputError("a Python function cannot be exported", field=f"{src}: gain")
    _check_noise("sigma" if sigma is not None else f"{src}: noise.sigma", spec.noise.sigma)
    law, res = _certified_law(
        top,
        spec.theta,
        spec.margin,
        spec.delta,
        spec.gain,
        spec.noise,
        dg,
        src,
    )
    if isinstance(top, Topology):
        law = _named(law, top.name or Path(src).stem)
    x_init, _ = spec.initial_state(top.n, top.dim)
    return ExportSource(
        law, src, "scenario", np.asarray(x_init, dtype=float), spec.T, (_certified(res),)
    )


def _check_noise(where: str, sigma: Any, f: Any = None) -> None:
    """Refuse a σ or f that no certificate can state (a nonzero magnitude outside
    [2^-250, 2^250], e.g. the subnormal 5e-324), before any work."""
    for value in (sigma, f):
        if value is None or callable(value):
            continue
        if out_of_range(np.asarray(value, dtype=float)):
            raise InputError(f"{value!r} has {RANGE_TEXT}"[: max(0, 198 - len(where))], field=where)


def _certified_law(
    top: Topology | SwitchingTopology,
    theta: Any,
    margin: float,
    delta: float | None,
    gain: str | ScheduleGain,
    noise: NoiseModel,
    dg: Digital,
    src: str,
) -> tuple[AgentLaw, Any]:
    """Certify the sampled protocol (period h, delay D, the gain and the noise) of Lemma 1's
    design and give its agents' law; refused unless the certificate verifies and its
    sampled theorems are guaranteed (nothing is exported unproven); on lossy links the
    ``digital_loss`` certificate, and the law with each edge's 1 − p_e and the policy."""
    losses = _losses(top, dg, src)
    _check_noise(f"{src}: noise", noise.sigma, None if callable(noise.f) else noise.f)
    for value in noise.sigma_edges.values():
        _check_noise(f"{src}: noise.sigma_edges", value)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", AssumptionWarning)  # the verdict says it
        f_cert = noise.f if not callable(noise.f) else 0.0
        res = certify(
            top,
            theta,
            margin,
            gain,
            delta,
            noise_sigma=noise.sigma,
            noise_f=f_cert,
            digital=dg,
            sigma_edges={(str(a), str(b)): v for (a, b), v in noise.sigma_edges.items()},
        )
    if not res.verification.valid:
        failed = "; ".join(c.name for c in res.verification.failed)[:300]
        raise InputError(
            f"the design's certificate ({res.certificate['kind']}) does not verify "
            f"({failed}); nothing exported",
            field=src,
        )
    if losses and dg.policy == "hold" and not _hold_proven(res.certificate):
        _unproven("hold", 0, src, False)  # before the theorems: what is missing is this proof
    sampled = [t for t in res.theorems if t.sampled]
    if not res.proven or not sampled or not any(t.guaranteed for t in sampled):
        raise InputError(
            f"no theorem is guaranteed for the sampled protocol at h = {dg.period:g}, "
            f"D = {dg.delay} with this gain (ntc certify "
            f"{Option('period', alias='with a period')} says why); nothing exported",
            field=src,
        )
    design = res.design.base if isinstance(res.design, DigitalDesign) else res.design
    if not isinstance(design, (ProtocolDesign, SwitchingDesign)):
        raise InputError("this design cannot be exported", field=f"{src}: topology")
    law = agent_law(design, dg, gain, noise.sigma, noise.f, noise.sigma_edges)
    if losses:
        if res.certificate["kind"] != "digital_loss":  # the lossy proof, nothing weaker
            raise InputError("lossy links are not certified; nothing exported", field=src)
        law = lossy_law(law, losses, dg.policy)
    return law, res


def _hold_proven(cert: dict) -> bool:
    """Whether a verified ``digital_loss`` certificate proves hold (its mean-square
    section, not ``results.digital.stopped``)."""
    res = cert.get("results", {}).get("digital", {})
    return (
        "digital_mean_square" in cert.get("certifies", [])
        and isinstance(res, dict)
        and res.get("policy") == "hold"
        and "stopped" not in res
    )


def _unproven(policy: str, delay: int, where: str, hold_proven: bool = True) -> None:
    """Refuse lossy links that no certificate proves (``hold`` whose certificate does not
    prove it), in one line; a delay is exported when the ``digital_loss`` certificate
    proves it (its delay line)."""
    if policy == "hold" and not hold_proven:
        raise InputError(
            "lossy links with the hold policy are not proven (the digital_loss "
            "certificate covers skip and rescale, and hold where its section proves it); "
            "nothing exported",
            field=where,
        )


def _losses(top: Topology | SwitchingTopology, dg: Digital, src: str) -> dict:
    """p_e of every edge (i, j) of a lossy design (its own ``loss:`` over the uniform
    one), empty when every message arrives; refused when not proven."""
    if isinstance(top, SwitchingTopology):
        lossy = dg.lossy or any(getattr(t, "loss", None) for t in top.modes.values())
        if lossy:
            raise InputError(
                "lossy links are certified for one topology (digital_loss), not a "
                "switching set; nothing exported",
                field=src,
            )
        return {}
    own = dict(getattr(top, "loss", {}) or {})
    losses = {k: float(own.get(k, dg.loss)) for k in top.edges}
    if not any(p > 0 for p in losses.values()):
        return {}
    _unproven(dg.policy, dg.delay, src)
    return losses


def _named(law: AgentLaw, name: str) -> AgentLaw:
    from dataclasses import replace

    return replace(law, name=name)


def _certified(res: Any) -> str:
    cont = ", ".join(str(t.theorem) for t in res.theorems if t.guaranteed and not t.sampled)
    samp = ", ".join(str(t.theorem) for t in res.theorems if t.guaranteed and t.sampled)
    k0 = res.certificate["results"].get("digital", {}).get("k0")
    return (
        f"certified: {res.certificate['kind']} certificate valid "
        f"({res.verification.method}); Theorem {cont} guaranteed for the continuous protocol"
        + (
            f", Theorem {samp} for the sampled one (contracting from step k₀ = {k0})"
            if samp
            else ""
        )
    )


def _number(name: str, value: Any, minimum: float | None = None) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(f"expected a number, got {value!r}", field=name, option=True)
    v = float(value)
    if not math.isfinite(v) or (minimum is not None and v < minimum):
        at_least = "" if minimum is None else f" >= {minimum:g}"
        text = f"expected a finite number{at_least}, got {v!r}"[:180]
        raise InputError(text, field=name, option=True)
    return v


def _same(name: str, given: Any, certified: Any, src: str) -> None:
    """Refuse an option that differs from the value the certificate proves (equal is fine)."""
    if given is None:
        return
    a = np.asarray(given, dtype=float)
    b = np.asarray(certified, dtype=float)
    if a.shape != b.shape or not np.array_equal(a, b):
        _differs(name, given, b.tolist(), src)  # plain numbers, not NumPy reprs


def _differs(name: str, given: Any, shown: Any, src: str) -> None:
    raise InputError(
        f"{given!r} differs from the certified value {shown!r} ({src}); "
        "the certificate proves only its own protocol: drop the option or certify anew"[:290],
        field=name,
        option=True,
    )


def _digital_gain(given: Any, where: str) -> str | ScheduleGain:
    return given if isinstance(given, str) else schedule_from_document(given, where)


def from_certificate(
    path: str | Path, options: ExportOptions = NO_OPTIONS, doc: dict | None = None
) -> ExportSource:
    """The agents' law of a certificate's design, from its verified reading only.

    A ``digital`` or ``digital_switching`` certificate proves the sampled protocol: h, D,
    the gain and the noise are its subject's as verify read them, and an option that differs
    from one of them is refused. A continuous one (``hurwitz``, ``switching``) proves
    nothing sampled: its design (the subject's topologies, θ, margin and δ) is certified as
    the sampled protocol at ``period`` first, as a scenario is, and refused unless the
    sampled theorems are guaranteed.

    Parameters
    ----------
    path : str or Path
        The certificate (JSON).
    options : ExportOptions, optional
        h and D (``period`` required for a continuous certificate); the gain of a
        continuous certificate (default: its tabulated schedule, else 1/(1+t)) and its
        noise (default: the paper's σ = 0.4, f = 0.3); p and the policy: a
        ``digital_loss`` certificate's are its verified reading's (an option that differs
        is refused), a continuous one is certified on lossy links.
    doc : dict, optional
        The certificate already read.

    Returns
    -------
    ExportSource

    Raises
    ------
    InputError
        A malformed certificate (an unknown field included), one that does not verify, a
        kind without dense modes, an option that differs from a certified value, a missing
        period, or a sampled protocol without a guaranteed theorem.
    """
    period, delay, gain, sigma, f, loss, policy = (
        options.period,
        options.delay,
        options.gain,
        options.sigma,
        options.f,
        options.loss,
        options.policy,
    )
    src = str(path)
    doc = read_document(path) if doc is None else doc
    ver = verify(doc, src)
    if not ver.valid:
        failed = "; ".join(c.name for c in ver.failed)[:300]
        raise InputError(f"the certificate does not verify ({failed}); nothing exported", field=src)
    kind = KINDS[str(doc["kind"])]
    reading = kind.read(doc, src)  # the reading verify proved things about
    if not isinstance(reading.state, DenseContext):
        raise InputError(
            f"a {kind.name} certificate cannot be exported (its subject has no "
            "dense modes; the hurwitz, switching and digital kinds can)",
            field=f"{src}: kind",
        )
    ctx: DenseContext = reading.state
    schedule = ver.about.schedule if ver.about is not None and ver.about.schedule else ()
    first = next(iter(ctx.modes.values()))
    if not isinstance(ctx, DigitalContext):
        return _continuous(doc, ctx, schedule, src, kind.name, options)
    state: DigitalState | LossState = ctx.digital
    sampled = state.subject
    ls = state.loss if isinstance(state, LossState) else None
    losses = _certified_losses(ls, sampled.delay, loss, policy, src, state.stated is not None)
    if state.stated is None:
        raise InputError(
            "the certificate does not prove the sampled protocol "
            "(results.digital.stopped); nothing exported",
            field=src,
        )
    _same("period", period, sampled.period, src)
    _same("delay", delay, sampled.delay, src)
    if sigma is not None:
        _same("sigma", _number("sigma", sigma, 0.0), sampled.sigma, src)
    fs = sampled.f
    if f is not None and not np.array_equal(_number("f", f) * np.eye(first.top.dim), fs):
        scalar = np.array_equal(fs, fs[0, 0] * np.eye(len(fs)))
        _differs("f", float(f), float(fs[0, 0]) if scalar else fs.tolist(), src)
    g = _digital_gain(sampled.gain, f"{src}: subject.digital.gain")
    if gain is not None:
        given = _gain_option(gain)
        text = given.text if isinstance(given, ScheduleGain) else given
        stated = g.text if isinstance(g, ScheduleGain) else g
        if "".join(str(text).split()) != "".join(str(stated).split()):  # spaces mean nothing
            raise InputError(
                f"{text!r} differs from the certified gain {stated!r} ({src}); drop "[:290],
                Option("gain"),
                field="gain",
                option=True,
            )
    _check_gain(g, f"{src}: subject.digital.gain")
    dg = Digital(sampled.period, sampled.delay)
    modes = []
    for name, m in ctx.modes.items():
        x0 = vector(doc["subject"]["modes"][name]["x0"], m.top.dim, f"{src}: x0")  # verified
        modes.append(
            mode_law(name, m.top, sorted(m.b), m.b, m.delta, x0, sampled.sigma, sampled.sigma_edges)
        )
    law = make_law(
        first.top.name or Path(src).stem,
        first.top,
        first.theta,
        modes,
        schedule,
        dg,
        g,
        sampled.f,
    )
    if losses and ls is not None:
        law = lossy_law(law, losses, ls.policy)
    notes = (f"certificate: {kind.name}, valid ({ver.method}); the sampled protocol proven",)
    return ExportSource(
        law, src, f"certificate ({kind.name})", np.zeros(law.n * law.dim), None, notes
    )


def _certified_losses(
    ls: Any, delay: int, loss: float | None, policy: str | None, src: str, proven: bool = False
) -> dict:
    """A sampled certificate's p_e by edge (empty: lossless), from its verified reading
    only: a ``loss`` or ``policy`` that differs is refused, as is what it does not prove."""
    if ls is None:
        if loss is not None and loss != 0:
            raise InputError(
                f"{loss!r} differs from the certified protocol ({src}), which has no "
                "lost messages; drop the option or certify anew"[:290],
                field="loss",
                option=True,
            )
        return {}
    if policy is not None and policy != ls.policy:
        raise InputError(
            f"{policy!r} differs from the certified policy {ls.policy!r} ({src}); "
            "drop the option or certify anew"[:290],
            field="policy",
            option=True,
        )
    values = sorted(set(ls.losses.values()))
    if loss is not None and values != [loss]:
        shown = values[0] if len(values) == 1 else "per-edge losses"
        raise InputError(
            f"{loss!r} differs from the certified {shown!r} ({src}); "
            "drop the option or certify anew"[:290],
            field="loss",
            option=True,
        )
    if not any(p > 0 for p in ls.losses.values()):
        return {}
    _unproven(ls.policy, delay, src, proven)
    return dict(ls.losses)


def _continuous(
    doc: dict,
    ctx: DenseContext,
    schedule: tuple,
    src: str,
    kind: str,
    options: ExportOptions,
) -> ExportSource:
    """A continuous certificate's design certified as the sampled protocol first."""
    period, delay, gain, sigma, f, loss, policy = (
        options.period,
        options.delay,
        options.gain,
        options.sigma,
        options.f,
        options.loss,
        options.policy,
    )
    dg = _digital(period, delay, None, None, f"{src} (a {kind} certificate)", loss, policy)
    stated = doc.get("gain")  # a tabulated schedule whose conditions verify derived
    if stated is not None and gain is not None:
        raise InputError(
            f"the certificate states its gain ({src}: gain); drop ",
            Option("gain"),
            field="gain",
            option=True,
        )
    g: str | ScheduleGain = (
        schedule_from_document(stated, f"{src}: gain")
        if stated is not None
        else (_gain_option(gain) or "1/(1+t)")
    )
    _check_gain(g, "gain" if gain is not None else f"{src}: gain")
    noise = NoiseModel(
        sigma=SIGMA if sigma is None else _number("sigma", sigma, 0.0),
        f=F_SCALE if f is None else _number("f", f),
    )
    _check_noise("sigma" if sigma is not None else "noise", noise.sigma, noise.f)
    tops = {name: m.top for name, m in ctx.modes.items()}
    first_name, first = next(iter(ctx.modes.items()))
    margin = float(doc["subject"]["modes"][first_name]["margin"])
    deltas = {m.delta for m in ctx.modes.values()}
    top: Topology | SwitchingTopology = (
        SwitchingTopology(tops, tuple(schedule), source=src) if schedule else first.top
    )
    law, res = _certified_law(
        top,
        first.theta,
        margin,
        deltas.pop() if len(deltas) == 1 else None,
        g,
        noise,
        dg,
        src,
    )
    for ml in law.modes:  # the design re-derived must be the certificate's
        m = ctx.modes.get(ml.name)
        if m is None or ml.delta != m.delta or sorted(ml.informed) != sorted(m.b):
            raise InputError(
                "Lemma 1's design of its topology is not the "
                "certificate's (δ or the informed agents differ); nothing exported",
                field=f"{src}: subject.modes.{ml.name}",
            )
    law = _named(law, first.top.name or Path(src).stem)
    notes = (
        f"certificate: {kind}, valid (continuous); the sampled protocol certified here",
        _certified(res),
    )
    return ExportSource(law, src, f"certificate ({kind})", np.zeros(law.n * law.dim), None, notes)


def is_certificate(doc: Any) -> bool:
    """Whether a document read from a file is a certificate (its ``format`` says so).

    Parameters
    ----------
    doc : Any
        The document.

    Returns
    -------
    bool
    """
    return isinstance(doc, dict) and doc.get("format") == FORMAT


def load_source(path: str | Path, options: ExportOptions = NO_OPTIONS) -> ExportSource:
    """A scenario's or a certificate's agents' law (:func:`from_scenario`,
    :func:`from_certificate`), told apart by the file's content.

    Parameters
    ----------
    path : str or Path
        The scenario or certificate.
    options : ExportOptions, optional
        What to set over the file's values.

    Returns
    -------
    ExportSource

    Raises
    ------
    InputError
        As :func:`from_scenario` and :func:`from_certificate`.
    """
    doc = read_document(path)
    if is_certificate(doc):
        return from_certificate(path, options, doc)
    return from_scenario(path, options)


__all__ = [
    "NO_OPTIONS",
    "ExportOptions",
    "ExportSource",
    "from_certificate",
    "from_scenario",
    "is_certificate",
    "load_source",
]
