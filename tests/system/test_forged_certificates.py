"""Forged certificates: every edit is made with the digests recomputed (anyone can), so
only the mathematics can reject it. verify derives what must be proven from the kind and
the subject; a forgery is rejected with exit 1 (or 2 when it is not a well-formed
certificate at all), and an accepted edit must still be a true statement."""

import copy
import json

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import ntc_design as nd
from ntc_design.certify import hurwitz_certificate, switching_certificate, verify
from ntc_design.certify.claims import Property, derive_claims
from ntc_design.certify.format import digest, document_hash
from ntc_design.errors import InputError
from ntc_design.io import files
from ntc_design.rigorous.exact import exact_affordable
from tests.cli_helpers import run_cli
from tests.conftest import ROOT

CERTS = ROOT / "certificates"
G1 = json.loads((CERTS / "g1.json").read_text())
SW = json.loads((CERTS / "switching.json").read_text())

hostile = pytest.mark.hostile


def redigest(doc):
    """What a forger does after editing: recompute both checksums."""
    if isinstance(doc.get("subject"), dict):
        doc["subject_digest"] = document_hash(doc["subject"])
    doc["digest"] = digest(doc)
    return doc


def rederive_claims(doc):
    """A careful forger also lists exactly the claims the edited certificate needs."""
    props = [Property(p) for p in doc["certifies"]]
    sched = doc["subject"].get("schedule")
    modes = (
        list(dict.fromkeys(s["mode"] for s in sched)) if sched else list(doc["subject"]["modes"])
    )
    alpha = doc["results"].get("lmi", {}).get("alpha", 0.0)
    doc["claims"] = [c.to_dict() for c in derive_claims(props, modes, alpha)]
    return doc


def cli(doc, tmp_path, capsys, monkeypatch, *extra):
    p = tmp_path / "forged.json"
    p.write_text(doc if isinstance(doc, str) else json.dumps(doc))
    code, out, err = run_cli(["verify", p, *extra], capsys, monkeypatch)
    assert "Traceback" not in err
    return code, out, err


def expect_invalid(doc, tmp_path, capsys, monkeypatch, *needles, extra=()):
    code, out, err = cli(doc, tmp_path, capsys, monkeypatch, *extra)
    assert code == 1, (code, out, err)
    line = err.strip().splitlines()[-1]
    assert line.startswith("INVALID"), err
    for n in needles:
        assert n in line, (n, line)
    return line


# ------------------------------------------------------------------ the forgeries


@hostile
def test_all_claims_deleted(tmp_path, capsys, monkeypatch):
    doc = copy.deepcopy(G1)
    doc["claims"] = []
    expect_invalid(redigest(doc), tmp_path, capsys, monkeypatch, "listed claims")


@hostile
def test_only_p_positive_definite_left(tmp_path, capsys, monkeypatch):
    doc = copy.deepcopy(G1)
    doc["claims"] = [c for c in doc["claims"] if c["id"] == "P_lyapunov ≻ 0"]
    doc["certifies"] = ["hurwitz"]
    assert len(doc["claims"]) == 1
    expect_invalid(redigest(doc), tmp_path, capsys, monkeypatch, "listed claims")


@hostile
def test_switching_mode_removed_but_still_scheduled(tmp_path, capsys, monkeypatch):
    doc = copy.deepcopy(SW)
    for part in (doc["subject"]["modes"], doc["matrices"]["L_B"]):
        del part["G3"]
    doc["claims"] = [c for c in doc["claims"] if c.get("mode") != "G3"]
    expect_invalid(redigest(doc), tmp_path, capsys, monkeypatch, "every scheduled mode")


