"""OSM import on the real extracts of ``../shared/osm/`` (ODbL; read in place, never copied).

Skipped where that folder does not exist.
"""

from __future__ import annotations

import os
from pathlib import Path
from xml.etree.ElementTree import iterparse

import networkx as nx
import pytest

from flyover.osm import OsmOptions, read_osm_topologies
from flyover.topology import Kind, class_id
from flyover.topology.catalog import catalog_topologies

#: the team's shared extracts: FLYOVER_OSM_DIR, else ../shared/osm beside the checkout
OSM_DIR = Path(os.environ.get("FLYOVER_OSM_DIR")
               or Path(__file__).resolve().parents[2] / "shared" / "osm")
pytestmark = pytest.mark.skipif(not OSM_DIR.is_dir(), reason=f"no real OSM extracts at {OSM_DIR}")
CATALOG = catalog_topologies()


def _one(stem):
    ts = read_osm_topologies(OSM_DIR / f"{stem}.osm", OsmOptions())
    assert len(ts) == 1, [t.summary() for t in ts]
    return ts[0]


def _link_ways(stem):
    out = set()
    for _, el in iterparse(OSM_DIR / f"{stem}.osm"):
        if el.tag == "way" and any(t.get("k") == "highway" and t.get("v") == "motorway_link"
                                   for t in el if t.tag == "tag"):
            out.add(int(el.get("id")))
        if el.tag in ("node", "way", "relation"):
            el.clear()
    return out


def _movements(t):
    """(from road, to road) pairs of two expressways joined by a path through ramps only."""
    g = t.graph
    ramps = g.subgraph(t.ramps)
    out = set()
    for r in t.roads:
        for _, first in g.out_edges(r):
            for ramp in nx.descendants(ramps, first) | {first}:
                out |= {(r, v) for _, v in g.out_edges(ramp) if g.nodes[v]["kind"] is Kind.ROAD
                        and g.nodes[v]["expressway"] != g.nodes[r]["expressway"]}
    return out


def _accounted(stem, t):
    in_ramps = {int(w) for r in t.ramps for w in t.graph.nodes[r]["osm_ways"].split()}
    ignored = {int(w) for w in t.attrs["osm"]["ignored_links"]}
    return _link_ways(stem) - in_ramps - ignored, in_ramps


def test_bangor_full_cloverleaf_is_the_catalog_cloverleaf():
    t = _one("06_us_me_bangor_i95_i395")
    assert class_id(t) == class_id(CATALOG["cloverleaf"])
    assert t.shape == "cross" and set(t.expressways) == {"I395", "I95"}
    assert len(_movements(t)) == 8
    missing, _ = _accounted("06_us_me_bangor_i95_i395", t)
    assert not missing


def test_porto_trumpet_is_the_catalog_trumpet():
    t = _one("13_pt_porto_a41_a43")
    assert class_id(t) == class_id(CATALOG["trumpet"])
    assert t.shape == "T" and set(t.expressways) == {"A41", "A43"}
    assert "treated as motorway_link" in "\n".join(t.attrs["osm"]["quirks"])  # way 138837139
    loop = max(t.ramps, key=lambda r: -t.graph.nodes[r]["min_radius_m"])
    assert t.graph.nodes[loop]["min_radius_m"] < 100


def test_bayreuth_dreieck_is_a_valid_t_with_every_ramp_accounted_for():
    stem = "02_de_bayreuth_dreieck_a9_a70"
    t = _one(stem)
    assert t.shape == "T" and set(t.expressways) == {"A70", "A9"}
    assert len(_movements(t)) == 4
    notes = "\n".join(t.attrs["osm"]["quirks"])
    assert "way 24157038: link end" in notes and "snapped" in notes
    assert "oneway=no" in notes
    missing, in_ramps = _accounted(stem, t)
    assert not missing
    assert 24157038 in in_ramps and 4834250 not in in_ramps  # the service exit is a distractor


def test_columbus_hybrid_is_valid_with_every_ramp_accounted_for():
    stem = "09_us_oh_columbus_i70_i270_west"
    t = _one(stem)
    assert t.shape == "cross" and set(t.expressways) == {"I270", "I70"}
    assert len(_movements(t)) == 8
    missing, in_ramps = _accounted(stem, t)
    assert not missing
    loops = [r for r in t.ramps if t.graph.nodes[r]["min_radius_m"] < 80]
    assert loops  # the loop ramps, split over several ways, are measured as such
