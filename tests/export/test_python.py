"""Tests of :mod:`ntc_design.export.python`: the exported module, run as ``python
ntc_protocol.py < input``, agrees bit for bit with the toolkit's replay; it imports only
the standard library's math and sys; malformed input gets one line and exit 2."""

import ast
import importlib.util
import subprocess
import warnings

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.export.python import python_module
from ntc_design.gain.schedule import ScheduleGain, join_tail
from ntc_design.protocol.agents import agent_law
from ntc_design.protocol.digital import Digital
from ntc_design.simulate.replay import replay
from tests.conftest import X0
from tests.support.export import normals_for, run_program, stdin_text, write_python


@pytest.fixture(scope="module")
def g1_design(g1, theta):
    return nd.design(g1, theta, thresholds=False)


@pytest.fixture(scope="module")
def sw_design(switching_set, theta):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return nd.design(switching_set, theta, thresholds=False)


def _table_gain(interpolation="linear"):
    t = np.linspace(0.0, 6.0, 61)
    c = 1.2 / (0.5 + t) ** 0.9
    return ScheduleGain(t, c, interpolation, join_tail(6.0, float(c[-1])))


@pytest.mark.parametrize(
    "which, delay, gain, h, steps",
    [
        ("g1", 0, "1/(1+t)", 0.01, 400),
        ("g1", 2, "1/(1+t)", 0.01, 400),
        ("g1", 1, "table", 0.07, 200),
        ("g1", 1, "previous", 0.07, 200),
        ("g1", 0, "min(1, 2*(1+t)^(-0.75))", 0.05, 100),
        ("sw", 1, "1/(1+t)", 0.013, 300),
    ],
)
def test_bit_for_bit(g1_design, sw_design, tmp_path, which, delay, gain, h, steps):
    g = (
        _table_gain("previous" if gain == "previous" else "linear")
        if gain in ("table", "previous")
        else gain
    )
    des = g1_design if which == "g1" else sw_design
    law = agent_law(des, Digital(h, delay), g, 0.4, 0.3)
    if which == "sw":
        assert set(law.step_modes(steps).tolist()) == {0, 1, 2}
    cmd = write_python(tmp_path, law)
    z = normals_for(law, steps, seed=delay)
    got = run_program(cmd, law, X0, steps, z)
    assert (got == replay(law, X0, z, steps)).all()


def test_imports_only_math_and_sys(g1_design):
    law = agent_law(g1_design, Digital(0.1), "max(0.1, exp(-t))", 0.4, 0.3)
    tree = ast.parse(python_module(law))
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            names.add(node.module or "")
    assert names == {"math", "sys"}


def test_importable_as_a_module(g1_design, tmp_path):
    labels = ['q"uote', "back\\slash", "'''", "new\nline", "é", "%s", "7"]
    top = nd.Topology(tuple(labels), 3, dict(g1_design.topology.weights), name="x'''y")
    law = agent_law(nd.design(top, [1, 2, -1], thresholds=False), Digital(0.1, 1), "1", 0.4, 0.3)
    write_python(tmp_path, law)
    spec = importlib.util.spec_from_file_location(
        "ntc_protocol_probe", tmp_path / "ntc_protocol.py"
    )
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    assert mod.LABELS == tuple(labels) and mod.MODES[0][0] == "x'''y"
    assert mod.gain(3.0) == 1.0 and mod.mode_at(5) == 0 and mod.time_of(3) == 3 * 0.1
    z = iter(normals_for(law, 4).tolist())
    x = mod.replay([list(X0[3 * i : 3 * i + 3]) for i in range(7)], 4, z)
    assert (np.array(x).ravel() == replay(law, X0, normals_for(law, 4), 4)).all()


@pytest.mark.hostile
@pytest.mark.parametrize(
    "cut, code, message",
    [
        (lambda s: s.rsplit(" ", 3)[0], 2, "expected 2E normals for every step"),
        (lambda s: s + " 0.5", 2, "more numbers than the K steps read"),
        (lambda s: "1 2 3", 2, "expected N*d numbers of the initial state"),
        (lambda s: s.split("\n", 1)[0], 2, "expected the number of steps K >= 0"),
        (lambda s: s.replace(" ", " x ", 1), 2, "expected N*d numbers"),
    ],
)
def test_malformed_input(g1_design, tmp_path, cut, code, message):
    law = agent_law(g1_design, Digital(0.1), "1/(1+t)", 0.4, 0.3)
    cmd = write_python(tmp_path, law)
    text = stdin_text(X0, 3, normals_for(law, 3)).strip()
    res = subprocess.run(cmd, input=cut(text), capture_output=True, text=True)
    assert res.returncode == code and res.stdout == ""
    assert len(res.stderr.splitlines()) == 1 and message in res.stderr


@pytest.mark.hostile
def test_a_gain_that_is_not_finite_stops_the_replay(g1_design, tmp_path):
    law = agent_law(g1_design, Digital(0.1), "1/(1-t)", 0.4, 0.3)
    res = run_program(write_python(tmp_path, law), law, X0, 20, normals_for(law, 20), expect=1)
    assert "c(t) = inf is not finite at step 10" in res.stderr


@pytest.mark.parametrize("delay", [0, 1, 2])
@pytest.mark.parametrize("policy", ["skip", "rescale"])
def test_lossy_links_bit_for_bit(g1_design, tmp_path, policy, delay):
    from ntc_design.protocol.agents import lossy_law
    from tests.support.export import arrivals_for

    base = agent_law(g1_design, Digital(0.05, delay), "1/(1+t)", 0.4, 0.3)
    ml = base.modes[0]
    law = lossy_law(
        base, {(int(i), int(j)): 0.25 for i, j in zip(ml.dst, ml.src, strict=True)}, policy
    )
    cmd = write_python(tmp_path, law)
    steps = 200
    z, chi = normals_for(law, steps, 7), arrivals_for(law, steps, 7)
    got = run_program(cmd, law, X0, steps, z, arrivals=chi)
    want = replay(law, X0, z, steps, arrivals=chi)
    assert (got == want).all() and np.max(np.abs(want - replay(base, X0, z, steps))) > 1e-3
    text = stdin_text(X0, steps, z, law, chi).rstrip("\n").split("\n")
    text[-1] = " ".join(["0.5", *text[-1].split()[1:]])
    res = run_program(cmd, law, X0, steps, z, expect=2, text="\n".join(text) + "\n")
    assert res.stderr.strip() == "ntc_protocol: stdin: an arrival flag is not 0 or 1"