@hostile
def test_switching_mode_removed_everywhere_is_not_the_users_system(
    tmp_path, capsys, monkeypatch, examples
):
    """Removed from modes, schedule, claims and hashes alike, the certificate is a true
    statement about another switching set: --topology shows it is not the user's."""
    doc = copy.deepcopy(SW)
    del doc["subject"]["modes"]["G3"], doc["matrices"]["L_B"]["G3"]
    doc["subject"]["schedule"] = [s for s in doc["subject"]["schedule"] if s["mode"] != "G3"]
    del doc["results"]["symmetric_part_min_eig"]["G3"]
    doc["results"]["common_lyapunov"]["margin"] = None
    sub = doc["subject"]
    from ntc_design.certify.format import switching_hash

    sub["switching_hash"] = switching_hash(
        {k: m["topology_hash"] for k, m in sub["modes"].items()},
        [(s["mode"], s["duration"]) for s in sub["schedule"]],
    )
    rederive_claims(doc)
    redigest(doc)
    code, out, _ = cli(doc, tmp_path, capsys, monkeypatch)
    assert code == 0 and "G3" not in out.split("certifies:")[0]  # it says what it is about
    expect_invalid(
        doc,
        tmp_path,
        capsys,
        monkeypatch,
        "about the given topology",
        extra=("--topology", examples / "switching.yaml"),
    )


@hostile
@pytest.mark.parametrize(
    "edit, needle",
    [
        (lambda s: s[0].update(mode="G9"), "every scheduled mode"),
        (lambda s: s[1].update(duration=5.0), "switching hash"),
        (lambda s: s.append({"mode": "G1", "duration": 0.5}), "switching hash"),
        (lambda s: s.pop(), "switching hash"),
        (lambda s: s.reverse(), "switching hash"),
    ],
)
def test_switching_schedule_changed(tmp_path, capsys, monkeypatch, edit, needle):
    doc = copy.deepcopy(SW)
    edit(doc["subject"]["schedule"])
    expect_invalid(redigest(doc), tmp_path, capsys, monkeypatch, needle)


@hostile
def test_schedule_changed_consistently_is_caught_by_topology(
    tmp_path, capsys, monkeypatch, examples
):
    doc = copy.deepcopy(SW)
    doc["subject"]["schedule"][1]["duration"] = 7.0
    sub = doc["subject"]
    from ntc_design.certify.format import switching_hash

    sub["switching_hash"] = switching_hash(
        {k: m["topology_hash"] for k, m in sub["modes"].items()},
        [(s["mode"], s["duration"]) for s in sub["schedule"]],
    )
    redigest(doc)
    expect_invalid(
        doc,
        tmp_path,
        capsys,
        monkeypatch,
        "about the given topology",
        extra=("--topology", examples / "switching.yaml"),
    )


@hostile
@pytest.mark.parametrize("cert", ["g1", "switching"])
def test_theta_changed(tmp_path, capsys, monkeypatch, cert):
    doc = copy.deepcopy(G1 if cert == "g1" else SW)
    for m in doc["subject"]["modes"].values():
        m["theta"] = [1.0, 2.0, 1.0]
    expect_invalid(redigest(doc), tmp_path, capsys, monkeypatch, "x0 = k1·θ")


@hostile
def test_theta_and_x0_changed_consistently_is_caught_by_theta(tmp_path, capsys, monkeypatch):
    doc = copy.deepcopy(G1)
    (m,) = doc["subject"]["modes"].values()
    m["theta"] = [5.0, 2.0, -1.0]
    m["x0"] = (m["k1"] * np.array(m["theta"])).tolist()
    redigest(doc)
    assert verify(doc).valid  # a true statement, about another θ
    expect_invalid(
        doc, tmp_path, capsys, monkeypatch, "θ is the one given", extra=("--theta", "1,2,-1")
    )


@hostile
@pytest.mark.parametrize("version", [0, 1, 3, 999, -1, 2**62])
def test_unknown_format_version_is_invalid(tmp_path, capsys, monkeypatch, version):
    """Documented choice: a well-formed certificate of a version this ntc does not know
    proves nothing here: exit 1 (not 2)."""
    doc = copy.deepcopy(G1)
    doc["version"] = version
    expect_invalid(redigest(doc), tmp_path, capsys, monkeypatch, "format version")


@hostile
@pytest.mark.parametrize("version", ["2", 2.0, None, True, [2]])
def test_version_of_the_wrong_type_is_malformed(tmp_path, capsys, monkeypatch, version):
    doc = copy.deepcopy(G1)
    doc["version"] = version
    code, out, err = cli(redigest(doc), tmp_path, capsys, monkeypatch)
    assert code == 2 and len(err.strip().splitlines()) == 1 and "version" in err


