"""The extension point for certificate kinds: a base class, what a kind reads from a
certificate's subject, and the audit of its reported results.

A kind (cvxpy's ``Reduction.accepts/apply``, diffrax's ``AbstractSolver``) says which
designs it ``accepts``, ``issue``s a certificate for one, and, for verification, ``read``s
the subject, derives the ``claims`` its properties need, ``prove``s each one and
``audit``s every number it reports. Everything common to the kinds (format, digests, θ,
the schedule, the certified properties, comparing the listed claims with the derived ones,
the user's own file) is done once, by :func:`ntc_design.certify.verify.verify`.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from ...choices import RateMethod
from ...errors import InputError
from ...model.paper import F_SCALE, SIGMA
from ..checks import Check
from ..claims import Claim, Property
from ..fields import finite_number
from ..format import RESULT_RTOL
from ..theorems import TheoremVerdict

if TYPE_CHECKING:  # the gain layer loads SymPy: only certify() builds an analysis
    from ...gain.conditions import GainAnalysis

_MISSING = object()


@dataclass(frozen=True, eq=False)
class ModeReading:
    """One mode of a certificate's subject as a kind read it (θ parsed, hash derived)."""

    name: str
    topology: str | None
    labels: tuple[str, ...]
    d: int
    hash: str
    delta: float | None
    theta: np.ndarray

    @property
    def n(self) -> int:
        """The number of agents N."""
        return len(self.labels)


@dataclass(frozen=True, eq=False)
class Reading:
    """What a kind read from a certificate: its modes, its own subject checks (topology
    hashes, informed agents = U, B_i, ...) and what its provers need (``state``)."""

    modes: dict[str, ModeReading]
    checks: tuple[Check, ...]
    state: Any


@dataclass(frozen=True)
class ResultRow:
    """One line of what a certificate reports, as every face shows it (the terminal, the
    HTML report, notebooks): the label is written once, here, by the kind."""

    label: str
    value: str
    estimate: bool = False  # an estimate, not a proof: every face says so

    def to_dict(self) -> dict:
        """The row as a JSON-ready mapping.

        Returns
        -------
        dict
            ``label``, ``value`` and ``estimate``.
        """
        return {"label": self.label, "value": self.value, "estimate": self.estimate}


def number_text(x: Any, digits: int = 6) -> str:
    """A reported number as text (``—`` when there is none).

    Parameters
    ----------
    x : Any
        The number, or None.
    digits : int, optional
        Significant digits.

    Returns
    -------
    str
    """
    v = finite_number(x)
    return "—" if v is None else f"{v:.{digits}g}"


@dataclass(frozen=True)
class Subject:
    """The subject as the common checks established it: the modes, the schedule (None
    for one topology) and the modes it uses, and the switching hash."""

    modes: dict[str, ModeReading]
    schedule: tuple[tuple[str, float], ...] | None
    scheduled: tuple[str, ...]
    switching_hash: str | None


