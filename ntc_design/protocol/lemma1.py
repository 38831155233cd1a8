"""The Lemma 1 protocol design (Niu & Wu, Sec. 3): informed agents, B_i, δ, k1, x0 and
L_B for a topology and θ, with the exact critical couplings of the same design family
(:mod:`ntc_design.protocol.thresholds`) and the table every face shows."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sparse

from ..errors import Option, one_line, require_positive, require_theta, require_x0, warn_user
from ..io.tablefiles import write_mat
from ..model import SwitchingTopology, Topology, block_coo
from ..numerics.linalg import require_dense
from ..present.rows import Table, matrix, set_text, verdict
from .assumption import AssumptionWarning, Decomposition, assumption2, fix_notes
from .thresholds import CriticalCouplings, critical_couplings, critical_couplings_sparse

if TYPE_CHECKING:
    from ..model.timevarying import ExpressionTopology

#: Up to this Nd the critical couplings are computed densely (exact Kronecker pencil /
#: eigenvalue scans, :func:`critical_couplings`); above it by the sparse method
#: (:func:`~ntc_design.protocol.thresholds.critical_couplings_sparse`), which says what it computed.
THRESHOLDS_MAX_ND = 200
#: By default the critical couplings are computed up to this Nd; above it only when asked
#: (``thresholds=True``, the thresholds option of ``ntc design``), and a note says so.
THRESHOLDS_DEFAULT_MAX_ND = 30_000


DESIGN_KEYS = (
    "C",
    "delta",
    "k1",
    "x0",
    "informed",
    "B",
    "V1",
    "V2",
    "assumption_holds",
    "violations",
    "identity_residual",
    "thresholds",
)


@dataclass(frozen=True, eq=False, kw_only=True)
class ProtocolDesign:
    """Lemma 1 parameters for one topology and target θ.

    ``informed = U``; ``B_i = Σ_{Ω_i}|A_ij|`` (sgn B_i = +1); δ_i = δ on informed agents;
    ``k1 = 1 + 2/δ``; ``x0 = k1·θ``; ``L_B = L + (Δ⊗I_d)·blockdiag(|B_i|)`` (Niu & Wu,
    Lemma 1 and eq. (8)).
    """

    topology: Topology
    theta: np.ndarray
    margin: float
    decomposition: Decomposition
    C: float | None
    delta: float
    k1: float
    x0: np.ndarray
    informed: tuple[int, ...]
    B: Mapping[int, np.ndarray]
    identity_residual: float
    thresholds: CriticalCouplings | None
    notes: tuple[str, ...] = field(default=())
    explicit_delta: bool = False  # δ was given, not Lemma 1's C + ΔC

    @property
    def lemma1_margin(self) -> float | None:
        """ΔC when δ is Lemma 1's C + ΔC; None when δ was given directly (a certificate
        then states no margin: it is about that δ, not about Lemma 1's)."""
        return None if self.explicit_delta else self.margin

    @property
    def assumption_holds(self) -> bool:
        """Whether Assumption 2 holds (else Lemma 1 does not apply: certify first)."""
        return self.decomposition.holds

    @property
    def has_informed_agents(self) -> bool:
        """Whether U is non-empty: with no informed agent L_B = L does not depend on δ,
        L(1⊗θ) = 0 for every θ and nothing draws the agents to θ (Lemma 1 designs
        nothing)."""
        return bool(self.informed)

    @property
    def informed_agents(self) -> tuple:
        """V_I = U as agent labels (``informed`` holds the internal 0-based indices)."""
        lab = self.topology.labels
        return tuple(lab[i] for i in self.informed)

    @property
    def v1_agents(self) -> tuple:
        """V1 as agent labels."""
        return tuple(self.decomposition.agents(self.topology)["V1"])

    @property
    def v2_agents(self) -> tuple:
        """V2 as agent labels."""
        return tuple(self.decomposition.agents(self.topology)["V2"])

    @property
    def violating_agents(self) -> tuple:
        """Agents that violate Assumption 2, as labels (empty when it holds)."""
        return tuple(self.decomposition.agents(self.topology)["violating"])

    @property
    def B_by_agent(self) -> dict:  # noqa: N802 - B_i is the paper's name
        """B_i keyed by agent label."""
        lab = self.topology.labels
        return {lab[i]: b for i, b in self.B.items()}

    def coupling_matrix_sparse(self) -> sparse.csr_matrix:
        """``D = blockdiag(|B_i|)`` as a sparse matrix.

        Returns
        -------
        scipy.sparse.csr_matrix
            D, Nd×Nd, zero blocks for naive agents.
        """
        return coupling_matrix_sparse(self.topology, self.B)

    def grounded_laplacian_sparse(self, delta: float | None = None) -> sparse.csr_matrix:
        """``L_B = L + δD`` (eq. (8)) as a sparse matrix, linear in the edges.

        Parameters
        ----------
        delta : float, optional
            δ; this design's when omitted.

        Returns
        -------
        scipy.sparse.csr_matrix
            L_B, Nd×Nd (d×d blocks).
        """
        dl = self.delta if delta is None else delta
        return (self.topology.laplacian_sparse() + dl * self.coupling_matrix_sparse()).tocsr()

    def coupling_matrix(self) -> np.ndarray:
        """``D = blockdiag(|B_i|)`` with zero blocks for naive agents, so L_B = L + δD.

        Returns
        -------
        numpy.ndarray
            D, Nd×Nd, dense.
        """
        return coupling_matrix(self.topology, self.B)

    def grounded_laplacian(self, delta: float | None = None) -> np.ndarray:
        """``L_B = L + (Δ⊗I_d)·blockdiag(|B_i|)`` (Niu & Wu, eq. (8)).

        Parameters
        ----------
        delta : float, optional
            δ; this design's when omitted.

        Returns
        -------
        numpy.ndarray
            L_B, Nd×Nd, dense.
        """
        dl = self.delta if delta is None else delta
        return self.topology.laplacian() + dl * self.coupling_matrix()

    def input_vector(self) -> np.ndarray:
        """The constant drift from the external signal, ``k1 (Δ⊗I_d) B θ = (Δ⊗I_d) B x0``.

        Returns
        -------
        numpy.ndarray
            A vector of length Nd.
        """
        return input_vector(self.topology, self.B, self.delta, self.x0)

    def table(self, title: str | None = None) -> Table:
        """The design as the table every face shows (see :func:`design_table`).

        Parameters
        ----------
        title : str, optional
            The table's title (default: Lemma 1 design with θ and ΔC).

        Returns
        -------
        ntc_design.present.rows.Table
        """
        return design_table({self.topology.name or "topology": self}, title)

    def _repr_html_(self) -> str:
        return self.table().html()

    def __repr__(self) -> str:
        holds = "holds" if self.assumption_holds else "fails"
        c = "undefined" if self.C is None else f"{self.C:.6g}"
        return (
            f"ProtocolDesign({self.topology.name or 'unnamed'!r}, δ={self.delta:.6g}, C={c}, "
            f"informed={set_text(self.informed_agents, 12)}, Assumption 2 {holds})"
        )

    def to_mat(self, path) -> None:
        """Write the design for MATLAB/Simulink (atomically): ``L_B`` (sparse, Nd×Nd),
        ``delta``, ``k1``, ``x0``, ``theta``, ``C``, ``B`` (the B_i of the informed agents
        stacked, (|V_I|·d)×d), ``informed`` (1-based agent indices, as MATLAB counts),
        ``labels`` (a cell array of strings), ``delta_i`` (N×1: δ on the informed agents,
        0 elsewhere), ``Delta`` (sparse Nd×Nd, Δ⊗I_d = diag(δ_i)⊗I_d) and ``B_all`` (Nd×d:
        every agent's B_i stacked, zero blocks for the uninformed), so that Lemma 1's
        identity reads in MATLAB or Octave::

            e = kron(ones(N, 1), theta(:));
            norm(L_B*e - k1*Delta*B_all*theta(:)) / norm(L_B*e)   % ~1e-16

        Parameters
        ----------
        path : str or pathlib.Path
            The ``.mat`` file.
        """
        d, n = self.topology.dim, self.topology.n
        informed = list(self.informed)
        b = np.vstack([self.B[i] for i in informed]) if informed else np.zeros((0, d))
        delta_i = np.zeros(n)
        delta_i[informed] = float(self.delta)
        b_all = np.zeros((n, d, d))
        for i in informed:
            b_all[i] = self.B[i]
        write_mat(
            path,
            {
                "L_B": self.grounded_laplacian_sparse().tocsc(),
                "delta": float(self.delta),
                "k1": float(self.k1),
                "x0": np.asarray(self.x0, dtype=float),
                "theta": np.asarray(self.theta, dtype=float),
                "C": float("nan") if self.C is None else float(self.C),
                "B": b,
                "informed": np.asarray(informed, dtype=float) + 1.0,
                "labels": np.array([str(x) for x in self.topology.labels], dtype=object),
                "delta_i": delta_i.reshape(n, 1),
                "Delta": sparse.kron(sparse.diags(delta_i), sparse.identity(d)).tocsc(),
                "B_all": b_all.reshape(n * d, d),
            },
        )

    def to_dict(self) -> dict:
        """The design as a JSON-ready mapping, agents as labels.

        Returns
        -------
        dict
            θ, ΔC, C and C_i, δ, k1, x0, the informed agents and B_i, V1, V2, the
            violations, the identity residual, the critical couplings and notes.
        """
        lab = self.topology.labels
        dec = self.decomposition
        th = self.thresholds
        return {
            "topology": self.topology.name,
            "theta": self.theta.tolist(),
            "margin": self.margin,
            "C": self.C,
            "C_i": {str(lab[i]): c for i, c in sorted(dec.coefficients.items())},
            "delta": self.delta,
            "k1": self.k1,
            "x0": self.x0.tolist(),
            "informed": [lab[i] for i in self.informed],
            "B": {str(lab[i]): b.tolist() for i, b in sorted(self.B.items())},
            "V1": [lab[i] for i in dec.v1],
            "V2": [lab[i] for i in dec.v2],
            "assumption_holds": dec.holds,
            "violations": [
                {"agent": lab[v.agent], "reason": v.reason, "fix": v.fix} for v in dec.violations
            ],
            "identity_residual": self.identity_residual,
            "thresholds": th.to_dict() if th is not None else None,
            "conservatism": (self.delta / th.hurwitz if th is not None and th.hurwitz else None),
            "notes": list(self.notes),
        }


