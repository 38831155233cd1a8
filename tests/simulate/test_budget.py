"""Tests of :mod:`ntc_design.simulate.budget`."""

import numpy as np
import pytest

import ntc_design as nd
from ntc_design.errors import InputError
from ntc_design.model.paper import THETA
from ntc_design.simulate import simulate
from ntc_design.simulate.budget import MAX_PATH_STEPS, check_budget, estimate
from tests.conftest import ROOT


@pytest.mark.parametrize(
    "topology, gain, t_end, every",
    [
        ("g1.yaml", "1/(1+t)", 100.0, 1.0),
        ("g1.yaml", "2/(1+t)^0.5", 10.0, 1.0),
        ("g1.yaml", "1", 20.0, 0.5),
        ("switching.yaml", "1/(1+t)", 10.0, 0.1),  # the largest ρ of the modes, and switches
    ],
)
def test_exact_step_estimate_matches_the_run(monkeypatch, topology, gain, t_end, every):
    """The estimate that refuses long exact runs counts the RK4 steps the run takes (within
    a factor of 2, never below by more than 10 %)."""
    import ntc_design.simulate.driver as drv

    seen = []
    orig = drv.estimate_exact_steps
    monkeypatch.setattr(drv, "estimate_exact_steps", lambda *a: seen.append(orig(*a)) or seen[-1])
    top = nd.load(ROOT / "examples" / topology)
    res = simulate(top, THETA, T=t_end, gain=gain, method="exact", save_every=every)
    steps = res.stats.exact_rk4_steps
    assert len(seen) == 1 and 0.9 * steps <= seen[0] <= 2 * steps, (seen, steps)


def test_budget_refuses_before_allocating():
    kw = dict(
        n=7,
        d=3,
        edges=12,
        modes=1,
        segments=1,
        steps=1e4,
        paths=1000,
        block_size=500,
        workers=2,
        mc=True,
        exact=True,
    )
    small = estimate(saves=101, store_paths=10, **kw)
    check_budget(small, available=2**30)
    assert small.total < 50 * 2**20  # the paper's run needs tens of MB, not GB
    big = estimate(saves=1e9, store_paths=10, **kw)
    with pytest.raises(InputError, match=r"^save_every: the run would need about .* GiB"):
        check_budget(big, available=2**30)
    stored = estimate(saves=1e5, store_paths=10**6, **{**kw, "paths": 10**6})
    with pytest.raises(InputError, match=r"^store_paths: .*stored paths"):
        check_budget(stored, available=2**30)
    work = estimate(saves=10, store_paths=1, **{**kw, "paths": 10**12})
    assert work.path_steps > MAX_PATH_STEPS
    with pytest.raises(InputError, match=r"^paths: .* path-steps"):
        check_budget(work, available=2**40)
    # memory grows linearly with the save count (statistics and tables)
    s2 = estimate(saves=2e6, store_paths=10, **kw).total
    s1 = estimate(saves=1e6, store_paths=10, **kw).total
    assert 1.8 < s2 / s1 < 2.1


@pytest.mark.hostile
@pytest.mark.parametrize(
    "over, needle",
    [
        ({"save_every": 1e-12, "T": 10.0}, "save_every"),
        ({"dt": 1e-13}, "dt"),
        ({"T": 1e300, "method": "exact"}, "dt"),
        ({"paths": 10**15}, "paths"),
        ({"store_paths": 10**9, "paths": 10**9, "T": 10.0, "dt": 0.01}, "store_paths"),
        ({"stepping": "intrinsic", "ds": 1e-300}, "dt"),
    ],
)
def test_huge_requests_refused_by_field(g1, over, needle):
    with pytest.raises(InputError) as exc:
        simulate(g1, THETA, **{"T": 1.0, "paths": 10, **over})
    assert str(exc.value).startswith(needle + ":"), str(exc.value)


@pytest.mark.hostile
def test_large_topology_refused_before_the_design(monkeypatch):
    monkeypatch.setattr("ntc_design.simulate.budget.available_memory", lambda: 2.0**30)
    top = nd.Topology.from_edges(20000, 1, [(1, 2, np.eye(1))])
    with pytest.raises(InputError, match=r"^method: .* GiB .*use method: mc"):
        simulate(top, [1.0], T=1.0, paths=10)
    with pytest.raises(InputError, match=r"^topology: .* GiB .*too large"):
        simulate(top, [1.0], T=1.0, paths=10, method="mc")
