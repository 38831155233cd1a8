"""The digital protocol as code an agent runs: each agent's tables (per mode) and THE AGENT
LAW, defined here once; the exported C and Python (:mod:`ntc_design.export`) and the
toolkit's reference (:func:`ntc_design.simulate.replay.replay`) implement it with the same
operations in the same order, so all three agree bit for bit.

The model (:mod:`ntc_design.protocol.digital`): period h, delay D, t_k = k·h (the double
product), c_k = c(t_k), the mode of step k by :func:`~ntc_design.protocol.digital.step_modes`
(exact: t_k = k·h against the schedule, h and the durations as their decimals), the initial state held before the start. In x coordinates

    x_{k+1} = x_k + h c_k (u − L_B x_{k−D}) + c_k √h Σ_e (g_e ξ_{k,e,1} + G_e x_{k−D} ξ_{k,e,2}),

u = (Δ⊗I)·blockdiag(|B_i|)·x0, g_e = e_i ⊗ σ_e|A_ij| 1_d, G_e x = e_i ⊗ |A_ij| F (x_j − x_i)
for edge e = (j → i), F the d×d matrix of f(x) = F x.

**File edge order.** A mode's edges in the order of its topology's ``weights`` mapping
(the order of the file, or of a certificate's subject), leaving out zero weights
(sgn A_ij = 0). (The simulator's :class:`~ntc_design.simulate.system.ModeSystem` sorts its
edges, :attr:`Topology.edges`; :attr:`ModeLaw.sorted_index` maps one to the other.)
Agent i's in-edges ("slots") are the edges into i, in file order.

**The measurement** of in-neighbour j (edge e = j → i) at step k, from the state D samples
old, xd = x_{k−D}, with the edge's two normals z1 (additive) and z2 (multiplicative)::

    diff[b] = xd_j[b] − xd_i[b]
    fd[a]   = F[a][0]*diff[0];  fd[a] += F[a][b]*diff[b]  for b = 1 … d−1
    m[a]    = s_e*xd_j[a] − xd_i[a] + (sigma_e*z1 + fd[a]*z2) / sqrth

(s_e = sgn A_ij = ±1, sigma_e the edge's σ, sqrth = √h as a constant). With h c |A_ij|
this is the edge's share of the drift and of the noise above.

**The update** of agent i, with hc = h*c_k::

    acc = u_i[a]                                   (0.0 for an uninformed agent)
    acc -= bd_i[a][b]*xd_i[b]   for b = 0 … d−1    (informed agents; bd_i = δ·|B_i|)
    acc += W_e[a][b]*m_e[b]     for each slot e in file order, for b = 0 … d−1 (W_e = |A_ij|)
    x_next[a] = x_i[a] + hc*acc

for a = 0 … d−1, where x_i is the agent's current state x_k. Summed over the edges, in
exact arithmetic, this is the recursion above.

**Lossy links** (:mod:`.loss`; :attr:`AgentLaw.policy` ``skip`` or ``rescale``): each in-edge
has an arrival flag χ_e ∈ {0, 1} at each step and keep_e = 1 − p_e (the double 1.0 − p_e).
A slot whose message is lost (χ_e = 0) adds nothing (its term and its noise are left out);
under ``rescale`` a received slot adds ``|A_ij|[a][b]*(m_e[b]/keep_e)`` instead (the mean
drift unbiased). With every flag 1 and keep_e = 1, this is the lossless law bit for bit.
Under ``hold`` each slot keeps a held measurement held_e (d numbers, agent i's state):
before the first arrival the noiseless measurement of x(0) (the measurement above with
z1 = z2 = 0.0), and at each step held_e ← m_e when the message arrives (a copy); every slot
then adds ``W_e[a][b]*held_e[b]`` (the update above with held_e for m_e). Exported only
where the ``digital_loss`` certificate proves it.

:class:`AgentLaw` holds what that needs: per mode (:class:`ModeLaw`) the edges in file order
with their sources, signs, |A_ij| and σ_e, per agent δ·|B_i| and u_i, and the period, the
delay, F, the gain (:class:`~ntc_design.gain.code.GainCode`) and the schedule.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError
from ..gain.code import GainCode
from ..gain.schedule import ScheduleGain
from ..model import ExpressionFamily, Label, Topology
from .digital import Digital, ScheduleTicks, step_modes
from .lemma1 import ProtocolDesign, SwitchingDesign, input_vector
from .loss import require_loss

#: Why the digital protocol refuses a topology given as expressions of t (one text for
#: the simulator, the tuners and the certificate).
NOT_SAMPLED = (
    "a topology given as expressions of t is not sampled by the digital protocol; give it "
    "as a switching schedule or a fixed topology"
)


def require_sampled(topology: object, field: str = "digital", option: bool = False) -> None:
    """Refuse a topology given as expressions of t (A(t)) for the digital protocol, the
    one check of every caller that samples: the protocol runs one topology or a switching
    set, whose mode at each sample t_k it knows (:func:`.digital.step_modes`). Here, not
    in :mod:`.digital`, which the command line loads before any topology.

    Parameters
    ----------
    topology : object
        The network.
    field : str, optional
        The field the error names (what asked for the sampled protocol).
    option : bool, optional
        The field is a parameter of the call (the command line names it by its flag).

    Raises
    ------
    InputError
        ``FIELD: a topology given as expressions of t is not sampled ...``.

    Examples
    --------
    >>> import ntc_design as nd
    >>> require_sampled(nd.load("examples/g1.yaml"))  # one fixed topology: sampled
    """
    if isinstance(topology, ExpressionFamily):
        raise InputError(NOT_SAMPLED, field=field, option=option)


def file_edges(top: Topology) -> list[tuple[int, int]]:
    """The edges (i, j), j → i, in file order: the topology's ``weights`` mapping in its
    insertion order, without zero weights.

    Parameters
    ----------
    top : Topology
        The topology.

    Returns
    -------
    list of (int, int)
    """
    return [(i, j) for i, j in top.weights if top.sign(i, j) != 0]


@dataclass(frozen=True, eq=False)
class ModeLaw:
    """One mode's tables, edges in file order (:func:`file_edges`).

    Attributes
    ----------
    name : str
        The mode.
    dst, src : numpy.ndarray
        (E,) agent i and agent j of edge e = j → i.
    sign : numpy.ndarray
        (E,) sgn A_ij, ±1.0.
    weight : numpy.ndarray
        (E, d, d) ``|A_ij|``.
    sigma : numpy.ndarray
        (E,) the additive noise σ_e of the edge's measurement.
    informed : tuple of int
        The informed agents (0-based).
    delta : float
        δ (δ_i on the informed agents).
    bd : numpy.ndarray
        (N, d, d) ``δ·|B_i|`` (zero blocks for the uninformed).
    u : numpy.ndarray
        (N, d) ``u_i = δ|B_i|x0`` (zero for the uninformed).
    sorted_index : numpy.ndarray
        (E,) where edge e sits in :attr:`Topology.edges` (the simulator's order).
    keep : numpy.ndarray or None
        (E,) 1 − p_e, the probability that the edge's message arrives (lossy links;
        None: every message arrives).
    """

    name: str
    dst: np.ndarray
    src: np.ndarray
    sign: np.ndarray
    weight: np.ndarray
    sigma: np.ndarray
    informed: tuple[int, ...]
    delta: float
    bd: np.ndarray
    u: np.ndarray
    sorted_index: np.ndarray
    keep: np.ndarray | None = None

    @property
    def n_edges(self) -> int:
        """E, the mode's edges."""
        return int(self.dst.size)

    def in_edges(self, i: int) -> list[int]:
        """Agent i's slots: the edges into i (their file-order indices, in order).

        Parameters
        ----------
        i : int
            0-based agent.

        Returns
        -------
        list of int
        """
        return np.flatnonzero(self.dst == i).tolist()

    @cached_property
    def slots(self) -> tuple[tuple[np.ndarray, np.ndarray], ...]:
        """Slot by slot: (the agents with an s-th in-edge, those edges), s = 0, 1, …; an
        agent appears at most once per slot (the vectorised replay adds slot by slot)."""
        n = self.bd.shape[0]
        by_agent: list[list[int]] = [[] for _ in range(n)]
        for e, i in enumerate(self.dst.tolist()):
            by_agent[i].append(e)
        width = max((len(x) for x in by_agent), default=0)
        out = []
        for s in range(width):
            agents = [i for i in range(n) if len(by_agent[i]) > s]
            out.append(
                (
                    np.array(agents, dtype=np.int64),
                    np.array([by_agent[i][s] for i in agents], dtype=np.int64),
                )
            )
        return tuple(out)

    @property
    def max_in_degree(self) -> int:
        """The most in-edges of one agent."""
        return len(self.slots)


