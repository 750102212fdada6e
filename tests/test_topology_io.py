"""Formats: native GraphML, FLYOVER dataset GraphML, YAML spec — round trips and errors."""

from __future__ import annotations

import pytest

from flyover.errors import InputFormatError, TopologyError
from flyover.topology import (
    Label,
    class_id,
    read_graphml,
    read_topologies,
    read_yaml_spec,
    write_graphml,
    write_yaml_spec,
)
from flyover.topology.catalog import catalog_topologies


def same(a, b) -> bool:
    edges = lambda t: sorted((c.source, c.target, c.label, c.pos) for c in t.connections())  # noqa: E731
    nodes = lambda t: sorted((n, d["kind"], d.get("expressway"), d.get("lanes"))  # noqa: E731
                             for n, d in t.graph.nodes(data=True))
    return edges(a) == edges(b) and nodes(a) == nodes(b)


@pytest.mark.parametrize("name", sorted(catalog_topologies()))
def test_native_graphml_round_trip(tmp_path, name):
    t = catalog_topologies()[name]
    write_graphml(t, tmp_path / "t.graphml")
    back = read_graphml(tmp_path / "t.graphml")
    assert same(t, back) and back.name == t.name


@pytest.mark.parametrize("name", sorted(catalog_topologies()))
def test_yaml_spec_round_trip(tmp_path, name):
    t = catalog_topologies()[name]
    write_yaml_spec(t, tmp_path / "t.yaml")
    assert same(t, read_yaml_spec(tmp_path / "t.yaml"))


def test_graphml_bytes_are_deterministic(tmp_path):
    t = catalog_topologies()["stack4"]
    shuffled = t.relabeled({n: n for n in reversed(list(t.graph))})
    write_graphml(t, tmp_path / "a.graphml")
    write_graphml(shuffled, tmp_path / "b.graphml")
    assert (tmp_path / "a.graphml").read_bytes() == (tmp_path / "b.graphml").read_bytes()


def test_lanes_survive_both_formats(tmp_path):
    spec = tmp_path / "l.yaml"
    spec.write_text("expressways: {A: [A1, A2]}\nlanes: {A1: 5}\n"
                    "ramps:\n  u: {from: A1 left, to: A2 left}\n  v: {from: A2 left, to: A1 left}\n")
    t = read_yaml_spec(spec)
    assert t.graph.nodes["A1"]["lanes"] == 5 and "lanes" not in t.graph.nodes["A2"]
    write_graphml(t, tmp_path / "l.graphml")
    assert read_graphml(tmp_path / "l.graphml").graph.nodes["A1"]["lanes"] == 5


FLYOVER_HEAD = """<?xml version="1.0" encoding="UTF-8"?>
<graphml xmlns="http://graphml.graphdrawing.org/xmlns">
  <key id="d0" for="node" attr.name="type" attr.type="string"/>
  <key id="d1" for="node" attr.name="name" attr.type="string"/>
  <key id="d2" for="node" attr.name="lane" attr.type="int"/>
  <key id="d3" for="node" attr.name="radius" attr.type="double"/>
  <key id="d4" for="node" attr.name="curv" attr.type="string"/>
  <key id="d5" for="node" attr.name="geo" attr.type="string"/>
  <key id="d6" for="node" attr.name="ctrl" attr.type="string"/>
  <key id="d7" for="edge" attr.name="ramp" attr.type="string"/>
  <key id="d8" for="edge" attr.name="junc" attr.type="string"/>
  <key id="d9" for="edge" attr.name="part" attr.type="double"/>
  <graph id="G" edgedefault="directed">
"""


def flyover_graphml(nodes, edges) -> str:
    """GraphML in the FLYOVER dataset's published schema (DESIGN.md)."""
    out = [FLYOVER_HEAD]
    for i, (typ, name, lane) in enumerate(nodes):
        extra = ('<data key="d3">150.0</data><data key="d4">0.0066</data>'
                 '<data key="d5">1.2,3.4</data><data key="d6">0,0_10,5_20,5_30,0</data>'
                 if typ == "link" else "")
        out.append(f'    <node id="n{i}"><data key="d0">{typ}</data><data key="d1">{name}</data>'
                   f'<data key="d2">{lane}</data>{extra}</node>\n')
    index = {name: i for i, (_, name, _) in enumerate(nodes)}
    for j, (u, v, ramp, junc, part) in enumerate(edges):
        out.append(f'    <edge id="e{j}" source="n{index[u]}" target="n{index[v]}">'
                   f'<data key="d7">{ramp}</data><data key="d8">{junc}</data>'
                   f'<data key="d9">{part}</data></edge>\n')
    out.append("  </graph>\n</graphml>\n")
    return "".join(out)


T_NODES = [("main", "A1", 3), ("main", "A2", 3), ("main", "B1", 4), ("main", "B2", 4),
           ("link", "rR", 1), ("link", "rL", 1), ("link", "rA1", 1), ("link", "rA2", 2)]
