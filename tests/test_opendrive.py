"""OpenDRIVE export and validation on small generated interchanges (loop, flyover, T)."""

from __future__ import annotations

import io
import math

import numpy as np
import pytest
from lxml import etree

from flyover.opendrive.continuity import check_continuity
from flyover.opendrive.reader import read_xodr
from flyover.opendrive.samples import SAMPLES, detached_ramp, sample_geometry
from flyover.opendrive.validate import movements, xsd_errors
from flyover.opendrive.writer import ExportError, ExportOptions, xodr_bytes


@pytest.fixture(scope="module")
def xodrs(tmp_path_factory):
    root = tmp_path_factory.mktemp("xodr")
    out = {}
    for kind in SAMPLES:
        path = root / f"{kind}.xodr"
        path.write_bytes(xodr_bytes(sample_geometry(kind)))
        out[kind] = path
    return out


@pytest.mark.parametrize("kind", SAMPLES)
def test_written_file_is_valid_against_the_asam_xsd(xodrs, kind):
    net = read_xodr(xodrs[kind])
    assert net.version == (1, 8)
    assert xsd_errors(xodrs[kind], net.version) == []


@pytest.mark.parametrize("kind", SAMPLES)
def test_every_road_is_named_after_its_topology_element(xodrs, kind):
    g = sample_geometry(kind)
    names = {r.name for r in read_xodr(xodrs[kind]).roads.values()}
    assert names == {r.id for r in g.roads} | {r.id for r in g.ramps}


@pytest.mark.parametrize("kind", SAMPLES)
def test_roads_are_lines_and_ramps_are_normalized_parampoly3(xodrs, kind):
    doc = etree.parse(str(xodrs[kind]))
    ramps = {r.id for r in sample_geometry(kind).ramps}
    for road in doc.iter("road"):
        kinds = {g[0].tag for g in road.iter("geometry")}
        assert kinds == ({"paramPoly3"} if road.get("name") in ramps else {"line"})
    assert {p.get("pRange") for p in doc.iter("paramPoly3")} == {"normalized"}


@pytest.mark.parametrize("kind", SAMPLES)
def test_a_ramps_height_where_a_reader_puts_it_is_the_geometrys_height_there(xodrs, kind):
    # readers place road position s of a normalized paramPoly3 at p = s/length, not at arc
    # length s, while heights are written along arc length: one paramPoly3 per Bézier piece
    # put a ramp's heights up to 47 m (here; 356 m on the catalog) from their place
    from flyover.geometry.bezier import sample_spline
    from flyover.geometry.profile import evaluate_polys
    g, net = sample_geometry(kind), read_xodr(xodrs[kind])
    worst = 0.0
    for ramp in g.ramps:
        smp = sample_spline(np.array([p.p for p in ramp.plan], float), 4000)
        z_geo, _ = evaluate_polys(ramp.elevation, smp.s)
        for road in (r for r in net.roads.values() if r.name == ramp.id):
            x, y, z, _ = road.reference(np.linspace(0.0, road.length, 41)[1:-1])
            for xi, yi, zi in zip(x, y, z):
                d = np.hypot(smp.xy[:, 0] - xi, smp.xy[:, 1] - yi)
                assert d.min() < 0.6  # on the ramp (its ends snapped by at most 0.5 m)
                worst = max(worst, abs(zi - z_geo[np.argmin(d)]))
    assert worst < 0.01, worst


@pytest.mark.parametrize("kind", SAMPLES)
def test_links_agree_both_ways(xodrs, kind):
    net = read_xodr(xodrs[kind])
    for r in net.roads.values():
        for mine, end in (("successor", "end"), ("predecessor", "start")):
            link = getattr(r, mine)
            if link is None or link[0] != "road":
                continue
            other = net.roads[link[1]]
            back = getattr(other, "predecessor" if link[2] == "start" else "successor")
            if other.junction != "-1" and r.junction == "-1":
                # incoming road -> connecting road is listed in the junction
                assert any(c.connecting == other.id and c.incoming == r.id
                           for c in net.junctions[other.junction].connections)
            elif r.junction != "-1" and other.junction == "-1":
                assert back is not None and back[:2] == ("junction", r.junction)
            else:
                assert back is not None and back[1] == r.id and back[2] == end