def _noise_matrix(f: Any, d: int) -> np.ndarray:
    """F of f(x) = F x: s·I for a number s (as the simulator's ScalarNoise), a d×d matrix."""
    if callable(f):
        raise InputError(
            "a Python function cannot be exported; give a number or a matrix", field="noise.f"
        )
    arr = np.asarray(f, dtype=float)
    if arr.ndim == 0:
        return float(arr) * np.eye(d)
    if arr.shape != (d, d):
        raise InputError(
            f"expected a scalar or a {d}x{d} matrix, got shape {arr.shape}", field="noise.f"
        )
    if not np.all(np.isfinite(arr)):
        raise InputError("an entry is not finite", field="noise.f")
    return arr.copy()


def mode_law(
    name: str,
    top: Topology,
    informed: Sequence[int],
    b: Mapping[int, np.ndarray],
    delta: float,
    x0: np.ndarray,
    sigma: float,
    sigma_edges: Mapping[tuple, float] | None = None,
) -> ModeLaw:
    """One mode's tables from its design's numbers.

    Parameters
    ----------
    name : str
        The mode.
    top : Topology
        Its topology (the file order of its ``weights``).
    informed : sequence of int
        The informed agents (0-based).
    b : mapping of int to numpy.ndarray
        B_i of the informed agents.
    delta : float
        δ.
    x0 : numpy.ndarray
        Lemma 1's x0 = k1·θ (d numbers).
    sigma : float
        σ of every edge without its own.
    sigma_edges : mapping, optional
        (from label, to label) → σ of that edge (as ``noise.sigma_edges``).

    Returns
    -------
    ModeLaw

    Raises
    ------
    InputError
        A per-edge σ names an edge that is not in the mode.
    """
    d, n = top.dim, top.n
    edges = file_edges(top)
    lab = top.labels
    sig_by = {(str(a), str(c)): float(s) for (a, c), s in (sigma_edges or {}).items()}
    known = {(str(lab[j]), str(lab[i])) for i, j in edges}
    for key in sig_by:
        if key not in known:
            raise InputError(f"no edge {key[0]}->{key[1]} in {name}", field="noise.sigma_edges")
    position = {e: k for k, e in enumerate(top.edges)}
    e_n = len(edges)
    bd = np.zeros((n, d, d))
    for i in informed:
        bd[i] = delta * np.asarray(b[i], dtype=float)
    u = input_vector(top, {i: np.asarray(b[i], dtype=float) for i in informed}, delta, x0)
    return ModeLaw(
        name=name,
        dst=np.array([i for i, _ in edges], dtype=np.int64),
        src=np.array([j for _, j in edges], dtype=np.int64),
        sign=np.array([float(top.sign(i, j)) for i, j in edges]),
        weight=np.array([top.abs_weight(i, j) for i, j in edges], dtype=float).reshape(e_n, d, d),
        sigma=np.array(
            [sig_by.get((str(lab[j]), str(lab[i])), float(sigma)) for i, j in edges], dtype=float
        ),
        informed=tuple(sorted(int(i) for i in informed)),
        delta=float(delta),
        bd=bd,
        u=np.asarray(u, dtype=float).reshape(n, d),
        sorted_index=np.array([position[e] for e in edges], dtype=np.int64),
    )


