"""Tests of :mod:`ntc_design.certify.kinds.base`."""

import dataclasses
import math

import numpy as np
import pytest

from ntc_design.certify.checks import Check
from ntc_design.certify.claims import Claim, ClaimKind, Property
from ntc_design.certify.format import RESULT_RTOL
from ntc_design.certify.kinds.base import (
    CertificateKind,
    IssueOptions,
    ModeReading,
    Reading,
    ResultRow,
    ResultsAudit,
    Subject,
    number_text,
)
from ntc_design.errors import InputError
from ntc_design.model.paper import F_SCALE, SIGMA


class _Stub(CertificateKind):
    """The least a kind must write: the class attributes and the abstract methods."""

    name = "stub"
    description = "a kind for tests"
    properties = (Property.HURWITZ,)
    required = frozenset({Property.HURWITZ})
    switching = False
    method = "by hand"

    def accepts(self, design):
        return design == "mine"

    def issue(self, design, options=None):
        return {"kind": self.name}

    def verdicts(self, design, certificate, verification, gain):
        return ()

    def read(self, doc, source):
        return Reading({}, (), None)

    def claims(self, properties, subject, reading, alpha):
        return ()

    def prove(self, claim, subject, reading):
        return Check("stub", True, "")

    def audit(self, audit, doc, subject, reading, alpha):
        """The stub's own audit."""

    def helper(self):
        return 1


# -- the base class ----------------------------------------------------------------------


def test_overrides_without_a_docstring_inherit_the_base_one():
    for name in ("accepts", "issue", "verdicts", "read", "claims", "prove"):
        doc = getattr(_Stub, name).__doc__
        assert doc is not None and doc == getattr(CertificateKind, name).__doc__
    assert _Stub.audit.__doc__ == "The stub's own audit."  # its own is kept
    assert _Stub.helper.__doc__ is None  # nothing to inherit from


def test_the_abstract_methods_must_be_written():
    assert CertificateKind.__abstractmethods__ == {
        "accepts",
        "issue",
        "verdicts",
        "read",
        "claims",
        "prove",
        "audit",
    }

    class Half(CertificateKind):
        def accepts(self, design):
            return False

    with pytest.raises(TypeError, match="abstract"):
        Half()


def test_defaults_of_the_optional_methods():
    kind = _Stub()
    reading = Reading({}, (), None)
    claim = Claim(ClaimKind.LYAPUNOV, Property.DECAY_RATE, mode="G1", p="rate", alpha=0.5)
    assert kind.agent_margins({}, 3) is None
    assert kind.verification_method(reading) == "by hand"
    assert kind.rate({}, "cert") == 0.0
    assert kind.record(claim) == claim.to_dict()
    assert kind.stated((Property.HURWITZ,), reading) == ()
    assert kind.rows({"anything": 1}) == ()


def test_issue_options_are_typed_keywords_with_the_paper_defaults():
    opts = IssueOptions()
    assert (opts.gain, opts.rate_method) == (None, "lyapunov")
    assert opts.noise_sigma == SIGMA and opts.noise_f == F_SCALE
    assert IssueOptions(rate_method="lmi", noise_sigma=0.2).noise_sigma == 0.2
    # the robust kind's radius and searches are its design's (RobustDesign), not options
    assert {f.name for f in dataclasses.fields(IssueOptions)} == {
        "gain",
        "noise_sigma",
        "noise_f",
        "rate_method",
    }
    with pytest.raises(TypeError):
        IssueOptions(None)  # keywords only: a positional value would be ambiguous
    with pytest.raises(dataclasses.FrozenInstanceError):
        opts.rate_method = "lmi"  # type: ignore[misc]


# -- readings and rows -------------------------------------------------------------------


def test_mode_reading_counts_its_agents():
    m = ModeReading("G1", "g1.yaml", ("a", "b", "c"), 2, "h", 0.5, np.array([1.0, 2.0]))
    assert m.n == 3
    subject = Subject({"G1": m}, None, ("G1",), None)
    assert subject.modes["G1"].n == 3


def test_result_row_to_dict():
    assert ResultRow("rate", "0.5").to_dict() == {
        "label": "rate",
        "value": "0.5",
        "estimate": False,
    }
    assert ResultRow("λ", "1", estimate=True).to_dict()["estimate"] is True