@dataclass(frozen=True, eq=False)
class SwitchingDesign:
    """One Lemma 1 design per mode of a switching topology."""

    switching: SwitchingTopology
    modes: Mapping[str, ProtocolDesign]

    def table(self, title: str | None = None) -> Table:
        """The designs as one table, a column per mode (see :func:`design_table`).

        Parameters
        ----------
        title : str, optional
            The table's title.

        Returns
        -------
        ntc_design.present.rows.Table
        """
        return design_table(dict(self.modes), title)

    def _repr_html_(self) -> str:
        return self.table().html()

    def __repr__(self) -> str:
        deltas = ", ".join(f"{k}: δ={d.delta:.6g}" for k, d in self.modes.items())
        return f"SwitchingDesign({deltas})"

    def to_dict(self) -> dict:
        """The designs as a JSON-ready mapping.

        Returns
        -------
        dict
            The schedule, its period and each mode's :meth:`ProtocolDesign.to_dict`.
        """
        return {
            "schedule": [{"mode": m, "duration": d} for m, d in self.switching.schedule],
            "period": self.switching.period,
            "modes": {k: v.to_dict() for k, v in self.modes.items()},
        }


MAX_VIOLATIONS_SHOWN = 10  # in a table's notes (the JSON output and to_dict() list them all)
MAX_AGENTS_SHOWN = 12  # agents named in a set, and B_i rows, in a table (the JSON has all)


