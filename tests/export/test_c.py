"""Tests of :mod:`ntc_design.export.c`: the exported C, compiled with ``cc -std=c99 -O2
-ffp-contract=off -Wall -Wextra -Werror``, agrees bit for bit with the toolkit's replay fed
the same normals (G1 with D = 0 and 2, the switching schedule with every mode sampled, a
schedule-table gain), and its replay program refuses malformed input."""

import subprocess
import sys
import warnings

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.export.c import c_files, c_string, header, protocol
from ntc_design.gain.schedule import ScheduleGain, join_tail
from ntc_design.protocol.agents import agent_law
from ntc_design.protocol.digital import Digital
from ntc_design.simulate.replay import replay
from tests.conftest import X0
from tests.support.export import CC, CFLAGS, build_c, needs_cc, normals_for, run_program, stdin_text


@pytest.fixture(scope="module")
def g1_design(g1, theta):
    return nd.design(g1, theta, thresholds=False)


@pytest.fixture(scope="module")
def sw_design(switching_set, theta):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return nd.design(switching_set, theta, thresholds=False)


def _table_gain():
    t = np.linspace(0.0, 6.0, 61)
    c = 1.2 / (0.5 + t) ** 0.9
    return ScheduleGain(t, c, "linear", join_tail(6.0, float(c[-1])))


def _same(law, tmp_path, steps, delay_note="", x0=X0, seed=0):
    exe = build_c(tmp_path, law)
    z = normals_for(law, steps, seed)
    got = run_program(exe, law, x0, steps, z)
    want = replay(law, x0, z, steps)
    assert (got == want).all(), (delay_note, np.max(np.abs(got - want)))
    return got


@needs_cc
@pytest.mark.parametrize("delay", [0, 2])
def test_g1_bit_for_bit(g1_design, tmp_path, delay):
    law = agent_law(g1_design, Digital(0.01, delay), "1/(1+t)", 0.4, 0.3)
    x = _same(law, tmp_path, 1000, f"D = {delay}")
    assert np.all(np.isfinite(x)) and np.max(np.abs(x - X0)) > 0.1  # it moved


@needs_cc
def test_switching_schedule_bit_for_bit(sw_design, tmp_path):
    law = agent_law(sw_design, Digital(0.013, 1), "1/(1+t)", 0.4, 0.3)
    assert set(law.step_modes(600).tolist()) == {0, 1, 2}  # every mode is sampled
    _same(law, tmp_path, 600)


@needs_cc
@pytest.mark.parametrize("interpolation", ["linear", "previous"])
def test_schedule_table_gain_bit_for_bit(g1_design, tmp_path, interpolation):
    g = _table_gain()
    g = ScheduleGain(g.t, g.c, interpolation, g.tail)
    law = agent_law(g1_design, Digital(0.07, 1), g, 0.4, 0.3)
    _same(law, tmp_path, 200)  # 14 time units: the table and its tail
    assert "#define NTC_TABLE 61" in protocol(law)


@needs_cc
@pytest.mark.parametrize(
    "gain", ["min(1, 2*(1+t)^(-0.75))", "max(0.1, exp(-t/3))*sqrt(1+t)/(1+t)", "0.5", "2/(2+t)^2"]
)
def test_gains_with_helpers_compile_cleanly_and_agree(g1_design, tmp_path, gain):
    law = agent_law(g1_design, Digital(0.05, 0), gain, 0.4, 0.3)
    _same(law, tmp_path, 100)


@needs_cc
def test_matrix_noise_per_edge_sigma_and_a_listener_without_inputs(tmp_path):
    eye = np.eye(2)
    top = nd.Topology.from_edges(
        ["a", "b", "c", "d"],
        2,
        [("b", "a", -eye), ("a", "b", 2 * eye), ("a", "c", np.diag([1.0, 3.0])), ("c", "d", eye)],
    )
    des = nd.design(top, [1.0, -2.0], thresholds=False)
    f = np.array([[0.2, 0.05], [0.05, 0.1]])
    law = agent_law(des, Digital(0.02, 3), "1/(1+t)", 0.3, f, {("a", "c"): 0.9})
    assert law.modes[0].n_edges == 4 and law.modes[0].in_edges(0) == [0]
    _same(law, tmp_path, 300, x0=np.arange(8.0))


