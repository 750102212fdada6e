"""Fuzzing the GraphML readers (native and the FLYOVER dataset's schema) and the city
import of GraphML files (issue 19).

Seeds: every catalog design written as native GraphML by our writer, and as the
FLYOVER dataset publishes it (``type``/``name``/``lane``..., node names repeated
as in the published data). Mutations: attribute values and text swapped for
hostile ones, lines dropped, duplicated or swapped, XML tricks (entities, DTDs)
pasted in, the file cut short. Each either loads or raises a FlyoverError naming
the file; the import writes nothing outside its output folder.
"""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from flyover.errors import InputFormatError, UnsafeNameError
from flyover.topology.catalog import catalog_topologies
from flyover.topology.io import graphml_bytes, read_graphml
from flyover.topology.model import Kind
from tests.fuzz_support import (
    FUZZ,
    assert_names_file,
    import_stays_inside,
    loads_or_names_file,
    mutated_xml,
    sandbox,
    write_text,
)

TOPOLOGIES = [t for _, t in sorted(catalog_topologies().items())]
NATIVE = [graphml_bytes(t).decode() for t in TOPOLOGIES]

_FLYOVER_KEYS = """<?xml version="1.0" encoding="UTF-8"?>
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


def flyover_dataset_graphml(t, repeat_names: bool = False) -> str:
    """``t`` in the FLYOVER dataset's published schema; ``repeat_names`` gives every ramp
    the name ``r`` (the published data repeats names; ids stay unique)."""
    ids = {n: f"n{i}" for i, n in enumerate(sorted(t.graph.nodes))}
    out = [_FLYOVER_KEYS]
    for n, d in sorted(t.graph.nodes(data=True)):
        road = d["kind"] is Kind.ROAD
        name = d["expressway"] + n[-1] if road else ("r" if repeat_names else n)
        extra = "" if road else ('<data key="d3">150.0</data><data key="d4">0.0066</data>'
                                 '<data key="d5">1.2,3.4</data><data key="d6">0,0_10,5_20,5</data>')
        out.append(f'    <node id="{ids[n]}"><data key="d0">{"main" if road else "link"}</data>'
                   f'<data key="d1">{name}</data><data key="d2">{d.get("lanes") or 2}</data>{extra}</node>\n')
    for k, c in enumerate(t.connections()):
        part = "" if c.pos is None else f'<data key="d9">{c.pos}</data>'
        out.append(f'    <edge id="e{k}" source="{ids[c.source]}" target="{ids[c.target]}">'
                   f'<data key="d7">{"out" if c.label.is_out else "in"}</data>'
                   f'<data key="d8">{c.label.side}</data>{part}</edge>\n')
    out.append("  </graph>\n</graphml>\n")
    return "".join(out)


FLYOVER = [flyover_dataset_graphml(t, repeat) for t in TOPOLOGIES for repeat in (False, True)]
WORDS = ["road", "ramp", "Out-R", "Out-L", "Out-M", "In-R", "In-L", "In-M", "main", "link", "out", "in",
         "right", "left", "middle", "A", "A1", "B2", "n0", "n1", "n5", "int", "long", "double", "float",
         "boolean", "string", "node", "edge", "graph", "all", "directed", "undirected", "true", "false",
         "kind", "label", "lanes", "pos", "expressway", "name", "type", "lane", "ramp", "junc", "part",
         "d0", "d1", "d7", "d8"]
STEMS = st.sampled_from(["g", "J1", "a b", "x" * 120, "..", "ü"])


def _check_one(text: str, stem: str) -> None:
    with sandbox() as root:
        folder = root / "in"
        folder.mkdir()
        path = write_text(folder / f"{stem}.graphml", text)
        t = loads_or_names_file(read_graphml, path)
        index = import_stays_inside([path], root)
        assert len(index["interchanges"]) == (t is not None)


def test_seeds_load():
    """The unmutated seeds are valid (so mutations start from files that load)."""
    with sandbox() as root:
        for k, text in enumerate(NATIVE + FLYOVER):
            assert read_graphml(write_text(root / f"s{k}.graphml", text)).n_ramps > 0


@FUZZ
@given(text=st.sampled_from(NATIVE).flatmap(lambda s: mutated_xml(s, WORDS)), stem=STEMS)
def test_fuzz_native_graphml_loads_or_names_the_file(text, stem):
    _check_one(text, stem)


@FUZZ
@given(text=st.sampled_from(FLYOVER).flatmap(lambda s: mutated_xml(s, WORDS)), stem=STEMS)
def test_fuzz_flyover_dataset_graphml_loads_or_names_the_file(text, stem):
    _check_one(text, stem)


# -- what the fuzzers found, kept as plain regression tests ----------------------------------

@pytest.mark.parametrize("old, new, reason", [
    ('<data key="d2">2</data>', '<data key="d2">2.5</data>', "not readable as GraphML"),
    ('attr.name="lane" attr.type="int"', 'attr.name="lane" attr.type="string"', None),
])
def test_flyover_lane_that_is_not_a_count_is_named(tmp_path, old, new, reason):
    text = FLYOVER[0].replace(old, new, 1)
    if reason is None:  # lane declared as text: a non-number is named as a lanes error
        text = text.replace('<data key="d2">2</data>', '<data key="d2">two</data>', 1)
        reason = "lanes must be a positive integer, got 'two'"
    path = write_text(tmp_path / "lanes.graphml", text)
    with pytest.raises((InputFormatError, Exception)) as info:
        read_graphml(path)
    assert reason in str(info.value)
    assert_names_file(info.value, path)


def test_graph_name_that_is_a_path_is_refused(tmp_path):
    name = TOPOLOGIES[0].name
    assert NATIVE[0].count(f">{name}</data>") == 1
    path = write_text(tmp_path / "g.graphml", NATIVE[0].replace(f">{name}</data>", ">../../evil</data>"))
    with pytest.raises(UnsafeNameError, match=r"'../../evil': unsafe interchange name") as info:
        read_graphml(path)
    assert_names_file(info.value, path)