def _non_hurwitz_certificate():
    """Agent 3 has no edges: L_B has a zero block row, −L_B is not Hurwitz."""
    top = nd.Topology.from_edges(3, 1, [(1, 2, [[-1.0]]), (2, 1, [[1.0]])], name="iso")
    return hurwitz_certificate(nd.design(top, [1.0]), rate=False)


@hostile
def test_non_hurwitz_with_identity_p_and_negative_alpha(tmp_path, capsys, monkeypatch):
    doc = _non_hurwitz_certificate()
    assert not verify(doc).valid
    eye = np.eye(3).tolist()
    doc["matrices"]["P"] = {"lyapunov": eye, "rate": eye}
    doc["certifies"] = ["hurwitz", "decay_rate"]
    doc["results"]["lmi"] = {"alpha": -10.0, "eig_bound": 0.0, "gap": 10.0}
    rederive_claims(doc)
    redigest(doc)
    line = expect_invalid(doc, tmp_path, capsys, monkeypatch, "α > 0", "P_lyapunov·L_B(iso)")
    assert "P_rate·L_B(iso)" not in line  # P L + Lᵀ P + 20 P ≻ 0 holds but proves nothing


def _count_exact_pd(monkeypatch) -> list:
    """Record (order, bits) of every exact-rational positive-definiteness test."""
    import ntc_design.certify.dense as dense

    calls: list = []
    real = dense.exact_pd

    def spy(m, *a, **kw):
        calls.append((m.num.shape[0], m.bits))
        return real(m, *a, **kw)

    monkeypatch.setattr(dense, "exact_pd", spy)
    return calls


@hostile
@pytest.mark.parametrize("tiny, huge", [(1e-300, 1e300), (1e-100, 1e100), (5e-324, 1.7e308)])
def test_p_with_extreme_dynamic_range_is_rejected_quickly(
    tmp_path, capsys, monkeypatch, tiny, huge
):
    doc = copy.deepcopy(G1)
    p = np.array(doc["matrices"]["P"]["lyapunov"])
    p[0, 1] = p[1, 0] = tiny
    p[2, 2] = huge
    doc["matrices"]["P"]["lyapunov"] = p.tolist()
    calls = _count_exact_pd(monkeypatch)
    expect_invalid(redigest(doc), tmp_path, capsys, monkeypatch, "P_lyapunov ≻ 0")
    # P_lyapunov is refused from its range alone; what is tested exactly stays in budget
    assert all(exact_affordable(n, bits) for n, bits in calls)


@hostile
@pytest.mark.parametrize("tiny, huge", [(2.0**-240, 2.0**240), (2.0**-100, 1.0)])
def test_wide_but_bounded_range_is_decided_quickly(tiny, huge, monkeypatch):
    """Within the range the entries are long, but the proof is bounded: exact while
    n·bits is within budget, else the verified-float test; either way fast and right."""
    doc = copy.deepcopy(G1)
    p = np.array(doc["matrices"]["P"]["lyapunov"])
    p[0, 1] = p[1, 0] = tiny
    p[2, 2] += huge
    doc["matrices"]["P"]["lyapunov"] = p.tolist()
    calls = _count_exact_pd(monkeypatch)
    ver = verify(redigest(doc))
    # the work stays bounded: exact rationals only within the size-by-bits budget
    assert calls and all(exact_affordable(n, bits) for n, bits in calls)
    pd = [c for c in ver.checks if c.name == "P_lyapunov ≻ 0"][0]
    assert pd.ok  # still positive definite: a true claim stays proven


# ----------------------------------------------------------- forgeries over the fields


def _set(doc, path, value):
    node = doc
    for k in path[:-1]:
        node = node[k]
    if value is DELETE:
        del node[path[-1]]
    else:
        node[path[-1]] = value(node[path[-1]]) if callable(value) else value


DELETE = object()
ONE_G1 = ("subject", "modes", "G1")

