"""Building and running the exported agents (C and Python) for the tests: the compiler
command the README gives, with warnings as errors, and a run on a given stdin."""

import hashlib
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from ntc_design.export.c import c_files
from ntc_design.export.python import python_files
from ntc_design.export.run import read_state, stdin_text
from ntc_design.protocol.digital import Digital

__all__ = [
    "CC",
    "CFLAGS",
    "arrivals_for",
    "build_c",
    "g1_d1_certified",
    "needs_cc",
    "normals_for",
    "read_state",
    "run_program",
    "stdin_text",
    "write_files",
    "write_python",
]

CC = shutil.which("cc")
needs_cc = pytest.mark.skipif(CC is None, reason="no C compiler 'cc' on this machine")
# exactly what the task asks of the build: C99, no FMA contraction, every warning (the
# pedantic and the conversion ones included) an error
CFLAGS = [
    "-std=c99",
    "-O2",
    "-ffp-contract=off",
    "-Wall",
    "-Wextra",
    "-Werror",
    "-pedantic",
    "-Wconversion",
]


def write_files(folder: Path, files: dict[str, str]) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        (folder / name).write_text(text, encoding="utf-8")
    return folder


_BUILT: dict[str, Path] = {}  # the sources' hash -> a program compiled from them


def build_c(folder: Path, law) -> Path:
    """Write and compile the C export of ``law``; the program's path. Sources already
    compiled in this process (byte for byte, the same command) are not compiled again: the
    program is copied (the parametrized tests build one law many times)."""
    files = c_files(law)
    write_files(folder, files)
    exe = folder / "ntc_replay"
    cmd = [CC, *CFLAGS, "-o", "ntc_replay", "ntc_replay.c", "ntc_protocol.c", "-lm"]
    key = hashlib.sha256(repr((cmd, sorted(files.items()))).encode()).hexdigest()
    if key in _BUILT and _BUILT[key].is_file():
        shutil.copy2(_BUILT[key], exe)
        return exe
    res = subprocess.run(cmd, cwd=folder, capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    _BUILT[key] = exe
    return exe


def write_python(folder: Path, law) -> list[str]:
    """Write the Python export of ``law``; the command that runs it."""
    write_files(folder, python_files(law))
    return [sys.executable, str(folder / "ntc_protocol.py")]


def arrivals_for(law, steps, seed=0):
    """Arrival flags (0 or 1), each edge's message arriving with probability 1 − p_e."""
    keep = np.concatenate([np.zeros(0)] + [law.modes[int(m)].keep for m in law.step_modes(steps)])
    return (np.random.default_rng(seed + 1000).random(keep.size) < keep).astype(np.int64)


def run_program(cmd, law, x_init, steps, normals, expect=0, arrivals=None, text=None):
    """Run an exported program on x(0), K and the normals (and the arrival flags on lossy
    links; ``text``: this stdin instead); x_K (or the completed process when the exit code
    is not 0)."""
    res = subprocess.run(
        cmd if isinstance(cmd, list) else [str(cmd)],
        input=text if text is not None else stdin_text(x_init, steps, normals, law, arrivals),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert res.returncode == expect, res.stderr
    if expect:
        return res
    return read_state(res.stdout, law.n * law.dim)


def normals_for(law, steps, seed=0, paths=None):
    """Independent standard normals from a seeded Generator, as many as K steps read."""
    count = int(law.normals_per_step(steps).sum())
    rng = np.random.default_rng(seed)
    return rng.standard_normal(count if paths is None else (paths, count))


def g1_d1_certified(monkeypatch, g1, g1_digital_d1):
    """Answer the export's certify call for examples/scenarios/g1_deadline.yaml at h = 0.1,
    D = 1 with the session's g1_digital_d1 = certify(G1, θ, "1/(1+t)", Digital(0.1, 1)) at
    the paper's noise (0.4, 0.3), after checking that the call is exactly that one (each
    argument as read from the file): its delay line's certificate (about 10 s) is issued
    once per worker, and tests/certify/kinds/test_digital.py proves it. Any other call
    fails the test."""
    from ntc_design.export import source

    def certify(top, theta, margin, gain, delta, **kw):
        assert top.labels == g1.labels and top.dim == g1.dim
        assert top.weights.keys() == g1.weights.keys()
        assert all(np.array_equal(top.weights[k], g1.weights[k]) for k in g1.weights)
        assert list(theta) == [1, 2, -1] and margin == 0.1 and delta is None
        assert gain == "1/(1+t)" and kw["digital"] == Digital(0.1, 1)
        assert (kw["noise_sigma"], kw["noise_f"], kw["sigma_edges"]) == (0.4, 0.3, {})
        return g1_digital_d1

    monkeypatch.setattr(source, "certify", certify)
