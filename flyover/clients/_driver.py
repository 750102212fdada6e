"""Run inside the clients' environment (``.venv-clients``); never imported by flyover.

Reads one JSON request from stdin: ``{"jobs": [{"xodr": path, "commonroad": path|null,
"lanelet2": path|null, "lanelet2_shared_nodes": path|null, "verify": bool,
"verify_exclude": [formula id, ...], "attribution": bool, "routing": bool,
"pyopendrive": bool, "pyxodr": bool}, ...]}``
and prints one JSON line per job, in order. Each client
runs in its own ``try``: one failure is reported (type, message, where) and the
others still run.
"""

import contextlib
import json
import logging
import os
import sys
import time
import traceback
import warnings



def _failure(e):
    tb = traceback.extract_tb(e.__traceback__)
    where = f"{tb[-1].filename.split('site-packages/')[-1]}:{tb[-1].lineno}" if tb else ""
    return {"ok": False, "error": f"{type(e).__name__}: {e}", "where": where}


def _verify(network, exclude=()):
    """The map verifier's invalid states per formula, verification only (no repair).

    ``exclude``: formula ids (their string values) left out, e.g. the two
    ``potential_*_opposite_dir_parallel_adj`` formulas that take two thirds of its time.
    A formula that raises (``left_right_boundary_assignment`` does, with a ``TypeError``,
    on a lanelet whose curvilinear frame it cannot build: 1.9 km loop-ramp lanelets) is
    ``crashed`` (formula → error, where) and the others still run; for that one formula
    :func:`_boundary_sides` answers instead.
    """
    from crdesigner.verification_repairing.config import MapVerParams
    from crdesigner.verification_repairing.verification.formula_ids import extract_formula_ids
    from crdesigner.verification_repairing.verification.groups_handler import GroupsHandler
    from crdesigner.verification_repairing.verification.map_verifier import MapVerifier

    config = MapVerParams()
    every = [f for f in extract_formula_ids() if getattr(f, "value", str(f)) not in set(exclude)]
    counts, examples, locations_of, crashed = {}, {}, {}, {}

    def run(formulas):
        config.verification.formulas = formulas
        for fid, locations in MapVerifier(network, config).verify().items():
            key = getattr(fid, "value", str(fid))
            counts[key] = counts.get(key, 0) + len(locations)
            locations_of.setdefault(key, []).extend(locations)
            examples.setdefault(key, [list(map(int, loc)) if isinstance(loc, tuple) else int(loc)
                                      for loc in locations[:3]])

    groups = GroupsHandler()
    while groups.is_next_group():
        formulas = sorted(set(every) & set(groups.next_group()), key=str)
        if not formulas:
            continue
        try:
            run(formulas)
        except Exception:  # noqa: BLE001 - one formula's crash is reported, the rest still run
            for f in formulas:  # again one by one, to know which (a group's results are lost)
                try:
                    run([f])
                except Exception as e:  # noqa: BLE001
                    crashed[getattr(f, "value", str(f))] = _failure(e)
    out = {"ok": True, "errors": counts, "examples": examples, "formulas": len(every),
           "crashed": crashed,
           "connection_gaps_m": _connection_gaps(network, locations_of),
           "intersections": _intersections(network, locations_of.get("polylines_intersection", [])),
           "self_crossings": [
               {"lanelet": int(loc[0] if isinstance(loc, (tuple, list)) else loc), "side": side,
                "points": _crossings(getattr(network.find_lanelet_by_id(
                    int(loc[0] if isinstance(loc, (tuple, list)) else loc)), f"{side}_vertices"))}
               for side in ("left", "right")
               for loc in locations_of.get(f"{side}_self_intersection", [])]}
    if "left_right_boundary_assignment" in crashed:
        out["boundary_sides"] = _boundary_sides(network)
    return out