@pytest.mark.parametrize(
    ("x", "digits", "text"),
    [
        (1 / 3, 6, "0.333333"),
        (2.0 / 3.0, 3, "0.667"),
        (12345678, 6, "1.23457e+07"),
        (5, 6, "5"),
        (None, 6, "—"),
        (True, 6, "—"),  # a flag is not a number
        (math.nan, 6, "—"),
        ("0.5", 6, "—"),
    ],
)
def test_number_text(x, digits, text):
    assert number_text(x, digits) == text


# -- the audit of reported results ---------------------------------------------------------


def _results():
    return {
        "alpha": 0.5,
        "count": 3,
        "flag": True,
        "name": "x",
        "modes": [{"eig": 1.0}, {"eig": 2.0}],
        "seconds": 0.25,
        "none": None,
    }


def test_audit_needs_an_object():
    with pytest.raises(InputError, match=r"^cert\.json: results: expected an object$"):
        ResultsAudit([1, 2], "cert.json")


def test_audit_paths_and_names():
    a = ResultsAudit(_results(), "c")
    assert a.get("modes", 1, "eig") == 2.0
    assert a.has("none") and a.get("none") is None  # null is present, not missing
    assert not a.has("modes", 2) and not a.has("modes", -1)  # no negative indexing
    assert not a.has("modes", "0") and not a.has("alpha", "x") and not a.has("nope")
    assert ResultsAudit.name(("modes", 1, "eig")) == "modes[1].eig"
    assert ResultsAudit.name((0, "a")) == "[0].a"
    # every number is found (bools are flags, not numbers)
    assert set(a.numbers()) == {
        ("alpha",),
        ("count",),
        ("modes", 0, "eig"),
        ("modes", 1, "eig"),
        ("seconds",),
    }


def test_a_fully_accounted_audit_passes():
    a = ResultsAudit(_results(), "c")
    a.recomputed(("alpha",), 0.5 * (1 + 0.5 * RESULT_RTOL))
    a.exact(("count",), 3)
    a.exact(("flag",), True)
    a.exact(("name",), "x")
    a.exact(("none",), None)
    a.estimate(("modes", 0, "eig"), 0.9, 1.1)
    a.estimate(("modes", 1, "eig"), 2.0, None)
    a.informational(("seconds",))
    a.informational(("absent",))  # an informational number may be left out
    chk = a.check()
    assert chk.ok, chk.detail
    assert chk.detail == "recomputed (2 estimate(s) within their bounds)"
    assert a.estimates == ["modes[0].eig", "modes[1].eig"]


def test_recomputed_tolerance_and_failures():
    a = ResultsAudit({"x": 1.0, "s": "1.0", "z": 1e-9}, "c")
    a.recomputed(("x",), 1.0 + 3 * RESULT_RTOL)  # beyond the relative tolerance
    a.recomputed(("s",), 1.0)  # a string is not a number
    a.recomputed(("missing",), 1.0)
    a.recomputed(("z",), 0.0, scale=1.0)  # within rtol of the scale floor
    assert a.bad[0].startswith("x: reported 1.0, recomputed 1.00000003")
    assert a.bad[1] == "s: reported '1.0', recomputed 1.0"
    assert a.bad[2] == "missing: reported nothing, recomputed 1.0"
    assert len(a.bad) == 3
    b = ResultsAudit({"x": 1.0}, "c")
    b.recomputed(("x",), math.inf)  # nothing can equal a non-finite recomputation
    assert b.bad == ["x: reported 1.0, recomputed inf"]


@pytest.mark.parametrize(
    ("got", "value"),
    [(3.0, 3), (True, 1), (1, True), ("x", "y"), (None, 0), (2, 2.5), ("2.0", 2.0)],
)
def test_exact_compares_value_and_type(got, value):
    a = ResultsAudit({"v": got}, "c")
    a.exact(("v",), value)
    assert len(a.bad) == 1 and a.bad[0].startswith("v: reported ")


def test_exact_float_accepts_an_equal_integer():
    a = ResultsAudit({"v": 2}, "c")
    a.exact(("v",), 2.0)
    assert a.bad == []