@needs_cc
def test_hostile_labels_and_mode_names_stay_strings(tmp_path, g1_design):
    labels = ['q"uote', "back\\slash", "tri??=graph", "*/ end", "new\nline", "é", "%s"]
    top = nd.Topology(tuple(labels), 3, dict(g1_design.topology.weights), name='x */ "y')
    law = agent_law(nd.design(top, [1, 2, -1], thresholds=False), Digital(0.1), "1", 0.4, 0.3)
    exe = build_c(tmp_path, law)
    assert exe.exists()
    probe = tmp_path / "probe.c"
    probe.write_text(
        '#include <stdio.h>\n#include "ntc_protocol.h"\nint main(void)\n{\n    int i;\n'
        '    for (i = 0; i < NTC_N; i++) printf("%s\\x1f", ntc_labels[i]);\n'
        '    printf("%s", ntc_modes[0].name);\n    return 0;\n}\n'
    )
    cmd = [CC, *CFLAGS, "-o", "probe", "probe.c", "ntc_protocol.c", "-lm"]
    assert subprocess.run(cmd, cwd=tmp_path, capture_output=True).returncode == 0
    out = subprocess.run([str(tmp_path / "probe")], capture_output=True).stdout.decode("utf-8")
    assert out.split("\x1f") == [*labels, 'x */ "y']


def test_c_string_escapes_every_unsafe_byte():
    assert c_string("G1") == '"G1"'
    assert c_string('a"b') == '"a\\042b"'
    assert c_string("??=") == '"\\077\\077="'
    assert c_string("é") == '"\\303\\251"'


def test_the_header_states_the_sizes(g1_design):
    law = agent_law(g1_design, Digital(0.1, 3), "1/(1+t)", 0.4, 0.3)
    h = header(law)
    for line in (
        "#define NTC_N 7",
        "#define NTC_D 3",
        "#define NTC_DELAY 3",
        "#define NTC_MODES 1",
    ):
        assert line in h


@needs_cc
@pytest.mark.hostile
@pytest.mark.parametrize(
    "cut, message",
    [
        (lambda s: s.rsplit(" ", 3)[0], "expected 2E normals (step"),
        (lambda s: s + " 0.5", "more numbers than the K steps read"),
        (lambda s: "1 2 3", "expected N*d numbers of the initial state"),
        (lambda s: s.split("\n", 1)[0], "expected the number of steps K >= 0"),
    ],
)
def test_the_replay_program_refuses_malformed_input(g1_design, tmp_path, cut, message):
    from tests.support.export import stdin_text

    law = agent_law(g1_design, Digital(0.1), "1/(1+t)", 0.4, 0.3)
    exe = build_c(tmp_path, law)
    text = stdin_text(X0, 3, normals_for(law, 3)).strip()
    res = subprocess.run([str(exe)], input=cut(text), capture_output=True, text=True)
    assert res.returncode == 2 and res.stdout == ""
    assert len(res.stderr.splitlines()) == 1 and message in res.stderr


@needs_cc
@pytest.mark.hostile
def test_a_gain_that_is_not_finite_stops_the_replay(g1_design, tmp_path):
    law = agent_law(g1_design, Digital(0.1), "1/(1-t)", 0.4, 0.3)
    exe = build_c(tmp_path, law)
    res = run_program(exe, law, X0, 20, normals_for(law, 20), expect=1)
    assert "c(t) = inf is not finite at step 10" in res.stderr


def _exact_modes(law, steps):
    """The mode of t_k = k·h, h and the durations exact fractions of their decimals."""
    from fractions import Fraction

    h = Fraction(repr(law.digital.period))
    ds = [Fraction(repr(d)) for _, d in law.schedule]
    period = sum(ds)
    out = []
    for k in range(steps):
        tau = (k * h) % period
        ends = [sum(ds[: s + 1]) for s in range(len(ds))]
        pick = next(s for s, e in enumerate(ends) if tau < e)
        out.append(law.mode_names.index(law.schedule[pick][0]))
    return out