def _boundary_sides(network):
    """Lanelets whose left boundary is not left of their right one somewhere (where the
    lanelet is wider than 1 mm): what ``left_right_boundary_assignment`` asks, by the
    sign of the cross product of the centre line's direction and right → left."""
    import numpy as np

    wrong = []
    for ll in network.lanelets:
        c = ll.center_vertices
        d = np.gradient(c, axis=0)
        v = ll.left_vertices - ll.right_vertices
        cross = d[:, 0] * v[:, 1] - d[:, 1] * v[:, 0]
        wide = np.linalg.norm(v, axis=1) > 1e-3
        if (cross[wide] <= 0).any():
            wrong.append(int(ll.lanelet_id))
    return {"lanelets": len(network.lanelets), "wrong": wrong}


def _connection_gaps(network, locations_of):
    """Per connection error type, the largest distance between the linked lanelets' boundary ends.

    The verifier calls two linked lanelets unconnected when their boundary end
    points differ by more than its ``connection_thresh`` (1e-8 m); this is how much
    they actually differ in the converted map.
    """
    import numpy as np

    def pairs(locations):  # the flagged lanelet pairs that the network still has
        for loc in locations:
            a = network.find_lanelet_by_id(int(loc[0]))
            b = network.find_lanelet_by_id(int(loc[1]))
            if a is not None and b is not None:
                yield a, b

    def connection_gap(key, a, b):
        first, second = (b, a) if key == "connections_predecessor" else (a, b)
        return max(float(np.linalg.norm(first.left_vertices[-1] - second.left_vertices[0])),
                   float(np.linalg.norm(first.right_vertices[-1] - second.right_vertices[0])))

    def adjacency_gap(key, a, b):
        # a lanelet that forks from (merges into) its neighbour: at its start (end) its
        # boundary ends should lie on the neighbour's; the distance they are apart
        at = 0 if "forking" in key else -1
        return min(float(np.linalg.norm(p - q)) for p in (a.left_vertices[at], a.right_vertices[at])
                   for q in (b.left_vertices[at], b.right_vertices[at]))

    out = {}
    for measure, wanted in ((connection_gap, lambda k: k in ("connections_predecessor",
                                                             "connections_successor")),
                            (adjacency_gap, lambda k: "forking_adj" in k or "merging_adj" in k)):
        for key, locations in locations_of.items():
            if wanted(key):
                out[key] = max((measure(key, a, b) for a, b in pairs(locations)), default=0.0)
    return out


def _crossings(a, b=None):
    """Where polyline ``a`` crosses ``b`` (or itself, non-adjacent segments, when ``b`` is
    None): ``[[x, y], ...]``."""
    import numpy as np

    a = np.asarray(a, dtype=float)
    b = a if b is None else np.asarray(b, dtype=float)
    p, r = a[:-1], a[1:] - a[:-1]
    q, t = b[:-1], b[1:] - b[:-1]
    out = []
    for i in range(len(p)):
        den = r[i, 0] * t[:, 1] - r[i, 1] * t[:, 0]
        qp = q - p[i]
        with np.errstate(divide="ignore", invalid="ignore"):
            u = (qp[:, 0] * t[:, 1] - qp[:, 1] * t[:, 0]) / den
            v = (qp[:, 0] * r[i, 1] - qp[:, 1] * r[i, 0]) / den
        hit = (den != 0) & (u >= 0) & (u <= 1) & (v >= 0) & (v <= 1)
        if b is a:
            hit[max(i - 1, 0):i + 2] = False
        out += [(p[i] + u[k] * r[i]).tolist() for k in np.flatnonzero(hit)]
    return out


def _intersections(network, locations):
    """Each lanelet whose left and right boundaries the verifier finds intersecting:
    its width at both ends and the least width between them, and where they cross."""
    import numpy as np

    out = []
    for loc in locations:
        ll = network.find_lanelet_by_id(int(loc[0] if isinstance(loc, (tuple, list)) else loc))
        if ll is None:
            continue
        w = np.linalg.norm(ll.left_vertices - ll.right_vertices, axis=1)
        out.append({"lanelet": int(ll.lanelet_id), "type": str(getattr(ll, "lanelet_type", "")),
                    "width_start_m": float(w[0]), "width_end_m": float(w[-1]),
                    "min_inner_width_m": float(w[1:-1].min()) if len(w) > 2 else None,
                    "crossings": _crossings(ll.left_vertices, ll.right_vertices)})
    return out


