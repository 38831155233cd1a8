"""Start-up cost (issue 30): what `import ntc_design` and the light commands load. Times
are measured in benchmarks/bench_inputs.py; here the modules loaded are asserted, which
is what the time follows and what does not depend on the machine."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import ROOT

HEAVY = ("sympy", "cvxpy", "scipy.sparse", "scipy.stats", "matplotlib", "dask", "numba", "pandas")


def loaded_after(code: str) -> set[str]:
    probe = f"import sys\n{code}\nimport json; print(json.dumps(sorted(sys.modules)))"
    out = subprocess.run(
        [sys.executable, "-c", probe], cwd=ROOT, capture_output=True, text=True, check=True
    )
    return set(json.loads(out.stdout.strip().splitlines()[-1]))


def heavy_in(mods: set[str]) -> list[str]:
    return sorted(h for h in HEAVY if h in mods)


# each command in a child forked from one interpreter that has imported only the CLI (as
# `ntc` has when it parses the command line): the modules a fresh process would hold, for
# one interpreter start instead of one each
_PROBE = """
import contextlib, io, json, os, sys
from ntc_design.cli import main
for argv, where in json.loads(sys.argv[1]):
    pid = os.fork()
    if pid == 0:
        try:
            sys.argv = ['ntc', *argv]
            err = io.StringIO()
            with (
                contextlib.suppress(SystemExit),
                contextlib.redirect_stdout(io.StringIO()),
                contextlib.redirect_stderr(err),
            ):
                main()
            with open(where, 'w') as f:
                json.dump([err.getvalue(), sorted(sys.modules)], f)
        finally:
            os._exit(0)
    os.waitpid(pid, 0)