@needs_cc
@pytest.mark.parametrize("h, steps", [(0.1, 1000), (0.013, 2000)])
def test_the_switching_rule_is_exact_in_the_toolkit_c_and_python(sw_design, tmp_path, h, steps):
    # the paper's set, G2 G2 G1 G3 G3 with Δt = 0.02 (P = 0.1): h = P and h = 0.013 hit
    # the switching instants exactly; every implementation decides them as exact fractions
    law = agent_law(sw_design, Digital(h, 0), "1/(1+t)", 0.4, 0.3)
    truth = _exact_modes(law, steps)
    assert law.step_modes(steps).tolist() == truth
    if h == 0.1:
        assert set(truth) == {law.mode_names.index("G2")}
    build_c(tmp_path, law)
    probe = tmp_path / "modes.c"
    probe.write_text(
        '#include <stdio.h>\n#include "ntc_protocol.h"\nint main(void)\n{\n    long k;\n'
        f'    for (k = 0; k < {steps}; k++) printf("%d\\n", ntc_mode_at(k));\n'
        "    return 0;\n}\n"
    )
    cmd = [CC, *CFLAGS, "-o", "modes", "modes.c", "ntc_protocol.c", "-lm"]
    res = subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    out = subprocess.run([str(tmp_path / "modes")], capture_output=True, text=True).stdout
    assert [int(w) for w in out.split()] == truth
    from tests.support.export import write_python

    write_python(tmp_path / "py", law)
    code = (
        "import sys; sys.path.insert(0, sys.argv[1]); import ntc_protocol as p; "
        f"print(*[p.mode_at(k) for k in range({steps})])"
    )
    res = subprocess.run(
        [sys.executable, "-c", code, str(tmp_path / "py")], capture_output=True, text=True
    )
    assert [int(w) for w in res.stdout.split()] == truth, res.stderr


AGENT_MAIN = r"""#include <stdio.h>
#include "ntc_protocol.h"
/* the replay through the embedding API: N agent states, each its own delay line */
static ntc_agent_state st[NTC_N];
static double z[2 * NTC_MAX_EDGES + 1];
static double m[NTC_N][NTC_MAX_IN * NTC_D + 1];
int main(void)
{
    double x0[NTC_D];
    long K, k;
    int i, b, s;
    for (i = 0; i < NTC_N; i++) {
        for (b = 0; b < NTC_D; b++)
            if (scanf("%lf", &x0[b]) != 1) return 2;
        if (ntc_agent_init(&st[i], i, x0) != 0) return 3;
    }
    if (scanf("%ld", &K) != 1) return 2;
    for (k = 0; k < K; k++) {
        const ntc_mode *md = &ntc_modes[ntc_agent_mode(&st[0])];
        for (s = 0; s < 2 * md->n_edges; s++)
            if (scanf("%lf", &z[s]) != 1) return 2;
        for (i = 0; i < NTC_N; i++) {  /* every measurement from the delayed states first */
            const ntc_agent *ag = ntc_agent_law(&st[i]);
            for (s = 0; s < ag->n_in; s++) {
                const ntc_in_edge *e = &ag->in[s];
                ntc_measure(e, ntc_agent_delayed(&st[i]), ntc_agent_delayed(&st[e->from]),
                            z[2 * e->edge], z[2 * e->edge + 1], m[i] + s * NTC_D);
            }
        }
        for (i = 0; i < NTC_N; i++)
            if (ntc_agent_step(&st[i], m[i]) < 0) return 1;
    }
    for (i = 0; i < NTC_N; i++) {
        for (b = 0; b < NTC_D; b++) printf(b ? " %.17g" : "%.17g", ntc_agent_x(&st[i])[b]);
        printf("\n");
    }
    return 0;
}
"""


