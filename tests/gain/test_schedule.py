"""Tests of :mod:`ntc_design.gain.schedule`."""

import numpy as np
import pytest

from ntc_design.errors import InputError
from ntc_design.gain.schedule import (
    ScheduleGain,
    analyse_schedule,
    join_tail,
    read_schedule,
    schedule_checks,
)
from tests.cli_helpers import assert_input_error

# -- the schedule gain ----------------------------------------------------------------------


def test_schedule_values_between_and_after_the_table():
    g = ScheduleGain([0, 1, 3], [2.0, 1.0, 0.5], tail="2/(1 + t)")
    assert g(np.array([0.5, 2.0, 3.0, 7.0])).tolist() == pytest.approx([1.5, 0.75, 0.5, 0.25])
    step = ScheduleGain([0, 1, 3], [2.0, 1.0, 0.5], "previous", tail="2/(1 + t)")
    assert step(np.array([0.5, 1.0, 2.9])).tolist() == [2.0, 1.0, 1.0]
    i1, i2 = g.integrals(3.0)  # trapezoids of a linear table, exact
    assert i1 == pytest.approx(1.5 + 1.5) and i2 == pytest.approx(
        (4 + 2 + 1) / 3 + 2 * (1 + 0.5 + 0.25) / 3
    )


@pytest.mark.hostile
@pytest.mark.parametrize(
    "t, c, interp, tail, needle",
    [
        ([0, 1], [1.0, -0.1], "linear", "1/(1+t)", "c[1] = -0.1"),
        ([0, 1], [1.0, float("nan")], "linear", "1/(1+t)", "c[1] is not finite"),
        ([0, 2, 1], [1.0, 1.0, 1.0], "linear", "1/(1+t)", "t[2] = 1 after t[1] = 2"),
        ([0.5, 1], [1.0, 1.0], "linear", "1/(1+t)", "t[0] must be 0"),
        ([0, 1], [1.0, 1.0], "cubic", "1/(1+t)", "interpolation"),
        ([0, 1], [1.0, 1.0], "linear", "__import__('os')", "tail"),
        ([0], [1.0], "linear", "1/(1+t)", "2 to"),
        # a 400-digit integer from a document: OverflowError before
        ([0, 10**400], [1.0, 1.0], "linear", "1/(1+t)", "t[1]: an integer of 401 digits"),
        ([0, 1], [1.0, -(10**400)], "linear", "1/(1+t)", "c[1]: an integer of 401 digits"),
    ],
    ids=str,
)
def test_a_malformed_schedule_is_refused_naming_the_field(t, c, interp, tail, needle):
    with pytest.raises(InputError, match=None) as err:
        ScheduleGain(t, c, interp, tail)
    assert needle in str(err.value)


def test_csv_round_trip_and_line_errors(tmp_path):
    g = ScheduleGain(np.linspace(0, 2, 5), [1.0, 0.8, 0.61, 0.5, 0.4], tail=join_tail(2.0, 0.4))
    p = tmp_path / "s.csv"
    p.write_text(g.csv_text(), encoding="utf-8")
    back = read_schedule(p)
    assert back.t.tolist() == g.t.tolist() and back.c.tolist() == g.c.tolist()
    assert back.tail == g.tail == "1.2/(1 + t)"
    bad = tmp_path / "bad.csv"
    bad.write_text("# tail: 1/(1+t)\nt,c\n0,1\n1,x\n", encoding="utf-8")
    with pytest.raises(InputError, match="line 4: c: expected a number"):
        read_schedule(bad)
    no_tail = tmp_path / "nt.csv"
    no_tail.write_text("t,c\n0,1\n1,1\n", encoding="utf-8")
    with pytest.raises(InputError, match="tail: missing"):
        read_schedule(no_tail)
    with pytest.raises(InputError, match="differs from the file"):
        read_schedule(p, tail="2/(1+t)")


def test_the_conditions_of_a_schedule():
    ok = analyse_schedule(ScheduleGain([0, 1], [1.0, 0.5], tail="1/(1 + t)"))
    assert ok.mean_square is True and ok.almost_sure is True
    # γ = 0.4 <= 1/2: ∫c² diverges, so only the mean-square theorems hold
    slow = analyse_schedule(ScheduleGain([0, 1], [1.0, 2**-0.4], tail="(1 + t)^(-0.4)"))
    assert slow.square_integrable.value is False and slow.mean_square is True
    step = analyse_schedule(ScheduleGain([0, 1], [1.0, 0.5], "previous", tail="1/(1 + t)"))
    assert step.continuous_nonnegative.value is False and step.mean_square is False
    gap = analyse_schedule(ScheduleGain([0, 1], [1.0, 0.6], tail="1/(1 + t)"))
    assert gap.continuous_nonnegative.value is False and "gap" in gap.continuous_nonnegative.reason