class ResultsAudit:
    """Every number a certificate reports in ``results`` must be accounted for: recomputed
    (:meth:`recomputed`, :meth:`exact`), a one-sided bound in its sound direction
    (:meth:`bound`), an estimate between rigorous bounds (:meth:`estimate`), or declared
    informational (:meth:`informational`: run times,
    iteration counts, which prove nothing). A number nobody accounted for fails the audit,
    so a forged or added result cannot pass unread.

    Parameters
    ----------
    results : Any
        The certificate's ``results``.
    source : str
        The certificate's name, for messages.

    Raises
    ------
    InputError
        ``results`` is not an object.
    """

    def __init__(self, results: Any, source: str) -> None:
        if not isinstance(results, dict):
            raise InputError("expected an object", field=f"{source}: results")
        self.results = results
        self.bad: list[str] = []
        self._seen: set[tuple] = set()
        self.estimates: list[str] = []

    # -------------------------------------------------------------- lookups
    def get(self, *path: Any) -> Any:
        """The value at a path of keys and list indices.

        Parameters
        ----------
        *path : str or int
            Keys and indices from ``results`` down.

        Returns
        -------
        Any
            The value, or a sentinel (never equal to a JSON value) when absent.
        """
        x: Any = self.results
        for k in path:
            if isinstance(x, dict) and isinstance(k, str) and k in x:
                x = x[k]
            elif isinstance(x, list) and isinstance(k, int) and 0 <= k < len(x):
                x = x[k]
            else:
                return _MISSING
        return x

    def has(self, *path: Any) -> bool:
        """Whether a path is present.

        Parameters
        ----------
        *path : str or int
            Keys and indices.

        Returns
        -------
        bool
        """
        return self.get(*path) is not _MISSING

    @staticmethod
    def name(path: tuple) -> str:
        """A path as it is written in messages, ``a.b[2].c``.

        Parameters
        ----------
        path : tuple
            Keys and indices.

        Returns
        -------
        str
        """
        out = ""
        for k in path:
            out += f"[{k}]" if isinstance(k, int) else (f".{k}" if out else str(k))
        return out

    def _mark(self, path: tuple) -> None:
        self._seen.add(path)

    # -------------------------------------------------------------- verdicts
    def recomputed(
        self, path: tuple, value: float, scale: float = 0.0, rtol: float = RESULT_RTOL
    ) -> None:
        """The reported number equals ``value`` (recomputed by verify) to ``rtol``
        relative to ``max(|value|, scale)``; a missing or non-finite one fails.

        Parameters
        ----------
        path : tuple
            Where it is reported.
        value : float
            What verify recomputed.
        scale : float, optional
            A floor for the tolerance's scale (e.g. the matrix norm).
        rtol : float, optional
            The relative tolerance (documented by each kind).
        """
        self._mark(path)
        got = finite_number(self.get(*path))
        if got is None or not math.isfinite(value):
            self.bad.append(f"{self.name(path)}: reported {self._show(path)}, recomputed {value!r}")
        elif abs(got - value) > rtol * max(abs(value), scale, 1e-300):
            self.bad.append(f"{self.name(path)}: reported {got!r}, recomputed {value:.10g}")

    def bound(
        self,
        path: tuple,
        value: float,
        side: str,
        scale: float = 0.0,
        rtol: float = RESULT_RTOL,
    ) -> None:
        """A reported one-sided bound, checked in its sound direction against ``value``
        (the bound verify re-derived): an upper bound must be at or above it, a lower bound
        at or below it (within ``rtol`` relative to ``max(|value|, scale)``, on that side
        only). A looser bound than the one re-derived is still true and passes: a
        certificate keeps verifying when a later version encloses or searches more
        tightly. A missing or non-finite one fails.

        Parameters
        ----------
        path : tuple
            Where it is reported.
        value : float
            What verify re-derived (an upper bound for ``"upper"``, a lower one for
            ``"lower"``).
        side : {"upper", "lower"}
            Which bound the reported number is.
        scale : float, optional
            A floor for the tolerance's scale (e.g. the matrix norm).
        rtol : float, optional
            The relative tolerance (documented by each kind).

        Raises
        ------
        ValueError
            ``side`` is neither ``"upper"`` nor ``"lower"``.
        """
        if side not in ("upper", "lower"):
            raise ValueError(f"side must be 'upper' or 'lower', not {side!r}")
        self._mark(path)
        got = finite_number(self.get(*path))
        if got is None or not math.isfinite(value):
            self.bad.append(f"{self.name(path)}: reported {self._show(path)}, recomputed {value!r}")
            return
        slack = rtol * max(abs(value), scale, 1e-300)
        if side == "upper" and got < value - slack:
            self.bad.append(
                f"{self.name(path)}: reported upper bound {got!r} is below the re-derived "
                f"{value:.10g}"
            )
        elif side == "lower" and got > value + slack:
            self.bad.append(
                f"{self.name(path)}: reported lower bound {got!r} is above the re-derived "
                f"{value:.10g}"
            )

    def exact(self, path: tuple, value: Any) -> None:
        """The reported value (a count, a flag, a name, None) is exactly ``value``.

        Parameters
        ----------
        path : tuple
            Where it is reported.
        value : Any
            What verify derived.
        """
        self._mark(path)
        got = self.get(*path)
        same = (
            got == value and type(got) is type(value)
            if not isinstance(value, float)
            else (finite_number(got) == value)
        )
        if not same:
            self.bad.append(f"{self.name(path)}: reported {self._show(path)}, is {value!r}")

    def estimate(
        self,
        path: tuple,
        lower: float | None,
        upper: float | None,
        what: str = "",
        optional: bool = False,
        rtol: float = RESULT_RTOL,
    ) -> None:
        """An estimate (not a proof) that must lie between rigorous bounds: ``lower`` (a
        proven bound) <= x <= ``upper`` (both with a relative slack of ``RESULT_RTOL``);
        None for a side with no bound.

        Parameters
        ----------
        path : tuple
            Where it is reported.
        lower, upper : float or None
            The rigorous bounds.
        what : str, optional
            Why the upper bound holds, for the message.
        optional : bool, optional
            A null estimate (none was computed) is allowed.
        rtol : float, optional
            The relative slack (an iterative eigensolver's tolerance).
        """
        self._mark(path)
        raw = self.get(*path)
        if optional and raw is None:
            return
        got = finite_number(raw)
        label = self.name(path)
        if got is None:
            self.bad.append(f"{label}: reported {self._show(path)}, expected a finite estimate")
            return
        slack = rtol * max(abs(got), 1e-300)
        if lower is not None and got < lower - slack:
            self.bad.append(f"{label}: estimate {got!r} below the proven lower bound {lower:.10g}")
        elif upper is not None and got > upper + slack:
            self.bad.append(f"{label}: estimate {got!r} above {upper:.10g}{what}")
        else:
            self.estimates.append(label)

    def proven(self, path: tuple) -> None:
        """A number that a derived claim states (the kind read it from here to build the
        claim), so its proof among the checks fails if the number is false: it must be a
        finite number.

        Parameters
        ----------
        path : tuple
            Where it is reported.
        """
        self._mark(path)
        if finite_number(self.get(*path)) is None:
            self.bad.append(f"{self.name(path)}: reported {self._show(path)}, expected a number")

    def informational(self, path: tuple, integer: bool = False) -> None:
        """A number that proves nothing (a run time, an iteration count): it must be a
        finite number >= 0 (an integer when asked), and is never used as evidence.

        Parameters
        ----------
        path : tuple
            Where it is reported.
        integer : bool, optional
            It must be an integer.
        """
        self._mark(path)
        raw = self.get(*path)
        got = finite_number(raw)
        if raw is _MISSING:
            return
        if got is None or got < 0 or (integer and not isinstance(raw, int)):
            self.bad.append(f"{self.name(path)}: expected a number >= 0, got {self._show(path)}")

    def fail(self, why: str) -> None:
        """Record a failure found by the kind itself.

        Parameters
        ----------
        why : str
            What is wrong, naming the field.
        """
        self.bad.append(why)

    # -------------------------------------------------------------- the verdict
    def _show(self, path: tuple) -> str:
        v = self.get(*path)
        return "nothing" if v is _MISSING else repr(v)[:60]

    def numbers(self) -> Iterator[tuple]:
        """Every path in ``results`` that holds a number (bool excluded).

        Yields
        ------
        tuple
            The path.
        """
        stack: list[tuple[tuple, Any]] = [((), self.results)]
        while stack:
            path, x = stack.pop()
            if isinstance(x, dict):
                stack += [((*path, k), v) for k, v in x.items()]
            elif isinstance(x, list):
                stack += [((*path, i), v) for i, v in enumerate(x)]
            elif isinstance(x, (int, float)) and not isinstance(x, bool):
                yield path

    def check(self) -> Check:
        """The audit's verdict: no failure, and no number left unaccounted for.

        Returns
        -------
        Check
        """
        unread = sorted((p for p in self.numbers() if p not in self._seen), key=str)
        bad = self.bad + [
            f"{self.name(p)}: a reported number this kind does not report" for p in unread[:5]
        ]
        note = f" ({len(self.estimates)} estimate(s) within their bounds)" if self.estimates else ""
        return Check(
            "reported results (each number recomputed, bounded or informational)",
            not bad,
            "; ".join(bad[:6]) + (f"; … {len(bad) - 6} more" if len(bad) > 6 else "")
            if bad
            else "recomputed" + note,
        )