@dataclass(frozen=True, eq=False)
class AgentLaw:
    """Everything the agents of a digital protocol run (see the module docstring).

    Attributes
    ----------
    name : str
        The network's name.
    labels : tuple
        The agents' labels.
    dim : int
        d.
    theta : numpy.ndarray
        θ.
    modes : tuple of ModeLaw
        The modes (one for a fixed topology).
    schedule : tuple of (str, float)
        The switching schedule's (mode, duration) pairs; empty for one mode.
    digital : Digital
        h and D.
    noise_f : numpy.ndarray
        F (d×d).
    gain : GainCode
        c(t).
    policy : str or None
        What an agent does with a lost message (``skip``, ``rescale`` or ``hold``) on lossy links;
        None: every message arrives.
    """

    name: str
    labels: tuple[Label, ...]
    dim: int
    theta: np.ndarray
    modes: tuple[ModeLaw, ...]
    schedule: tuple[tuple[str, float], ...]
    digital: Digital
    noise_f: np.ndarray
    gain: GainCode
    policy: str | None = None

    @property
    def lossy(self) -> bool:
        """Whether the agents take an arrival flag per in-edge at each step."""
        return self.policy is not None

    @property
    def n(self) -> int:
        """N, the agents."""
        return len(self.labels)

    @property
    def sqrt_period(self) -> float:
        """√h (the constant the measurement divides by)."""
        return math.sqrt(self.digital.period)

    @property
    def mode_names(self) -> list[str]:
        """The modes' names, in the order the indices refer to."""
        return [m.name for m in self.modes]

    @property
    def schedule_period(self) -> float:
        """The schedule's period, the plain sum of its durations (as :func:`step_modes`)."""
        return float(sum(float(d) for _, d in self.schedule))

    @property
    def schedule_ends(self) -> list[float]:
        """The cumulative ends of the schedule's entries (as :func:`step_modes`)."""
        return np.cumsum([float(d) for _, d in self.schedule]).tolist()

    @property
    def schedule_ticks(self) -> ScheduleTicks:
        """The schedule and h on one integer clock (:class:`ScheduleTicks`), the exact
        rule of :func:`step_modes` that the exported code runs."""
        return ScheduleTicks.of(self.schedule, self.digital.period)

    @property
    def schedule_modes(self) -> list[int]:
        """The mode index of each schedule entry."""
        names = self.mode_names
        return [names.index(m) for m, _ in self.schedule]

    def step_modes(self, steps: int) -> np.ndarray:
        """The mode of each step k = 0 … K−1 (:func:`step_modes` at t_k = k·h).

        Parameters
        ----------
        steps : int
            K.

        Returns
        -------
        numpy.ndarray
            (K,) mode indices.
        """
        if not self.schedule:
            return np.zeros(steps, dtype=np.int64)
        t = np.arange(steps, dtype=float) * self.digital.period
        return step_modes(self.schedule, t, self.mode_names, self.digital.period)

    def normals_per_step(self, steps: int) -> np.ndarray:
        """2·E of each step's mode: the normals step k consumes.

        Parameters
        ----------
        steps : int
            K.

        Returns
        -------
        numpy.ndarray
            (K,) counts.
        """
        counts = np.array([2 * m.n_edges for m in self.modes], dtype=np.int64)
        return counts[self.step_modes(steps)]

    def flags_per_step(self, steps: int) -> np.ndarray:
        """E of each step's mode: the arrival flags step k reads (none when lossless).

        Parameters
        ----------
        steps : int
            K.

        Returns
        -------
        numpy.ndarray
            (K,) counts.
        """
        if not self.lossy:
            return np.zeros(steps, dtype=np.int64)
        return self.normals_per_step(steps) // 2