def design_table(designs: Mapping[str, ProtocolDesign], title: str | None = None) -> Table:
    """Lemma 1's parameters as a table, one value column per design (mode): the labels
    the terminal, the HTML report and notebooks show.

    Parameters
    ----------
    designs : mapping of str to ProtocolDesign
        The designs, by mode name (one for a fixed topology).
    title : str, optional
        The title (default: Lemma 1 design with θ and ΔC).

    Returns
    -------
    ntc_design.present.rows.Table
        Rows: Assumption 2, V1 / V2, C, δ, k1, θ, x0, the informed agents, B_i per agent,
        the identity residual and the critical couplings; notes: the violations, the
        design's notes and the thresholds' notes.
    """
    ds = list(designs.values())
    first = ds[0]
    lab = first.topology.labels
    informed = sorted({i for d in ds for i in d.informed})
    hidden = max(0, len(informed) - MAX_AGENTS_SHOWN)
    informed = informed[:MAX_AGENTS_SHOWN]

    def row(label: str, f):
        return (label, *[f(d) for d in ds])

    def crit(d: ProtocolDesign, key: str):
        return None if d.thresholds is None else getattr(d.thresholds, key)

    def best_delta(d: ProtocolDesign):
        th = d.thresholds
        if th is not None and th.best_rate_delta is None:
            if th.method == "constant":
                return "none: L_B does not depend on δ (no informed agent)"
            if math.isnan(th.best_rate):
                return "none: the best rate is not computed at this size"
            return "none: approached as δ → ∞ (not attained)"
        return crit(d, "best_rate_delta")

    def holds(d: ProtocolDesign):
        return verdict(d.assumption_holds, word="holds" if d.assumption_holds else "fails")

    rows = [
        row("Assumption 2", holds),
        row(
            "V1 / V2",
            lambda d: (
                f"{set_text(d.v1_agents, MAX_AGENTS_SHOWN)} / "
                f"{set_text(d.v2_agents, MAX_AGENTS_SHOWN)}"
            ),
        ),
        row("C", lambda d: d.C),
        row("δ = C + ΔC", lambda d: d.delta),
        row("k1 = 1 + 2/δ", lambda d: d.k1),
        row("θ", lambda d: matrix([d.theta])),
        row("x0 = k1·θ", lambda d: matrix([d.x0])),
        row("informed agents V_I = U", lambda d: set_text(d.informed_agents, MAX_AGENTS_SHOWN)),
        *[
            row(f"B_{lab[i]}", lambda d, i=i: matrix(d.B[i]) if i in d.B else "— (naive)")
            for i in informed
        ],
        row(
            "identity residual ‖L_B(1⊗θ) − k1(Δ⊗I)Bθ‖ (relative)",
            lambda d: f"{d.identity_residual:.2e}",
        ),
        row("δ_H (−L_B Hurwitz for δ > δ_H)", lambda d: crit(d, "hurwitz")),
        row("δ_S (L_B + L_Bᵀ ≻ 0 for δ > δ_S)", lambda d: crit(d, "symmetric")),
        row("best decay rate", lambda d: crit(d, "best_rate")),
        row("δ of the best rate", best_delta),
    ]
    if hidden:
        rows.insert(
            rows.index(
                next(
                    r for r in rows if r[0] == "identity residual ‖L_B(1⊗θ) − k1(Δ⊗I)Bθ‖ (relative)"
                )
            ),
            (
                f"B_i of {hidden} more informed agents",
                *[f"in {Option('json', alias='JSON')} / to_dict()" for _ in ds],
            ),
        )
    several = len(designs) > 1
    notes: list[str] = []
    for name, d in designs.items():
        notes += _design_notes(d, f"mode {name}: " if several else "")
    columns = ("quantity", *([f"mode {k}" for k in designs] if several else ["value"]))
    if title is None:
        title = f"Lemma 1 design, θ = {first.theta.tolist()}, ΔC = {first.margin:g}"
    return Table.build(title, columns, rows, notes)