@needs_cc
@pytest.mark.parametrize("which", ["g1", "switching"])
def test_the_agent_api_reproduces_the_replay_bit_for_bit(g1_design, sw_design, tmp_path, which):
    from tests.support.export import write_files

    law = (
        agent_law(g1_design, Digital(0.05, 2), "1/(1+t)", 0.4, 0.3)
        if which == "g1"
        else agent_law(sw_design, Digital(0.013, 1), "1/(1+t)", 0.4, 0.3)
    )
    write_files(tmp_path, c_files(law))
    (tmp_path / "agents.c").write_text(AGENT_MAIN)
    cmd = [CC, *CFLAGS, "-o", "agents", "agents.c", "ntc_protocol.c", "-lm"]
    res = subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    steps = 400
    z = normals_for(law, steps, seed=3)
    got = run_program(tmp_path / "agents", law, X0, steps, z)
    want = replay(law, X0, z, steps)
    assert (got == want).all() and np.max(np.abs(got - X0)) > 0.1


@needs_cc
def test_one_agents_tables_compile_and_step_as_in_the_full_export(g1_design, tmp_path):
    # agent 2 (0-based; label 3) alone: its tables only, the same step as the full export
    law = agent_law(g1_design, Digital(0.1, 1), "1/(1+t)", 0.4, 0.3)
    files = c_files(law, agent=2)
    assert sorted(files) == ["ntc_protocol.c", "ntc_protocol.h"]
    assert "#define NTC_AGENTS 1" in files["ntc_protocol.h"]
    assert "#define NTC_SELF 2" in files["ntc_protocol.h"]
    assert protocol(law).count("ntc_in_m0_a") > files["ntc_protocol.c"].count("ntc_in_m0_a") > 0
    probe = r"""#include <stdio.h>
#include "ntc_protocol.h"
int main(void)
{
    ntc_agent_state s;
    static const double x0[NTC_D] = {1.0, -2.0, 0.5};
    double m[NTC_MAX_IN * NTC_D + 1];
    int j;
    if (NTC_SELF >= 0 && ntc_agent_init(&s, 0, x0) != -1) return 3;  /* not its agent */
    if (ntc_agent_init(&s, 2, x0) != 0) return 4;
    for (j = 0; j < NTC_MAX_IN * NTC_D; j++) m[j] = 0.25 * (double)(j + 1);
    if (ntc_agent_step(&s, m) != 0) return 5;
    printf("%.17g %.17g %.17g\n", ntc_agent_x(&s)[0], ntc_agent_x(&s)[1], ntc_agent_x(&s)[2]);
    return 0;
}
"""
    outs = []
    for name, agent in (("one", 2), ("all", None)):
        folder = tmp_path / name
        from tests.support.export import write_files

        write_files(folder, c_files(law, agent=agent))
        (folder / "probe.c").write_text(probe)
        cmd = [CC, *CFLAGS, "-o", "probe", "probe.c", "ntc_protocol.c", "-lm"]
        res = subprocess.run(cmd, cwd=folder, capture_output=True, text=True)
        assert res.returncode == 0, res.stderr
        run = subprocess.run([str(folder / "probe")], capture_output=True, text=True)
        assert run.returncode == 0, run.returncode
        outs.append(run.stdout)
    assert outs[0] == outs[1] and len(outs[0].split()) == 3
    # the same numbers as the law written out: x + h c (u − δ|B| x + Σ W m)
    ml = law.modes[0]
    x = np.array([1.0, -2.0, 0.5])
    acc = ml.u[2] - ml.bd[2] @ x if 2 in ml.informed else np.zeros(3)
    mm = 0.25 * np.arange(1, 3 * len(ml.in_edges(2)) + 1).reshape(-1, 3)
    for s, e in enumerate(ml.in_edges(2)):
        acc = acc + ml.weight[e] @ mm[s]
    want = x + 0.1 * 1.0 * acc
    assert np.allclose([float(w) for w in outs[0].split()], want, rtol=1e-14, atol=1e-14)


def _lossy(design, policy, delay=0, h=0.05):
    from ntc_design.protocol.agents import lossy_law

    law = agent_law(design, Digital(h, delay), "1/(1+t)", 0.4, 0.3)
    ml = law.modes[0]
    losses = {
        (int(i), int(j)): 0.1 + 0.1 * (k % 3)
        for k, (i, j) in enumerate(zip(ml.dst, ml.src, strict=True))
    }
    return lossy_law(law, losses, policy)


