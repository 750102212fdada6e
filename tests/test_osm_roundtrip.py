"""Round trip: generated interchange geometry → OSM XML → import → the same class.

Needs the geometry stage's layout (``flyover.geometry.layout``); a short fit
(60 generations) is enough: sides are read back from the plan view only.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from flyover.osm import OsmOptions, read_osm_topologies
from flyover.osm.geom import point_at
from flyover.topology import class_id
from flyover.topology.catalog import catalog_topologies

layout = pytest.importorskip("flyover.geometry.layout")
fit = pytest.importorskip("flyover.geometry.fit")

sys.path.insert(0, str(Path(__file__).resolve().parent))
from test_osm import write_osm  # noqa: E402  (the OSM XML writer of the unit tests)

CATALOG = catalog_topologies()


def _bezier(p, m=24):
    p = np.asarray(p, float)
    t = np.linspace(0.0, 1.0, m)[:, None]
    return ((1 - t) ** 3 * p[0] + 3 * (1 - t) ** 2 * t * p[1] + 3 * (1 - t) * t ** 2 * p[2] + t ** 3 * p[3])


def geometry_to_ways(geo):
    """OSM ways of an :class:`InterchangeGeometry`: reference lines as motorways, ramp
    plans as links whose ends are moved onto their parents at the attachment points."""
    lines = {}
    for r in geo.roads:
        start = np.array(r.start, float)
        d = np.array([np.cos(r.heading_rad), np.sin(r.heading_rad)])
        lines[r.id] = np.array([start, start + r.length_m * d])
    for r in geo.ramps:
        pts = np.concatenate([_bezier(piece.p)[(1 if k else 0):] for k, piece in enumerate(r.plan)])
        lines[r.id] = pts

    def anchor(att):
        parent = lines[att.parent]
        total = float(np.hypot(*np.diff(parent, axis=0).T).sum())
        s = 0.0 if att.s_m < 0.5 else total if att.s_m > total - 0.5 else att.s_m
        return tuple(point_at(parent, s))

    ends = {r.id: (anchor(r.start) if r.start else None, anchor(r.end) if r.end else None) for r in geo.ramps}
    ways = [{"points": [tuple(p) for p in lines[r.id]],
             "tags": {"highway": "motorway", "ref": r.expressway, "oneway": "yes"}} for r in geo.roads]
    for r in geo.ramps:
        a, b = ends[r.id]
        pts = [tuple(p) for p in lines[r.id]]
        pts = ([a] if a else []) + pts[1:-1] + ([b] if b else [])
        ways.append({"points": pts, "tags": {"highway": "motorway_link"}})
    return ways


@pytest.mark.parametrize("design", ["trumpet", "cloverleaf", "semidirectional_t"])
def test_generated_interchange_survives_osm_round_trip(tmp_path, design):
    topo = CATALOG[design]
    feats = {r: layout.RampFeatures(radius_m=80.0, slope_pct=4.0) for r in topo.ramps}
    settings = layout.LayoutSettings(fit=fit.FitSettings(popsize=8, maxiter=60, min_generations=10),
                                     max_resamples=0)
    for seed in (1, 2, 3):  # the round trip is about the import: use a geometry whose ramps all fit
        geo = layout.build_interchange(topo, {}, feats, class_id=class_id(topo), seed=seed,
                                       settings=settings).geometry
        if all(r.ok for r in geo.ramps):
            break
    else:
        pytest.skip(f"no valid generated {design} geometry in 3 seeds: "
                    f"{[(r.id, r.infeasible) for r in geo.ramps if not r.ok]}")
    path = write_osm(tmp_path / f"{design}.osm", geometry_to_ways(geo))
    ts = read_osm_topologies(path, OsmOptions(stem_length_m=0.0))
    assert len(ts) == 1
    assert class_id(ts[0]) == class_id(topo)