@pytest.mark.parametrize("kind", SAMPLES)
def test_elevation_matches_the_geometry_within_1cm(xodrs, kind):
    g = sample_geometry(kind)
    net = read_xodr(xodrs[kind])
    for ramp in g.ramps:
        pieces = sorted((r for r in net.roads.values() if r.name == ramp.id),
                        key=lambda r: r.reference(0.0)[0][0] * 0 + _start_s(net, r, ramp.id))
        s_total = 0.0
        for r in pieces:
            s = np.linspace(0.0, r.length, 7)
            z = r.reference(s)[2]
            expect = [_geom_z(ramp, s_total + si) for si in s]
            assert np.allclose(z, expect, atol=0.01)
            s_total += r.length


def _geom_z(ramp, s):
    rec = [e for e in ramp.elevation if e.s_m <= s + 1e-9][-1]
    ds = s - rec.s_m
    return rec.a + rec.b * ds + rec.c * ds ** 2 + rec.d * ds ** 3


def _start_s(net, road, name):
    """Position of a piece along its element: count predecessors with the same name."""
    n, r = 0, road
    while r.predecessor is not None:
        if r.predecessor[0] == "road":
            prev = net.roads[r.predecessor[1]]
        else:
            j = net.junctions[r.predecessor[1]]
            prev = next((net.roads[c.connecting] for c in j.connections
                         if net.roads[c.connecting].name == name
                         and net.roads[c.connecting].successor[1] == r.id), None)
            if prev is None:
                break
        if prev.name != name:
            break
        n, r = n + 1, prev
    return n


@pytest.mark.parametrize("kind", SAMPLES)
def test_lane_ends_meet_in_3d_at_every_link(xodrs, kind):
    ok, detail = check_continuity(read_xodr(xodrs[kind]))
    assert ok, detail


def test_continuity_check_catches_a_gap(xodrs, tmp_path):
    doc = etree.parse(str(xodrs["loop"]))
    geo = next(r for r in doc.iter("road") if r.get("name") == "r1").find("planView/geometry")
    geo.set("x", repr(float(geo.get("x")) + 0.05))
    bad = tmp_path / "bad.xodr"
    doc.write(str(bad))
    ok, detail = check_continuity(read_xodr(bad))
    assert not ok
    assert " 0 off" not in detail and "xy 0.05" in detail


@pytest.mark.parametrize("kind", SAMPLES)
def test_lane_headings_are_read_without_finite_difference_error(xodrs, kind):
    # lanes tapering with cubic widths up to a link once read as a 0.56 deg kink
    from flyover.opendrive.continuity import lane_link_gaps
    gaps = lane_link_gaps(read_xodr(xodrs[kind]))
    assert gaps and max(g.heading_deg for g in gaps) < 0.05


def test_continuity_check_catches_a_heading_kink(xodrs, tmp_path):
    doc = etree.parse(str(xodrs["loop"]))
    geo = next(r for r in doc.iter("road") if r.get("name") == "r1").find("planView/geometry")
    geo.set("hdg", repr(float(geo.get("hdg")) + math.radians(1.0)))
    bad = tmp_path / "kink.xodr"
    doc.write(str(bad))
    ok, detail = check_continuity(read_xodr(bad))
    assert not ok
    assert "heading 1.0" in detail


def test_continuity_check_catches_a_height_step(xodrs, tmp_path):
    doc = etree.parse(str(xodrs["flyover"]))
    road = next(r for r in doc.iter("road") if r.get("name") == "B1")
    el = road.find("elevationProfile/elevation")
    el.set("a", repr(float(el.get("a")) + 0.03))
    bad = tmp_path / "step.xodr"
    doc.write(str(bad))
    ok, detail = check_continuity(read_xodr(bad))
    assert not ok
    assert "z 0.03" in detail