#: CommonRoad's ``are_equal_vertices`` (verification/hol/functions/predicates/lanelet_predicates.py):
#: two boundary points are "equal" when closer than this, whatever ``connection_thresh`` says
EQUAL_VERTICES_M = 1e-5


def _adjacency_type(lanelet, adj, is_left):
    """The verifier's ``is_adj_type``: parallel, merging or forking, from end-point distances."""
    import numpy as np

    same = lanelet.adj_left_same_direction if is_left else lanelet.adj_right_same_direction
    if not same:
        return "parallel"
    ap = adj.right_vertices if is_left else adj.left_vertices
    ls, le = (float(np.linalg.norm(lanelet.left_vertices[i] - ap[i])) for i in (0, -1))
    rs, re = (float(np.linalg.norm(lanelet.right_vertices[i] - ap[i])) for i in (0, -1))
    if ls > rs and le < re:
        return "forking" if is_left else "merging"
    if ls < rs and le > re:
        return "merging" if is_left else "forking"
    return "parallel"


def formula_errors(network):
    """The verifier's connection, adjacency and ``polylines_intersection`` formulas, re-evaluated.

    Same predicates and threshold as its HOL formulas (:data:`EQUAL_VERTICES_M`), in
    milliseconds instead of minutes: ``{formula: [(where, gap_m), ...]}`` where ``where``
    is the flagged lanelet's left boundary point the formula looks at (lanelet ids differ
    from one conversion to the next) and ``gap_m`` the largest distance between the
    points the formula wants equal (for ``polylines_intersection``: the lanelet's least
    width at its two ends).
    """
    import numpy as np
    from shapely.geometry import LineString

    by_id = {ll.lanelet_id: ll for ll in network.lanelets}
    out = {}
    norm = lambda v: float(np.linalg.norm(v))  # noqa: E731
    for ll in network.lanelets:
        for key, others, mine, theirs in (("connections_successor", ll.successor, -1, 0),
                                          ("connections_predecessor", ll.predecessor, 0, -1)):
            for oid in others:
                o = by_id.get(oid)
                if o is None:
                    continue
                gap = max(norm(ll.left_vertices[mine] - o.left_vertices[theirs]),
                          norm(ll.right_vertices[mine] - o.right_vertices[theirs]))
                if gap >= EQUAL_VERTICES_M:
                    out.setdefault(key, []).append((ll.left_vertices[mine], gap))
        for side in ("left", "right"):
            a = by_id.get(getattr(ll, f"adj_{side}"))
            if a is None:
                continue
            kind = _adjacency_type(ll, a, side == "left")
            if kind == "parallel":
                continue
            at, other = (0, -1) if kind == "forking" else (-1, 0)
            # forking: both start points equal, the far end on the neighbour's border;
            # merging: both end points equal, the near start on the neighbour's border
            far = (ll.left_vertices[other] - a.right_vertices[other] if side == "left"
                   else ll.right_vertices[other] - a.left_vertices[other])
            gap = max(norm(ll.left_vertices[at] - a.left_vertices[at]),
                      norm(ll.right_vertices[at] - a.right_vertices[at]), norm(far))
            if gap >= EQUAL_VERTICES_M:
                out.setdefault(f"connections_{side}_{kind}_adj", []).append(
                    (ll.left_vertices[other], gap))
        if not LineString(ll.left_vertices).intersection(LineString(ll.right_vertices)).is_empty:
            w = np.linalg.norm(ll.left_vertices - ll.right_vertices, axis=1)
            out.setdefault("polylines_intersection", []).append(
                (ll.left_vertices[0], min(float(w[0]), float(w[-1]))))
    return out