def _design_notes(d: ProtocolDesign, at: str) -> list[str]:
    """The violations (the first few), the design's notes and the thresholds' notes."""
    lab = d.topology.labels
    viol = d.decomposition.violations
    notes = [
        f"{at}violation, agent {lab[v.agent]}: {v.reason}" for v in viol[:MAX_VIOLATIONS_SHOWN]
    ]
    if len(viol) > MAX_VIOLATIONS_SHOWN:
        more = len(viol) - MAX_VIOLATIONS_SHOWN
        json = Option("json", alias="to_dict()")
        notes.append(f"{at}… and {more} more violations ({json} lists them all)")
    notes += [f"{at}{n}" for n in fix_notes(viol, lab)]
    notes += [f"{at}{n}" for n in d.notes]
    if d.thresholds is not None:
        notes += [f"{at}{n}" for n in d.thresholds.notes]
    return notes


def coupling_matrix_sparse(top: Topology, b: Mapping[int, np.ndarray]) -> sparse.csr_matrix:
    """``blockdiag(B_i)`` (zero blocks for agents not in ``b``) as CSR."""

    idx = np.array(sorted(b), dtype=np.int64)
    blocks = np.array([b[i] for i in idx.tolist()]).reshape(-1, top.dim, top.dim)
    return block_coo(top.n, top.dim, idx, idx, blocks)


