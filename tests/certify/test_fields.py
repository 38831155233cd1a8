"""Tests of :mod:`ntc_design.certify.fields`."""

import math

import numpy as np
import pytest

from ntc_design.certify.fields import (
    finite_number,
    matrix,
    need,
    number,
    parse_schedule,
    vector,
)
from ntc_design.certify.format import MAX_SCHEDULE
from ntc_design.errors import InputError

HUGE = 10**400  # a JSON integer beyond any double


def test_need_returns_the_value_of_the_right_type():
    doc = {"n": 3, "x": 1.5, "flag": True, "name": "G1"}
    assert need(doc, "n", int, "cert") == 3
    assert need(doc, "x", (int, float), "cert") == 1.5
    assert need(doc, "flag", bool, "cert") is True
    assert need(doc, "flag", (bool, str), "cert") is True


@pytest.mark.parametrize(
    ("doc", "key", "typ", "message"),
    [
        ([1, 2], "n", int, r"^cert\.subject: expected an object$"),
        ({}, "n", int, r"^cert\.subject: missing field 'n'$"),
        # a bool is an int in Python, but not a number in a certificate
        ({"n": True}, "n", int, r"^cert\.subject: field 'n' has the wrong type \(bool\)$"),
        ({"n": 2.0}, "n", int, r"^cert\.subject: field 'n' has the wrong type \(float\)$"),
        ({"n": "3"}, "n", (int, float), r"field 'n' has the wrong type \(str\)$"),
    ],
)
def test_need_refuses_in_one_line(doc, key, typ, message):
    with pytest.raises(InputError, match=message):
        need(doc, key, typ, "cert.subject")


def test_number_accepts_finite_numbers():
    assert number(3, "a") == 3.0 and type(number(3, "a")) is float
    assert number(-2.5e-300, "a") == -2.5e-300
    assert number(2**1000, "a") == float(2**1000)


@pytest.mark.parametrize(
    ("x", "message"),
    [
        (True, r"^results\.alpha: expected a number, got bool$"),
        ("1.0", r"^results\.alpha: expected a number, got str$"),
        (None, r"expected a number, got NoneType$"),
        (HUGE, r"^results\.alpha: number too large$"),
        (math.nan, r"^results\.alpha: must be finite$"),
        (-math.inf, r"^results\.alpha: must be finite$"),
    ],
)
def test_number_refuses(x, message):
    with pytest.raises(InputError, match=message):
        number(x, "results.alpha")


def test_vector_of_n_numbers():
    v = vector([1, 2.5, -3], 3, "theta")
    assert v.dtype == float and v.tolist() == [1.0, 2.5, -3.0]
    with pytest.raises(InputError, match=r"^theta: expected a list of 3 numbers$"):
        vector([1, 2], 3, "theta")
    with pytest.raises(InputError, match=r"^theta: expected a list of 3 numbers$"):
        vector((1, 2, 3), 3, "theta")  # a tuple is not what JSON gives
    with pytest.raises(InputError, match=r"^theta: must be finite$"):
        vector([1, math.inf, 3], 3, "theta")


def test_matrix_of_numbers():
    a = matrix([[1, 2], [3.5, -4]], 2, "P")
    np.testing.assert_array_equal(a, np.array([[1.0, 2.0], [3.5, -4.0]]))
    assert matrix([[7]], 1, "P").shape == (1, 1)


@pytest.mark.parametrize(
    ("x", "message"),
    [
        ([[1, 2], [3, 4]], r"^P\.G1: expected a 3x3 matrix$"),  # too few rows
        ([[1, 2, 3], [4, 5, 6], [7, 8]], r"^P\.G1: expected a 3x3 matrix$"),  # ragged
        ([[1, 2, 3], [4, 5, 6], "789"], r"^P\.G1: expected a 3x3 matrix$"),
        ([[1, 2, 3], [4, True, 6], [7, 8, 9]], r"^P\.G1: non-numeric entry$"),
        ([[1, 2, 3], [4, None, 6], [7, 8, 9]], r"^P\.G1: non-numeric entry$"),
        ([[1, 2, 3], [4, HUGE, 6], [7, 8, 9]], r"^P\.G1: non-numeric or too large entry$"),
        ([[1, 2, 3], [4, math.nan, 6], [7, 8, 9]], r"^P\.G1: non-finite entry$"),
    ],
)
def test_matrix_refuses(x, message):
    with pytest.raises(InputError, match=message):
        matrix(x, 3, "P.G1")


@pytest.mark.parametrize(
    ("x", "expected"),
    [(2, 2.0), (-0.5, -0.5), (True, None), ("1", None), (None, None), ([1.0], None)],
)
def test_finite_number_of_json_values(x, expected):
    assert finite_number(x) == expected


@pytest.mark.parametrize("x", [math.nan, math.inf, -math.inf, HUGE])
def test_finite_number_is_none_beyond_doubles(x):
    assert finite_number(x) is None


def test_parse_schedule_reads_modes_and_durations():
    subject = {"schedule": [{"mode": "G1", "duration": 2}, {"mode": "G2", "duration": 0.5}]}
    got = parse_schedule(subject, "subject")
    assert got == (("G1", 2.0), ("G2", 0.5)) and type(got[0][1]) is float
    # the largest schedule allowed is read whole
    big = {"schedule": [{"mode": "G1", "duration": 1}] * MAX_SCHEDULE}
    assert len(parse_schedule(big, "subject")) == MAX_SCHEDULE


@pytest.mark.parametrize(
    ("schedule", "message"),
    [
        ([], rf"^subject\.schedule: expected 1 to {MAX_SCHEDULE} entries$"),
        (
            [{"mode": "G1", "duration": 1}] * (MAX_SCHEDULE + 1),
            rf"^subject\.schedule: expected 1 to {MAX_SCHEDULE} entries$",
        ),
        (["G1"], r"^subject\.schedule\[0\]: expected \{mode, duration\}$"),
        (
            [{"mode": "G1", "duration": 1}, {"mode": "G2"}],
            r"^subject\.schedule\[1\]: expected \{mode, duration\}$",
        ),
        (
            [{"mode": "G1", "duration": 1, "extra": 0}],
            r"^subject\.schedule\[0\]: expected \{mode, duration\}$",
        ),
        ([{"mode": 1, "duration": 1}], r"^subject\.schedule\[0\]\.mode: expected a mode name$"),
        (
            [{"mode": "G1", "duration": True}],
            r"^subject\.schedule\[0\]\.duration: expected a number, got bool$",
        ),
        (
            [{"mode": "G1", "duration": 0}],
            r"^subject\.schedule\[0\]\.duration: must be positive and finite$",
        ),
        (
            [{"mode": "G1", "duration": -1.0}],
            r"^subject\.schedule\[0\]\.duration: must be positive and finite$",
        ),
        # durations are capped below 1e300 (10 000 of them still sum to a finite double)
        (
            [{"mode": "G1", "duration": 1e300}],
            r"^subject\.schedule\[0\]\.duration: must be positive and finite$",
        ),
        ([{"mode": "G1", "duration": math.inf}], r"duration: must be finite$"),
    ],
)
def test_parse_schedule_refuses(schedule, message):
    with pytest.raises(InputError, match=message):
        parse_schedule({"schedule": schedule}, "subject")


def test_parse_schedule_needs_a_list():
    with pytest.raises(InputError, match=r"^subject: missing field 'schedule'$"):
        parse_schedule({}, "subject")
    with pytest.raises(
        InputError, match=r"^subject: field 'schedule' has the wrong type \(dict\)$"
    ):
        parse_schedule({"schedule": {"mode": "G1"}}, "subject")