@contextlib.contextmanager
def _converter_steps(exact_s, join_split):
    """The converter with two of its own steps neutralised, to tell their errors from ours.

    ``exact_s``: its lane borders call ``PlanView.calc(..., is_last_pos=...)``, a keyword
    the plan view does not take; the ``TypeError`` falls back to evaluating the
    reference line at ``s`` rounded to 1 mm (``border.py``), so a road whose length is
    not a whole millimetre ends up to 0.5 mm off. ``exact_s`` accepts the keyword.
    ``join_split``: False skips ``join_and_split_possible_lanes``, which re-draws the
    borders of lanes that open from (close to) zero width by mirroring a neighbour.
    """
    import crdesigner.map_conversion.common.conversion_lanelet_network as cln
    from crdesigner.map_conversion.opendrive.odr2cr.opendrive_parser.elements.roadPlanView import \
        PlanView

    calc, js = PlanView.calc, cln.ConversionLaneletNetwork.join_and_split_possible_lanes
    if exact_s:
        PlanView.calc = lambda self, s_pos, compute_curvature=True, reverse=True, is_last_pos=False: \
            calc(self, s_pos, compute_curvature, reverse)
    if not join_split:
        cln.ConversionLaneletNetwork.join_and_split_possible_lanes = lambda self: None
    try:
        yield
    finally:
        PlanView.calc, cln.ConversionLaneletNetwork.join_and_split_possible_lanes = calc, js


def _attribute(path, stock_network):
    """The formulas' errors on the stock conversion and with the converter's own steps
    neutralised (:func:`_converter_steps`): which step each error comes from.

    ``rounding_max_gap_m``: the largest gap among the stock errors that neutralising
    the 1 mm rounding alone removes (matched by place, within 5 cm).
    """
    import numpy as np
    from crdesigner.map_conversion.map_conversion_interface import opendrive_to_commonroad

    out = {}
    for name, exact_s, join_split in (("stock", False, True), ("exact_s", True, True),
                                      ("exact_s_no_join_split", True, False)):
        if name == "stock":
            net = stock_network
        else:
            with _converter_steps(exact_s, join_split):
                net = opendrive_to_commonroad(path).lanelet_network
        errs = formula_errors(net)
        out[name] = {"errors": {k: len(v) for k, v in errs.items()},
                     "max_gap_m": {k: max(g for _, g in v) for k, v in errs.items()}}
        if name == "exact_s_no_join_split":
            # bounds that cross where the lanelet is not zero wide at an end: where they cross
            wide = [ll for ll in net.lanelets
                    if min(np.linalg.norm(ll.left_vertices[i] - ll.right_vertices[i])
                           for i in (0, -1)) >= 1e-6]
            out[name]["wide_intersections"] = [
                {"lanelet": int(ll.lanelet_id), "crossings": c} for ll in wide
                for c in [_crossings(ll.left_vertices, ll.right_vertices)] if c]
            out[name]["wide_intersection_errors"] = sum(
                g >= 1e-6 for _, g in errs.get("polylines_intersection", []))
        if name == "stock":
            stock = errs
        elif name == "exact_s":
            # the errors that the 1 mm rounding alone made: their largest gap
            gone = [g for k, v in stock.items() for p, g in v
                    if not any(np.linalg.norm(p - q) < 0.05 for q, _ in errs.get(k, []))]
            out["rounding_max_gap_m"] = max(gone, default=0.0)
            out["rounding_errors"] = len(gone)
    return {"ok": True, **out}


def _write_commonroad(scenario, path):
    from commonroad.common.file_reader import CommonRoadFileReader
    from commonroad.common.file_writer import CommonRoadFileWriter, OverwriteExistingFile
    from commonroad.planning.planning_problem import PlanningProblemSet

    CommonRoadFileWriter(scenario, PlanningProblemSet(), author="flyover", affiliation="",
                         source="flyover OpenDRIVE via commonroad-scenario-designer",
                         tags=set()).write_to_file(path, OverwriteExistingFile.ALWAYS)
    back, _ = CommonRoadFileReader(path).open()  # its own library reads it back
    return {"ok": True, "lanelets": len(back.lanelet_network.lanelets)}