def coupling_matrix(top: Topology, b: Mapping[int, np.ndarray]) -> np.ndarray:
    require_dense(top.nd, "coupling matrix D")
    d = top.dim
    out = np.zeros((top.nd, top.nd))
    for i, bi in b.items():
        out[i * d : (i + 1) * d, i * d : (i + 1) * d] = bi
    return out


def input_vector(
    top: Topology, b: Mapping[int, np.ndarray], delta: float, x0: np.ndarray
) -> np.ndarray:
    """``(Δ⊗I_d) B x0`` with δ_i = δ on the informed agents (the keys of ``b``)."""
    d = top.dim
    u = np.zeros((top.n, d))
    if b:
        idx = np.array(list(b), dtype=np.int64)
        u[idx] = delta * (np.array([b[i] for i in idx.tolist()]) @ x0)
    return u.reshape(-1)


def identity_residual(lap_b, u: np.ndarray, theta: np.ndarray) -> float:
    """``‖-L_B(1⊗θ) + k1(Δ⊗I_d)Bθ‖_∞`` relative to ``‖L_B‖_∞‖θ‖_∞`` (Niu & Wu, eq. (11));
    ``lap_b`` dense or sparse."""
    n = lap_b.shape[0] // theta.size
    r = -(lap_b @ np.tile(theta, n)) + u
    if sparse.issparse(lap_b):
        norm = float(abs(lap_b).sum(axis=1).max()) if lap_b.nnz else 0.0
    else:
        norm = float(np.linalg.norm(lap_b, np.inf))
    scale = max(norm * np.max(np.abs(theta)), 1e-300)
    return float(np.max(np.abs(r)) / scale)


#: Up to this Nd the design also assembles the dense L_B (results identical to the
#: dense-only releases at the paper's size); above it everything is sparse.
DENSE_DESIGN_MAX_ND = 600