def agent_law(
    design: ProtocolDesign | SwitchingDesign,
    digital: Digital,
    gain: str | ScheduleGain,
    sigma: float,
    f: Any,
    sigma_edges: Mapping[tuple, float] | None = None,
) -> AgentLaw:
    """The agents' law of a Lemma 1 design (one per mode for a switching set).

    Parameters
    ----------
    design : ProtocolDesign or SwitchingDesign
        The design.
    digital : Digital
        h and D.
    gain : str or ScheduleGain
        c(t).
    sigma : float
        σ of every edge without its own.
    f : float or array_like
        f(x) = F x: a number s (F = s·I) or F.
    sigma_edges : mapping, optional
        (from label, to label) → σ.

    Returns
    -------
    AgentLaw

    Raises
    ------
    InputError
        A callable gain or f, a per-edge σ on a missing edge, or F of the wrong shape.
    """
    if isinstance(design, SwitchingDesign):
        designs = dict(design.modes)
        schedule = tuple((str(m), float(t)) for m, t in design.switching.schedule)
        src = design.switching.source
        name = Path(src).stem if src else "switching"
    else:
        designs = {design.topology.name or "topology": design}
        schedule = ()
        name = design.topology.name or "topology"
    first = next(iter(designs.values()))
    modes = tuple(
        mode_law(k, des.topology, des.informed, des.B, des.delta, des.x0, sigma, sigma_edges)
        for k, des in designs.items()
    )
    return make_law(name, first.topology, first.theta, modes, schedule, digital, gain, f)