"""


@pytest.fixture(scope="module")
def forked_cli(tmp_path_factory):
    """``(name, commands)`` -> per command (its folder, stderr, the modules loaded), from
    one probe per name; ``OUT`` in a command is a path in its folder (not made)."""
    done: dict = {}

    def run(name, commands):
        if name not in done:
            runs = []
            for k, argv in enumerate(commands):
                d = tmp_path_factory.mktemp(f"{name}{k}")
                argv = [str(d / "out") if a == "OUT" else a for a in argv]
                runs.append((argv, str(d / "probe.json")))
            subprocess.run(
                [sys.executable, "-c", _PROBE, json.dumps(runs)], cwd=ROOT, check=True, timeout=120
            )
            done[name] = []
            for _, where in runs:
                err, mods = json.loads(Path(where).read_text())
                done[name].append((Path(where).parent, err, set(mods)))
        return done[name]

    return run


def test_import_ntc_design_loads_no_heavy_library():
    mods = loaded_after("import ntc_design")
    assert heavy_in(mods) == []
    assert "numpy" not in mods  # the package namespace itself is free


LIGHT = [["--help"], ["--version"], ["check", "--help"], ["nope"]]


@pytest.mark.parametrize("k", range(len(LIGHT)), ids=[" ".join(a) for a in LIGHT])
def test_help_version_and_typos_load_no_library(forked_cli, k):
    _, _, mods = forked_cli("light", LIGHT)[k]
    assert heavy_in(mods) == [] and "numpy" not in mods and "ntc_design.cli" in mods


def test_check_of_a_fixed_topology_loads_no_sympy_or_optimiser():
    code = (
        "import contextlib, io\n"
        "sys.argv = ['ntc', 'check', 'examples/g1.yaml']\n"
        "from ntc_design.cli import main\n"
        "with contextlib.suppress(SystemExit), contextlib.redirect_stdout(io.StringIO()):\n"
        "    main()"
    )
    mods = loaded_after(code)
    assert heavy_in(mods) == ["scipy.sparse"]  # the graph's reachability needs csgraph
    assert "scipy.optimize" not in mods and "ntc_design.protocol.thresholds" not in mods


def test_a_monte_carlo_simulation_loads_no_sympy_and_one_kernel(tmp_path):
    # the gain is read by the NumPy backend of the expression parser; only the fused
    # kernel is loaded from Numba's cache
    code = (
        "import contextlib, io\n"
        "sys.argv = ['ntc', 'simulate', 'examples/scenarios/g1_fixed.yaml', '--out', "
        f"{str(tmp_path / 'o')!r}, '--paths', '4', '--horizon', '0.01', '--method', 'mc']\n"
        "from ntc_design.cli import main\n"
        "with contextlib.suppress(SystemExit), contextlib.redirect_stdout(io.StringIO()):\n"
        "    main()\n"
        "from ntc_design.simulate import kernels\n"
        "core = kernels._em_core\n"
        "print(json.dumps([len(core.overloads), sum(str(a[1]) != 'none' for a in core.overloads), "
        "len(kernels.fill_normals.overloads)]))"
    )
    probe = f"import sys, json\n{code}\nprint(json.dumps(sorted(sys.modules)))"
    out = (
        subprocess.run(
            [sys.executable, "-c", probe], cwd=ROOT, capture_output=True, text=True, check=True
        )
        .stdout.strip()
        .splitlines()
    )
    mods = set(json.loads(out[-1]))
    assert (tmp_path / "o" / "summary.json").is_file()
    assert "sympy" not in mods and "cvxpy" not in mods and "numba" in mods
    # one specialisation of the kernel, the fused one (normals drawn: xi is None)
    assert json.loads(out[-2]) == [1, 0, 0]


def test_certify_of_a_fixed_topology_loads_no_optimiser():
    # the critical couplings' roots by brent_root (ntc_design.numerics.roots), not scipy.optimize
    code = (
        "import contextlib, io\n"
        "sys.argv = ['ntc', 'certify', 'examples/g1.yaml', '--theta', '1,2,-1', '--gain', "
        "'1/(1+t)']\n"
        "from ntc_design.cli import main\n"
        "with contextlib.suppress(SystemExit), contextlib.redirect_stdout(io.StringIO()):\n"
        "    main()"
    )
    mods = loaded_after(code)
    assert "ntc_design.numerics.roots" in mods and "ntc_design.protocol.thresholds" in mods
    assert "scipy.optimize" not in mods and "cvxpy" not in mods


def test_the_lazy_names_are_the_same_objects():
    import ntc_design as nd
    from ntc_design.errors import AssumptionWarning
    from ntc_design.model import Topology
    from ntc_design.protocol import lemma1

    assert nd.design is lemma1.design and nd.Topology is Topology
    assert nd.AssumptionWarning is AssumptionWarning
    assert sorted(dir(nd)) == sorted(set(dir(nd)))
    assert set(nd.__all__) <= set(dir(nd))
    with pytest.raises(AttributeError):
        nd.no_such_name  # noqa: B018


# -- large YAML: any machine-written style through yaml-rs, under the same guards ----------


@pytest.fixture
def compiled(monkeypatch):
    from ntc_design.io import documents

    monkeypatch.setattr(documents, "COMPILED_YAML_MIN_CHARS", 200)  # small texts take the path
    return documents


@pytest.mark.parametrize("style", ["flow", "block", "json"])
def test_every_style_reads_as_pyyaml_reads_it(compiled, tmp_path, style):
    import json as js

    import yaml

    from ntc_design.model.generate import random_network

    doc = random_network(60, 2, seed=1).to_dict()
    text = {
        "flow": yaml.safe_dump(doc, sort_keys=False, default_flow_style=None),
        "block": yaml.safe_dump(doc, sort_keys=False, default_flow_style=False),
        "json": js.dumps(doc),
    }[style]
    assert len(text) > 200
    p = tmp_path / "net.yaml"
    p.write_text(text)
    assert compiled.read_document(p) == yaml.safe_load(text) == doc


@pytest.mark.hostile
@pytest.mark.parametrize(
    "text, needle",
    [
        ("x: " + "[" * 1000 + "]" * 1000 + "\n", "YAML"),
        ("x: " + "[" * 70 + "]" * 70 + "\n" + "# pad\n" * 40, "nested deeper than 64"),
        (
            'a0: &a0 ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]\n'
            + "".join(
                f"a{k}: &a{k} [" + ", ".join([f"*a{k - 1}"] * 9) + "]\n" for k in range(1, 10)
            ),
            "alias",
        ),
        ("dim: 3\ndim: 4\n" + "# pad\n" * 50, "duplicate"),
        ("dim: [1, 2\n" + "# pad\n" * 50, "not valid YAML"),
    ],
    ids=["nesting-1000", "nesting-70", "billion-laughs", "duplicate-key", "unclosed"],
)
def test_the_compiled_path_keeps_the_guards(compiled, tmp_path, text, needle):
    p = tmp_path / "bad.yaml"
    p.write_text(text)
    with pytest.raises(compiled.InputError) as exc:
        compiled.read_document(p)
    assert needle.lower() in str(exc.value).lower() and str(p) in str(exc.value)
    assert "\n" not in str(exc.value)


@pytest.mark.parametrize(
    "scalar",
    ["010", "0o17", "1e3", "-2E+5", "yes", "Off", "n", "1:20", "007", "1.5e-05", "0.5", "10"],
)
def test_a_file_means_the_same_at_every_size(compiled, tmp_path, scalar):
    import yaml

    text = f"dim: 3\nvalue: {scalar}\nitems: [{scalar}, 1.0e-05, 0.25]\n" + "# pad\n" * 40
    p = tmp_path / "v.yaml"
    p.write_text(text)
    assert compiled.read_document(p) == yaml.safe_load(text)  # PyYAML's reading, big or small


def test_a_json_text_is_read_as_json_at_every_size(compiled, tmp_path, monkeypatch):
    p = tmp_path / "j.yaml"
    p.write_text('{"dim": 3, "w": [1e-05, 2.5E+3, 10]}' + " " * 300)
    assert compiled.read_document(p) == {"dim": 3, "w": [1e-05, 2500.0, 10]}
    monkeypatch.setattr(compiled, "COMPILED_YAML_MIN_CHARS", 1 << 40)
    assert compiled.read_document(p) == {"dim": 3, "w": [1e-05, 2500.0, 10]}


def test_simulate_writes_its_outputs_without_pandas_or_an_optimiser(tmp_path):
    code = (
        "import contextlib, io\n"
        f"sys.argv = ['ntc', 'simulate', 'examples/scenarios/g1_fixed.yaml', '--out', "
        f"{str(tmp_path / 'o')!r}, '--paths', '20', '--horizon', '0.5', '--method', 'mc', "
        "'--workers', '1']\n"
        "from ntc_design.cli import main\n"
        "with contextlib.suppress(SystemExit), contextlib.redirect_stdout(io.StringIO()):\n"
        "    main()"
    )
    mods = loaded_after(code)
    assert (tmp_path / "o" / "ms_error_long.csv").is_file()
    assert "pandas" not in mods and "scipy.optimize" not in mods and "cvxpy" not in mods


@pytest.mark.parametrize("method", ["mc", "exact", "both"])
def test_the_tidy_csv_is_what_pandas_writes(method):
    from ntc_design.simulate import simulate
    from ntc_design.simulate.scenario import load_scenario, tidy_csv

    top, spec, _ = load_scenario(
        ROOT / "examples" / "scenarios" / "g1_fixed.yaml",
        {"paths": 30, "method": method, "T": 1.0},
    )
    res = simulate(top, spec)
    text = tidy_csv(res)
    assert text == res.to_pandas().to_csv(index=False)  # the independent writer
    assert text.count("\n") == 1 + res.save_times.size * len(res.labels)


# buffered streams (a user's shell does not set PYTHONUNBUFFERED) and no coverage tracer,
# under which the ordinary exit is taken: the quick exit itself is what runs
_PLAIN_ENV = {
    k: v
    for k, v in os.environ.items()
    if k != "PYTHONUNBUFFERED" and not k.startswith("COVERAGE_PROCESS")
}


def test_the_program_exits_with_its_code_and_every_line_written(tmp_path):
    # ntc's exit skips the interpreter's teardown: nothing printed may be lost, the code
    # must be main()'s, and exit handlers (here one that writes a file) still run
    probe = tmp_path / "probe.py"
    probe.write_text(
        "import atexit, pathlib, sys\n"
        f"atexit.register(lambda: pathlib.Path({str(tmp_path / 'ran')!r}).write_text('yes'))\n"
        "sys.argv = ['ntc', *sys.argv[1:]]\n"
        "from ntc_design.cli import run\nrun()\n"
    )
    ok = subprocess.run(
        [sys.executable, str(probe), "check", "examples/g1.yaml", "--json"],
        cwd=ROOT, capture_output=True, text=True, env=_PLAIN_ENV,
    )  # fmt: skip
    assert ok.returncode == 0
    assert json.loads(ok.stdout)["assumption_holds"] is True  # the whole text arrived
    assert (tmp_path / "ran").read_text() == "yes"
    bad = subprocess.run(
        [sys.executable, "-m", "ntc_design", "check", "examples/nope.yaml"],
        cwd=ROOT, capture_output=True, text=True,
    )  # fmt: skip
    assert bad.returncode == 2 and bad.stderr.startswith("error: ") and bad.stderr.count("\n") == 1


def test_the_ordinary_exit_is_kept_while_a_thread_lives():
    import threading

    from ntc_design.io.outputs import exit_process

    stop = threading.Event()
    t = threading.Thread(target=stop.wait)
    t.start()
    try:
        with pytest.raises(SystemExit) as exc:
            exit_process(3)
        assert exc.value.code == 3
    finally:
        stop.set()
        t.join()
    with pytest.raises(SystemExit) as exc:
        exit_process("a message")  # not a number: the interpreter's own handling
    assert exc.value.code == "a message"


def test_python_dash_m_runs_the_program(monkeypatch):
    import runpy

    from ntc_design import cli

    calls = []
    monkeypatch.setattr(cli, "run", lambda: calls.append("run"))
    runpy.run_module("ntc_design", run_name="__main__")
    assert calls == ["run"]  # python -m ntc_design is the ntc program, with its exit


@pytest.mark.parametrize("ignored", [False, True])
def test_the_program_notes_ctrl_c_and_keeps_an_ignored_one_ignored(ignored):
    # a background job starts with SIGINT ignored: ntc leaves it so, as Python does. The
    # child sets its starting state itself: pytest may run in a background job too
    code = (
        "import signal, sys\n"
        + ("signal.signal(signal.SIGINT, signal.SIG_IGN)\n" if ignored else "")
        + ("" if ignored else "signal.signal(signal.SIGINT, signal.default_int_handler)\n")
        + "from ntc_design import errors\n"
        + "from ntc_design.cli import program as cli\n"
        "cli.main = lambda: print(signal.getsignal(signal.SIGINT) is errors.note_interrupt,"
        " signal.getsignal(signal.SIGINT) is signal.SIG_IGN)\n"
        "cli.run()\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout.split()
    assert out == (["False", "True"] if ignored else ["True", "False"])


def test_output_lost_at_exit_is_a_failure_not_a_success():
    # the reader closes the pipe before the (buffered) JSON is written: the final flush
    # fails, and the exit code says so (1, as for a broken pipe during the command)
    proc = subprocess.Popen(
        [sys.executable, "-m", "ntc_design", "check", "examples/g1.yaml", "--json"],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=_PLAIN_ENV,
    )  # fmt: skip
    proc.stdout.close()
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 1, err
    assert b"Traceback" not in err


REFUSED = [
    (["certify", "nope.yaml", "--theta", "1,2,-1"], "nope.yaml: no such file"),
    (["certify", "examples/g1.yaml", "--theta", "1,2"], "--theta: expected 3 numbers"),
    (["certify", "examples/g1.yaml", "--theta", "1,2,-1", "--period", "0"], "--period:"),
    (["design", "examples/g1.yaml", "--theta", "1"], "--theta: expected 3 numbers"),
    (["robust", "examples/g1.yaml", "--theta", "1,2,3,4"], "--theta: expected 3 numbers"),
    (["check", "nope.yaml"], "nope.yaml: no such file"),
    (["verify", "nope.json"], "nope.json: no such file; expected a certificate"),
    (["simulate", "nope.yaml", "--out", "OUT"], "nope.yaml: no such file"),
    (["simulate", "examples/scenarios/g1_fixed.yaml", "--out", "OUT", "--period", "0"],
     "--period: must be a positive number"),
    (["tune", "examples/scenarios/g1_fixed.yaml", "--period", "0"], "--period: must be"),
    (["tune", "nope.yaml"], "nope.yaml: no such file"),
    (["export", "nope.yaml", "--out", "OUT"], "nope.yaml: no such file"),
    (["export", "examples/scenarios/g1_deadline.yaml", "--out", "OUT", "--delay", "-1"],
     "--delay: must be an integer >= 0"),
    (["report", "OUT", "--period", "0"], "--period: must be a positive number"),
    (["sweep", "nope.yaml", "--out", "OUT"], "nope.yaml: no such file"),
]  # fmt: skip


@pytest.mark.hostile
@pytest.mark.parametrize("k", range(len(REFUSED)), ids=[" ".join(a) for a, _ in REFUSED])
def test_trivially_bad_input_is_refused_before_the_heavy_imports(forked_cli, k):
    # a missing file, --period 0, a θ of the wrong length: refused in one line before the
    # library's layers (SciPy's sparse matrices, SymPy, Numba, the optimisers) are imported
    d, err, mods = forked_cli("refused", [argv for argv, _ in REFUSED])[k]
    needle = REFUSED[k][1]
    assert err.startswith("error: ") and needle in err and err.count("\n") == 1, err
    assert heavy_in(mods) == [] and "ntc_design.model.topology" not in mods
    assert not (d / "out").exists()