def test_estimate_outside_its_bounds():
    a = ResultsAudit({"lo": 0.5, "hi": 3.0, "s": "x", "n": None}, "c")
    a.estimate(("lo",), 1.0, 2.0)
    a.estimate(("hi",), 1.0, 2.0, what=" (the Gershgorin bound)")
    a.estimate(("s",), None, None)
    a.estimate(("n",), None, None, optional=True)  # none computed: allowed when optional
    assert a.bad == [
        "lo: estimate 0.5 below the proven lower bound 1",
        "hi: estimate 3.0 above 2 (the Gershgorin bound)",
        "s: reported 'x', expected a finite estimate",
    ]
    assert a.estimates == []
    # a relative slack of rtol around the bounds
    b = ResultsAudit({"x": 1.0 + 0.5e-3}, "c")
    b.estimate(("x",), None, 1.0, rtol=1e-3)
    b.estimate(("x",), None, 1.0, rtol=1e-4)
    assert len(b.bad) == 1 and b.estimates == ["x"]


@pytest.mark.parametrize(
    ("raw", "integer", "ok"),
    [(3, True, True), (0.5, False, True), (3.0, True, False), (-1, False, False)]
    + [(True, False, False), ("1", False, False), (math.nan, False, False)],
)
def test_informational_numbers(raw, integer, ok):
    a = ResultsAudit({"v": raw}, "c")
    a.informational(("v",), integer=integer)
    assert (a.bad == []) is ok


def test_unread_numbers_fail_the_audit():
    a = ResultsAudit({"alpha": 0.5, "forged": 1.0, "deep": {"x": [1, 2]}}, "c")
    a.recomputed(("alpha",), 0.5)
    chk = a.check()
    assert not chk.ok
    for p in ("forged", "deep.x[0]", "deep.x[1]"):
        assert f"{p}: a reported number this kind does not report" in chk.detail
    assert "alpha" not in chk.detail


def test_many_failures_are_summarised():
    a = ResultsAudit({f"k{i}": float(i) for i in range(9)}, "c")  # 9 unread numbers
    for i in range(4):
        a.fail(f"own failure {i}")
    chk = a.check()
    # 4 failures + the first 5 unread numbers: 6 shown, the rest counted
    assert not chk.ok
    assert chk.detail.count(";") == 6 and chk.detail.endswith("; … 3 more")
    assert chk.detail.startswith("own failure 0; own failure 1")


@pytest.mark.parametrize(
    ("got", "value", "side", "ok"),
    [
        (2.0, 1.0, "upper", True),  # a looser upper bound is still true
        (1.0 - 0.5 * RESULT_RTOL, 1.0, "upper", True),  # rounding on the unsound side
        (1.0 - 3 * RESULT_RTOL, 1.0, "upper", False),  # below the re-derived upper bound
        (0.5, 1.0, "lower", True),  # a looser lower bound is still true
        (-1e9, 1.0, "lower", True),
        (1.0 + 3 * RESULT_RTOL, 1.0, "lower", False),  # above the re-derived lower bound
        (1.0, math.inf, "upper", False),  # nothing re-derived: no bound to compare
        ("1.0", 1.0, "upper", False),
        (None, 1.0, "lower", False),
    ],
)
def test_a_bound_is_checked_in_its_sound_direction(got, value, side, ok):
    a = ResultsAudit({"b": got}, "c")
    a.bound(("b",), value, side)
    assert (a.bad == []) is ok, a.bad
    assert a.check().ok is ok  # accounted for either way: no "not accounted for"


def test_a_bound_says_which_side_it_failed():
    a = ResultsAudit({"u": 0.5, "l": 2.0, "z": 1e-9}, "c")
    a.bound(("u",), 1.0, "upper")
    a.bound(("l",), 1.0, "lower")
    a.bound(("z",), 0.0, "lower", scale=1.0)  # within rtol of the scale floor
    assert a.bad == [
        "u: reported upper bound 0.5 is below the re-derived 1",
        "l: reported lower bound 2.0 is above the re-derived 1",
    ]
    with pytest.raises(ValueError, match="side must be 'upper' or 'lower'"):
        a.bound(("u",), 1.0, "both")