FIELD_FORGERIES = [
    # claims
    *[("g1", ("claims", k), DELETE, "listed claims") for k in range(5)],
    *[("sw", ("claims", k), DELETE, "listed claims") for k in range(7)],
    ("g1", ("claims", 4, "alpha"), 0.9, "listed claims"),
    ("g1", ("claims", 1, "mode"), "G2", "listed claims"),
    ("g1", ("claims", 0, "P"), "rate", "listed claims"),
    ("g1", ("claims", 0, "kind"), "symmetric_part", "listed claims"),
    ("g1", ("claims", 1, "property"), "decay_rate", "listed claims"),
    ("sw", ("claims", 0, "mode"), "G9", "listed claims"),
    # what the kind certifies
    ("g1", ("certifies",), [], "certifies"),
    ("g1", ("certifies",), ["decay_rate"], "certifies"),
    ("g1", ("certifies",), ["hurwitz"], "listed claims"),
    ("g1", ("certifies",), ["hurwitz", "hurwitz", "decay_rate"], "certifies"),
    ("g1", ("certifies",), ["hurwitz", "decay_rate", "symmetric_part"], "certifies"),
    ("g1", ("certifies",), ["stable"], "certifies"),
    ("sw", ("certifies",), [], "certifies"),
    ("sw", ("certifies",), ["hurwitz"], "certifies"),
    # unknown kinds
    ("g1", ("kind",), "Hurwitz", "certificate kind"),
    ("g1", ("kind",), "sos", "certificate kind"),
    ("g1", ("kind",), "", "certificate kind"),
    ("sw", ("kind",), "switching-arbitrary", "certificate kind"),
    # the matrices P
    ("g1", ("matrices", "P", "lyapunov"), lambda p: (-np.array(p)).tolist(), "P_lyapunov ≻ 0"),
    ("g1", ("matrices", "P", "lyapunov"), np.zeros((21, 21)).tolist(), "P_lyapunov ≻ 0"),
    # P = I is a true Lyapunov matrix for G1 (L_B + L_Bᵀ ≻ 0): only the reported residual lies
    ("g1", ("matrices", "P", "lyapunov"), np.eye(21).tolist(), "lyapunov.residual"),
    ("g1", ("matrices", "P", "rate"), np.eye(21).tolist(), "P_rate·L_B(G1)"),
    ("g1", ("matrices", "P", "rate"), lambda p: (np.array(p) * -1).tolist(), "P_rate ≻ 0"),
    ("g1", ("matrices", "P", "lyapunov", 0), lambda r: [x * 1e300 for x in r], "P_lyapunov"),
    ("sw", ("matrices", "P", "common"), (-np.eye(21)).tolist(), "P_common ≻ 0"),
    (
        "sw",
        ("matrices", "P", "common"),
        np.diag([1e-3] * 3 + [1e3] * 18).tolist(),
        "P_common·L_B",
    ),
    # the subject
    ("g1", (*ONE_G1, "theta"), [1.0, 2.0, 1.0], "x0 = k1·θ"),
    ("g1", (*ONE_G1, "x0"), lambda x: [v * 2 for v in x], "x0 = k1·θ"),
    ("g1", (*ONE_G1, "k1"), lambda k: k * (1 + 2**-52), "x0 = k1·θ"),
    ("g1", (*ONE_G1, "theta"), [0.0, 0.0, 0.0], "θ ≠ 0"),
    ("g1", (*ONE_G1, "delta"), lambda d: d * 1.01, "matches its topology"),
    ("g1", (*ONE_G1, "delta"), 0.01, "matches its topology"),
    ("g1", (*ONE_G1, "informed"), lambda a: a[:-1], "informed agents are U"),
    ("g1", (*ONE_G1, "informed"), lambda a: [*a, 1], "informed agents are U"),
    ("g1", (*ONE_G1, "B", "2", 0, 0), lambda x: x * 1.5, "B_i"),
    ("g1", (*ONE_G1, "topology", "edges", 0, "weight", 2, 2), 3.0, "topology hash"),
    ("g1", (*ONE_G1, "topology", "agents"), [1, 2, 3, 4, 5, 7, 6], "topology hash"),
    ("g1", (*ONE_G1, "topology_hash"), "sha256:" + "0" * 64, "topology hash"),
    ("g1", ("matrices", "L_B", "G1", 0, 0), lambda x: x + 1e-6, "matches its topology"),
    ("sw", ("subject", "modes", "G2", "theta"), [1.0, 2.0, -2.0], "x0 = k1·θ"),
    ("sw", ("subject", "modes", "G3", "delta"), 0.5, "matches its topology"),
    ("sw", ("subject", "switching_hash"), "sha256:" + "1" * 64, "switching hash"),
    ("sw", ("subject", "schedule", 0, "mode"), "G1", "switching hash"),
    # reported results
    ("g1", ("results", "eig_bound"), lambda x: x * 1.1, "eig_bound: reported"),
    ("g1", ("results", "lmi", "eig_bound"), 5.0, "lmi.eig_bound"),
    ("g1", ("results", "lmi", "gap"), 0.0, "lmi.gap"),
    ("g1", ("results", "lmi", "alpha"), lambda a: a * 2, "listed claims"),
    ("g1", ("results", "lyapunov", "residual"), 0.5, "lyapunov.residual"),
    ("g1", ("results", "lyapunov", "P_min_eig"), 1.0, "lyapunov.P_min_eig"),
    ("sw", ("results", "symmetric_part_min_eig", "G1"), 10.0, "symmetric_part_min_eig.G1"),
    ("sw", ("results", "symmetric_part_min_eig", "G7"), 1.0, "symmetric_part_min_eig.G7"),
    ("sw", ("results", "common_lyapunov", "margin"), 0.9, "common_lyapunov.margin"),
]


