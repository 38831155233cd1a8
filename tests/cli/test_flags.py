"""Tests of :mod:`ntc_design.cli.flags`: every flag of every command is a field of the
library, and every field of a command's map is one of its flags."""

import pytest
import typer

from ntc_design.cli.flags import DEPRECATED, FLAGS, digital_flags, flags_named, flags_of
from ntc_design.errors import InputError, Option


def _commands() -> dict:
    import ntc_design.cli.commands  # noqa: F401 (registers every command on the app)
    from ntc_design.cli.app import app

    return typer.main.get_command(app).commands  # type: ignore[attr-defined]


def _options(command) -> dict[str, bool]:
    """Each option of a command by its first spelling -> whether it is hidden."""
    return {
        p.opts[0]: bool(getattr(p, "hidden", False))
        for p in command.params
        if p.param_type_name == "option"
    }


def test_every_command_has_its_map():
    assert sorted(_commands()) == sorted(FLAGS)


@pytest.mark.parametrize("name", sorted(FLAGS))
def test_every_flag_a_command_defines_has_a_field_and_every_field_a_flag(name):
    options = _options(_commands()[name])
    shown = {flag for flag, hidden in options.items() if not hidden}
    hidden = {flag for flag, hidden in options.items() if hidden}
    assert set(FLAGS[name].values()) == shown  # every flag a field, every field a flag
    # a hidden spelling is a deprecated one, standing for a flag of the map
    old = DEPRECATED.get(name, {})
    assert set(old) == hidden
    assert set(old.values()) <= shown
    assert all(field and not field.startswith("-") for field in FLAGS[name])


def test_flags_of_narrows_to_the_flags_given():
    assert flags_of("robust", {"theta": [1.0], "radius": None}) == {"theta": "--theta"}
    got = flags_of("export", {"sigma": 0.1}, sigma="--sigma")
    assert got == {"sigma": "--sigma"}  # the spelling typed
    assert digital_flags(0.1, None, 0.2) == {
        "digital.period": "--period",
        "digital.loss": "--loss",
    }


def test_an_error_about_a_given_flag_names_it_and_advice_is_in_flags():
    with pytest.raises(InputError) as err, flags_named("tune", "max_gain"):
        raise InputError(
            "expected a number, got -1; or use ", Option("schedule", "power"), field="max_gain"
        )
    assert str(err.value) == "--max-gain: expected a number, got -1; or use --schedule power"
    with pytest.raises(InputError) as err, flags_named("design", "theta"):
        raise InputError("must be non-zero", field="margin")  # no flag given for it here
    assert str(err.value) == "margin: must be non-zero"