@dataclass(frozen=True, kw_only=True)
class IssueOptions:
    """What a kind may use when it issues a certificate, typed and built once by
    :func:`ntc_design.certify.certify`: the gain analysed once (its expression and its
    conditions, never parsed again), the noise and how the rate is found. A kind reads the
    fields it needs and ignores the others (the robust kind's radius and searches are its
    design's: :class:`ntc_design.certify.robust.RobustDesign`).

    Attributes
    ----------
    gain : GainAnalysis or None
        c(t), analysed (:func:`ntc_design.gain.schedule.analyse_any_gain`).
    noise_sigma : float
        σ of the additive noise.
    noise_f : float or array_like
        f of the state-dependent noise (a scale, or a d×d matrix).
    rate_method : str
        ``"lyapunov"`` or ``"lmi"`` (the fixed kind's decay rate).
    """

    gain: GainAnalysis | None = None
    noise_sigma: float = SIGMA
    noise_f: Any = F_SCALE
    rate_method: RateMethod = "lyapunov"


#: The top-level fields of every kind's certificates (``gain``: a tabulated schedule, whose
#: conditions verify derives; ``verification_method``: the kinds that state it).
COMMON_FIELDS = frozenset(
    {
        "format",
        "version",
        "kind",
        "certifies",
        "size",
        "subject",
        "claims",
        "results",
        "solver",
        "subject_digest",
        "versions",
        "digest",
        "verification_method",
        "gain",
    }
)