@hostile
@pytest.mark.parametrize(
    "which, path, value, needle",
    FIELD_FORGERIES,
    ids=[f"{w}-{'.'.join(map(str, p))}-{i}" for i, (w, p, _, _) in enumerate(FIELD_FORGERIES)],
)
def test_field_forgery_is_invalid(which, path, value, needle):
    doc = copy.deepcopy(G1 if which == "g1" else SW)
    _set(doc, path, value)
    ver = verify(redigest(doc))
    assert not ver.valid
    assert any(needle in f"{c.name}: {c.detail}" for c in ver.failed), [
        (c.name, c.detail) for c in ver.failed
    ]
    assert all(c.name != "digest" for c in ver.failed)  # the checksum was recomputed


def test_weaker_but_consistent_edit_is_still_a_true_certificate():
    """Dropping the decay rate (and its claims, consistently) leaves a true statement."""
    doc = copy.deepcopy(G1)
    doc["certifies"] = ["hurwitz"]
    del doc["matrices"]["P"]["rate"]
    doc["results"]["lmi"].update(alpha=0.0, gap=doc["results"]["lmi"]["eig_bound"])
    ver = verify(redigest(rederive_claims(doc)))
    assert ver.valid, ver.failed
    assert ver.about.properties == (Property.HURWITZ,) and ver.about.alpha is None


@hostile
def test_consistent_certificate_of_another_topology_is_caught_by_topology(
    tmp_path, capsys, monkeypatch, examples
):
    g1 = nd.load(examples / "g1.yaml")
    w = dict(g1.weights)
    key = next(iter(w))
    w[key] = w[key] * (1 + 2**-40)
    other = nd.Topology(g1.labels, g1.dim, w, name="G1")
    doc = hurwitz_certificate(nd.design(other, [1, 2, -1]), rate=False)
    assert verify(doc).valid
    expect_invalid(
        doc,
        tmp_path,
        capsys,
        monkeypatch,
        "about the given topology",
        extra=("--topology", examples / "g1.yaml"),
    )
    code, _, err = cli(
        doc, tmp_path, capsys, monkeypatch, "--topology", examples / "switching.yaml"
    )
    assert code == 1 and "about the given topology" in err


def test_switching_certificate_with_a_failing_mode_is_invalid(examples):
    sd = nd.design(nd.load(examples / "switching.yaml"), [1, 2, -1], delta=0.5)
    ver = verify(switching_certificate(sd, structures=("identity",)))
    assert not ver.valid
    assert "L_B(G1) + L_B(G1)ᵀ ≻ 0" in {c.name for c in ver.failed}
    assert all(c.claim is not None for c in ver.failed)  # only the mathematics fails


