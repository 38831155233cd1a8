"""Tests of :mod:`ntc_design.numerics.memory`."""

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
