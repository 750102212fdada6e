"""Fuzzing the OpenStreetMap import (issue 19): reader, network builder, city import.

Seeds are the real extracts of ``../shared/osm/`` (ODbL: read in place, never
copied into the repository; the tests skip when the folder is absent), cut down
in memory to their motorway network (motorway/trunk ways, the ordinary ways
touching them, their nodes) so that mutations hit what the import reads.
Mutations: ``ref`` tags set to hostile text (spaces, ``;``, ``/``, ``..``, any
script), attribute values and tags swapped, lines dropped, duplicated or
swapped, XML tricks pasted in, the file cut short. Each either loads or raises a
FlyoverError naming the file; the city import writes nothing outside its output
folder and names every interchange safely.
"""

from __future__ import annotations

import json
import os
import re
from functools import lru_cache
from pathlib import Path
from xml.etree import ElementTree as ET
from xml.sax.saxutils import escape, quoteattr

import pytest
from hypothesis import given
from hypothesis import strategies as st

from flyover.errors import FlyoverError
from flyover.osm import OsmOptions, read_osm_topologies
from flyover.topology.names import is_safe_name
from tests.fuzz_support import (
    HOSTILE_WORDS,
    assert_names_file,
    fuzz,
    hard_timeout,
    import_stays_inside,
    loads_or_names_file,
    mutated_xml,
    sandbox,
    write_text,
)

#: the team's shared extracts: FLYOVER_OSM_DIR, else ../shared/osm beside the checkout
OSM_DIR = Path(os.environ.get("FLYOVER_OSM_DIR") or Path(__file__).resolve().parents[2] / "shared" / "osm")
needs_osm = pytest.mark.skipif(not OSM_DIR.is_dir(), reason=f"no real OSM extracts at {OSM_DIR} "
                               "(ODbL data is read from the shared folder, never copied here)")

_NETWORK = {"motorway", "motorway_link", "trunk", "trunk_link"}
WORDS = ["motorway", "motorway_link", "trunk", "trunk_link", "primary", "residential", "yes", "no", "-1",
         "1", "reversible", "A 1", "A 9;A 70", "I 5;US 30", "2", "3", "highway", "ref", "oneway", "lanes",
         "ele", "123 m", "node", "way", "nd", "tag"]
OPTIONS = [OsmOptions(), OsmOptions(keep_exits=True), OsmOptions(trunk_as_motorway=True, keep_exits=True),
           OsmOptions(snap_tolerance_m=0.0, cluster_distance_m=5000.0)]


def _line(el: ET.Element) -> str:
    attrs = "".join(f" {k}={quoteattr(v)}" for k, v in el.attrib.items())
    kids = list(el)
    if not kids:
        return f"  <{el.tag}{attrs}/>\n"
    inner = "".join(f"    <{c.tag}" + "".join(f" {k}={quoteattr(v)}" for k, v in c.attrib.items()) + "/>\n"
                    for c in kids)
    return f"  <{el.tag}{attrs}>\n{inner}  </{el.tag}>\n"


@lru_cache(maxsize=None)
def motorway_network(name: str) -> str:
    """The motorway network of ``OSM_DIR/name`` as OSM XML text, one element or child per line."""
    root = ET.parse(OSM_DIR / name).getroot()
    ways = [w for w in root.iter("way")
            if any(t.get("k") == "highway" and t.get("v") in _NETWORK for t in w.iter("tag"))]
    needed = {nd.get("ref") for w in ways for nd in w.iter("nd")}
    touching = [w for w in root.iter("way") if w not in ways
                and any(nd.get("ref") in needed for nd in w.iter("nd"))][:15]
    needed |= {nd.get("ref") for w in touching for nd in w.iter("nd")}
    nodes = [n for n in root.iter("node") if n.get("id") in needed]
    body = "".join(_line(e) for e in nodes + ways + touching)
    return f"<?xml version='1.0' encoding='UTF-8'?>\n<osm version=\"0.6\">\n{body}</osm>\n"


SEEDS = sorted(p.name for p in OSM_DIR.glob("*.osm")) if OSM_DIR.is_dir() else []


@st.composite
def mutated_osm(draw) -> str:
    """A seed's motorway network with hostile refs and/or generic XML mutations."""
    text = motorway_network(draw(st.sampled_from(SEEDS)))
    refs = [m.span(1) for m in re.finditer(r'<tag k="ref" v="([^"]*)"', text)]
    for _ in range(draw(st.integers(0, 3)) if refs else 0):
        a, b = refs[draw(st.integers(0, len(refs) - 1))]
        new = escape(draw(st.sampled_from(HOSTILE_WORDS) | st.text(max_size=40)), {'"': "&quot;"})
        text = text[:a] + new + text[b:]
        refs = [m.span(1) for m in re.finditer(r'<tag k="ref" v="([^"]*)"', text)]
    if draw(st.booleans()):
        text = draw(mutated_xml(text, WORDS))
    return text


@needs_osm
def test_seeds_are_the_real_interchanges():
    """The cut-down networks still hold the extracts' interchanges (mutations start from them)."""
    with sandbox() as root:
        found = sum(len(read_osm_topologies(write_text(root / s, motorway_network(s)), OsmOptions()))
                    for s in SEEDS)
    assert found >= 10


@needs_osm
@fuzz(0.7)
@given(text=mutated_osm(), options=st.sampled_from(OPTIONS), do_import=st.integers(0, 7))
def test_fuzz_osm_loads_or_names_the_file(text, options, do_import):
    with sandbox() as root:
        folder = root / "in"
        folder.mkdir()
        path = write_text(folder / "extract.osm", text)
        found = loads_or_names_file(lambda p: read_osm_topologies(p, options), path)
        for t in found or []:
            assert is_safe_name(t.name), t.name
        if do_import == 0:  # the import draws a PNG per interchange (~0.2 s): one case in eight
            index = _import(path, root, options)
            assert len(index["interchanges"]) + len(index["rejected"]) >= (found is None) + len(found or [])