def design_topology(
    top: Topology,
    theta: Sequence[float] | np.ndarray,
    margin: float = 0.1,
    delta: float | None = None,
    thresholds: bool | None = None,
) -> ProtocolDesign:
    """Lemma 1 design for one topology: δ = C + ΔC (``margin``), or an explicit δ.

    Parameters
    ----------
    top : Topology
        The topology.
    theta : sequence of float
        The target consensus state θ ≠ 0 (d numbers).
    margin : float, optional
        ΔC > 0.
    delta : float, optional
        An explicit δ > 0 instead of C + ΔC.
    thresholds : bool, optional
        Compute the critical couplings δ_H, δ_S; by default only up to
        ``THRESHOLDS_DEFAULT_MAX_ND``.

    Returns
    -------
    ProtocolDesign
        The parameters; ``assumption_holds`` False (with an :class:`AssumptionWarning`)
        when Assumption 2 fails.

    Raises
    ------
    InputError
        A bad θ, margin or δ.
    """
    th = require_theta(theta, top.dim)
    require_positive("margin (ΔC)", margin)
    dec = assumption2(top)
    notes: list[str] = []
    c = lemma1_c(dec)
    if not dec.holds:
        notes.append(
            "Assumption 2 fails: C is taken over the agents of U whose antagonistic "
            "in-weight is positive definite; certify the design before trusting it"
        )
    dl = _choose_delta(c, margin, delta, notes)
    if not dec.holds:
        warn_user(
            f"Assumption 2 fails for {top.name or 'the topology'} "
            f"({len(dec.violations)} violating agent(s), e.g. "
            f"{top.labels[dec.violations[0].agent]}): Lemma 1 does not apply",
            AssumptionWarning,
        )
    informed = top.antagonised
    ant = top.degree_sums[2]
    b = {i: ant[i].copy() for i in informed}
    k1 = 1.0 + 2.0 / dl
    require_x0(th, k1)
    x0 = k1 * th
    u = input_vector(top, b, dl, x0)
    res, crit = _residual_and_thresholds(top, b, dl, u, th, thresholds, notes)
    return ProtocolDesign(
        topology=top,
        theta=th,
        margin=float(margin),
        decomposition=dec,
        C=c,
        delta=dl,
        k1=k1,
        x0=x0,
        informed=informed,
        B=b,
        identity_residual=res,
        thresholds=crit,
        notes=tuple(notes),
        explicit_delta=delta is not None,
    )


def lemma1_c(dec: Decomposition) -> float | None:
    """Lemma 1's C = max_{i ∈ V1} C_i; when Assumption 2 fails, the largest C_i of the
    agents that can be in V1; None when no agent can.

    Parameters
    ----------
    dec : Decomposition
        Assumption 2's decomposition (:func:`~ntc_design.protocol.assumption.assumption2`).

    Returns
    -------
    float or None
    """
    if dec.holds:
        return max((dec.coefficients[i] for i in dec.v1), default=None)
    return max(dec.coefficients.values(), default=None)


def lemma1_delta(top: Topology, margin: float) -> tuple[float | None, float]:
    """C and the δ that the design chooses for a margin ΔC: δ = C + ΔC, or ΔC when C is
    undefined or C + ΔC <= 0 (what :func:`design_topology` computes, for a certificate to
    re-derive δ from its subject's topology and stated margin).

    Parameters
    ----------
    top : Topology
        The topology.
    margin : float
        ΔC > 0.

    Returns
    -------
    (float or None, float)
        C (None when no agent can be in V1) and δ.

    Raises
    ------
    InputError
        ΔC is not a positive number.
    """
    require_positive("margin (ΔC)", margin)
    c = lemma1_c(assumption2(top))
    return c, _choose_delta(c, margin, None, [])


def _choose_delta(c: float | None, margin: float, delta: float | None, notes: list[str]) -> float:
    """δ = C + ΔC (Lemma 1), or ΔC when C is undefined or C + ΔC <= 0; an explicit δ as
    given, with a note when it is not above C."""
    if delta is None:
        if c is None:
            dl = float(margin)
            notes.append("no agent can be in V1: C is undefined, δ = ΔC")
        elif c + margin <= 0:
            dl = float(margin)
            notes.append(f"C = {c:.6g} < 0 but δ must be positive: δ = ΔC")
        else:
            dl = float(c + margin)
    else:
        require_positive("delta", delta)
        dl = float(delta)
        if c is not None and dl <= c:
            notes.append(f"explicit δ = {dl:.6g} is not above C = {c:.6g}: Lemma 1 does not apply")
    return dl


