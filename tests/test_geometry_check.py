"""The independent dense same-level check of a geometry.json value."""

import math

import pytest

from flyover.geometry.check import same_level_conflicts
from flyover.geometry.model import (Attachment, BezierPiece, ElevationPoly, InterchangeGeometry,
                                    RampGeometry, RoadGeometry)


def _straight(id_, p0, p1, z=0.0, lanes=1):
    """A straight one-lane ramp from p0 to p1 at height z (one cubic piece)."""
    (x0, y0), (x1, y1) = p0, p1
    ctrl = tuple((x0 + (x1 - x0) * t, y0 + (y1 - y0) * t) for t in (0, 1 / 3, 2 / 3, 1))
    length = math.hypot(x1 - x0, y1 - y0)
    h = math.atan2(y1 - y0, x1 - x0)
    return RampGeometry(
        id=id_, lanes=lanes, plan=(BezierPiece(ctrl, length),),
        elevation=(ElevationPoly(0.0, z, 0.0, 0.0, 0.0),),
        start=Attachment("", "", 0.0, 0.0, h, z), end=Attachment("", "", 0.0, 0.0, h, z),
        target_radius_m=math.inf, target_slope_pct=0.0, min_radius_m=math.inf,
        max_slope_pct=0.0, length_m=length)


def _loop(id_, rise_m, radius=50.0, lead=200.0):
    """A one-lane ramp east along y = 0 to (0, 0), 270 degrees left around (0, radius), then
    south: it crosses its own lead-in at x = -radius, climbing ``rise_m`` in between."""
    k = 4.0 / 3.0 * math.tan(math.pi / 8) * radius  # a quarter circle's Bézier handle
    pieces = [BezierPiece(((-lead, 0.0), (-2 * lead / 3, 0.0), (-lead / 3, 0.0), (0.0, 0.0)),
                          lead)]
    p, h = (0.0, 0.0), 0.0
    for _ in range(3):
        c = (p[0] - radius * math.sin(h), p[1] + radius * math.cos(h))  # the centre
        q = (c[0] + radius * math.sin(h + math.pi / 2), c[1] - radius * math.cos(h + math.pi / 2))
        h2 = h + math.pi / 2
        pieces.append(BezierPiece((p, (p[0] + k * math.cos(h), p[1] + k * math.sin(h)),
                                   (q[0] - k * math.cos(h2), q[1] - k * math.sin(h2)), q),
                                  radius * math.pi / 2))
        p, h = q, h2
    pieces.append(BezierPiece((p, (p[0], p[1] - lead / 3), (p[0], p[1] - 2 * lead / 3),
                               (p[0], p[1] - lead)), lead))
    length = sum(q.length_m for q in pieces)
    apart = 1.5 * math.pi * radius + 2 * radius  # stations of the crossing, along the ramp
    grade = rise_m / apart
    return RampGeometry(
        id=id_, lanes=1, plan=tuple(pieces),
        elevation=(ElevationPoly(0.0, 0.0, grade, 0.0, 0.0),),
        start=Attachment("", "", 0.0, 0.0, 0.0, 0.0),
        end=Attachment("", "", 0.0, 0.0, -math.pi / 2, grade * length),
        target_radius_m=radius, target_slope_pct=100 * grade, min_radius_m=radius,
        max_slope_pct=100 * grade, length_m=length)


def _geometry(*ramps, roads=()):
    return InterchangeGeometry("c0", 0, 1, levels_m=(0.0, 6.5), roads=roads, ramps=ramps)


def test_two_ramps_crossing_at_one_level_conflict_once_each_crossing():
    a = _straight("a", (-200.0, 0.0), (200.0, 0.0))
    b = _straight("b", (0.0, -200.0), (0.0, 200.0))
    found = same_level_conflicts(_geometry(a, b))
    assert [(c.ramp, c.other) for c in found] == [("a", "b")]
    c = found[0]
    # the lane centres are 2 m right of the reference lines: they cross at (2, -2), and
    # are closer than the two half widths (less the margins: 3 m) from x = -1 to 5
    assert c.s_m == pytest.approx(199.0, abs=0.6) and c.length_m == pytest.approx(6.0, abs=1.2)
    assert c.dz_m == 0.0


