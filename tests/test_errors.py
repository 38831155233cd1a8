"""Tests of :mod:`ntc_design.errors`."""

import warnings

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.errors import (
    EXTRAS,
    MIN_HORIZON,
    InputError,
    Option,
    blame,
    one_line,
    quote,
    real_float,
    require_horizon,
    require_number,
    require_positive,
    require_radius,
)
from ntc_design.simulate import simulate
from tests.cli_helpers import assert_input_error
from tests.conftest import EXAMPLES, ROOT


def test_assumption_warning_points_at_the_users_call():
    top = nd.load(EXAMPLES / "g3.yaml")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        nd.design(top, [1, 2, -1], 0.1)
    (w,) = [w for w in caught if issubclass(w.category, nd.AssumptionWarning)]
    assert w.filename == __file__


@pytest.mark.hostile
@pytest.mark.parametrize(
    "radius, needle",
    [("1.5", "below 1"), ("-0.1", ">= 0"), ("nan", "finite"), ("1", "below 1")],
)
def test_a_bad_radius_is_one_line_exit_2(radius, needle, capsys, monkeypatch):
    g1_robust = ROOT / "examples" / "g1.yaml"
    args = ["robust", g1_robust, "--theta", "1,2,-1", "--radius", radius]
    assert_input_error(args, capsys, monkeypatch, needle, "--radius")


@pytest.mark.hostile
def test_theta_length_checked_against_the_topology(g1):
    with pytest.raises(InputError, match=r"^theta: expected 3 numbers"):
        simulate(g1, [1, 2], T=0.1, paths=2)


def test_quote_and_one_line():
    assert quote(3) == "3" and quote("a") == "'a'"
    assert "\n" not in quote("a\nerror: forged")
    assert one_line("a\nb\rc\x1b") == "a\\nb\\rc\\x1b"


@pytest.mark.parametrize(
    "field, message, flags, fields, values, want",
    [
        # a field a flag gave: the flag, not the file
        ("paths", "must be positive", {"paths": "--paths"}, None, None, "--paths: must be positive"),
        ("T", "too long", {"T": "--horizon"}, None, None, "--horizon: too long"),
        ("initial.seed", "bad", {"initial": "--x"}, None, None, "--x.seed: bad"),
        # a field of the file: the file, with the flags that took part
        ("dt", "too small", {"T": "--horizon"}, None, {"T": 1e12}, "s.yaml: dt: too small "
         "(with --horizon 1e+12)"),
        ("gain", "bad", None, None, None, "s.yaml: gain: bad"),
        # an error that names its flag already is kept
        ("--period", "too long", {"digital": "--period"}, None, None, "--period: too long"),
        # a parameter the file gave (no flag): the file's name for it
        ("horizon", "must be positive", {}, {"horizon": "T"}, None, "s.yaml: T: must be positive"),
        # advice as data: in the file's words, or the flag's where the user typed one
        ("device", ("gpu: no driver; use ", Option("device", "cpu", document=True)),
         {"device": "--device"}, None, None, "--device: gpu: no driver; use --device cpu"),
        # a flag for the very field, beside the flag for its block
        ("digital.delay", "too long", {"digital": "--period", "digital.delay": "--delay"}, None,
         None, "--delay: too long"),
        ("device", ("gpu: no driver; use ", Option("device", "cpu", document=True)), {}, None,
         None, "s.yaml: device: gpu: no driver; use device: cpu"),
    ],
)  # fmt: skip
def test_blame_names_the_flag_or_the_file(field, message, flags, fields, values, want):
    from ntc_design.errors import blame

    parts = (message,) if isinstance(message, str) else message
    exc = InputError(*parts, field=field)
    got = blame(exc, "s.yaml", flags, fields, values)
    assert isinstance(got, InputError) and str(got) == want
    assert got.field.startswith("--") or got.field == "s.yaml"  # as data: the flag or the file
    assert str(blame(InputError("x", field="dt"), None, {"dt": "--dt"})) == "--dt: x"
    unmapped = blame(InputError("x", field="seed"), None, {"dt": "--dt"})
    assert str(unmapped) == "seed: x" and unmapped.field == "seed"


@pytest.mark.hostile
@pytest.mark.parametrize(
    "check",
    [
        real_float,
        require_number,
        require_positive,
        require_horizon,
        lambda n, v: require_radius(v, n),
    ],
)
@pytest.mark.parametrize("value", [10**400, -(10**400)], ids=["big", "-big"])
def test_an_integer_beyond_the_float_range_is_named_not_an_overflow(check, value):
    # float(10**400) raises OverflowError: it used to escape as an internal error
    with pytest.raises(InputError, match=r"^field: .*(401 digits|positive)") as info:
        check("field", value)
    assert "9999" not in str(info.value) and "0000000000" not in str(info.value)


@pytest.mark.hostile
@pytest.mark.parametrize("value", [5e-324, 1e-300, MIN_HORIZON / 2, 0.0, -1.0, float("inf")])
def test_a_horizon_below_the_time_grids_resolution_is_refused(value):
    with pytest.raises(InputError, match=r"^--horizon: "):
        require_horizon("--horizon", value)