@contextlib.contextmanager
def _nodes_shared_by_position():
    """The converter's Lanelet2 export with one node per boundary point position (1 µm, z too
    where the vertices have it).

    Its ``_create_nodes`` shares nodes only along predecessor/successor chains and
    adjacent ways: where two lanelets from different predecessors continue side by
    side (a merge), the point their borders meet at becomes two nodes, and whichever
    lanelet it converts later has no following lanelet in Lanelet2 although the
    CommonRoad map has its successor. Here a new node is made only where none is yet.
    """
    from crdesigner.map_conversion.lanelet2.cr2lanelet import CR2LaneletConverter

    make = CR2LaneletConverter._create_nodes_from_vertices

    def shared(self, vertices):
        at = self.__dict__.setdefault("_flyover_nodes_at", {})
        out = []
        for v in vertices:
            key = tuple(round(float(c), 6) for c in v)
            if key not in at:
                at[key] = make(self, [v])[0]
            out.append(at[key])
        return out

    CR2LaneletConverter._create_nodes_from_vertices = shared
    try:
        yield
    finally:
        CR2LaneletConverter._create_nodes_from_vertices = make


def _lanelet2(scenario, path, routing):
    import lanelet2
    from crdesigner.map_conversion.lanelet2.cr2lanelet import CR2LaneletConverter
    from lxml import etree
    from pyproj import Transformer

    conv = CR2LaneletConverter()
    osm = conv(scenario)
    with open(path, "wb") as f:
        f.write(etree.tostring(osm, xml_declaration=True, encoding="UTF-8", pretty_print=True))
    projector = lanelet2.projection.UtmProjector(lanelet2.io.Origin(0.0, 0.0))
    lmap, load_errors = lanelet2.io.loadRobust(path, projector)
    out = {"ok": not load_errors, "load_errors": [str(e) for e in load_errors][:10],
           "n_load_errors": len(load_errors), "lanelets": len(lmap.laneletLayer)}
    if not routing:
        return out
    rules = lanelet2.traffic_rules.create(lanelet2.traffic_rules.Locations.Germany,
                                          lanelet2.traffic_rules.Participants.Vehicle)
    graph = lanelet2.routing.RoutingGraph(lmap, rules)
    out["routing_errors"] = [str(e) for e in graph.checkValidity()][:10]
    back = Transformer.from_crs(conv.transformer.target_crs, conv.transformer.source_crs,
                                always_xy=False)

    def local(p3):
        gps = projector.reverse(lanelet2.core.BasicPoint3d(p3.x, p3.y, p3.z))
        x, y = back.transform(gps.lat, gps.lon)
        return [x - conv.origin_utm[0], y - conv.origin_utm[1]]

    passable = [ll for ll in lmap.laneletLayer if rules.canPass(ll)]
    sources = [ll for ll in passable if not graph.previous(ll)]
    sinks = {ll.id for ll in passable if not graph.following(ll)}
    routes = []
    for src in sources:
        reach = {ll.id for ll in graph.reachableSet(src, 1e12, 0, True)}
        routes += [[src.id, s] for s in sorted(reach & sinks)]
    ends = {ll.id: (local(ll.centerline[0]), local(ll.centerline[-1])) for ll in passable}
    out.update(sources={ll.id: ends[ll.id][0] for ll in sources},
               sinks={i: ends[i][1] for i in sinks}, routes=routes)
    return out


def _shared_nodes(scenario, job):
    with _nodes_shared_by_position():
        return _lanelet2(scenario, job["lanelet2_shared_nodes"], job.get("routing"))


