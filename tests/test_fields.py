"""Tests of :mod:`ntc_design.fields`: a parameter named in a message, written in each
reader's words."""

import pickle

from ntc_design.fields import Option, flag_value, options_written_as


def test_an_option_in_the_python_callers_words():
    assert str(Option("schedule", "power")) == 'schedule="power"'
    assert str(Option("max_gain")) == "max_gain"
    assert str(Option("period", 0.137)) == "period=0.137"
    assert str(Option("max_gain", "50.0000", quoted=False)) == "max_gain=50.0000"
    assert str(Option("device", "cpu", document=True)) == "device: cpu"


def test_an_option_in_the_command_lines_words_while_its_map_holds():
    opt = Option("schedule", "power")
    with options_written_as({"schedule": "--schedule"}):
        assert str(opt) == "--schedule power" and f"use {opt}" == "use --schedule power"
        assert str(Option("method", "mc")) == 'method="mc"'  # not a flag of this command
        # a document's field stays the file's word: the flag did not give it
        assert str(Option("schedule", "power", document=True)) == "schedule: power"
        with options_written_as({}):  # nested: the inner map
            assert str(opt) == 'schedule="power"'
        assert str(opt) == "--schedule power"
    assert str(opt) == 'schedule="power"'  # the map is gone after the block


def test_a_value_as_typed_after_its_flag():
    assert flag_value(1e12) == "1e+12" and flag_value(3) == "3" and flag_value("mc") == "mc"
    assert flag_value({"period": 0.1, "delay": 1}) == "period 0.1, delay 1"
    assert pickle.loads(pickle.dumps(Option("a", 1.5))) == Option("a", 1.5)
