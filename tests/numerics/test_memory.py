"""Tests of :mod:`ntc_design.numerics.memory`."""

import math
import resource

import pytest

from ntc_design.errors import InputError
from ntc_design.numerics.memory import MEMORY_ENV, available_memory


@pytest.mark.parametrize(
    "text, size",
    [
        ("8G", 8 * 2**30),
        ("512M", 512 * 2**20),
        ("1.5G", 1.5 * 2**30),
        ("8589934592", 8589934592.0),
        (" 2 GiB ", 2 * 2**30),
        ("4kb", 4 * 2**10),
        ("1T", 2.0**40),
    ],
)
def test_the_pinned_size_is_read_with_binary_suffixes(monkeypatch, text, size):
    monkeypatch.setenv(MEMORY_ENV, text)
    assert available_memory() == size


@pytest.mark.hostile
@pytest.mark.parametrize("text", ["", "0", "-1G", "lots", "8X", "1e9", "nan", "8 G B"])
def test_a_pinned_value_that_is_not_a_size_is_one_line(monkeypatch, text):
    monkeypatch.setenv(MEMORY_ENV, text)
    with pytest.raises(InputError, match=rf"^{MEMORY_ENV}: expected a positive size") as exc:
        available_memory()
    assert "\n" not in str(exc.value)


def test_unpinned_it_is_memavailable_else_the_physical_memory(monkeypatch):
    import io

    from ntc_design.numerics import memory

    monkeypatch.delenv(MEMORY_ENV, raising=False)
    monkeypatch.setattr(memory, "address_space_left", lambda: math.inf)  # no ulimit -v
    meminfo = "MemTotal:       16000000 kB\nMemFree:  1000 kB\nMemAvailable:    5242880 kB\n"

    def fake_open(path, *a, **k):
        assert path == "/proc/meminfo"
        return io.StringIO(meminfo)

    monkeypatch.setattr(memory, "open", fake_open, raising=False)
    assert available_memory() == 5242880 * 1024.0  # kB, not the total
    meminfo = "MemTotal:       16000000 kB\n"  # an old kernel: no MemAvailable line
    monkeypatch.setattr(memory.os, "sysconf", {"SC_PAGE_SIZE": 4096, "SC_PHYS_PAGES": 1000}.get)
    assert available_memory() == 4096 * 1000.0

    def no_file(path, *a, **k):
        raise OSError("no /proc here")

    def no_sysconf(name):
        raise ValueError(name)

    monkeypatch.setattr(memory, "open", no_file, raising=False)
    monkeypatch.setattr(memory.os, "sysconf", no_sysconf)
    assert available_memory() == 4.0 * 2**30  # the documented last resort


def test_the_process_limit_caps_the_pinned_and_the_free_memory(monkeypatch):
    from ntc_design.numerics import memory

    monkeypatch.setattr(memory, "_address_space_used", lambda: 3.0 * 2**30)
    limit = [resource.RLIM_INFINITY]
    monkeypatch.setattr(resource, "getrlimit", lambda which: (limit[0], resource.RLIM_INFINITY))
    monkeypatch.setenv(MEMORY_ENV, "64G")
    assert memory.address_space_left() == math.inf and available_memory() == 64 * 2**30
    limit[0] = 7 * 2**30  # ulimit -v 7G with 3 GiB mapped: 4 GiB left, whatever is free
    assert memory.address_space_left() == 4 * 2**30 and available_memory() == 4 * 2**30
    monkeypatch.setenv(MEMORY_ENV, "1G")  # the smaller of the two
    assert available_memory() == 2**30
    limit[0] = 2 * 2**30  # already past the limit: nothing left, not a negative size
    assert memory.address_space_left() == 1.0 and available_memory() == 1.0
    monkeypatch.delenv(MEMORY_ENV)
    monkeypatch.setattr(
        memory, "open", lambda *a, **k: (_ for _ in ()).throw(OSError()), raising=False
    )
    monkeypatch.setattr(memory.os, "sysconf", {"SC_PAGE_SIZE": 4096, "SC_PHYS_PAGES": 2**30}.get)
    assert available_memory() == 1.0  # 4 TiB free, the process may map no more


def test_the_address_space_used_is_this_processs_vmsize():
    from ntc_design.numerics import memory

    with open("/proc/self/status", encoding="ascii") as fh:
        vm = next(int(ln.split()[1]) for ln in fh if ln.startswith("VmSize:"))
    assert memory._address_space_used() == pytest.approx(vm * 1024.0, rel=0.05)


def _limit_left(monkeypatch, left: float) -> None:
    """RLIMIT_AS set so that ``left`` bytes remain above what the process maps now."""
    from ntc_design.numerics import memory

    soft = int(memory._address_space_used() + left)
    monkeypatch.setattr(resource, "getrlimit", lambda which: (soft, resource.RLIM_INFINITY))


@pytest.mark.hostile
def test_a_delay_whose_moments_pass_the_process_limit_is_refused(monkeypatch, tmp_path, capsys):
    # --delay 600 on G1: ((D+1)·Nd)² numbers, 4.7 GiB, with 64 GiB free but a 4 GiB ulimit
    from ntc_design.simulate.digital import check_digital_moments
    from tests.cli_helpers import assert_input_error
    from tests.conftest import EXAMPLES

    monkeypatch.setenv(MEMORY_ENV, "64G")
    check_digital_moments(21, 600, 100)  # the machine's memory holds it
    _limit_left(monkeypatch, 4 * 2**30)
    with pytest.raises(InputError, match=r"^digital.delay: .* about 4.7 GiB, more than 2.0 GiB"):
        check_digital_moments(21, 600, 100)
    out = tmp_path / "run"
    sc = EXAMPLES / "scenarios" / "g1_fixed.yaml"
    args = ["simulate", sc, "--out", out, "--period", "0.1", "--delay", "600", "--method", "exact"]
    assert_input_error(args, capsys, monkeypatch, "--delay", "4.7 GiB")
    assert not out.exists()
