"""Tests of :mod:`ntc_design.certify.scale`."""

import json
import warnings

import numpy as np
import pytest
import scipy.sparse as sp

import ntc_design as nd
from ntc_design.certify import certify, verify
from ntc_design.certify.scale import component_matrix, lap_b_blocks, symmetric_part_bound
from ntc_design.errors import InputError
from ntc_design.model import Topology
from ntc_design.model.generate import random_network, write_topology
from ntc_design.numerics.linalg import DenseRefused, SPDFamily
from tests.cli_helpers import run_cli
from tests.support.scale import _methods
from tests.support.switching_scale import THETA_SW

# ----------------------------------------------------------- scalable certificates


def _two_agent_cycle(delta):
    """Two agents hearing each other through ND, strongly anisotropic weights: the
    comparison matrix is an M-matrix only for δ > 99, L_B + L_Bᵀ ≻ 0 only for δ > ~4.05,
    yet −L_B is Hurwitz for every δ > 0 (each coordinate is a 2×2 block with positive
    trace and determinant)."""
    top = Topology.from_edges(
        2, 2, [(2, 1, -np.diag([1.0, 0.01])), (1, 2, -np.diag([0.01, 1.0]))], name="cycle"
    )
    return nd.design(top, [1.0, 2.0], delta=delta, thresholds=False)


def test_dominance_fails_and_the_fallbacks_decide():
    from ntc_design.certify import scale_certificate

    low = scale_certificate(_two_agent_cycle(1.0))  # neither dominance nor symmetric part
    assert _methods(low) == {"dominance": 0, "symmetric": 0, "lyapunov": 1, "none": 0}
    assert verify(low).valid
    mid = scale_certificate(_two_agent_cycle(10.0))  # symmetric part ≻ 0, no dominance
    assert _methods(mid)["symmetric"] == 1 and _methods(mid)["dominance"] == 0
    assert verify(mid).valid
    high = scale_certificate(_two_agent_cycle(120.0))  # dominance
    assert _methods(high)["dominance"] == 1
    assert verify(high).valid


def test_certify_cli_at_scale_and_the_lmi_guard(tmp_path, capsys, monkeypatch):
    from ntc_design.certify import hurwitz_certificate

    p = tmp_path / "n200.npz"
    write_topology(random_network(200, 2, seed=3), p)  # the N = 200, d = 2 abort
    cert = tmp_path / "c.json"
    code, out, _ = run_cli(["certify", p, "--theta", "1,2", "--out", cert], capsys, monkeypatch)
    assert code == 0 and "skipped: decay-rate LMI" in out.replace("\n", " ")
    code, out, _ = run_cli(["verify", cert], capsys, monkeypatch)
    assert code == 0 and "VALID" in out
    des = nd.design(nd.load(p), [1.0, 2.0], thresholds=False)
    with pytest.raises(DenseRefused, match="decay-rate LMI: a dense 400×400 P needs about"):
        hurwitz_certificate(des, rate_method="lmi")  # the default needs no SDP: no guard


def test_symmetric_part_bound_just_above_and_below_definiteness():
    """prove_symmetric_part on L = diag-shifted matrices around λ_min(L + Lᵀ) = 0."""
    import scipy.sparse as sp

    from ntc_design.certify.scale import prove_symmetric_part

    rng = np.random.default_rng(11)
    n = 60
    g = sp.random(n, n, density=0.1, random_state=rng).toarray()
    s = g + g.T
    lam = np.linalg.eigvalsh(s)[0]
    for rel, expect in ((1e-6, True), (-1e-6, False)):
        shift = -lam / 2 + rel * abs(lam)
        lap = sp.csr_matrix(g + shift * np.eye(n))
        ok, _ = prove_symmetric_part(lap, sp.csr_matrix((n, n)))
        assert ok is expect
    # an error bound larger than the margin refuses the proof
    lap = sp.csr_matrix(g + (-lam / 2 + 1e-6 * abs(lam)) * np.eye(n))
    ok, _ = prove_symmetric_part(lap, sp.csr_matrix(np.full((n, n), 1e-3)))
    assert not ok