def test_the_same_file_is_valid_when_declared_opendrive_1_7(tmp_path):
    path = tmp_path / "t17.xodr"
    path.write_bytes(xodr_bytes(sample_geometry("t"), ExportOptions(opendrive_minor=7)))
    net = read_xodr(path)
    assert net.version == (1, 7)
    assert xsd_errors(path, net.version) == []


def test_unsupported_version_is_rejected():
    with pytest.raises(ExportError, match="opendrive_minor"):
        ExportOptions(opendrive_minor=5)


def test_export_is_byte_reproducible():
    g = sample_geometry("t")
    assert xodr_bytes(g) == xodr_bytes(g)


def test_header_has_bounds_and_documents_the_frame(xodrs):
    head = etree.parse(str(xodrs["flyover"])).getroot().find("header")
    assert float(head.get("north")) > float(head.get("south"))
    assert float(head.get("east")) > float(head.get("west"))
    frame = [u.get("value") for u in head.iter("userData") if u.get("code") == "flyover:frame"]
    assert frame and "x east" in frame[0]


def test_ramp_far_from_its_attachment_is_rejected_naming_it():
    with pytest.raises(ExportError, match="r1"):
        xodr_bytes(detached_ramp(sample_geometry("loop")))


def test_movements_of_the_t_follow_ramps_downstream():
    assert movements(sample_geometry("t")) == [("A1", "A1"), ("A2", "A2"), ("C1", "A1"), ("C1", "A2")]


def test_movements_through_a_fork_reach_both_branches():
    assert movements(sample_geometry("fork")) == [("A1", "A1"), ("A1", "B2"), ("B2", "B2")]


def test_movements_of_a_carriageway_end_split_in_two():
    assert movements(sample_geometry("y")) == [("A1", "A1"), ("A2", "A2"), ("C1", "A1"), ("C1", "A2")]


def test_elevation_records_that_continue_one_polynomial_are_merged():
    from flyover.opendrive.reader import Cubic
    from flyover.opendrive.writer import _merge_same

    a = Cubic(0.0, 1.0, 0.1, 0.01, 0.0)
    same = Cubic(10.0, float(a(10.0)), 0.1 + 2 * 0.01 * 10, 0.01, 0.0)
    other = Cubic(20.0, 5.0, 0.0, 0.0, 0.0)
    assert _merge_same([a, same, other]) == [a, other]


def test_movements_of_the_loop():
    assert movements(sample_geometry("loop")) == [("A1", "A1"), ("A1", "B1"), ("B1", "B1")]


def test_heading_is_direction_agnostic_in_continuity():
    from flyover.opendrive.continuity import LinkGap

    assert LinkGap("a", "b", 0.0, 0.0, 0.2).ok(0.01, 0.5)
    assert not LinkGap("a", "b", 0.0, 0.02, 0.0).ok(0.01, 0.5)
    assert not LinkGap("a", "b", 0.0, 0.0, 0.6).ok(0.01, 0.5)
    assert LinkGap("a", "b", 0.0, 0.0, math.nan).ok(0.01, 0.5)


def _two_roads(x1: float, y1: float, h1: float) -> bytes:
    lanes = ('<lanes><laneSection s="0"><center><lane id="0" type="none"/></center><right>'
             '<lane id="-1" type="driving">{link}<width sOffset="0" a="3.5" b="0" c="0" d="0"/></lane>'
             '</right></laneSection></lanes>')
    return (f'<OpenDRIVE><header revMajor="1" revMinor="7"/>'
            f'<road id="1" length="100" junction="-1"><link><successor elementType="road" '
            f'elementId="2" contactPoint="start"/></link><planView>'
            f'<geometry s="0" x="0" y="0" hdg="0" length="50"><spiral curvStart="0" curvEnd="0.01"/></geometry>'
            f'<geometry s="50" x="49.688402921" y="4.148102427" hdg="0.25" length="50"><arc curvature="0.01"/></geometry>'
            f'</planView>' + lanes.format(link='<link><successor id="-1"/></link>') + '</road>'
            f'<road id="2" length="10" junction="-1"><link><predecessor elementType="road" '
            f'elementId="1" contactPoint="end"/></link><planView>'
            f'<geometry s="0" x="{x1!r}" y="{y1!r}" hdg="{h1!r}" length="10"><line/></geometry></planView>'
            + lanes.format(link='<link><predecessor id="-1"/></link>') + '</road></OpenDRIVE>').encode()