def make_law(
    name: str,
    top: Topology,
    theta: np.ndarray,
    modes: Sequence[ModeLaw],
    schedule: Sequence[tuple[str, float]],
    digital: Digital,
    gain: str | ScheduleGain | GainCode,
    f: Any,
) -> AgentLaw:
    """An :class:`AgentLaw` from its modes' tables (a design's or a certificate's).

    Parameters
    ----------
    name : str
        The network's name.
    top : Topology
        A mode's topology (the agents and d).
    theta : numpy.ndarray
        θ.
    modes : sequence of ModeLaw
        The modes.
    schedule : sequence of (str, float)
        The schedule (empty for one mode).
    digital : Digital
        h and D.
    gain : str, ScheduleGain or GainCode
        c(t).
    f : float or array_like
        f(x) = F x.

    Returns
    -------
    AgentLaw

    Raises
    ------
    InputError
        A callable gain or f, F of the wrong shape, a schedule naming an unknown mode.
    """
    names = [m.name for m in modes]
    for k, (m, _) in enumerate(schedule):
        if m not in names:
            raise InputError(f"unknown mode {m!r}", field=f"schedule[{k}]")
    code = gain if isinstance(gain, GainCode) else GainCode.of(gain)
    return AgentLaw(
        name=str(name),
        labels=tuple(top.labels),
        dim=top.dim,
        theta=np.asarray(theta, dtype=float).copy(),
        modes=tuple(modes),
        schedule=tuple((str(m), float(t)) for m, t in schedule),
        digital=digital,
        noise_f=_noise_matrix(f, top.dim),
        gain=code,
    )


#: The policies the exported law runs (``hold`` has no certificate).
LAW_POLICIES = ("skip", "rescale", "hold")


def lossy_law(law: AgentLaw, losses: Mapping[tuple[int, int], float], policy: str) -> AgentLaw:
    """The law on lossy links: each mode's keep_e = 1 − p_e (file order) and the policy.

    Parameters
    ----------
    law : AgentLaw
        The lossless law.
    losses : mapping of (int, int) to float
        p_e by edge (i, j), j → i; an edge without one has p = 0.
    policy : str
        ``skip``, ``rescale`` or ``hold``.

    Returns
    -------
    AgentLaw

    Raises
    ------
    InputError
        Another policy, or a p outside [0, 1).
    """
    if policy not in LAW_POLICIES:
        raise InputError(
            f"{policy!r} is not exported (the exported law runs {' or '.join(LAW_POLICIES)})",
            field="digital.policy",
        )
    modes = []
    for ml in law.modes:
        p = [
            require_loss("digital.loss", losses.get((int(i), int(j)), 0.0))
            for i, j in zip(ml.dst.tolist(), ml.src.tolist(), strict=True)
        ]
        modes.append(replace(ml, keep=np.array([1.0 - v for v in p], dtype=float)))
    return replace(law, modes=tuple(modes), policy=policy)


__all__ = [
    "LAW_POLICIES",
    "NOT_SAMPLED",
    "AgentLaw",
    "ModeLaw",
    "agent_law",
    "file_edges",
    "lossy_law",
    "make_law",
    "mode_law",
    "require_sampled",
]
