"""The topology model (paper Def. 1) and its validation rules."""

from __future__ import annotations

import pytest

from flyover.errors import TopologyError
from flyover.topology import Label, read_yaml_spec
from flyover.topology.catalog import catalog_topologies
from tests.conftest import J1_EDGES, build_j1


def test_j1_has_exactly_the_papers_edges_and_labels(j1):
    got = {(u, v, d["label"].value) for u, v, d in j1.graph.edges(data=True)}
    assert got == set(J1_EDGES)
    assert j1.roads == ("R1", "R2", "R3", "R4")
    assert j1.ramps == ("r1", "r2", "r3", "r4")


def test_catalog_j1_spec_is_the_papers_j1(j1):
    spec = catalog_topologies()["j1"]
    assert {(c.source, c.target, c.label) for c in spec.connections()} == \
        {(c.source, c.target, c.label) for c in j1.connections()}


def test_label_counts_and_summary(j1):
    counts = j1.label_counts()
    assert counts == {"Out-R": 3, "Out-L": 1, "Out-M": 0, "In-R": 3, "In-L": 1, "In-M": 0}
    assert "4 roads, 4 ramps" in j1.summary()


@pytest.mark.parametrize("name, shape", [
    ("cloverleaf", "cross"), ("stack4", "cross"), ("trumpet", "T"), ("directional_t", "T"),
])
def test_shape_counts_legs(name, shape):
    assert catalog_topologies()[name].shape == shape


def write_spec(tmp_path, ramps: str, expressways: str = "{A: [A1, A2], B: [B1, B2]}",
               extra: str = "") -> str:
    path = tmp_path / "bad.yaml"
    path.write_text(f"name: bad\nexpressways: {expressways}\n{extra}ramps:\n{ramps}")
    return str(path)


GOOD = ("  r1: {from: A1 right, to: B1 right}\n"
        "  r2: {from: B1 right, to: A2 right}\n"
        "  r3: {from: A2 right, to: B2 right}\n"
        "  r4: {from: B2 right, to: A1 right}\n")


def test_good_spec_validates(tmp_path):
    assert read_yaml_spec(write_spec(tmp_path, GOOD)).n_ramps == 4


@pytest.mark.parametrize("ramps, expressways, element, rule", [
    # unknown label: side word outside right/left/straight
    (GOOD + "  r5: {from: A1 sideways, to: B1 right}\n", None, "ramps.r5.from", "is not"),
    # road -> road: a 'ramp' endpoint naming a road as ramp is impossible, so use a road id twice
    (GOOD + "  r5: {from: r5 right, to: B1 right}\n", None, "r5->r5", "self-loop"),
    (GOOD + "  r5: {from: [A1 right, A1 left], to: B1 right}\n", None, "A1->r5", "duplicate edge"),
    (GOOD + "  r5: {from: A1 right}\n", None, "r5", "no way out"),
    (GOOD + "  r5: {to: A1 right}\n", None, "r5", "no way in"),
    (GOOD + "  r5: {from: A1 straight, to: B1 right}\n  r6: {from: A1 straight, to: B2 right}\n",
     None, "A1", "more than one Out-M"),
    (GOOD + "  r5: {from: A1 right, to: B1 straight}\n  r6: {from: A2 right, to: B1 straight}\n",
     None, "B1", "more than one In-M"),
    (GOOD, "{A: [A1, A2, A3], B: [B1, B2]}", "expressway A", "more than two carriageways"),
    (GOOD + "  r5: {from: r6 right, to: B1 right}\n  r6: {from: r5 right, to: A1 right}\n",
     None, "r5, r6", "unreachable"),
    (GOOD + "  r5: {from: C9 right, to: B1 right}\n", None, "C9->r5", "unknown node"),
])
def test_each_bad_input_rule_names_file_element_and_rule(tmp_path, ramps, expressways, element, rule):
    path = write_spec(tmp_path, ramps, expressways or "{A: [A1, A2], B: [B1, B2]}")
    with pytest.raises(Exception) as info:
        read_yaml_spec(path)
    message = str(info.value)
    assert message.startswith(path)
    assert element in message and rule in message
    assert "\n" not in message


def _edges_with(replacement):
    return [replacement.get((u, v), (u, v, lab)) for u, v, lab in J1_EDGES]


@pytest.mark.parametrize("edges, element, rule", [
    (J1_EDGES + [("R1", "R3", "Out-R")], "R1->R3", "road -> road"),
    (_edges_with({("r1", "R3"): ("r1", "R3", "Out-R")}), "r1->R3", "target must be a ramp"),
    (_edges_with({("R2", "r3"): ("R2", "r3", "In-R")}), "R2->r3", "source must be a ramp"),
])
def test_edge_rules_on_built_topologies(edges, element, rule):
    with pytest.raises(TopologyError) as info:
        build_j1(edges)
    assert info.value.element == element and rule in info.value.reason


def test_unknown_label_and_kind_in_graphml(tmp_path):
    from flyover.topology import read_graphml
    text = (tmp_path / "x.graphml")
    good = ("""<?xml version='1.0' encoding='utf-8'?>
<graphml xmlns="http://graphml.graphdrawing.org/xmlns">
<key id="k" for="node" attr.name="kind" attr.type="string"/>
<key id="e" for="node" attr.name="expressway" attr.type="string"/>
<key id="l" for="edge" attr.name="label" attr.type="string"/>
<graph edgedefault="directed">
<node id="A1"><data key="k">road</data><data key="e">A</data></node>
<node id="B1"><data key="k">{kind}</data><data key="e">B</data></node>
<node id="r1"><data key="k">ramp</data></node>
<edge source="A1" target="r1"><data key="l">{label}</data></edge>
<edge source="r1" target="B1"><data key="l">In-R</data></edge>
</graph></graphml>""")
    text.write_text(good.format(kind="road", label="Out-R"))
    assert read_graphml(text).n_ramps == 1
    text.write_text(good.format(kind="road", label="Out-X"))
    with pytest.raises(TopologyError, match=r"A1->r1: unknown label 'Out-X'"):
        read_graphml(text)
    text.write_text(good.format(kind="bridge", label="Out-R"))
    with pytest.raises(TopologyError, match=r"B1: unknown kind 'bridge'"):
        read_graphml(text)


def test_every_label_has_a_side_and_direction():
    assert Label.OUT_M.side == "middle" and Label.OUT_M.is_out
    assert Label.of(False, "left") is Label.IN_L