@hostile
@pytest.mark.parametrize(
    "text, needle",
    [
        ("[" * 100_000 + "]" * 100_000, "nested too deeply"),
        (
            '{"format": "ntc-design/certificate", "version": 2, "size": 1' + "0" * 5000 + "}",
            "cannot read",
        ),
        (json.dumps({**G1, "size": 10**9}), "size"),
        (json.dumps({**G1, "size": 22}), "Nd=21"),
        (
            json.dumps(
                {
                    **G1,
                    "matrices": {**G1["matrices"], "P": {"lyapunov": [[float("nan")] * 21] * 21}},
                }
            ),
            "non-finite",
        ),
        (json.dumps({**G1, "certifies": [1]}), "certifies"),
    ],
)
def test_malformed_certificates_exit_2(tmp_path, capsys, monkeypatch, text, needle):
    code, out, err = cli(text, tmp_path, capsys, monkeypatch)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and needle in lines[0], (code, err)


def test_verify_json_output_says_what_and_which(tmp_path, capsys, monkeypatch, examples):
    code, out, err = run_cli(
        ["verify", CERTS / "switching.json", "--json", "--topology", examples / "switching.yaml"],
        capsys,
        monkeypatch,
    )
    assert code == 0, err
    doc = json.loads(out)
    assert doc["valid"] and "not a signature" in doc["digest_note"]
    ab = doc["certifies"]
    assert ab["kind"] == "switching" and ab["scheduled_modes"] == ["G2", "G1", "G3"]
    assert [m["N"] for m in ab["modes"]] == [7, 7, 7]
    assert {p["property"] for p in ab["properties"]} == {"symmetric_part", "common_lyapunov"}
    hashes = {m["name"]: m["topology_hash"] for m in ab["modes"]}
    assert hashes["G1"] == nd.certify.topology_hash(nd.load(examples / "g1.yaml"))


def test_topology_hash_is_canonical(tmp_path, examples):
    """Layout does not matter (named matrices, edge order, name); numbers do."""
    g1 = nd.load(examples / "g1.yaml")
    h = nd.certify.topology_hash(g1)
    rev = nd.Topology(g1.labels, g1.dim, dict(reversed(list(g1.weights.items()))), name="x")
    assert nd.certify.topology_hash(rev) == h
    w = dict(g1.weights)
    k = next(iter(w))
    w[k] = np.nextafter(w[k], np.inf) * (w[k] != 0) + w[k] * (w[k] == 0)
    assert nd.certify.topology_hash(nd.Topology(g1.labels, g1.dim, w)) != h


# ------------------------------------------------- property: never a false certificate


