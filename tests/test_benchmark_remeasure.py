"""The geometry benchmark's re-measure from the .xodr (benchmarks/geometry.py): the centre
of a ramp's own lanes, followed through the lane links, is what is measured."""

import importlib.util
from pathlib import Path

from flyover.clients.designs import catalog_geometry


def _benchmark():
    path = Path(__file__).resolve().parents[1] / "benchmarks" / "geometry.py"
    spec = importlib.util.spec_from_file_location("geometry_bench", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_a_carriageways_lanes_closing_on_a_ramp_are_not_its_own():
    """Semi-directional T, feature set 1: the carriageway ending into the left turn rL
    (one lane) hands it all its lanes; the extra ones close on rL's body, outermost first
    (export version 11). Followed from the link, they were counted as rL's own, and the
    centre of 'its lanes' swung across as they closed: 184.6 m read for a 203.7 m turn
    (a 200 m target). Its own lane's centre is the line width / 2 right of its reference
    line there: both measures agree."""
    bench = _benchmark()
    g = catalog_geometry("semidirectional_t", 1)
    measured = bench.remeasure(g)
    for r in g.ramps:
        own, _, ref, _ = measured[r.id]
        assert abs(own - ref) <= 0.02 * ref, (r.id, own, ref)