@needs_cc
@pytest.mark.parametrize("delay", [0, 1, 2])
@pytest.mark.parametrize("policy", ["skip", "rescale"])
def test_lossy_links_bit_for_bit(g1_design, tmp_path, policy, delay):
    from tests.support.export import arrivals_for

    law = _lossy(g1_design, policy, delay)
    assert f"#define NTC_POLICY {1 if policy == 'skip' else 2}" in header(law)
    exe = build_c(tmp_path, law)
    steps = 500
    z, chi = normals_for(law, steps, 2), arrivals_for(law, steps, 2)
    assert 0 < chi.sum() < chi.size
    got = run_program(exe, law, X0, steps, z, arrivals=chi)
    want = replay(law, X0, z, steps, arrivals=chi)
    assert (got == want).all(), np.max(np.abs(got - want))
    assert (
        np.max(
            np.abs(
                want
                - replay(
                    agent_law(g1_design, Digital(0.05, delay), "1/(1+t)", 0.4, 0.3), X0, z, steps
                )
            )
        )
        > 1e-3
    )


AGENT_LOSSY = (
    AGENT_MAIN.replace(
        "static double z[2 * NTC_MAX_EDGES + 1];",
        "static double z[2 * NTC_MAX_EDGES + 1];\nstatic int chi[NTC_MAX_EDGES + 1];\nstatic int got[NTC_N][NTC_MAX_IN + 1];",
    )
    .replace(
        '            if (scanf("%lf", &z[s]) != 1) return 2;\n',
        '            if (scanf("%lf", &z[s]) != 1) return 2;\n        for (s = 0; s < md->n_edges; s++)\n            if (scanf("%d", &chi[s]) != 1) return 2;\n',
    )
    .replace(
        "z[2 * e->edge], z[2 * e->edge + 1], m[i] + s * NTC_D);\n",
        "z[2 * e->edge], z[2 * e->edge + 1], m[i] + s * NTC_D);\n                got[i][s] = chi[e->edge];\n",
    )
    .replace("ntc_agent_step(&st[i], m[i])", "ntc_agent_step_arrived(&st[i], m[i], got[i])")
)


@needs_cc
@pytest.mark.parametrize("delay", [0, 1])
@pytest.mark.parametrize("policy", ["skip", "rescale"])
def test_the_agent_api_on_lossy_links_reproduces_the_replay(g1_design, tmp_path, policy, delay):
    from tests.support.export import arrivals_for, write_files

    assert AGENT_LOSSY.count("chi") == 3 and "ntc_agent_step_arrived" in AGENT_LOSSY
    law = _lossy(g1_design, policy, delay)
    write_files(tmp_path, c_files(law))
    (tmp_path / "agents.c").write_text(AGENT_LOSSY)
    cmd = [CC, *CFLAGS, "-o", "agents", "agents.c", "ntc_protocol.c", "-lm"]
    res = subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    steps = 300
    z, chi = normals_for(law, steps, seed=4), arrivals_for(law, steps, 4)
    got = run_program(tmp_path / "agents", law, X0, steps, z, arrivals=chi)
    assert (got == replay(law, X0, z, steps, arrivals=chi)).all()


@needs_cc
@pytest.mark.hostile
@pytest.mark.parametrize("bad", ["2", "0.5", "1.0", "-1", "x"])
def test_the_replay_program_refuses_a_flag_other_than_0_or_1(g1_design, tmp_path, bad):
    from tests.support.export import arrivals_for

    law = _lossy(g1_design, "skip")
    exe = build_c(tmp_path, law)
    steps = 3
    z, chi = normals_for(law, steps), arrivals_for(law, steps)
    text = stdin_text(X0, steps, z, law, chi).rstrip("\n").split("\n")
    text[-1] = " ".join([bad, *text[-1].split()[1:]])  # the last step's first flag
    res = run_program(exe, law, X0, steps, z, expect=2, text="\n".join(text) + "\n")
    assert res.stderr.strip() == "ntc_replay: stdin: an arrival flag is not 0 or 1 (step 2)"
    short = stdin_text(X0, steps, z, law, chi).rsplit(" ", 1)[0]
    res = run_program(exe, law, X0, steps, z, expect=2, text=short)
    assert "expected E arrival flags (0 or 1) (step 2)" in res.stderr