def test_join_tail_meets_the_table_and_is_admissible():
    for t_end, c_end in [(10.0, 0.0308), (3.0, 1.7), (0.5, 1e-4)]:
        tail = join_tail(t_end, c_end)
        g = ScheduleGain([0, t_end], [1.0, c_end], tail=tail)
        assert float(g(np.array([t_end + 1e-12]))[0]) == pytest.approx(c_end, rel=1e-9)
        assert analyse_schedule(g).almost_sure is True
    with pytest.raises(InputError, match="c\\(T\\) > 0"):
        join_tail(1.0, 0.0)


@pytest.mark.hostile
def test_schedule_checks_refuse_a_malformed_field():
    with pytest.raises(InputError, match="gain.tail: missing"):
        schedule_checks({"t": [0, 1], "c": [1, 1]})
    checks = schedule_checks({"t": [0, 1], "c": [1, float("inf")], "tail": "1/(1+t)"})
    assert checks[0][1] is False


@pytest.mark.hostile
def test_cli_malformed_schedule_in_a_scenario(tmp_path, capsys, monkeypatch):
    (tmp_path / "s.csv").write_text("# tail: 1/(1+t)\nt,c\n0,1\n0,2\n", encoding="utf-8")
    sc = tmp_path / "sc.yaml"
    sc.write_text(
        f"topology: {__import__('pathlib').Path('examples/g1.yaml').resolve()}\n"
        "theta: [1, 2, -1]\ngain: {schedule: s.csv}\nT: 1\npaths: 4\n",
        encoding="utf-8",
    )
    assert_input_error(
        ["simulate", sc, "--out", tmp_path / "o"], capsys, monkeypatch, "times must increase"
    )


@pytest.mark.parametrize(
    "c, tail, ok, words",
    [
        ([1.0, 0.5], "1/(1+t)", True, "∫c = ∞: yes, c → 0: yes, ∫c² < ∞: yes"),
        ([1.0, 1.0], "1", False, "∫c = ∞: yes, c → 0: no, ∫c² < ∞: no"),
    ],
)
def test_schedule_checks_say_the_tail_conditions_in_words(c, tail, ok, words):
    # the detail a report and ntc verify print: verdict words, never Python's True/False
    name, holds, detail = schedule_checks({"t": [0, 1], "c": c, "tail": tail})[-1]
    assert (name, holds) == ("gain schedule: tail admissible", ok)
    assert detail == f"{words} ({tail})"


def _schedule_path(tmp_path, kind: str):
    """A ``--gain`` schedule path that is not a readable table: a folder, a FIFO (opening
    it would wait for a writer), a device, or a file with a fault on a named line."""
    import os

    p = tmp_path / "s.csv"
    if kind == "folder":
        p.mkdir()
    elif kind == "fifo":
        os.mkfifo(p)
    elif kind == "device":
        p.symlink_to("/dev/null")
    elif kind == "two-tails":
        p.write_text("# tail: 1/(1+t)\n# tail: 2/(1+t)\nt,c\n0,1\n1,0.5\n", encoding="utf-8")
    elif kind == "arabic-digit":
        p.write_text("# tail: 1/(1+t)\nt,c\n0,1\n\u0661,0.5\n", encoding="utf-8")
    elif kind == "full-width-digit":
        p.write_text("# tail: 1/(1+t)\nt,c\n0,1\n1,0.\uff15\n", encoding="utf-8")
    return p


@pytest.mark.hostile
@pytest.mark.parametrize(
    "kind, needles",
    [
        ("missing", ["--gain.schedule: no such file"]),
        ("folder", ["--gain.schedule:", "is a directory"]),
        ("fifo", ["--gain.schedule:", "is not a regular file"]),
        ("device", ["--gain.schedule:", "is not a regular file"]),
        ("two-tails", ["line 2: a second '# tail:' line (line 1 gave one already)"]),
        ("arabic-digit", ["line 4: t: expected a number, got '\u0661'"]),
        ("full-width-digit", ["line 4: c: expected a number"]),
    ],
    ids=lambda v: v if isinstance(v, str) else None,
)
def test_cli_schedule_file_faults_named(kind, needles, tmp_path, capsys, monkeypatch):
    from tests.conftest import EXAMPLES

    p = _schedule_path(tmp_path, kind)
    args = ["certify", EXAMPLES / "g1.yaml", "--theta", "1,2,-1", "--gain", p]
    line = assert_input_error(args, capsys, monkeypatch, str(p), *needles)
    assert "no such file" not in line or kind == "missing"


def test_one_tail_line_reads(tmp_path):
    p = tmp_path / "s.csv"
    p.write_text("# tail: 0.5/(1+t)\n# interpolation: linear\nt,c\n0,1\n1,0.25\n", encoding="utf-8")
    g = read_schedule(p)
    assert g.tail == "0.5/(1+t)" and g.c.tolist() == [1.0, 0.25]