def test_ramps_a_clearance_apart_or_side_by_side_do_not_conflict():
    a = _straight("a", (-200.0, 0.0), (200.0, 0.0))
    over = _straight("b", (0.0, -200.0), (0.0, 200.0), z=6.5)
    assert same_level_conflicts(_geometry(a, over)) == ()
    beside = _straight("c", (-200.0, -4.0), (200.0, -4.0))  # the next lane to the right
    assert same_level_conflicts(_geometry(a, beside)) == ()
    overlapping = _straight("d", (-200.0, -2.5), (200.0, -2.5))
    (c,) = same_level_conflicts(_geometry(a, overlapping))
    assert c.length_m == pytest.approx(400.0 - 2 * 15.0, abs=1.0)  # but the end zones


def test_a_ramp_on_a_road_at_its_height_conflicts_and_names_the_road():
    road = RoadGeometry("A1", "A", 3, 0, 0.0, (-500.0, 10.0), 0.0, 1000.0)  # lanes y 10 .. -1.25
    ramp = _straight("r", (0.0, -100.0), (0.0, 100.0))
    (c,) = same_level_conflicts(_geometry(ramp, roads=(road,)))
    assert (c.ramp, c.other) == ("r", "A1")
    # lane centre x = 2: on the lanes (plus its half width) from y = -2.75 to 11.5
    assert c.s_m == pytest.approx(100.0 - 2.75, abs=0.6)
    assert c.length_m == pytest.approx(14.25, abs=1.2)
    up = _straight("r", (0.0, -100.0), (0.0, 100.0), z=5.6)
    assert same_level_conflicts(_geometry(up, roads=(road,))) == ()


def test_a_loop_passing_under_itself_below_the_clearance_conflicts_with_itself():
    (c,) = same_level_conflicts(_geometry(_loop("l", 3.5)))
    assert (c.ramp, c.other) == ("l", "l")
    # the lane centre (its half width right of the reference line: outside the loop)
    # crosses its own lead-in at x = -52 (station 148), 3.5 m under the loop's last leg
    assert c.s_m < 148.0 < c.s_m + c.length_m and c.length_m < 8.0
    assert c.dz_m == pytest.approx(3.5, abs=0.2)


def test_a_loop_clearing_itself_or_a_plain_curve_has_no_self_conflict():
    assert same_level_conflicts(_geometry(_loop("l", 6.0))) == ()
    # a tight curve's neighbouring stations are never a crossing (a level loop's are)
    assert [c.other for c in same_level_conflicts(_geometry(_loop("l", 0.0, radius=15.0)))] \
        == ["l"]


def test_the_clearance_row_names_the_file_and_what_meets_what(tmp_path):
    from flyover.geometry.model import write_geometry
    from flyover.opendrive.pipeline import clearance_check

    path = tmp_path / "geometry.json"
    write_geometry(_geometry(_straight("a", (-200.0, 0.0), (200.0, 0.0)),
                             _straight("b", (0.0, -200.0), (0.0, 200.0))), path)
    row = clearance_check(path)
    assert row.check == "clearance" and not row.ok
    assert row.detail.startswith(f"{path}: a meets b at s=199 m") and "\n" not in row.detail
    write_geometry(_geometry(_straight("a", (-200.0, 0.0), (200.0, 0.0)),
                             _straight("b", (0.0, -200.0), (0.0, 200.0), z=6.5)), path)
    assert clearance_check(path).ok
    assert not clearance_check(path, clearance_m=7.0).ok
    write_geometry(_geometry(_loop("l", 3.5)), path)
    row = clearance_check(path)
    assert not row.ok and row.detail.startswith(f"{path}: l meets l at s=1")
    write_geometry(_geometry(_loop("l", 6.0)), path)
    assert clearance_check(path).ok


def test_ramp_crossings_of_chosen_pairs_are_those_of_every_pair():
    """``pairs`` keeps the crossings of those pairs only, the same as among all."""
    from flyover.geometry.check import ramp_crossings  # noqa: PLC0415
    from flyover.geometry.layout import RampFeatures, build_interchange  # noqa: PLC0415
    from flyover.topology.catalog import catalog_topologies  # noqa: PLC0415

    topo = catalog_topologies()["cloverstack"]
    ic = build_interchange(topo, {}, {r: RampFeatures(150.0, 3.0) for r in topo.ramps},
                           seed=3)
    every = ramp_crossings(ic.geometry)
    assert every
    pairs = {frozenset((c.ramp, c.other)) for c in every[::2]} | {frozenset(("oA1", "lB1"))}
    assert ramp_crossings(ic.geometry, pairs=pairs) == tuple(
        c for c in every if frozenset((c.ramp, c.other)) in pairs)
    assert ramp_crossings(ic.geometry, pairs=set()) == ()