def _residual_and_thresholds(top, b, dl, u, th, thresholds, notes):
    """‖L_B(1⊗θ) − u‖ relative (dense or sparse by size) and the critical couplings when
    asked for (by default up to THRESHOLDS_DEFAULT_MAX_ND)."""
    if top.nd <= DENSE_DESIGN_MAX_ND:
        lap = top.laplacian()
        dmat = coupling_matrix(top, b)
        res = identity_residual(lap + dl * dmat, u, th)
    else:
        lap_s = top.laplacian_sparse()
        dmat_s = coupling_matrix_sparse(top, b)
        res = identity_residual((lap_s + dl * dmat_s).tocsr(), u, th)
    want = top.nd <= THRESHOLDS_DEFAULT_MAX_ND if thresholds is None else bool(thresholds)
    if want and top.nd <= THRESHOLDS_MAX_ND:
        crit = critical_couplings(lap, dmat)
    elif want:
        crit = critical_couplings_sparse(
            top.laplacian_sparse(), coupling_matrix_sparse(top, b), top.dim
        )
    else:
        crit = None
        notes.append(
            "critical couplings δ_H, δ_S not computed "
            + (
                "(not asked for here; "
                if thresholds is False
                else f"by default above Nd = {THRESHOLDS_DEFAULT_MAX_ND} ("
            )
            + f"ntc design {Option('thresholds', alias='with its thresholds flag')} computes "
            "them, as does the thresholds option of design in Python)"
        )
    return res, crit


def design(
    topology: Topology | SwitchingTopology,
    theta: Sequence[float] | np.ndarray,
    margin: float = 0.1,
    delta: float | None = None,
    thresholds: bool | None = None,
) -> ProtocolDesign | SwitchingDesign:
    """Lemma 1 design for a topology, or one per mode for a switching topology.

    For a topology given as functions of time use ``design(tv.at(t), theta)``.

    Parameters
    ----------
    topology : Topology or SwitchingTopology
        The network.
    theta : sequence of float
        The target consensus state θ ≠ 0 (d numbers).
    margin : float, optional
        ΔC > 0: δ = C + ΔC.
    delta : float, optional
        An explicit δ > 0 instead of C + ΔC.
    thresholds : bool, optional
        Compute the critical couplings δ_H, δ_S (see :func:`design_topology`).

    Returns
    -------
    ProtocolDesign or SwitchingDesign
        One design, or one per mode.

    Raises
    ------
    InputError
        A bad θ, margin or δ.

    Examples
    --------
    >>> import ntc_design as nd
    >>> d = nd.design(nd.load("examples/g1.yaml"), [1, 2, -1], margin=0.1)
    >>> round(d.delta, 4), d.informed_agents, d.assumption_holds
    (7.244, (2, 3), True)
    """
    if isinstance(topology, SwitchingTopology):
        return SwitchingDesign(
            topology,
            {
                name: design_topology(top, theta, margin, delta, thresholds)
                for name, top in topology.modes.items()
            },
        )
    return design_topology(topology, theta, margin, delta, thresholds)


def uninformed_modes(top: Topology | SwitchingTopology | ExpressionTopology) -> list:
    """The modes with no informed agent (U empty; None stands for a fixed topology's only
    one), found from the edge signs before any design or proof.

    Parameters
    ----------
    top : Topology, SwitchingTopology or ExpressionTopology
        The network (a time-varying one: its ``structure``, whose classes are fixed).

    Returns
    -------
    list
        Mode names, ``[None]`` for a fixed topology without one, ``[]`` when every mode has
        an informed agent.
    """
    if isinstance(top, SwitchingTopology):
        return [k for k, m in top.modes.items() if not m.antagonised]
    fixed = top if isinstance(top, Topology) else top.structure
    return [None] if not fixed.antagonised else []


def no_informed_agent_text(modes: list) -> str:
    """Why nothing can be designed, certified or exported when :func:`uninformed_modes`
    found modes, with the fix: one line.

    Parameters
    ----------
    modes : list
        What :func:`uninformed_modes` returned (not empty).

    Returns
    -------
    str
    """
    where = (
        f"mode(s) {', '.join(one_line(str(k)) for k in modes)} have"
        if modes != [None]
        else "the network has"
    )
    return (
        f"{where} no informed agent (U is empty), so L_B = L does not depend on δ and Lemma 1 "
        "cannot bring the agents to θ; an antagonistic edge (A_ij negative definite) into an "
        "agent makes it informed"
    )


__all__ = [
    "ProtocolDesign",
    "SwitchingDesign",
    "design",
    "design_table",
    "design_topology",
    "lemma1_c",
    "lemma1_delta",
    "no_informed_agent_text",
    "uninformed_modes",
]