def test_reader_follows_spirals_and_arcs_of_other_tools(tmp_path):
    import io

    from flyover.opendrive.reader import read_xodr as rx

    probe = rx(io.BytesIO(_two_roads(0.0, 0.0, 0.0)))
    # the end of the clothoid (Fresnel integrals) is where the arc record starts
    x, y, _, h = (float(v[0]) for v in probe.roads["1"].reference(50.0 - 1e-7))
    assert abs(h - 0.25) < 1e-6 and abs(x - 49.688402921) < 1e-5 and abs(y - 4.148102427) < 1e-5
    x, y, _, h = (float(v[0]) for v in probe.roads["1"].reference(100.0))
    good = rx(io.BytesIO(_two_roads(x, y, h)))
    assert check_continuity(good)[0]
    bad = rx(io.BytesIO(_two_roads(x + 0.02, y, h)))
    assert not check_continuity(bad)[0]


def test_straight_on_branch_of_a_fork_changes_lane_width_over_a_taper_not_the_junction():
    """A carriageway of 3.75 m lanes ends by splitting into a straight-on ramp of 4 m lanes
    and a ramp beside it ("y"): the straight-on ramp's lane keeps the carriageway's width
    on its connecting road and widens over the taper on its body, so its centre line moves
    sideways gently (on the 15 m connecting road it moved 0.125 m: a bend of ~200 m radius
    that the ramp's own curve does not have)."""
    g = sample_geometry("y")
    net = read_xodr(io.BytesIO(xodr_bytes(g)))
    roads = sorted((r for r in net.roads.values() if r.name == "r1"), key=lambda r: int(r.id))
    conn, body = roads[0], roads[1]
    assert conn.junction != "-1" and body.junction == "-1"
    for s in (0.0, conn.length):
        inner, outer = conn.lane_t(-1, s, at_end=s > 0)
        assert abs(inner - outer) == pytest.approx(g.lane_width_m)
    drift = []
    for road in (conn, body):
        s = np.linspace(0.0, min(road.length, 120.0), 241)
        t = np.array([sum(road.lane_t(-1, x)) / 2 for x in s])
        drift.append(np.abs(np.diff(t) / np.diff(s)).max())
    assert max(drift) < 0.004
    end = body.lane_t(-1, 100.0)
    assert abs(end[0] - end[1]) == pytest.approx(g.ramp_lane_width_m)


def _lanes_ending_together(xodr: bytes) -> list[tuple]:
    """(road, section s, 'close'|'open', lane ids): lane sections where two driving lanes or
    more close to (open from) zero width together."""
    def width(recs, ds):
        s, a, b, c, d = [r for r in recs if r[0] <= ds + 1e-9][-1]
        t = ds - s
        return a + b * t + c * t * t + d * t ** 3

    out = []
    for road in etree.parse(io.BytesIO(xodr)).getroot().iter("road"):
        secs = road.findall("lanes/laneSection")
        for i, sec in enumerate(secs):
            s0 = float(sec.get("s"))
            s1 = float(secs[i + 1].get("s")) if i + 1 < len(secs) else float(road.get("length"))
            ends = {"close": [], "open": []}
            for lane in sec.findall("right/lane"):
                if lane.get("type") != "driving":
                    continue
                recs = [tuple(float(w.get(k)) for k in ("sOffset", "a", "b", "c", "d"))
                        for w in lane.findall("width")]
                w0, w1 = width(recs, 0.0), width(recs, s1 - s0)
                if w0 > 1e-6 and w1 < 1e-6:
                    ends["close"].append(lane.get("id"))
                if w0 < 1e-6 and w1 > 1e-6:
                    ends["open"].append(lane.get("id"))
            out += [(road.get("id"), s0, kind, ids) for kind, ids in ends.items() if len(ids) > 1]
    return out