T_EDGES = [("B1", "rR", "out", "right", 1.0), ("B1", "rL", "out", "middle", 1.0),
           ("rR", "A1", "in", "right", 0.7), ("rL", "A2", "in", "right", 0.7),
           ("A1", "rA1", "out", "right", 0.3), ("A2", "rA2", "out", "right", 0.3),
           ("rA1", "B2", "in", "right", 0.0), ("rA2", "B2", "in", "middle", 0.0)]


def test_flyover_dataset_graphml_imports_including_junc_middle(tmp_path):
    path = tmp_path / "flyover_T.graphml"
    path.write_text(flyover_graphml(T_NODES, T_EDGES))
    t = read_graphml(path)
    # nodes are keyed on their GraphML id; the dataset's name is kept as an attribute
    node = {d["name"]: n for n, d in t.graph.nodes(data=True)}
    assert t.roads == ("n0", "n1", "n2", "n3") and t.n_ramps == 4
    assert [node[r] for r in ("A1", "A2", "B1", "B2")] == ["n0", "n1", "n2", "n3"]
    assert t.expressways == {"A": ("n0", "n1"), "B": ("n2", "n3")}
    assert t.graph.edges[node["B1"], node["rL"]]["label"] is Label.OUT_M
    assert t.graph.edges[node["rA2"], node["B2"]]["label"] is Label.IN_M
    assert t.graph.edges[node["A1"], node["rA1"]]["pos"] == pytest.approx(0.3)
    assert t.graph.nodes[node["B1"]]["lanes"] == 4
    assert t.graph.nodes[node["rA1"]]["radius"] == pytest.approx(150.0)
    assert t.shape == "T"
    # this is the catalog's semi-directional T, whatever the node names
    assert class_id(t) == class_id(catalog_topologies()["semidirectional_t"])


def test_flyover_dataset_repeated_node_names_are_read_by_node_id(tmp_path):
    """The published dataset repeats `name` within a file (ids are unique): not an error."""
    renamed = {"rR": "r", "rL": "r", "rA1": "r", "rA2": "r2"}  # three ramps called 'r'
    nodes = [(typ, renamed.get(name, name), lane) for typ, name, lane in T_NODES]
    text = flyover_graphml(T_NODES, T_EDGES)
    for (_, old, _), (_, new, _) in zip(T_NODES, nodes):
        text = text.replace(f'<data key="d1">{old}</data>', f'<data key="d1">{new}</data>')
    assert text.count('<data key="d1">r</data>') == 3
    path = tmp_path / "repeated.graphml"
    path.write_text(text)
    t = read_graphml(path)
    assert t.n_roads == 4 and t.n_ramps == 4
    assert sorted(d["name"] for _, d in t.graph.nodes(data=True)) == sorted(n for _, n, _ in nodes)
    assert class_id(t) == class_id(catalog_topologies()["semidirectional_t"])
    # and the name survives a round trip through native GraphML
    write_graphml(t, tmp_path / "native.graphml")
    back = read_graphml(tmp_path / "native.graphml")
    assert back.graph.nodes["n4"]["name"] == "r" and class_id(back) == class_id(t)


def test_flyover_dataset_bad_junc_is_named(tmp_path):
    path = tmp_path / "bad.graphml"
    edges = [e if e[0] != "A1" else ("A1", "rA1", "out", "up", 0.3) for e in T_EDGES]
    path.write_text(flyover_graphml(T_NODES, edges))
    with pytest.raises(TopologyError, match=r"bad.graphml: n0 \(A1\)->n6 \(rA1\): unknown junc 'up'"):
        read_graphml(path)


def test_malformed_files_give_one_line_errors(tmp_path):
    xml = tmp_path / "broken.graphml"
    xml.write_text("<graphml><graph><node id='a'></graph>")
    with pytest.raises(InputFormatError, match=r"broken.graphml: not readable as GraphML"):
        read_topologies(xml)
    yml = tmp_path / "broken.yaml"
    yml.write_text("expressways: {A: [A1\nramps: [")
    with pytest.raises(InputFormatError, match=r"broken.yaml: malformed YAML \(line"):
        read_topologies(yml)
    with pytest.raises(InputFormatError, match=r"unknown file type '.txt'"):
        read_topologies(tmp_path / "notes.txt")


def test_measured_node_attributes_survive_native_graphml(tmp_path):
    from flyover.topology import Connection, Ramp, Road, Topology
    t = Topology.build("m", [Road("A1", "A"), Road("B1", "B")], [Ramp("r")],
                       [Connection("A1", "r", Label.OUT_R), Connection("r", "B1", Label.IN_R)],
                       node_attrs={"r": {"length_m": 412.5, "min_radius_m": 88.0, "osm_ways": "1 2"}})
    write_graphml(t, tmp_path / "m.graphml")
    back = read_graphml(tmp_path / "m.graphml").graph.nodes["r"]
    assert back["length_m"] == 412.5 and back["min_radius_m"] == 88.0 and back["osm_ways"] == "1 2"


def test_atomic_write_gives_results_the_umask_mode_not_the_temp_files(tmp_path):
    import os
    import stat

    from flyover.topology.io import atomic_write

    old = os.umask(0o022)
    try:
        atomic_write(tmp_path / "out.bin", b"x")
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "out.bin").stat().st_mode) == 0o644
    assert [p.name for p in tmp_path.iterdir()] == ["out.bin"]
