"""Tests of :mod:`ntc_design.choices`: every choice written once, as a ``Literal`` that
mypy checks and that the runtime checks read back."""

import subprocess
import sys
import typing

import pytest

from ntc_design import choices as ch
from ntc_design.certify.kinds.hurwitz import RATE_METHODS
from ntc_design.export.run import LANGUAGES
from ntc_design.gain.schedule import INTERPOLATIONS, ScheduleGain
from ntc_design.protocol.digital import Digital
from ntc_design.protocol.loss import POLICIES
from ntc_design.simulate.gpu import LAYOUTS
from ntc_design.simulate.implicit import METHODS as SOLVERS
from ntc_design.simulate.options import DEVICES, MonteCarlo, Stepping
from ntc_design.simulate.rng import GENERATORS
from ntc_design.simulate.spec import METHODS, SimulationSpec
from ntc_design.simulate.system import SCHEMES
from ntc_design.tune.entry import SCHEDULES
from ntc_design.tune.family import REQUIRE
from tests.conftest import ROOT


def test_the_runtime_sets_are_the_literals():
    """The tuples the runtime checks (and their messages) use are the aliases' values."""
    pairs = {
        ch.SimulateMethod: METHODS,
        ch.Rng: GENERATORS,
        ch.Device: DEVICES,
        ch.Scheme: SCHEMES,
        ch.Layout: LAYOUTS,
        ch.Solver: SOLVERS,
        ch.RateMethod: RATE_METHODS,
        ch.Schedule: SCHEDULES,
        ch.Require: REQUIRE,
        ch.LossPolicy: POLICIES,
        ch.Interpolation: INTERPOLATIONS,
        ch.Language: LANGUAGES,
    }
    for alias, values in pairs.items():
        assert values == typing.get_args(alias) == ch.choices(alias)
    assert ch.choices(ch.TuneMethod) == ("auto", "exact", "mc")
    assert ch.choices(ch.SteppingKind) == ("uniform", "intrinsic")


def test_the_fields_are_typed_by_the_aliases():
    hints = {
        (SimulationSpec, "method"): ch.SimulateMethod,
        (MonteCarlo, "rng"): ch.Rng,
        (MonteCarlo, "device"): ch.Device,
        (Stepping, "kind"): ch.SteppingKind,
        (Stepping, "scheme"): ch.Scheme,
        (Digital, "policy"): ch.LossPolicy,
        (ScheduleGain, "interpolation"): ch.Interpolation,
    }
    for (cls, name), alias in hints.items():
        assert typing.get_type_hints(cls)[name] == alias, (cls, name)


@pytest.mark.hostile
def test_a_runtime_check_refuses_what_the_alias_does_not_allow():
    from ntc_design.errors import InputError

    with pytest.raises(InputError, match="^rng: expected xoshiro or numpy, got 'xoshirro'"):
        MonteCarlo(rng="xoshirro")  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="not a Literal of strings"):
        ch.choices(int)


@pytest.mark.slow  # mypy reads the package (a few seconds with its cache, ~1 min without)
def test_mypy_catches_a_misspelt_choice(tmp_path):
    snippet = tmp_path / "misspelt.py"
    snippet.write_text(
        "from ntc_design.certify import certify\n"
        "from ntc_design.model import Topology\n"
        "from ntc_design.simulate.options import MonteCarlo, Stepping\n"
        "MonteCarlo(rng='xoshiro', device='gpu')  # spelt right: no error\n"
        "MonteCarlo(rng='xoshirro')\n"
        "Stepping(scheme='implicitt')\n"
        "def check(top: Topology) -> None:\n"
        "    certify(top, [1.0], rate_method='lmii')\n"
    )
    done = subprocess.run(
        [sys.executable, "-m", "mypy", "--no-error-summary", str(snippet)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
    )
    errors = [ln for ln in done.stdout.splitlines() if ": error:" in ln]
    lines = sorted(int(ln.split(":")[1]) for ln in errors if "Literal[" in ln)
    assert lines == [5, 6, 8], done.stdout
    assert len(errors) == 3, done.stdout  # nothing else