class CertificateKind(ABC):
    """A kind of certificate. Subclass it in one module, give it the class attributes,
    implement the abstract methods and add an instance to
    :data:`ntc_design.certify.kinds.registry.KINDS`.

    Attributes
    ----------
    name : str
        The ``kind`` field of its certificates.
    description : str
        What it certifies, for users.
    properties : tuple of Property
        The properties it may certify (the ``certifies`` list is a subset, in this order).
    required : frozenset of Property
        The properties it must certify.
    switching : bool
        Whether its subject is a schedule of modes.
    method : str
        How verify proves its claims (for ``Verification.method``).
    fields : frozenset of str
        The top-level fields its certificates may hold besides :data:`COMMON_FIELDS`
        (verify refuses any other: a field no reader checks is never trusted).
    subject_fields : frozenset of str
        The fields its ``subject`` may hold.
    mode_fields : frozenset of str
        The fields of each ``subject.modes`` entry (kinds with modes).
    """

    name: ClassVar[str]
    description: ClassVar[str]
    properties: ClassVar[tuple[Property, ...]]
    required: ClassVar[frozenset[Property]]
    switching: ClassVar[bool]
    method: ClassVar[str]
    fields: ClassVar[frozenset[str]] = frozenset({"matrices"})
    subject_fields: ClassVar[frozenset[str]] = frozenset({"modes"})
    mode_fields: ClassVar[frozenset[str]] = frozenset(
        {"topology", "topology_hash", "theta", "margin", "delta", "k1", "x0", "informed", "B"}
    )

    def __init_subclass__(cls, **kwargs: Any) -> None:
        # an override without a docstring inherits the base's (as Sphinx's autodoc does)
        super().__init_subclass__(**kwargs)
        for name, member in vars(cls).items():
            base = getattr(CertificateKind, name, None)
            if callable(member) and member.__doc__ is None and base is not None:
                member.__doc__ = base.__doc__

    # ------------------------------------------------------------ issuing
    @abstractmethod
    def accepts(self, design: Any) -> bool:
        """Whether this kind certifies ``design`` (the first kind that accepts issues).

        Parameters
        ----------
        design : ProtocolDesign, SwitchingDesign or TimeVaryingDesign
            A Lemma 1 design.

        Returns
        -------
        bool
        """

    @abstractmethod
    def issue(self, design: Any, options: IssueOptions | None = None) -> dict:
        """Certify ``design`` and return the certificate mapping (digest included).

        Parameters
        ----------
        design : ProtocolDesign, SwitchingDesign or TimeVaryingDesign
            A design this kind accepts.
        options : IssueOptions, optional
            The gain, noise, rate method and robust settings (default: none given).

        Returns
        -------
        dict
            The certificate.
        """

    @abstractmethod
    def verdicts(
        self, design: Any, certificate: dict, verification: Any, gain: Any
    ) -> tuple[TheoremVerdict, ...]:
        """The theorem verdicts that a certificate of this kind supports.

        Parameters
        ----------
        design : ProtocolDesign, SwitchingDesign or TimeVaryingDesign
            The design it certifies.
        certificate : dict
            The certificate.
        verification : Verification
            Its verification.
        gain : GainAnalysis or None
            The gain's conditions (None: no gain given).

        Returns
        -------
        tuple of TheoremVerdict
        """

    def agent_margins(self, certificate: dict, n: int) -> np.ndarray | None:
        """Per-agent margins the certificate records (μ_i of a component-wise proof), for
        a report's figure; None when the kind records none.

        Parameters
        ----------
        certificate : dict
            A certificate of this kind.
        n : int
            The number of agents.

        Returns
        -------
        numpy.ndarray or None
            (n,) margins.

        Raises
        ------
        InputError
            The recorded array is malformed.
        """
        return None

    # ------------------------------------------------------------ verifying
    @abstractmethod
    def read(self, doc: dict, source: str) -> Reading:
        """Parse the subject and re-derive what it determines (hashes, L_B, ...).

        Parameters
        ----------
        doc : dict
            The certificate.
        source : str
            Its name, for messages.

        Returns
        -------
        Reading
            The modes, the kind's own subject checks, and what its provers need.

        Raises
        ------
        InputError
            A malformed field, or sizes above the bounds.
        """

    def verification_method(self, reading: Reading) -> str:
        """How the claims were proven (``Verification.method``); by default ``method``.

        Parameters
        ----------
        reading : Reading
            From :meth:`read`, after the proofs.

        Returns
        -------
        str
        """
        return self.method

    def rate(self, doc: dict, source: str) -> float:
        """The decay rate α the certificate states (0 for kinds that state none).

        Parameters
        ----------
        doc : dict
            The certificate.
        source : str
            Its name, for messages.

        Returns
        -------
        float

        Raises
        ------
        InputError
            The rate is missing or not a number.
        """
        return 0.0

    @abstractmethod
    def claims(
        self, properties: tuple[Property, ...], subject: Subject, reading: Reading, alpha: float
    ) -> tuple[Claim, ...]:
        """Every claim the certified properties need for this subject.

        Parameters
        ----------
        properties : tuple of Property
            What the certificate certifies (already checked against the kind).
        subject : Subject
            The subject as the common checks established it.
        reading : Reading
            From :meth:`read`.
        alpha : float
            The decay rate stated (0 when no rate is certified).

        Returns
        -------
        tuple of Claim
        """

    def record(self, claim: Claim) -> dict:
        """The claim as the kind's certificates list it.

        Parameters
        ----------
        claim : Claim
            A derived claim.

        Returns
        -------
        dict
        """
        return claim.to_dict()

    @abstractmethod
    def prove(self, claim: Claim, subject: Subject, reading: Reading) -> Check | list[Check]:
        """Prove one claim from the certificate's content, never from its word.

        Parameters
        ----------
        claim : Claim
            A derived claim.
        subject : Subject
            The subject.
        reading : Reading
            From :meth:`read`.

        Returns
        -------
        Check or list of Check
            The claim's check, or the checks of its steps ending with the claim's own.

        Raises
        ------
        InputError
            A malformed field read only by this proof.
        """

    def stated(
        self, properties: tuple[Property, ...], reading: Reading
    ) -> tuple[tuple[Property, str], ...]:
        """The numbers each certified property states (``ntc verify`` shows them beside
        the property), e.g. a robust decay rate and its radius; none by default.

        Parameters
        ----------
        properties : tuple of Property
            What the certificate certifies.
        reading : Reading
            From :meth:`read`.

        Returns
        -------
        tuple of (Property, str)
        """
        return ()

    def rows(self, results: dict) -> tuple[ResultRow, ...]:
        """What a certificate of this kind reports, as rows for every face.

        Parameters
        ----------
        results : dict
            The certificate's ``results`` (as issued and verified).

        Returns
        -------
        tuple of ResultRow
        """
        return ()

    @abstractmethod
    def audit(
        self, audit: ResultsAudit, doc: dict, subject: Subject, reading: Reading, alpha: float
    ) -> None:
        """Account for every number in ``results`` (see :class:`ResultsAudit`).

        Parameters
        ----------
        audit : ResultsAudit
            Collects the verdicts.
        doc : dict
            The certificate.
        subject : Subject
            The subject.
        reading : Reading
            From :meth:`read`.
        alpha : float
            The decay rate stated.

        Raises
        ------
        InputError
            A malformed field read only by the audit.
        """


__all__ = [
    "COMMON_FIELDS",
    "CertificateKind",
    "IssueOptions",
    "ResultRow",
    "number_text",
    "ModeReading",
    "Reading",
    "ResultsAudit",
    "Subject",
]