def test_two_deceleration_lanes_open_one_after_the_other_each_over_its_own_taper():
    """A two-lane exit (the fork sample's r1 leaves A1 at s=200) adds two lanes: the inner
    one opens first, the outer one after a full-width stretch, never both over one taper
    (successive lane drops are separated; ending together, two lanes also meet CommonRoad's
    verifier as one point, which it reads as parallel, not merging)."""
    opts = ExportOptions()
    data = xodr_bytes(sample_geometry("fork"), opts)
    assert _lanes_ending_together(data) == []
    a1 = next(r for r in etree.parse(io.BytesIO(data)).getroot().iter("road")
              if r.get("name") == "A1")
    secs = [(float(s.get("s")), [ln.get("id") for ln in s.findall("right/lane")])
            for s in a1.findall("lanes/laneSection")]
    counts = [len(ids) for _, ids in secs]
    # 2 lanes + shoulder; the inner opens (4 lanes), full width beside it, the outer opens
    # (5), both full width to the diverge
    assert counts == [3, 4, 4, 5, 5]
    taper_inner, gap, taper_outer = (secs[i + 1][0] - secs[i][0] for i in (1, 2, 3))
    assert taper_inner == pytest.approx(taper_outer)
    # 200 m of road for 2 tapers, the spacing and the deceleration length: in proportion
    f = min(1.0, 0.8 * 200.0 / (2 * opts.taper_length_m + opts.lane_drop_spacing_m
                                + opts.decel_length_m))
    assert taper_inner == pytest.approx(opts.taper_length_m * f)
    assert gap == pytest.approx(opts.lane_drop_spacing_m * f)


def test_two_acceleration_lanes_close_one_after_the_other_on_stack4():
    """stack4's two-lane ramps merge on both carriageways: no two lanes end together
    anywhere (they did on 8 roads per feature set, e.g. road 10, A2)."""
    from flyover.clients.designs import catalog_geometry  # noqa: PLC0415

    assert _lanes_ending_together(xodr_bytes(catalog_geometry("stack4", 0))) == []


def _right_lanes(data: bytes):
    """(right ``<lane>`` element, its lane section's length) of every lane section of a file."""
    for road in etree.parse(io.BytesIO(data)).getroot().iter("road"):
        secs = road.findall("lanes/laneSection")
        stops = [float(x.get("s")) for x in secs[1:]] + [float(road.get("length"))]
        for sec, stop in zip(secs, stops):
            for lane in sec.findall("right/lane"):
                yield lane, stop - float(sec.get("s"))


def test_an_opening_lane_stops_widening_inside_its_lane_section_as_written():
    """CommonRoad's converter finds where a lane that opens from zero width reaches full
    width among the roots of its width's derivative no further than the lane section's
    length (written section starts subtracted), compared exactly; where the root came out
    beyond it (cloverleaf road 28: sections 79.99999999999999 m apart, root 80.0), it
    re-drew the lane over its whole 200 m lanelet, 1.14 cm off its successor at the end
    (the verifier's join/split connection errors). Every opening, as written, stops
    widening at least 0.05 mm before its section's end (a 10 m taper: 0.1 mm)."""
    from numpy.polynomial import polynomial as P

    from flyover.clients.designs import catalog_geometry  # noqa: PLC0415

    margins = []
    for lane, length in _right_lanes(xodr_bytes(catalog_geometry("cloverleaf", 0))):
        w = lane.findall("width")[0]
        coef = [float(w.get(k)) for k in "abcd"]
        if coef[0] != 0.0 or not any(coef[1:]):
            continue
        seg = (float(lane.findall("width")[1].get("sOffset"))
               if len(lane.findall("width")) > 1 else length)
        r = P.polyroots(P.polyder(coef)).real
        margins.append(seg - max(r))
    assert len(margins) >= 8
    assert min(margins) > 5e-5