def _leaves(node, path=()):
    if isinstance(node, dict):
        for k, v in node.items():
            if k not in ("versions", "solver", "digest", "subject_digest"):
                yield from _leaves(v, (*path, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _leaves(v, (*path, i))
    yield path


LEAVES = {"g1": [p for p in _leaves(G1) if p], "sw": [p for p in _leaves(SW) if p]}
EDITS = [
    lambda x: -x if isinstance(x, (int, float)) else x,
    lambda x: 0,
    lambda x: x * (1 + 2**-30) if isinstance(x, float) else x,
    lambda x: x * 2 if isinstance(x, (int, float)) else x,
    lambda x: 1e300,
    lambda x: 1e-300,
    lambda x: "x",
    lambda x: [],
    lambda x: None,
    DELETE,
]


def _independently_true(doc, ver):
    """What an accepted certificate says, checked another way: Lemma 1's design redone
    from the subject's topology, θ and δ, and the eigenvalues of the re-derived L_B."""
    for m in ver.about.modes:
        sub = doc["subject"]["modes"][m.name]
        top = nd.Topology.from_data(files.parse_topology(sub["topology"]))
        d = nd.design(top, sub["theta"], delta=sub["delta"], thresholds=False)
        assert [str(x) for x in sub["informed"]] == [str(top.labels[i]) for i in d.informed]
        assert sub["k1"] == d.k1 and sub["x0"] == d.x0.tolist()
        lap = d.grounded_laplacian()
        if m.name not in ver.about.scheduled:
            continue
        props = ver.about.properties
        if Property.HURWITZ in props:
            assert np.min(np.linalg.eigvals(lap).real) > 0
        if Property.DECAY_RATE in props:
            assert 0 < ver.about.alpha <= np.min(np.linalg.eigvals(lap).real) * (1 + 1e-8)
        if Property.SYMMETRIC_PART in props:
            assert np.linalg.eigvalsh(lap + lap.T)[0] > 0
        if Property.COMMON_LYAPUNOV in props:
            p = np.array(doc["matrices"]["P"]["common"])
            assert np.linalg.eigvalsh(p)[0] > 0
            assert np.linalg.eigvalsh(p @ lap + lap.T @ p)[0] > 0


@hostile
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    which=st.sampled_from(["g1", "sw"]),
    picks=st.lists(
        st.tuples(st.integers(0, 10**6), st.integers(0, len(EDITS) - 1)), min_size=1, max_size=3
    ),
)
def test_never_a_certificate_for_a_false_claim_even_forged(which, picks):
    doc = copy.deepcopy(G1 if which == "g1" else SW)
    leaves = LEAVES[which]
    for pos, e in picks:
        path = leaves[pos % len(leaves)]
        try:
            node = doc
            for k in path[:-1]:
                node = node[k]
            if EDITS[e] is DELETE:
                del node[path[-1]]
            else:
                node[path[-1]] = EDITS[e](node[path[-1]])
        except (KeyError, IndexError, TypeError):
            continue  # an earlier edit removed the path
    redigest(doc)
    try:
        ver = verify(json.loads(json.dumps(doc)))
    except InputError:
        return  # rejected as malformed
    if ver.valid:
        _independently_true(doc, ver)


# ------------------------------------------------------ certify: nothing unproven written

UNPROVEN = {
    "empty graph": "dim: 1\nagents: 3\nedges: []\n",
    "agent with no edges": (
        "dim: 1\nagents: 3\nedges:\n  - {from: 1, to: 2, weight: -1}\n  - {from: 2, to: 1, weight: 1}\n"
    ),
    # agents 3 and 4 only listen to each other (cooperatively) and no informed agent
    # grounds them: their block of L_B is singular, −L_B is not Hurwitz
    "ungrounded cycle": (
        "dim: 1\nagents: 4\nedges:\n  - {from: 1, to: 2, weight: -1}\n"
        "  - {from: 3, to: 4, weight: 1}\n  - {from: 4, to: 3, weight: 1}\n"
    ),
}


@hostile
@pytest.mark.parametrize("gain", [None, "1/(1+t)"])
@pytest.mark.parametrize("name", list(UNPROVEN))
def test_certify_exits_1_and_writes_nothing_when_nothing_is_proven(
    tmp_path, capsys, monkeypatch, name, gain
):
    top = tmp_path / "t.yaml"
    top.write_text(UNPROVEN[name])
    out = tmp_path / "c.json"
    args = ["certify", top, "--theta", "1", "--out", out] + (["--gain", gain] if gain else [])
    code, _, err = run_cli(args, capsys, monkeypatch)
    assert code == 1, err
    # no informed agent at all: said as ntc design says it (issue 47, item 11)
    why = (
        "not certified: the network has no informed agent"
        if name == "empty graph"
        else "not proven"
    )
    assert "Traceback" not in err and why in err
    assert not out.exists() and list(tmp_path.iterdir()) == [top]  # no stray temporary file


@hostile
@pytest.mark.parametrize(
    "args, needle",
    [
        (["verify", "no-such.json"], "no such file"),
        (["verify", "."], "is a folder"),
        (["verify", CERTS / "g1.json", "--topology", "no-such.yaml"], "no such file"),
        (["verify", CERTS / "g1.json", "--theta", "1,x"], "--theta"),
        (["verify", CERTS / "g1.json", "--theta", ""], "--theta"),
        (["verify", CERTS / "README.md"], "not valid JSON"),
        (["certify", ROOT / "examples" / "g1.yaml", "--theta", "1,2,-1", "--out", "."], "--out"),
    ],
)
def test_verify_and_certify_bad_arguments_are_one_line(capsys, monkeypatch, args, needle):
    code, out, err = run_cli(args, capsys, monkeypatch)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and needle in lines[0], (code, err)


def test_verify_with_theta_of_the_wrong_length_is_invalid(tmp_path, capsys, monkeypatch):
    code, _, err = run_cli(["verify", CERTS / "g1.json", "--theta", "1,2"], capsys, monkeypatch)
    assert code == 1 and "θ is the one given" in err


# -- a certificate relabelled as another kind ---------------------------------------------


def _relabelled():
    from ntc_design.certify import KINDS

    honest = ("robust", "hurwitz", "switching", "hurwitz-scale", "switching-scale", "time_varying")
    return [(h, k) for h in honest for k in KINDS if k != h]


@hostile
@pytest.mark.parametrize("as_json", [False, True], ids=["text", "json"])
@pytest.mark.parametrize("reseal", [False, True], ids=["as-edited", "resealed"])
@pytest.mark.parametrize("honest_kind, kind", _relabelled())
def test_a_certificate_relabelled_as_another_kind_is_refused(
    honest_kind, kind, reseal, as_json, honest_certificates, tmp_path, capsys, monkeypatch
):
    # one edit of a genuine certificate (its kind), with and without its digests
    # recomputed: invalid (1) or malformed (2), in one line, never an internal error
    doc = copy.deepcopy(honest_certificates[honest_kind])
    doc["kind"] = kind
    if reseal:
        redigest(doc)
    p = tmp_path / "relabelled.json"
    p.write_text(json.dumps(doc))
    code, out, err = run_cli(["verify", p, *(["--json"] if as_json else [])], capsys, monkeypatch)
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code in (1, 2), (code, err)
    assert len(lines) == 1 and "Traceback" not in err and "internal error" not in err, err
    if code == 2:
        assert lines[0].startswith(f"error: {p}: "), lines[0]
    if as_json:  # a script reading stdout gets JSON either way
        got = json.loads(out)
        if code == 1:
            assert got["valid"] is False
        else:
            assert got == {"ok": False, "error": lines[0][len("error: ") :], "exit_code": 2}


@hostile
def test_a_switching_certificate_relabelled_robust_names_the_field(capsys, monkeypatch, tmp_path):
    # the case that once unpacked three modes into one (ValueError, empty stdout)
    doc = copy.deepcopy(SW)
    doc["kind"] = "robust"
    p = tmp_path / "sw.json"
    p.write_text(json.dumps(doc))
    code, out, err = run_cli(["verify", p, "--json"], capsys, monkeypatch)
    msg = f"{p}: kind 'robust' is about one topology, but subject.modes lists 3 modes"
    assert (code, err) == (2, f"error: {msg}\n")
    assert json.loads(out) == {"ok": False, "error": msg, "exit_code": 2}


@hostile
@pytest.mark.parametrize("command", ["verify", "export"])
def test_a_lone_surrogate_label_is_one_line_and_exit_2(tmp_path, capsys, monkeypatch, command):
    # a re-sealed certificate whose agent 7 is a lone surrogate: not text, so nothing can
    # print it or write it (export crashed on encoding it to UTF-8)
    doc = json.loads((CERTS / "g1_digital.json").read_text())
    mode = doc["subject"]["modes"]["G1"]
    top = mode["topology"]
    top["agents"] = ["\ud800" if a == 7 else a for a in top["agents"]]
    for e in top["edges"]:
        e.update({k: "\ud800" for k in ("from", "to") if e[k] == 7})
    cert = tmp_path / "c.json"
    cert.write_text(json.dumps(redigest(doc)), encoding="ascii")  # re-sealed
    args = [command, cert] + (["--out", tmp_path / "o"] if command == "export" else [])
    code, out, err = run_cli(args, capsys, monkeypatch)
    assert code == 2 and out == "" and "Traceback" not in err
    k, key = next(
        (k, key) for k, e in enumerate(top["edges"]) for key in ("from", "to") if e[key] == "\ud800"
    )
    assert err.splitlines() == [
        f"error: {cert}: subject.modes.G1.topology.edges[{k}].{key}: a string that is not "
        "Unicode text (a lone surrogate, \\ud800)"
    ]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.json"]