def _import(path: Path, root: Path, options: OsmOptions) -> dict:
    import flyover.osm as osm

    saved = osm.default_options
    osm.default_options = lambda: options  # the import reads with these options
    try:
        return import_stays_inside([path], root)
    finally:
        osm.default_options = saved


@needs_osm
@fuzz(0.3)
@given(seed=st.sampled_from(SEEDS), ref=st.sampled_from(HOSTILE_WORDS) | st.text(min_size=1, max_size=60))
def test_fuzz_hostile_refs_give_safe_stable_names_shown_in_the_index(seed, ref):
    """Every ``ref`` of the extract set to one hostile text: names stay safe and stable,
    and index.json shows which ref became which part of the name."""
    text = re.sub(r'(<tag k="ref" v=")[^"]*(")', lambda m: m.group(1) + escape(ref, {'"': "&quot;"})
                  + m.group(2), motorway_network(seed))
    with sandbox() as root:
        path = write_text(root / "in.osm", text)
        first = loads_or_names_file(lambda p: read_osm_topologies(p, OsmOptions()), path)
        again = loads_or_names_file(lambda p: read_osm_topologies(p, OsmOptions()), path)
        assert [t.name for t in first or []] == [t.name for t in again or []]
        if first:
            index = _import(path, root, OsmOptions())
            assert {i["interchange"] for i in index["interchanges"]} == {t.name for t in first}
            for item in index["interchanges"]:
                assert all(is_safe_name(part) for part in item["name_from"]["refs"].values())
                assert item["interchange"].startswith("_".join(item["name_from"]["refs"].values())[:50])
            written = json.loads((Path(index["interchanges"][0]["graphml"]).parent / "index.json").read_text())
            assert written["interchanges"] == index["interchanges"]


@needs_osm
def test_refs_with_slashes_and_semicolons_are_mapped_and_shown(tmp_path):
    """A ref such as 'A 1/E 20;../x' (real data has '/', ';' and spaces) becomes a safe part."""
    seed = "13_pt_porto_a41_a43.osm"
    if seed not in SEEDS:
        pytest.skip(f"{seed} not in {OSM_DIR}")
    text = motorway_network(seed).replace('v="A 41"', 'v="A 41/E 1;../../x"')
    assert 'A 41/E 1;../../x' in text
    with sandbox() as root:
        path = write_text(root / "porto.osm", text)
        index = _import(path, root, OsmOptions())
    [item] = index["interchanges"]
    assert item["name_from"]["refs"] == {"../../x;A41/E1": "x-A41-E1", "A43": "A43"}
    assert item["interchange"] == "x-A41-E1_A43_1260536824"


def test_unknown_xml_encoding_is_named(tmp_path):
    path = tmp_path / "enc.osm"
    path.write_text('<?xml version="1.0" encoding="road"?>\n<osm version="0.6"/>\n')
    with pytest.raises(FlyoverError, match="malformed OSM XML") as info:
        read_osm_topologies(path, OsmOptions())
    assert_names_file(info.value, path)


def _tiny_osm(lat_far: str = "0.001") -> str:
    """Two motorways crossing, joined by one link whose middle node lies at ``lat_far``."""
    nodes = {1: (0, -0.01), 2: (0, 0.01), 3: (-0.01, 0.002), 4: (0.01, 0.002), 5: (0, -0.002),
             6: (lat_far, 0.0), 7: (0.008, 0.002)}
    ways = [(10, [1, 5, 2], "motorway", "A 1"), (11, [3, 7, 4], "motorway", "B 2"),
            (12, [5, 6, 7], "motorway_link", None)]
    out = ["<?xml version='1.0' encoding='UTF-8'?>", '<osm version="0.6">']
    out += [f'  <node id="{k}" lat="{la}" lon="{lo}"/>' for k, (la, lo) in nodes.items()]
    for wid, nds, hw, ref in ways:
        out.append(f'  <way id="{wid}">' + "".join(f'<nd ref="{n}"/>' for n in nds)
                   + f'<tag k="highway" v="{hw}"/><tag k="oneway" v="yes"/>'
                   + (f'<tag k="ref" v="{ref}"/>' if ref else "") + "</way>")
    return "\n".join(out + ["</osm>", ""])


@pytest.mark.parametrize("lat", ["89.9", "1e5", "nan", "inf", "-91"])
def test_coordinates_far_or_off_the_globe_stay_bounded(tmp_path, lat):
    """Found by the long fuzz run: a link node moved to lat 1e5 made a ramp astronomically
    long and min_radius tried to resample it every 10 m (a hang, or numpy's 'Maximum allowed
    size exceeded'). Coordinates off the globe are now treated as missing nodes, and
    min_radius takes at most MAX_SAMPLES points whatever the length."""
    path = write_text(tmp_path / "far.osm", _tiny_osm(lat))
    found = loads_or_names_file(lambda p: read_osm_topologies(p, OsmOptions()), path)
    for t in found or []:
        assert is_safe_name(t.name)


def test_min_radius_work_is_bounded_by_max_samples():
    import numpy as np

    from flyover.osm.geom import MAX_SAMPLES, min_radius

    xy = np.array([[0.0, 0.0], [1e12, 0.0], [1e12, 1e12]])
    with hard_timeout(10):
        r = min_radius(xy)
    assert r > 1e12 / MAX_SAMPLES
