"""The package as a user without a checkout gets it: the wheel built from this tree,
installed in a fresh virtual environment and run from a folder outside the checkout.

Every other test runs from the checkout (an editable install), where the examples are the
checkout's ``examples/``; a plain ``pip install .`` once could not find them. The
dependencies are borrowed from the environment running the tests (a ``.pth`` file names
its site-packages), so the check needs no network and no mirror: what is under test is
the package as the wheel lays it out. ``.ci/run`` does the same with every dependency
installed into the fresh environment by pip.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
pytestmark = pytest.mark.slow

# what a wheel is built from (a copy: a build in the checkout would leave build/ there,
# whose stale files a later build would ship)
_SOURCES = ("pyproject.toml", "README.md", "ntc_design", "examples")


def _run(args, cwd, env=None, timeout=600):
    env = {k: v for k, v in (env or os.environ).items() if k != "PYTHONPATH"}
    return subprocess.run(
        [str(a) for a in args],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=timeout,
        check=False,
    )


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """(the fresh environment's python, its bin folder, a folder outside the checkout)."""
    tmp = tmp_path_factory.mktemp("wheel")
    src = tmp / "src"
    src.mkdir()
    for name in _SOURCES:
        p = ROOT / name
        if p.is_dir():
            shutil.copytree(p, src / name, ignore=shutil.ignore_patterns("__pycache__", "figures"))
        else:
            shutil.copy(p, src / name)
    built = _run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", tmp / "dist", src], tmp
    )
    wheels = sorted((tmp / "dist").glob("ntc_design-*.whl"))
    if built.returncode != 0 or not wheels:
        pytest.skip(
            f"cannot build the wheel here (no build backend offline?): {built.stderr[-300:]}"
        )
    venv = tmp / "venv"
    made = _run([sys.executable, "-m", "venv", venv], tmp)
    if made.returncode != 0:
        pytest.skip(f"cannot create a virtual environment here: {made.stderr[-300:]}")
    bindir = venv / ("Scripts" if os.name == "nt" else "bin")
    python = bindir / ("python.exe" if os.name == "nt" else "python")
    purelib = _run(
        [python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"], tmp
    ).stdout.strip()
    ours = {sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]}
    # the dependencies: this environment's packages, after the fresh one's own
    (Path(purelib) / "borrowed_dependencies.pth").write_text("\n".join(sorted(ours)) + "\n")
    got = _run([python, "-m", "pip", "install", "--no-deps", "-q", wheels[0]], tmp)
    assert got.returncode == 0, got.stderr
    away = tmp / "elsewhere"
    away.mkdir()
    return python, bindir, away


def test_the_wheel_finds_its_examples_outside_the_checkout(installed):
    python, _, away = installed
    code = (
        "import ntc_design as nd, ntc_design.model.paper as p; "
        "print(nd.__file__); print(nd.example_path('g1.yaml')); "
        "print(nd.load(nd.example_path('g1.yaml')).n); "
        "print(len(p.example_files()))"
    )
    got = _run([python, "-c", code], away)
    assert got.returncode == 0, got.stderr
    module, g1, n, count = got.stdout.split("\n")[:4]
    venv = python.parent.parent
    # the installed package, not the checkout's, and its own copy of the examples
    assert Path(module).is_relative_to(venv) and Path(g1).is_relative_to(venv)
    assert Path(g1).read_bytes() == (ROOT / "examples" / "g1.yaml").read_bytes()
    assert int(n) == 7
    from ntc_design.model.paper import example_files

    assert int(count) == len(example_files()) == 15


def test_the_readme_first_command_and_examples_copy_from_the_wheel(installed):
    python, bindir, away = installed
    g1 = _run([python, "-c", "import ntc_design as nd; print(nd.example_path('g1.yaml'))"], away)
    env = {**os.environ, "MPLBACKEND": "Agg"}  # no display
    ntc = bindir / "ntc"
    got = _run(
        [ntc, "certify", g1.stdout.strip(), "--theta", "1,2,-1", "--gain", "1/(1+t)"], away, env
    )
    assert got.returncode == 0, got.stderr
    assert "Theorem 1 (mean square): guaranteed" in got.stdout
    got = _run([ntc, "examples", "--copy", "mine"], away, env)
    assert got.returncode == 0, got.stderr
    assert (away / "mine" / "g1.yaml").read_bytes() == (ROOT / "examples" / "g1.yaml").read_bytes()
    assert (away / "mine" / "scenarios" / "g1_fixed.yaml").is_file()
    # the copy is a user's: the README's commands run on it as in a checkout
    got = _run([ntc, "check", "mine/g1.yaml"], away, env)
    assert got.returncode == 0, got.stderr


@pytest.mark.parametrize("script", ["plot_02_switching.py", "plot_09_verify.py"])
def test_gallery_examples_run_from_the_wheel(installed, script):
    # every gallery script is run so by .ci/run; two here (a few seconds each)
    python, _, away = installed
    env = {**os.environ, "MPLBACKEND": "Agg"}
    got = _run([python, ROOT / "docs" / "gallery" / script], away, env)
    assert got.returncode == 0, got.stderr[-2000:]