@pytest.mark.hostile
def test_unreached_agents_are_refused_in_bulk_not_one_by_one(tmp_path, capsys, monkeypatch):
    """20,000 agents, one edge: every other agent is a one-agent block L_ii = 0. No
    fallback can prove such a block, so none is tried (the work stays linear in N: it
    took a sparse factorisation and a pass over all agents per agent before), and the
    verdict names the first violations only."""

    import yaml

    from ntc_design.certify import scale as scale_mod
    from tests.cli_helpers import run_cli

    calls = []
    real = scale_mod.prove_symmetric_part
    monkeypatch.setattr(scale_mod, "prove_symmetric_part", lambda *a: calls.append(1) or real(*a))
    f = tmp_path / "one_edge.yaml"
    f.write_text(
        yaml.safe_dump(
            {"dim": 1, "agents": 20000, "edges": [{"from": 1, "to": 2, "weight": [[-1.0]]}]}
        )
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        code, out, err = run_cli(["certify", f, "--theta", "1", "--json"], capsys, monkeypatch)
    assert code == 1 and calls == []
    doc = json.loads(out)
    res = doc["certificate"]["results"]
    assert res["methods"]["none"] == 19999 and res["methods"]["dominance"] == 1
    assert any("19999 one-agent component(s)" in s for s in res["skipped"])
    (a2,) = [p for p in doc["theorems"][0]["premises"] if p["premise"].startswith("Assumption 2")]
    detail = a2["detail"]
    assert "… (19999 in all)" in detail and len(detail) < 2000
    # each violation once, the first few, under the verdicts (not in each verdict)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        notes = certify(nd.load(f), [1.0]).theorems_table().notes
    assert len(notes) < 20 and sum(len(n) for n in notes) < 4000
    assert any("and 19989 more" in n for n in notes) and any("(19998 in all)" in n for n in notes)
    assert a2["holds"] is False and a2["replaced_by"] is None


def test_rate_estimate_skips_a_component_that_fills_in(monkeypatch):
    import ntc_design.certify.scale as sc

    top = random_network(700, 3, seed=1, extra=2.0)
    res = certify(top, THETA_SW)
    assert res.certificate["kind"] == "hurwitz-scale" and res.verification.valid
    big = res.certificate["results"]["largest_component_agents"]
    assert big * 3 > sc.RATE_DENSE_MAX_ND  # the big component goes to ARPACK ...
    assert "ARPACK" in res.certificate["results"]["rate_estimate"]["method"]
    monkeypatch.setattr(sc, "RATE_ARPACK_MAX_FLOPS", 1.0)  # ... unless it fills in
    res2 = certify(top, THETA_SW)
    assert res2.verification.valid
    assert "filling in too much" in res2.certificate["results"]["rate_estimate"]["method"]


def test_overflow_or_nan_never_proves_anything():
    """Review findings: an overflowing shift made CHOLMOD take NaN pivots as positive."""
    fam = SPDFamily([sp.csr_matrix(np.array([[np.nan, 1, 1], [1, 1, 1], [1, 1, -1.0]]))])
    assert fam.factor([1.0], 0.0) == (False, 0)
    # antagonistic −[[1,1],[1,1]] both ways and δ = 1e308: L_B x = 0 for x = (1,−1,1,−1)
    w = -np.ones((2, 2, 2))
    top = Topology.from_arrays(["a", "b"], 2, np.array([0, 1]), np.array([1, 0]), w)
    lap, err = component_matrix(lap_b_blocks(top, 1e308), np.arange(2))
    p = symmetric_part_bound(lap, err)
    assert not p.holds and "overflows" in p.detail
    # cooperative 1e308 and 1.7e308: the model refuses such weights; the bound itself
    # still proves nothing from entries whose sums overflow
    w2 = np.array([[[1e308]], [[1.7e308]]])
    with pytest.raises(InputError, match="outside"):
        Topology.from_arrays(["a", "b"], 1, np.array([0, 1]), np.array([1, 0]), w2)
    lap2 = sp.csr_matrix(np.array([[1e308, -1e308], [-1.7e308, 1.7e308]]))
    err2 = sp.csr_matrix(np.zeros((2, 2)))
    assert not symmetric_part_bound(lap2, err2, 2.0**250).holds


def test_the_block_memory_guard(monkeypatch):
    import ntc_design.certify.scale as sc

    top = random_network(50, 3, seed=1)
    monkeypatch.setattr(sc, "DENSE_MAX_BYTES", 4 * 8.0 * 50 * 9 - 1)
    with pytest.raises(InputError, match="diagonal blocks: N = 50 agents of d = 3"):
        lap_b_blocks(top, 1.0)
