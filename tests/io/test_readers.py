"""Tests of :mod:`ntc_design.io.readers`."""

import json
import shutil

import numpy as np
import pytest

from ntc_design.errors import InputError
from ntc_design.io.edgelist import EdgeListData, write_npz
from ntc_design.io.files import SwitchingData, TopologyData
from ntc_design.io.readers import parse_file
from ntc_design.io.tvfiles import TimeVaryingData
from ntc_design.model import SwitchingTopology, Topology, paper

TINY = "dim: 1\nagents: 2\nedges:\n  - {from: 1, to: 2, weight: [[2]]}\n"


def _same_as_g1(top: Topology) -> None:
    """The weights of the paper's G1 (built in code, not read from a file)."""
    ref = paper.g1()
    assert top.labels == ref.labels and top.dim == ref.dim
    assert set(top.weights) == set(ref.weights)
    for k, w in ref.weights.items():
        np.testing.assert_array_equal(top.weights[k], w, err_msg=str(k))


def _g1_npz(path) -> None:
    ref = paper.g1()
    ea = ref.edge_arrays
    write_npz(path, ref.labels, ref.dim, ea.rows, ea.cols, ea.w, name="G1")


@pytest.mark.parametrize("name", ["g1.yaml", "g1.csv", "g1.mat"])
def test_bundled_g1_in_every_format(examples, name):
    data = parse_file(examples / name)
    expected = TopologyData if name.endswith(".yaml") else EdgeListData
    assert type(data) is expected
    _same_as_g1(Topology.from_data(data))


def test_npz_edge_list(tmp_path):
    p = tmp_path / "g1.npz"
    _g1_npz(p)
    data = parse_file(str(p))  # a str path as well as a Path
    assert isinstance(data, EdgeListData) and data.name == "G1"
    _same_as_g1(Topology.from_data(data))


def test_json_topology(tmp_path):
    p = tmp_path / "g1.json"
    p.write_text(json.dumps(paper.g1().to_dict()))
    data = parse_file(p)
    assert isinstance(data, TopologyData)
    _same_as_g1(Topology.from_data(data))


@pytest.mark.parametrize("suffix", [".CSV", ".Mat", ".NPZ"])
def test_edge_list_suffix_is_case_insensitive(examples, tmp_path, suffix):
    p = tmp_path / f"G1{suffix}"
    if suffix == ".NPZ":
        _g1_npz(tmp_path / "g1.npz")
        shutil.copy(tmp_path / "g1.npz", p)
    else:
        shutil.copy(examples / f"g1{suffix.lower()}", p)
    data = parse_file(p)
    assert isinstance(data, EdgeListData)
    _same_as_g1(Topology.from_data(data))


def test_only_the_last_suffix_counts(tmp_path):
    # a YAML file whose name contains ".npz" is YAML; "x.yaml.csv" would be a CSV
    p = tmp_path / "net.npz.yaml"
    p.write_text(TINY)
    data = parse_file(p)
    assert isinstance(data, TopologyData) and data.dim == 1 and data.labels == (1, 2)


def test_switching_by_its_fields(examples):
    data = parse_file(examples / "switching.yaml")
    assert isinstance(data, SwitchingData)
    sw = SwitchingTopology.from_data(data)
    assert sw.schedule == paper.switching().schedule
    _same_as_g1(sw.modes["G1"])  # the mode file is found beside the switching file


@pytest.mark.parametrize(
    "body, needle",
    [
        ("schedule: [{mode: A, duration: 1}]\n", "modes: expected a non-empty mapping"),
        ("modes: {A: a.yaml}\n", "modes.A"),
        # with modes present the file is a switching one even if it declares a period
        ("modes: {}\nperiod: 1\n", "period: unknown field (allowed: modes, schedule, name)"),
    ],
)
def test_modes_or_schedule_make_a_switching_file(tmp_path, body, needle):
    p = tmp_path / "sw.yaml"
    p.write_text(body)
    with pytest.raises(InputError, match="sw.yaml: ") as exc:
        parse_file(p)
    assert needle in str(exc.value) and "\n" not in str(exc.value)


def test_time_varying_by_a_period(examples):
    data = parse_file(examples / "g1_tv.yaml")
    assert isinstance(data, TimeVaryingData)
    assert data.name == "G1-tv" and data.labels == tuple(range(1, 8))
    assert float(data.period) == pytest.approx(20 * np.pi, rel=1e-15)


@pytest.mark.parametrize(
    "extra, weight",
    [("constant_after: 2\n", "[[2]]"), ("", '[["2 + sin(t)"]]'), ("period: 3\n", "[[2]]")],
)
def test_time_varying_by_a_time_key_or_an_expression(tmp_path, extra, weight):
    p = tmp_path / "tv.yaml"
    p.write_text(f"dim: 1\nagents: 2\n{extra}edges:\n  - {{from: 1, to: 2, weight: {weight}}}\n")
    data = parse_file(p)
    assert isinstance(data, TimeVaryingData)
    assert data.source == str(p)
    assert (data.period is None) == ("period" not in extra)
    assert (data.constant_after is None) == ("constant_after" not in extra)


def test_constant_file_is_a_plain_topology(tmp_path):
    p = tmp_path / "c.yml"
    p.write_text(TINY)
    data = parse_file(p)
    assert type(data) is TopologyData and data.source == str(p)
    np.testing.assert_array_equal(data.edges[0].weight, [[2.0]])


@pytest.mark.parametrize(
    "name, content, needle",
    [
        ("missing.yaml", None, "no such file"),
        ("missing.npz", None, "no such file"),
        ("list.yaml", "- 1\n- 2\n", "expected a mapping at the top level"),
        ("bad.json", "{", "not valid JSON"),
        ("garbage.npz", "not a zip", "not a readable .npz edge list"),
    ],
)
def test_unreadable_files_are_one_line_errors(tmp_path, name, content, needle):
    p = tmp_path / name
    if content is not None:
        p.write_text(content)
    with pytest.raises(InputError, match=name.replace(".", r"\.")) as exc:
        parse_file(p)
    msg = str(exc.value)
    assert needle in msg and "\n" not in msg