def _pyopendrive(path):
    from pyopendrive import OpenDriveMap

    m = OpenDriveMap.load(path)
    lanes = links = 0
    for road in m.roads:
        for layer in road.lane_layers:
            for sec in layer.sections:
                for lane in (sec.lanes.left or ()) + (sec.lanes.right or ()):
                    lanes += 1
                    links += len(lane.links.predecessors) + len(lane.links.successors)
    # elements it does not parse (our header userData) are notes, not errors
    errors = [d for d in m.diagnostics if d.code != "unsupported-element"]
    return {"ok": not errors, "roads": len(m.roads), "junctions": len(m.junctions),
            "lanes": lanes, "lane_links": links,
            "diagnostics": [f"{d.code}: {d.message} ({d.element})" for d in m.diagnostics][:10]}


def _pyxodr(path):
    import numpy as np
    from pyxodr.road_objects.network import RoadNetwork

    net = RoadNetwork(path, resolution=0.5)
    links, lanes, finite = 0, 0, True
    for road in net.get_roads():
        for sec in road.lane_sections:
            for lane in sec.lanes:
                lanes += 1
                finite &= bool(np.isfinite(lane.boundary_line).all())
                links += len(lane.traffic_flow_successors)
    return {"ok": lanes > 0 and finite, "lanes": lanes, "lane_successors": links,
            "boundaries_finite": finite}


def run(job):
    res = {"xodr": job["xodr"], "seconds": {}}
    if job.get("pyopendrive"):
        t = time.perf_counter()
        try:
            res["pyopendrive"] = _pyopendrive(job["xodr"])
        except Exception as e:  # noqa: BLE001 - reported, not raised
            res["pyopendrive"] = _failure(e)
        res["seconds"]["pyopendrive"] = time.perf_counter() - t
    if job.get("pyxodr"):
        t = time.perf_counter()
        try:
            res["pyxodr"] = _pyxodr(job["xodr"])
        except Exception as e:  # noqa: BLE001
            res["pyxodr"] = _failure(e)
        res["seconds"]["pyxodr"] = time.perf_counter() - t
    if not (job.get("commonroad") or job.get("lanelet2") or job.get("lanelet2_shared_nodes")
            or job.get("verify") or job.get("attribution")):
        return res
    from crdesigner.map_conversion.map_conversion_interface import opendrive_to_commonroad

    t = time.perf_counter()
    try:
        scenario = opendrive_to_commonroad(job["xodr"])
        res["conversion"] = {"ok": True, "lanelets": len(scenario.lanelet_network.lanelets)}
    except Exception as e:  # noqa: BLE001
        res["conversion"] = _failure(e)
        return res
    finally:
        res["seconds"]["conversion"] = time.perf_counter() - t
    for key, fn in (("commonroad", lambda: _write_commonroad(scenario, job["commonroad"])),
                    ("lanelet2", lambda: _lanelet2(scenario, job["lanelet2"], job.get("routing"))),
                    ("lanelet2_shared_nodes", lambda: _shared_nodes(scenario, job)),
                    ("verifier", lambda: _verify(scenario.lanelet_network,
                                                 job.get("verify_exclude", ()))),
                    ("attribution", lambda: _attribute(job["xodr"], scenario.lanelet_network))):
        wanted = job.get("verify") if key == "verifier" else job.get(key)
        if not wanted:
            continue
        t = time.perf_counter()
        try:
            res[key] = fn()
        except Exception as e:  # noqa: BLE001
            res[key] = _failure(e)
        res["seconds"][key] = time.perf_counter() - t
    return res


def main():
    # the clients' own chatter, silenced in this process only (pytest imports this module
    # for its doctests: a module-level logging.disable silenced every test after it)
    warnings.filterwarnings("ignore")
    logging.disable(logging.WARNING)
    request = json.load(sys.stdin)
    # the answers get the real stdout to themselves: the clients' progress, from Python
    # or from their C++ parts (which bypass sys.stdout), goes to stderr
    sys.stdout.flush()
    out = os.fdopen(os.dup(1), "w")
    os.dup2(2, 1)
    for job in request["jobs"]:
        with contextlib.redirect_stdout(sys.stderr):
            res = run(job)
        out.write(json.dumps(res, default=str) + "\n")
        out.flush()


if __name__ == "__main__":
    main()
