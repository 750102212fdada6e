"""SUMO: netconvert from the eclipse-sumo wheel and routability with sumolib, for real."""

from __future__ import annotations

import pytest

from flyover.opendrive.reader import read_xodr
from flyover.opendrive.samples import sample_geometry
from flyover.opendrive.writer import write_xodr
from flyover.sumo.netconvert import run_netconvert
from flyover.sumo.routes import Movement, check_routes, generic_routes, road_edges

pytestmark = pytest.mark.integration


@pytest.fixture(scope="module")
def loop_net(tmp_path_factory):
    d = tmp_path_factory.mktemp("sumo")
    write_xodr(sample_geometry("loop"), d / "loop.xodr")
    res = run_netconvert(d / "loop.xodr", d / "loop.net.xml")
    return d, res


def _ends(xodr, name):
    net = read_xodr(xodr)
    first = next(r.id for r in net.roads.values() if r.name == name and r.predecessor is None)
    last = next(r.id for r in net.roads.values() if r.name == name and r.successor is None)
    return first, last


def test_netconvert_converts_without_errors(loop_net):
    d, res = loop_net
    assert res.ok and res.errors == ()
    assert (d / "loop.net.xml").stat().st_size > 1000


def test_every_opendrive_road_maps_to_sumo_edges(loop_net):
    d, _ = loop_net
    import sumolib

    edges = road_edges(sumolib.net.readNet(str(d / "loop.net.xml")))
    roads = {r.id for r in read_xodr(d / "loop.xodr").roads.values() if r.junction == "-1"}
    assert roads <= set(edges)


def test_allowed_movement_routes_and_forbidden_one_does_not(loop_net):
    d, _ = loop_net
    a1, b1 = _ends(d / "loop.xodr", "A1"), _ends(d / "loop.xodr", "B1")
    ok, detail, failed = check_routes(d / "loop.net.xml", [Movement("A1->B1", a1[0], b1[1])])
    assert ok and "1/1" in detail
    # the loop only turns A1 into B1: B1 cannot reach the end of A1
    ok, _, failed = check_routes(d / "loop.net.xml", [Movement("B1->A1", b1[0], a1[1])])
    assert not ok and failed == ["B1->A1"]


def test_generic_routes_on_any_network(loop_net):
    d, _ = loop_net
    ok, detail = generic_routes(d / "loop.net.xml")
    assert ok and "2 entry and 2 exit edges" in detail


def test_netconvert_failure_is_reported_and_leaves_no_file(tmp_path):
    bad = tmp_path / "bad.xodr"
    bad.write_text('<OpenDRIVE><header revMajor="1" revMinor="8"/><road id="1" length="10">'
                   '<planView/></road></OpenDRIVE>')
    res = run_netconvert(bad, tmp_path / "bad.net.xml")
    assert not res.ok and res.errors
    assert not (tmp_path / "bad.net.xml").exists()