def test_the_shortest_horizon_is_accepted():
    assert require_horizon("T", MIN_HORIZON) == MIN_HORIZON
    assert require_horizon("T", 3) == 3.0 and isinstance(require_horizon("T", 3), float)


@pytest.mark.hostile
@pytest.mark.parametrize(
    "text, why",
    [
        ("0_05", "without underscores"),
        ("1_000", "without underscores"),
        ("\u0663", "ASCII digits 0-9"),
        ("\uff13.5", "ASCII digits 0-9"),
        ("0x10", "ASCII digits, a point"),
        ("", "ASCII digits, a point"),
    ],
)
def test_number_from_text_takes_ascii_numerals_only(text, why):
    from ntc_design.errors import number_from_text

    with pytest.raises(InputError, match="--radius: ") as err:
        number_from_text(text, "--radius")
    assert why in str(err.value)


@pytest.mark.parametrize("text, value", [("0.05", 0.05), (" -1e3 ", -1000.0), (".5", 0.5)])
def test_number_from_text_reads_plain_numbers(text, value):
    from ntc_design.errors import number_from_text

    assert number_from_text(text, "x") == value


@pytest.mark.hostile
@pytest.mark.parametrize(
    "theta, k1, bound",
    [([1.7e308, 1.0], 1.27609, "1.409e+308"), ([-1e308, 1.0], [1.0, 2.0], "8.988e+307")],
)
def test_require_x0_refuses_an_overflowing_target(theta, k1, bound):
    from ntc_design.errors import require_x0

    with pytest.raises(InputError, match=r"^theta: x0 = k1·θ overflows") as err:
        require_x0(np.asarray(theta), np.asarray(k1))
    assert f"must be below {bound}" in str(err.value)
    require_x0(np.asarray([1e300, 1.0]), np.asarray(k1))  # fits: no error


@pytest.mark.parametrize("extra", sorted(EXTRAS))
def test_a_missing_optional_module_names_its_extra(extra):
    from ntc_design.errors import optional_module

    with pytest.raises(InputError) as exc:
        optional_module("ntc_design_no_such_module.sub", extra, "ntc sweep")
    assert str(exc.value) == (
        "ntc sweep needs ntc_design_no_such_module, which the core install leaves out: "
        f'pip install "ntc-design[{extra}]"'
    )
    assert optional_module("json", extra, "x").dumps([1]) == "[1]"  # installed: the module


@pytest.mark.hostile
def test_a_numpy_number_is_shown_as_the_number_not_its_repr():
    import numpy as np

    for value, shown in (
        (np.float64("inf"), "inf"),
        (np.float32("nan"), "nan"),
        (np.int64(-3), "-3"),
    ):
        with pytest.raises(InputError) as info:
            require_number("x", value, minimum=0)
        assert str(info.value).endswith(f"got {shown}") and "np." not in str(info.value)


def test_an_error_carries_its_field_as_data():
    exc = InputError("must be a positive integer, got -5", field="paths")
    assert (exc.field, exc.message) == ("paths", "must be a positive integer, got -5")
    assert str(exc) == "paths: must be a positive integer, got -5"
    # the text is never parsed for a field: a message that happens to hold "x: " has none
    plain = InputError("digital.period: must be a positive number, got -1")
    assert plain.field is None and plain.message == str(plain)
    assert InputError("no field here").field is None


def test_advice_is_data_that_each_reader_writes_in_its_words():
    exc = InputError(
        "exact moments need a linear f; use ",
        Option("schedule", "power"),
        " ",
        Option("method", "mc"),
        " or lower ",
        Option("max_gain"),
        field="schedule",
    )
    # a Python caller reads Python names
    assert str(exc) == (
        'schedule: exact moments need a linear f; use schedule="power" method="mc" or lower max_gain'
    )
    flags = {"schedule": "--schedule", "method": "--method", "max_gain": "--max-gain"}
    got = blame(exc, None, {"schedule": "--schedule"}, advice=flags)
    assert str(got) == (
        "--schedule: exact moments need a linear f; use --schedule power --method mc or lower "
        "--max-gain"
    )
    assert str(Option("period", 0.137)) == "period=0.137"
    assert Option("period", 0.137).as_flag("--period") == "--period 0.137"


def test_an_error_keeps_its_field_and_advice_across_processes():
    import pickle

    exc = InputError("lower ", Option("max_gain"), field="schedule")
    back = pickle.loads(pickle.dumps(exc))
    assert type(back) is InputError and (back.field, back.parts) == (exc.field, exc.parts)
    assert str(blame(back, None, advice={"max_gain": "--max-gain"})) == "schedule: lower --max-gain"


def test_an_error_about_a_value_of_a_field_names_both():
    exc = InputError("uses exact moments (", Option("method", "mc"), " is for power)",
                     field="schedule", value="optimal")  # fmt: skip
    assert str(exc) == 'schedule="optimal": uses exact moments (method="mc" is for power)'
    flags = {"schedule": "--schedule", "method": "--method"}
    assert str(blame(exc, "s.yaml", flags)) == (
        "--schedule optimal: uses exact moments (--method mc is for power)"
    )
    assert str(blame(exc, "s.yaml", {}, advice=flags)) == (
        's.yaml: schedule="optimal": uses exact moments (--method mc is for power)'
    )
