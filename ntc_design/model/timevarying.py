"""A continuously time-varying topology: weights A_ij(t) as expressions of t, each
proven to keep one sign class on its domain (one period, [0, constant_after] or t >= 0);
reading it from a file."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np
import sympy as sp

from ..errors import InputError
from ..expr.symbolic import compile_expression, symbol
from ..io.documents import read_document
from ..io.tvfiles import ExprWeight, TimeVaryingData, parse_time_varying
from ..numerics.linalg import Definiteness, classify, is_symmetric
from ..rigorous.interval import bounds, enclose, t_ball
from . import ExpressionFamily, Label, Topology
from .enclosure import SignProof


@dataclass(frozen=True, eq=False)
class ExprEdge:
    """One edge j -> i of an :class:`ExpressionTopology`: its weight A_ij(t) and the sign
    class proven for every t of the domain."""

    i: int  # to
    j: int  # from
    weight: ExprWeight
    cls: Definiteness
    field: str

    @property
    def sign(self) -> int:
        """sgn(A_ij(t)), the same for every t."""
        return self.cls.sign


@dataclass(frozen=True, eq=False)
class ExpressionTopology(ExpressionFamily):
    """A topology whose weights are expressions of t, each of one sign class for every t.

    ``domain`` is where the weights are given and the proofs hold: one period
    ``[0, period]`` (the weights repeat), ``[0, constant_after]`` (A(t) = A(T) afterwards)
    or ``None`` for every t >= 0."""

    labels: tuple[Label, ...]
    dim: int
    edges: tuple[ExprEdge, ...]
    period: sp.Expr | None = None
    constant_after: sp.Expr | None = None
    name: str | None = None
    source: str | None = None
    document: dict = field(default_factory=dict, repr=False)

    # -- construction --------------------------------------------------------------
    @classmethod
    def from_data(cls, data: TimeVaryingData) -> ExpressionTopology:
        """Build from a parsed file, proving each weight's sign class on the domain.

        Parameters
        ----------
        data : ntc_design.io.tvfiles.TimeVaryingData
            As :func:`ntc_design.io.tvfiles.parse_time_varying` returns it.

        Returns
        -------
        ExpressionTopology
            The topology with every edge's proven class.

        Raises
        ------
        InputError
            A weight whose class cannot be proven fixed (naming the edge and the t), or a
            weight that is not periodic with the declared period.
        """
        index = {str(a): k for k, a in enumerate(data.labels)}
        dom = None
        if data.period is not None:
            dom = (0.0, _upper(data.period))
        elif data.constant_after is not None:
            dom = (0.0, _upper(data.constant_after))
        edges = []
        for e in data.edges:
            i, j = index[str(e.target)], index[str(e.source)]

            def where(msg: str, f: str = e.field) -> InputError:
                return InputError(msg, field=f"{data.source}: {f}" if data.source else f)

            cls_ = _prove_class(e.weight, data.dim, SignProof(where, dom), where)
            if data.period is not None and not e.weight.constant:
                _check_periodic(e.weight, data.period, where)
            edges.append(ExprEdge(i, j, e.weight, cls_, e.field))
        return cls(
            data.labels,
            data.dim,
            tuple(edges),
            data.period,
            data.constant_after,
            data.name,
            data.source,
            data.document,
        )

    # -- basic accessors ---------------------------------------------------------------
    @property
    def n(self) -> int:
        """The number of agents N."""
        return len(self.labels)

    @property
    def nd(self) -> int:
        """N·d, the size of the stacked state."""
        return self.n * self.dim

    @property
    def constant(self) -> bool:
        """Every weight is a constant expression."""
        return all(e.weight.constant for e in self.edges)

    @property
    def domain(self) -> tuple[float, float] | None:
        """[0, period], [0, constant_after], or None for every t >= 0."""
        if self.period is not None:
            return (0.0, float(self.period))
        if self.constant_after is not None:
            return (0.0, float(self.constant_after))
        return None

    @cached_property
    def _compiled(self) -> list[Callable[[np.ndarray], np.ndarray]]:
        t = symbol("t")
        out: list[Callable[[np.ndarray], np.ndarray]] = []
        for e in self.edges:
            w = e.weight
            if w.form == "scale":
                out.append(_scaled(compile_expression(w.scale), np.asarray(w.base, dtype=float)))
            elif w.constant:
                out.append(_constant(np.array([[float(v) for v in r] for r in w.entries])))
            else:
                d = self.dim
                fns = {
                    (k, m): compile_expression(w.entries[k][m])
                    for k in range(d)
                    for m in range(d)
                    if w.entries[k][m].has(t)
                }
                const = np.array([[0.0 if v.has(t) else float(v) for v in r] for r in w.entries])

                def f(ts, fns=fns, const=const):
                    out_ = np.broadcast_to(const, (ts.size, *const.shape)).copy()
                    for (k, m), fn in fns.items():
                        out_[:, k, m] = fn(ts)
                    return out_

                out.append(f)
        return out

    def local_time(self, ts: np.ndarray) -> np.ndarray:
        """The time at which the expressions are evaluated.

        Parameters
        ----------
        ts : numpy.ndarray
            Times.

        Returns
        -------
        numpy.ndarray
            t, or min(t, constant_after), flattened.
        """
        ts = np.asarray(ts, dtype=float).reshape(-1)
        if self.constant_after is not None:
            return np.minimum(ts, float(self.constant_after))
        return ts

    def weights_at(self, ts: Sequence[float] | np.ndarray) -> np.ndarray:
        """A_ij(t) for every edge at every time.

        Parameters
        ----------
        ts : sequence of float or numpy.ndarray
            K times.

        Returns
        -------
        numpy.ndarray
            Shape (K, E, d, d), edges in :attr:`edges` order.

        Raises
        ------
        InputError
            A weight is not finite at one of the times.
        """
        tl = self.local_time(np.asarray(ts, dtype=float))
        if not self.edges:
            return np.zeros((tl.size, 0, self.dim, self.dim))
        w = np.stack([f(tl) for f in self._compiled], axis=1)
        if not np.all(np.isfinite(w)):
            k = int(np.argmax(~np.all(np.isfinite(w), axis=(1, 2, 3))))
            raise InputError(
                f"a weight is not finite at t = {tl[k]:.6g}", field=self.source or "topology"
            )
        return w

    def at(self, t: float) -> Topology:
        """The topology frozen at time t.

        Parameters
        ----------
        t : float
            The time.

        Returns
        -------
        Topology
            The weights A_ij(t) as a :class:`~ntc_design.model.Topology`.
        """
        w = self.weights_at([t])[0]
        weights = {(e.i, e.j): w[k] for k, e in enumerate(self.edges)}
        fields = {(e.i, e.j): e.field for e in self.edges}
        return Topology(self.labels, self.dim, weights, self.name, self.source, fields)

    def fixed(self) -> Topology:
        """The fixed topology of constant weights.

        Returns
        -------
        Topology
            The same network as a :class:`~ntc_design.model.Topology`.

        Raises
        ------
        ValueError
            A weight depends on t (see :attr:`constant`).
        """
        if not self.constant:
            raise ValueError("the weights depend on t")
        weights = {
            (e.i, e.j): np.array([[float(v) for v in r] for r in e.weight.entries])
            for e in self.edges
        }
        fields = {(e.i, e.j): e.field for e in self.edges}
        return Topology(self.labels, self.dim, weights, self.name, self.source, fields)

    @cached_property
    def structure(self) -> Topology:
        """The frozen topology at a reference time: its edges, signs, Ω_i, U and
        positive-negative paths hold at every t (the classes are proven fixed)."""
        ref = self.domain[1] / 2 if self.domain else 0.5
        top = self.at(ref)
        for _k, e in enumerate(self.edges):
            got = top.classes[(e.i, e.j)]
            if got is not e.cls:
                raise InputError(
                    f"classified {got.value} at t = {ref:.6g}, proven {e.cls.value}", field=e.field
                )
        return top

    def to_dict(self) -> dict:
        """The topology in its file form.

        Returns
        -------
        dict
            A copy of the mapping as read.
        """
        return dict(self.document)


def _scaled(s: Callable, base: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """t ↦ s(t)·base, vectorised over K times."""
    return lambda ts: s(ts)[:, None, None] * base


def _constant(m: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """t ↦ m at K times."""
    return lambda ts: np.broadcast_to(m, (ts.size, *m.shape)).copy()


def _upper(e: sp.Expr) -> float:
    from flint import arb  # noqa: F401 - enclose needs flint

    return bounds(enclose(e, t_ball(0.0, 0.0)))[1]


def _check_periodic(w: ExprWeight, period: sp.Expr, where: Callable[[str], InputError]) -> None:
    """A(t + P) = A(t) symbolically (sympy), else the file is refused."""
    t = symbol("t")
    exprs: list[sp.Expr] = (
        [w.scale]
        if w.form == "scale" and w.scale is not None
        else [e for r in w.entries for e in r]
    )
    for e in exprs:
        if not e.has(t):
            continue
        diff = e.subs(t, t + period) - e
        ok = diff == 0 or sp.simplify(sp.expand_trig(diff)) == 0
        if not ok:
            fn = compile_expression(diff)
            ts = np.linspace(0, float(period), 33)
            v = fn(ts)
            k = int(np.argmax(np.abs(v)))
            raise where(
                f"{e} is not periodic with period {period} (A(t+P) − A(t) = {v[k]:.4g} at "
                f"t = {ts[k]:.4g})"
                if np.max(np.abs(v)) > 1e-12
                else f"cannot prove that {e} has period {period}"
            )


def _prove_class(
    w: ExprWeight, d: int, proof: SignProof, where: Callable[[str], InputError]
) -> Definiteness:
    """The sign class of a weight, proven for every t of the domain."""
    t = symbol("t")
    if w.constant:
        m = np.array([[float(v) for v in r] for r in w.entries])
        if not is_symmetric(m):
            raise where("weight is not symmetric (A_ij must equal A_ijᵀ)")
        c = classify(m)
        if c is Definiteness.INDEFINITE:
            raise where("weight is indefinite; it must be positive or negative (semi)definite")
        return c
    if w.form == "scale":
        base = np.asarray(w.base, dtype=float)
        if not is_symmetric(base):
            raise where("matrix is not symmetric")
        c = classify(base)
        if c is Definiteness.INDEFINITE:
            raise where("matrix is indefinite")
        if c is Definiteness.ZERO:
            return c
        s = proof.scalar(w.scale, "scale")
        if s == 0:
            return Definiteness.ZERO
        flip = {
            Definiteness.PD: Definiteness.ND,
            Definiteness.PSD: Definiteness.NSD,
            Definiteness.ND: Definiteness.PD,
            Definiteness.NSD: Definiteness.PSD,
        }
        return c if s > 0 else flip[c]
    if w.form == "diag":
        signs = [proof.scalar(w.entries[k][k], f"diag[{k}]") for k in range(d)]
        nz = {s for s in signs if s != 0}
        if len(nz) > 1:
            raise where("diag has entries of both signs: the weight is indefinite")
        if not nz:
            return Definiteness.ZERO
        sign = nz.pop()
        full = all(x != 0 for x in signs)
        if sign > 0:
            return Definiteness.PD if full else Definiteness.PSD
        return Definiteness.ND if full else Definiteness.NSD
    # rows with expressions: symmetric identically, definite for every t
    for k in range(d):
        for col in range(k + 1, d):
            a, b = w.entries[k][col], w.entries[col][k]
            if a != b and sp.simplify(a - b) != 0:
                raise where(
                    f"weight is not symmetric: entry [{k}][{col}] = {a} but [{col}][{k}] = {b}"
                )
    del t
    lowest = proof.matrix(w.entries, "weight")
    return Definiteness.PD if lowest > 0 else Definiteness.ND


def load_time_varying(path: str | Path) -> ExpressionTopology:
    """Read a time-varying topology file.

    Parameters
    ----------
    path : str or pathlib.Path
        A YAML or JSON file with weights as expressions of t.

    Returns
    -------
    ExpressionTopology
        The topology with every edge's proven sign class.

    Raises
    ------
    InputError
        The file cannot be read, is malformed, or a weight's class cannot be proven.
    """

    return ExpressionTopology.from_data(parse_time_varying(read_document(path), str(path)))


def from_document(doc: dict, source: str | None = None) -> ExpressionTopology:
    """A time-varying topology from its parsed document (a file already read).

    Parameters
    ----------
    doc : dict
        The mapping, as a YAML or JSON file gives it.
    source : str, optional
        Its name, for messages.

    Returns
    -------
    ExpressionTopology

    Raises
    ------
    InputError
        The document is malformed, or a weight's class cannot be proven.
    """
    return ExpressionTopology.from_data(parse_time_varying(doc, source))