def test_a_closing_lane_is_zero_wide_at_its_end_as_written():
    """A lane that closes to zero width is, from its written coefficients, under 1e-8 m
    wide at its section's end (CommonRoad's test for a lane that ends: above it, the
    converter leaves the lane as it is and the verifier reports its crossing bounds). With
    coefficients written to 12 decimals, a 3.75 m lane closing over 80 m ended 2.56e-7 m
    wide (``d`` = 1.46484375e-05 rounded)."""
    from flyover.clients.designs import catalog_geometry  # noqa: PLC0415

    ends = []
    for lane, length in _right_lanes(xodr_bytes(catalog_geometry("directional_t", 1))):
        w = lane.findall("width")[-1]
        a, b, c, d = (float(w.get(k)) for k in "abcd")
        t = length - float(w.get("sOffset"))
        if a > 1.0 and abs(a + b * t + c * t * t + d * t ** 3) < 1e-3:
            ends.append(abs(a + b * t + c * t * t + d * t ** 3))
    assert len(ends) >= 4
    assert max(ends) < 1e-8


#: catalog designs and feature sets where a carriageway of 3 lanes ended into (began from) a
#: one-lane ramp straight on with its two other lanes closing (opening) together (export
#: version 10); the others are slow (a geometry build each)
_TWO_LANES_TOGETHER_BEFORE = {("directional_t", 1), ("semidirectional_t", 1), ("trumpet", 1)}


def _catalog_params():
    from flyover.clients.designs import FEATURE_SETS, catalog_names  # noqa: PLC0415

    return [pytest.param(n, v, id=f"{n}-{v}",
                         marks=() if (n, v) in _TWO_LANES_TOGETHER_BEFORE else pytest.mark.slow)
            for n in catalog_names() for v in range(len(FEATURE_SETS))]


@pytest.mark.parametrize("name, variant", _catalog_params())
def test_no_two_lanes_open_or_close_together_anywhere_on_the_catalog(name, variant):
    """Every lane section of every road: at most one driving lane closes to (opens from)
    zero width in it, the auxiliary lanes of speed-change regions and the lanes of a
    carriageway beyond a narrower straight-on ramp alike."""
    from flyover.clients.designs import catalog_geometry  # noqa: PLC0415

    assert _lanes_ending_together(xodr_bytes(catalog_geometry(name, variant))) == []


def test_carriageway_lanes_beyond_a_straight_on_ramp_close_one_at_a_time_on_its_body():
    """directional_t, 3 lanes per road: the carriageway's end forks into rL (one lane,
    straight on) and a ramp beside it. The connecting road carries the 3 lanes on at full
    width, each linked to the body of rL, where the outermost closes over a taper (rL's own
    lane widening to its width on the same taper), the middle one keeps full width for
    ``lane_drop_spacing_m``, then closes over its own taper."""
    from flyover.clients.designs import catalog_geometry  # noqa: PLC0415

    opts = ExportOptions()
    g = catalog_geometry("directional_t", 1)
    net = read_xodr(io.BytesIO(xodr_bytes(g, opts)))
    roads = sorted((r for r in net.roads.values() if r.name == "rL"), key=lambda r: int(r.id))
    conn, body = roads[0], roads[1]
    assert conn.junction != "-1" and body.junction == "-1"
    assert conn.lane_t(-3, conn.length, at_end=True)[1] == pytest.approx(-3 * 3.75)
    drive = lambda sec: [ln for ln in sec.lanes.values() if ln.type == "driving"]  # noqa: E731
    counts = [len(drive(sec)) for sec in body.sections]
    assert counts[:4] == [3, 2, 2, 1]
    starts = [sec.s for sec in body.sections[:4]]
    assert np.diff(starts) == pytest.approx([opts.taper_length_m, opts.lane_drop_spacing_m,
                                             opts.taper_length_m])
    ok, detail = check_continuity(net)
    assert ok, detail
    # every lane of the connecting road goes on into the body
    last = conn.sections[-1]
    assert sorted(k for ln in drive(last) for k in ln.successors) == [-3, -2, -1]
