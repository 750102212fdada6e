"""Benchmark of the geometry stage on the catalog city (one core).

For every catalog design, ``--samples`` feature sets are drawn (seeded) from
the configured sampling domains (config ``sampling.profiles``), or read from
``results/features/{class_id}.parquet`` with ``--from-results``. Each is built
into a concrete interchange (layout + DE ramps + resampling). Prints:

* per class: ramps, within tolerance on the first try, resampled, within
  tolerance at the end, recorded infeasible, with a same-level conflict;
* per design: ramp length median / p95 / max, footprint (bounding box of the
  ramps' lane centres), and the ramps' radius and slope **re-measured from the
  exported .xodr** (read back with :mod:`flyover.opendrive.reader`; the centre of the
  ramp's own lanes, followed through the lane links, along all its roads joined end to
  end, the junction connecting roads included;
  radius: the tightest held over 10 m of that line (heading change over arc length, the
  fit's definition, :data:`flyover.geometry._kernels.HOLD_M`), also by three-point
  circles spanning 10 m from every 0.5 m (:func:`flyover.osm.geom.min_radius`, the OSM
  importer's estimator); see :func:`remeasure`;
  slope as dz/ds of the elevation every metre) against the targets of
  geometry.parquet: within 5 % of the radius target (an ``inf`` target: no
  tighter than 0.95 × ``inf_reference_m``, 250 m, the radius an ``inf`` ramp is built
  with: :func:`flyover.geometry.straight.radius_met`, as the fit counts it) and 0.2 pp
  of the slope target;
* median / p95 seconds per interchange and per ramp (vectorised DE);
* the same ramps re-fitted alone with our DE, scipy's vectorised DE and
  scipy's plain (one call per candidate) DE on the same objective and with
  the same stopping rule, i.e. at equal accuracy.

Run (from the repository root; ``PYTHONPATH=.`` so that a git worktree's own ``flyover``
is imported, not the one the venv's editable install points at):
``OMP_NUM_THREADS=1 PYTHONPATH=. .venv/bin/python benchmarks/geometry.py --samples 3``;
the whole catalog city as the workflow samples it, one process per core:
``PYTHONPATH=. .venv/bin/python benchmarks/geometry.py --from-results --samples 0 --jobs 2``
(times are each interchange's CPU seconds in its own single-threaded process).
"""

from __future__ import annotations

import argparse
import io
import math
import multiprocessing
import os
import time
from dataclasses import replace
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from flyover.config import load_config  # noqa: E402
from flyover.errors import FlyoverError  # noqa: E402
from flyover.geometry._kernels import HOLD_M  # noqa: E402
from flyover.geometry.bezier import sample_spline  # noqa: E402
from flyover.geometry.dubins import shortest  # noqa: E402
from flyover.geometry.profile import climb_distance, evaluate_polys  # noqa: E402
from flyover.opendrive.reader import read_xodr  # noqa: E402
from flyover.opendrive.writer import xodr_bytes  # noqa: E402
from flyover.osm.geom import min_radius  # noqa: E402
from flyover.geometry.check import ramp_crossings, same_level_conflicts  # noqa: E402
from flyover.geometry.fit import fit_ramp  # noqa: E402
from flyover.geometry.layout import LayoutSettings, RampFeatures  # noqa: E402
from flyover.geometry.straight import radius_met  # noqa: E402
from flyover.geometry.tables import (  # noqa: E402
    build_sample, domain_resampler, geometry_rows, read_feature_sets, sample_seed, summary,
    write_sample,
)
from flyover.topology.canonical import class_id as class_id_of  # noqa: E402
from flyover.topology.catalog import catalog_topologies  # noqa: E402


def drawn_feature_sets(topology, profile, n, seed):
    """``n`` feature sets drawn from the domains; features geometry fixes up front
    (slope 0 on level ramps, :func:`flyover.geometry.feasibility.fixed_features`) are
    set, not drawn (the same draws as without them, so other designs are unchanged).
    As sampling forbids them (its ``extra=``, :func:`flyover.geometry.feasibility.
    forbidden_features`): no ``inf`` on a turning ramp, and an outer connector and its
    loop whose radii :meth:`~flyover.geometry.feasibility.RoundLoop.allows` does not are
    drawn again, both, from a generator of their own (the other draws stay the same), and
    so is a radius a ramp's fixed windows cannot hold with its road's lanes
    (:meth:`~flyover.geometry.feasibility.ShiftRoom.allows`), from another."""
    from flyover.geometry.feasibility import (
        fixed_features, round_loops, shift_rooms, turning_ramps,
    )
    from flyover.sampling.model import Feature, profile_from_dict

    fixed = fixed_features(topology)
    turning = turning_ramps(topology)  # inf is forbidden on them (sampling's extra=)
    pairs = round_loops(topology)
    rooms = shift_rooms(topology, profile_from_dict("drawn", profile))
    room_rng = np.random.default_rng([seed, 2])
    finite = [v for v in profile["ramp"]["radius_m"] if math.isfinite(float(v))]
    rng = np.random.default_rng(seed)
    again = np.random.default_rng([seed, 1])
    out = {}
    for k in range(n):
        lanes = {r: int(rng.choice(profile["road"]["lanes"])) for r in topology.roads}
        ramps = {r: RampFeatures(float(fixed.get((r, Feature.RADIUS_M), rng.choice(
                                     finite if r in turning else profile["ramp"]["radius_m"]))),
                                 float(fixed.get((r, Feature.SLOPE_PCT),
                                                 rng.choice(profile["ramp"]["slope_pct"]))))
                 for r in topology.ramps}
        for p in pairs:
            while not p.allows(ramps[p.connector].radius_m, ramps[p.loop].radius_m):
                for r in (p.connector, p.loop):
                    ramps[r] = replace(ramps[r], radius_m=float(again.choice(
                        finite if r in turning else profile["ramp"]["radius_m"])))
        for room in rooms:
            n = lanes.get(room.road) if room.road is not None else None
            while not room.allows(ramps[room.ramp].radius_m, n):
                ramps[room.ramp] = replace(ramps[room.ramp], radius_m=float(room_rng.choice(
                    profile["ramp"]["radius_m"])))
        out[k] = (lanes, ramps)
    return out


def real_feature_set(topology, profile, slope_pct: float):
    """One feature set from what the real interchange has: each ramp's radius target is
    the domain value nearest (in ratio) to its OSM ``min_radius_m`` (a finite one on a
    ramp that must turn), its slope ``slope_pct`` (OSM has no heights), the lanes of its
    roads the domain value nearest to their OSM ``lanes``; features geometry fixes up
    front are set as in :func:`drawn_feature_sets`."""
    from flyover.geometry.feasibility import fixed_features, turning_ramps
    from flyover.sampling.model import Feature

    fixed = fixed_features(topology)
    turning = turning_ramps(topology)
    radii = [float(v) for v in profile["ramp"]["radius_m"]]
    lanes_dom = [int(v) for v in profile["road"]["lanes"]]
    nodes = topology.graph.nodes

    def radius(r):
        real = float(nodes[r].get("min_radius_m") or math.inf)
        dom = [v for v in radii if math.isfinite(v)] if r in turning else radii
        return min(dom, key=lambda v: abs(math.log(min(v, 1e4) / min(real, 1e4))))

    lanes = {r: min(lanes_dom, key=lambda v: abs(v - int(nodes[r].get("lanes") or 0)))
             for r in topology.roads}
    ramps = {r: RampFeatures(radius(r), float(fixed.get((r, Feature.SLOPE_PCT), slope_pct)))
             for r in topology.ramps}
    return {0: (lanes, ramps)}


#: what the workers build from (set before they fork): class id → (design, topology, sets)
_WORK: dict = {}


def _build(job: tuple[str, int]) -> tuple:
    """Build one interchange; its CPU seconds, geometry rows and fits."""
    cid, sample = job
    name, topo, sets, seed, settings, keep = _WORK[cid]
    t0 = time.process_time()
    own = sample_seed(seed, cid, sample)
    where = str(topo.source or name)
    try:
        ic = build_sample(topo, sets[sample], class_id=cid, sample=sample, seed=seed,
                          settings=settings,
                          resampler=domain_resampler(sets, own, topo, settings, sample))
    except FlyoverError as exc:  # one interchange that cannot be built: its line, not a crash
        return name, sample, time.process_time() - t0, exc.located(where).one_line()
    secs = time.process_time() - t0
    try:
        net = read_xodr(io.BytesIO(xodr_bytes(ic.geometry)))  # exported and read back
        xodr = remeasure(ic.geometry, net=net)
    except FlyoverError as exc:
        return name, sample, secs, "export: " + exc.located(where).one_line()
    rebuilt = ic.geometry.seed != own  # kept a build with another seed (geometry.rebuilds)
    if keep:
        out = keep / cid / str(sample)
        write_sample(ic, out / "geometry.json", out / "geometry.parquet")
    dense = same_level_conflicts(ic.geometry)  # the independent checks, not timed
    crossing = ramp_crossings(ic.geometry)
    bridges = len(crossing)
    crossed = {frozenset((c.ramp, c.other)) for c in crossing}
    target = {o.ramp: o.fit.spec.target_radius_m for o in ic.outcomes}
    rounds = [(frozenset(p) not in crossed, p[0], p[1], target[p[0]], target[p[1]])
              for p in round_pairs(topo, settings)]
    rows = geometry_rows(ic)
    stretch = {o.ramp: o.fit.length_m / need_m(o.fit, settings) for o in ic.outcomes}
    detour = {o.ramp: o.fit.length_m / least_m(o.fit, settings) if o.fit.ok else math.nan
              for o in ic.outcomes}  # a ramp off its radius can be shorter than the least
    over = {o.ramp: o.fit.length_m > o.fit.max_length_m for o in ic.outcomes}
    for r in rows:
        r["stretch"] = stretch[r["ramp"]]
        r["detour"] = detour[r["ramp"]]
        r["over_bound"] = over[r["ramp"]]
    for r in rows:
        r["xodr_radius_m"], r["xodr_slope_pct"], r["xodr_ref_radius_m"], r["xodr_3pt_radius_m"] = \
            xodr.get(r["ramp"], (math.nan,) * 4)
    return (name, sample, secs, rows, [o.fit for o in ic.outcomes], dense, rebuilt,
            bridges, footprint(ic), (grade_jumps(ic.geometry), xodr_grade_jumps(net, ic.geometry)),
            rounds)


def print_real_comparison(rows, names, real_by_ramp) -> None:
    """Generated / real length of each ramp (the same topology, the real radii)."""
    print("generated / real length, ramp by ramp (the real radii as targets):")
    every = []
    for cid in sorted(real_by_ramp, key=lambda c: names.get(c, c)):
        pairs = [(r["length_m"], real_by_ramp[cid][r["ramp"]], r["ramp"],
                  r["target_radius_m"]) for r in rows
                 if r["class_id"] == cid and r["ramp"] in real_by_ramp[cid]]
        if not pairs:
            continue
        ratio = [g / max(real, 1.0) for g, real, _, _ in pairs]
        every += ratio
        worst = max(pairs, key=lambda p: p[0] / max(p[1], 1.0))
        print(f"  {names[cid]:<17} median {np.median(ratio):5.2f}  max {max(ratio):5.2f}  "
              f"(n={len(ratio)}; generated median {np.median([p[0] for p in pairs]):5.0f} m, "
              f"real {np.median([p[1] for p in pairs]):5.0f} m; longest relative: {worst[2]} "
              f"R {worst[3]:g} {worst[0]:.0f} vs {worst[1]:.0f} m)")
    if every:
        print(f"  {'total':<17} median {np.median(every):5.2f}  p95 "
              f"{np.percentile(every, 95):5.2f}  over 1.5: {sum(x > 1.5 for x in every)} of "
              f"{len(every)}")


def round_pairs(topo, settings) -> list[tuple[str, str]]:
    """(outer connector, loop) pairs: a cloverleaf's or parclo's outer connector and the
    loop joining the same two roads the other way round, on the road they share or
    through stubs (:func:`flyover.geometry.feasibility.round_loops`)."""
    from flyover.geometry.feasibility import round_loops  # noqa: PLC0415

    return [(p.connector, p.loop) for p in round_loops(topo, settings)]


def grade_jumps(geometry) -> list[float]:
    """For every end of a ramp attached to another ramp: |the child's grade there − the
    parent's grade at the attachment| (percentage points)."""
    ramps = {r.id: r for r in geometry.ramps}
    out = []
    for r in geometry.ramps:
        length = sum(p.length_m for p in r.plan)
        for att, s_child in ((r.start, 0.0), (r.end, length)):
            parent = ramps.get(att.parent)
            if parent is None:
                continue
            _, g_child = evaluate_polys(r.elevation, np.array([s_child]))
            _, g_parent = evaluate_polys(parent.elevation, np.array([att.s_m]))
            out.append(100.0 * abs(float(g_child[0]) - float(g_parent[0])))
    return out


def xodr_grade_jumps(net, geometry) -> list[float]:
    """For every road link of the exported .xodr (``net``, read back) between the roads of
    two different ramps (a ramp's junction connecting road and its parent's road): |the
    grade on one side − the grade on the other| (percentage points, in the direction of
    travel), from the elevation records the reader evaluates."""
    ramps = {r.id for r in geometry.ramps}

    def grade(road, s: float) -> float:
        a, b = max(0.0, s - 1e-3), min(road.length, s + 1e-3)
        z = road.reference(np.array([a, b]))[2]
        return float((z[1] - z[0]) / (b - a))

    out = []
    for road in net.roads.values():
        for here, link in ((0.0, road.predecessor), (road.length, road.successor)):
            if link is None or link[0] != "road" or link[1] not in net.roads:
                continue
            other = net.roads[link[1]]
            if road.name == other.name or road.name not in ramps or other.name not in ramps:
                continue
            there = 0.0 if link[2] == "start" else other.length
            # the other road goes on in this one's direction when the contact points differ
            sign = 1.0 if (here == 0.0) != (link[2] == "start") else -1.0
            out.append(100.0 * abs(grade(road, here) - sign * grade(other, there)))
    return out


def climb_m(fit, settings) -> float:
    """The run a fitted ramp needs to climb from its start to its crest and down to its
    end at its slope target (at least 0.5 %), vertical curves included."""
    g = max(fit.spec.target_slope_pct, 0.5) / 100.0
    za, zb = fit.start_pose[3], fit.end_pose[3]
    top = max(fit.z_crest, za, zb)
    tr = settings.fit.transition_m
    return float(climb_distance(top - za, g, tr) + climb_distance(top - zb, g, tr))


def need_m(fit, settings) -> float:
    """What a fitted ramp needed: the longer of its turn at its target radius (``inf``:
    ``inf_reference_m``) and its climb from its start to its crest and down to its end at
    its slope target, and a taper (``gap_m``) at each end (as
    :meth:`flyover.geometry.specs.RampSpecs.need_m` and the feature domains count it)."""
    sp = fit.spec
    r = sp.target_radius_m if math.isfinite(sp.target_radius_m) else \
        settings.fit.inf_reference_m
    return max(abs(sp.turn_rad) * r, climb_m(fit, settings)) + 2.0 * settings.gap_m


def least_m(fit, settings, n: int = 24) -> float:
    """The least a ramp between two attachment windows can be long (NaN for a stub or a
    collector-distributor road): the longest of the shortest path of curvature at most
    1 / (0.95 × its radius target) (``inf``: ``inf_reference_m``) from a point of its
    start window heading along its parent to one of its end window
    (:func:`flyover.geometry.dubins.shortest`, the windows sampled at ``n`` stations), its
    turn at that radius, and its climb from each end to its crest at its slope target. A
    ramp much longer than this detours: where its ends may attach, its radius and its
    climb do not ask for that length."""
    sp = fit.spec
    a, b = sp.start, sp.end
    if a is None or b is None or sp.free is not None or a.parent == b.parent:
        return math.nan
    r = 0.95 * (sp.target_radius_m if math.isfinite(sp.target_radius_m) else
                settings.fit.inf_reference_m)
    pa, ha, _ = a.at(np.linspace(a.lo, a.hi, n))
    pb, hb, _ = b.at(np.linspace(b.lo, b.hi, n))
    path = float(shortest(pa[:, None, :], ha[:, None], pb[None, :, :], hb[None, :], r).min())
    return max(path, abs(sp.turn_rad) * r, climb_m(fit, settings))


def footprint(ic) -> tuple[float, float]:
    """Bounding box (m × m) of the ramps' lane centres."""
    pts = np.concatenate([sample_spline(o.fit.ctrl, 40).xy.reshape(-1, 2) for o in ic.outcomes])
    span = pts.max(0) - pts.min(0)
    return float(span[0]), float(span[1])


def _lane_offset(road, s: np.ndarray) -> np.ndarray:
    if not road.lane_offset:
        return np.zeros_like(s)
    starts = np.array([c.s for c in road.lane_offset])
    idx = np.clip(np.searchsorted(starts, s, side="right") - 1, 0, len(starts) - 1)
    out = np.empty_like(s)
    for i in np.unique(idx):
        out[idx == i] = road.lane_offset[i](s[idx == i])
    return out


def _own_lanes(road, first: set[int] | None, last: set[int] | None, n: int) -> list[set[int]]:
    """The ramp's own driving lanes in each lane section of ``road`` (not the auxiliary
    lanes of a merging or diverging ramp beside them): ``first`` (``last``), the lane ids
    of its first (last) section that the ramp's adjacent connecting road links to, are
    followed section by section through the lane links, at most ``n`` of them (the
    innermost); without either (a piece between two straight-on links), its ``n``
    innermost driving lanes."""
    secs = road.sections
    driving = [{k for k, ln in sec.lanes.items() if ln.type == "driving"} for sec in secs]
    out: list[set[int]] = [set() for _ in secs]
    if first is not None:
        out[0] = first & driving[0]
        for i in range(1, len(secs)):
            out[i] = {n for k in out[i - 1] for n in secs[i - 1].lanes[k].successors} & driving[i]
    elif last is not None:
        out[-1] = last & driving[-1]
        for i in range(len(secs) - 2, -1, -1):
            out[i] = {p for k in out[i + 1] for p in secs[i + 1].lanes[k].predecessors} \
                & driving[i]
    else:
        out = [set(sorted(d, reverse=True)[:n]) for d in driving]
    # a carriageway's lanes beyond the ramp's close on its body, outermost first (the T
    # designs): the ramp's own are the n innermost of those followed
    out = [set(sorted(o, reverse=True)[:n]) for o in out]
    return [o if o else d for o, d in zip(out, driving)]


def _lane_centre_t(road, s: np.ndarray, own: list[set[int]], fixed: float | None) -> np.ndarray:
    """Lateral offset of the centre of the ramp's own lanes (``own`` per section) at ``s``;
    ``fixed``: that offset without the lane layout (width / 2 right of the reference line)."""
    if fixed is not None:
        return np.full_like(s, fixed)
    t = _lane_offset(road, s)
    starts = np.array([sec.s for sec in road.sections])
    idx = np.clip(np.searchsorted(starts, s + 1e-9, side="right") - 1, 0, len(starts) - 1)
    out = np.empty_like(s)
    for i in np.unique(idx):
        m = idx == i
        sec, ds = road.sections[i], s[m] - road.sections[i].s
        inner, edges = t[m], {}
        for k in range(1, max(abs(j) for j in own[i]) + 1):  # right lanes: ids -1, -2, ...
            w = sec.lanes[-k].width(ds) if -k in sec.lanes else 0.0
            edges[-k] = (inner, inner - w)
            inner = inner - w
        lo, hi = max(own[i]), min(own[i])  # innermost and outermost own lane
        out[m] = 0.5 * (edges[lo][0] + edges[hi][1])
    return out


def held_radius_xy(xy: np.ndarray, hold_m: float = HOLD_M, step_m: float = 0.5) -> float:
    """The tightest radius a polyline holds over ``hold_m`` of its own arc: its heading
    change between each point (resampled every ``step_m``) and the first one ``hold_m``
    further on, over that arc length, as :func:`flyover.geometry.bezier.held_radius`
    measures a fit (there on the reference line, offset to the lane centre)."""
    cum = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
    if cum[-1] < hold_m + 2 * step_m:
        return math.inf
    s = np.arange(0.0, cum[-1] + 1e-9, step_m)
    p = np.column_stack([np.interp(s, cum, xy[:, 0]), np.interp(s, cum, xy[:, 1])])
    d = np.diff(p, axis=0)
    head = np.unwrap(np.arctan2(d[:, 1], d[:, 0]))  # of each step, at its middle
    mid = 0.5 * (s[1:] + s[:-1])
    k = np.searchsorted(mid, mid + hold_m, side="left")
    ok = k < len(mid)
    j = np.flatnonzero(ok)
    turn = np.abs(head[k[ok]] - head[j])
    with np.errstate(divide="ignore"):
        r = (mid[k[ok]] - mid[j]) / turn
    return float(r.min()) if len(r) else math.inf


def remeasure(geometry, tapers: bool = True, net=None
              ) -> dict[str, tuple[float, float, float, float]]:
    """Ramp id → (min radius of the centre line of its own lanes, max slope %, min radius
    of the line width / 2 right of its reference line, min three-point radius of the
    centre line of its own lanes), read back from the exported .xodr (``tapers=False``:
    not its junction connecting roads).

    A ramp's roads are joined end to end (the writer numbers them along the ramp) and its
    lane centre is sampled every 0.5 m, across road ends too. The radius is the tightest
    held over 10 m (:data:`HOLD_M`) of that line, :func:`held_radius_xy`, the fit's
    definition (:func:`flyover.geometry.bezier.held_radius`); the last figure is the
    smallest three-point circle spanning 10 m (points 5 m apart) from every 0.5 m, the OSM
    importer's estimator (:func:`flyover.osm.geom.min_radius`), which reads a turn of
    heading concentrated within a few metres as up to twice as tight. (The former
    re-measure took three-point circles only from each road's start, on a 5 m grid: it
    missed a ramp's tightest 10 m where it lay across a junction's cut or off the grid, up
    to 15 % too wide.) The own lanes are followed through the lane links: on a piece
    where a merging or diverging ramp's auxiliary lane runs beside them (opened on the
    left by ``laneOffset``, which also shifts the reference line's lane layout), they do
    not move, and neither does their centre. ``net``: the .xodr already read back."""
    net = net or read_xodr(io.BytesIO(xodr_bytes(geometry)))
    out: dict[str, tuple[float, float, float]] = {}
    for name, (runs, slope) in lane_centre_runs(geometry, net, tapers=tapers).items():
        held = [min([held_radius_xy(xy) for xy in rs] + [math.inf]) for rs in runs]
        circles = min([min_radius(xy, step_m=0.5, chord_steps=int(HOLD_M)) for xy in runs[0]]
                      + [math.inf])
        out[name] = (held[0], slope, held[1], circles)
    return out


def lane_centre_runs(geometry, net, step_m: float = 0.5, tapers: bool = True
                     ) -> dict[str, tuple[list[list[np.ndarray]], float]]:
    """Ramp id → ((runs of the centre of its own lanes, runs of the line width / 2 right
    of its reference line), its max slope %) read back from the .xodr ``net``: each run
    contiguous points ``(N, 2)`` every ``step_m`` along the ramp's roads joined end to end
    (see :func:`remeasure`; ``tapers=False``: not its junction connecting roads)."""
    widths = {r.id: r.lanes * geometry.ramp_lane_width_m for r in geometry.ramps}
    lanes = {r.id: r.lanes for r in geometry.ramps}
    by_ramp: dict[str, list] = {}
    for road in sorted(net.roads.values(), key=lambda r: int(r.id)):
        if road.name in widths and (road.junction == "-1" or tapers):
            by_ramp.setdefault(road.name, []).append(road)
    out = {}
    for name, roads in by_ramp.items():
        lines: list[list[list[np.ndarray]]] = [[[]], [[]]]  # contiguous runs of points
        slope = 0.0
        for i, road in enumerate(roads):
            if road.length < 1e-3:
                continue
            s = np.linspace(0.0, road.length, max(3, int(road.length / step_m) + 1))
            x, y, z, h = road.reference(s)
            prev = roads[i - 1] if i else None
            nxt = roads[i + 1] if i + 1 < len(roads) else None
            first = last = None
            if prev is not None and prev.junction != "-1" and prev.successor == ("road", road.id, "start"):
                first = {n for k, ln in prev.sections[-1].lanes.items() if ln.type == "driving"
                         for n in ln.successors}
            elif nxt is not None and nxt.junction != "-1" and nxt.predecessor == ("road", road.id, "end"):
                last = {p for k, ln in nxt.sections[0].lanes.items() if ln.type == "driving"
                        for p in ln.predecessors}
            own = _own_lanes(road, first, last, lanes[name])
            for line, fixed in zip(lines, (None, -widths[name] / 2)):
                t = _lane_centre_t(road, s, own, fixed)
                xy = np.stack([x - np.sin(h) * t, y + np.cos(h) * t], -1)
                if line[-1] and np.hypot(*(line[-1][-1][-1] - xy[0])) < 1e-3:
                    xy = xy[1:]  # the same point: the road goes on from the previous one
                elif line[-1]:
                    line.append([])  # a gap (a connecting road left out): another run
                line[-1].append(xy)
            if len(s) > 1:
                slope = max(slope, float(np.abs(np.diff(z) / np.diff(s)).max()) * 100.0)
        runs = [[np.concatenate(run) for run in line if run] for line in lines]
        out[name] = (runs, slope)
    return out


def agrees(row: dict, inf_reference_m: float, key: str = "xodr_radius_m") -> tuple[bool, bool]:
    """Whether the re-measured radius (``key``) / slope agree with the row's targets."""
    radius = radius_met(row[key], row["target_radius_m"], inf_reference_m)  # as the fit
    slope = abs(row["xodr_slope_pct"] - row["target_slope_pct"]) <= 0.2
    return bool(radius), bool(slope)


def topologies(osm: list[Path] | None) -> dict:
    """The catalog designs, or every interchange :mod:`flyover.osm` finds in ``osm`` files
    (named ``file-stem:k``; catalog classes among them keep the design's name)."""
    if not osm:
        return catalog_topologies()
    from flyover.osm import read_osm_topologies  # noqa: PLC0415

    design = {class_id_of(t): n for n, t in catalog_topologies().items()}
    out = {}
    for path in osm:
        for k, topo in enumerate(read_osm_topologies(path)):
            if topo.ramps:
                name = design.get(class_id_of(topo), f"{path.stem[:14]}:{k}")
                out[name] = topo
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=3)
    ap.add_argument("--designs", nargs="*", default=None)
    ap.add_argument("--plain-ramps", type=int, default=12,
                    help="ramps re-fitted alone with each DE engine for comparison (0: skip)")
    ap.add_argument("--from-results", action="store_true",
                    help="the workflow's feature sets (results/features/), all of them with "
                         "--samples 0")
    ap.add_argument("--keep", type=Path, metavar="DIR",
                    help="write DIR/{class_id}/{sample}/geometry.json (as the workflow does)")
    ap.add_argument("--osm", nargs="*", type=Path, metavar="FILE",
                    help="build the interchanges of these .osm extracts instead of the catalog "
                         "(feature sets drawn from the domains)")
    ap.add_argument("--real-features", type=float, metavar="SLOPE_PCT",
                    help="with --osm: build each interchange once with the real ramps' radii "
                         "(nearest domain value) and this slope target, and compare lengths "
                         "ramp by ramp with the real ones")
    ap.add_argument("--show-misses", type=int, default=0,
                    help="print this many ramps whose re-measured radius or slope misses")
    ap.add_argument("--show-rounds", type=int, default=0,
                    help="print this many outer connectors that go over or under their loop")
    ap.add_argument("--jobs", type=int, default=1,
                    help="worker processes (one per core; each interchange is timed in its "
                         "worker)")
    args = ap.parse_args()
    cfg = load_config("config/config.yaml")
    settings = LayoutSettings.from_config(cfg["geometry"])
    profile = cfg["sampling"]["profiles"][cfg["sampling"]["profile"]]
    seed = int(cfg["seed"])
    rows, per_ic, names, fits, real_by_ramp = [], [], {}, [], {}
    jobs = []
    for name, topo in topologies(args.osm).items():
        if args.designs and name not in args.designs:
            continue
        cid = class_id_of(topo)
        if cid in names:  # the same class found again (another extract): built once
            continue
        names[cid] = name
        real_by_ramp[cid] = {r: float(topo.graph.nodes[r]["length_m"]) for r in topo.ramps
                             if topo.graph.nodes[r].get("length_m")}
        if args.real_features is not None:
            sets = real_feature_set(topo, profile, args.real_features)
        elif args.from_results:
            sets = read_feature_sets(f"results/features/{cid}.parquet")
        else:
            sets = drawn_feature_sets(topo, profile, args.samples, seed)
        _WORK[cid] = (name, topo, sets, seed, settings, args.keep)
        jobs += [(cid, sample) for sample in sorted(sets)[: args.samples or None]]
    if args.jobs > 1:
        pool = multiprocessing.get_context("fork").Pool(args.jobs)
        done = pool.imap(_build, jobs)
    else:
        pool, done = None, map(_build, jobs)
    by_design: dict[str, list[float]] = {}
    dense_bad: dict[str, int] = {}
    rebuilt: dict[str, int] = {}
    crossings: dict[str, list[int]] = {}
    boxes: dict[str, list[float]] = {}
    jumps: dict[str, list[float]] = {}
    xodr_jumps: dict[str, list[float]] = {}
    rounded: dict[str, list[bool]] = {}
    round_misses: list[tuple] = []
    round_named: dict[str, set[tuple[str, str]]] = {}  # the (connector, loop) pairs counted
    failed = []
    for name, sample, secs, *built in done:
        if len(built) == 1:
            failed.append(f"{name} sample {sample}: NOT BUILT ({secs:.2f} s): {built[0]}")
            print(failed[-1], flush=True)
            continue
        ic_rows, ic_fits, dense, again, bridges, box, jump, rnd = built
        rounded.setdefault(name, []).extend(r[0] for r in rnd)
        round_misses += [(name, sample, *r[1:]) for r in rnd if not r[0]]
        round_named.setdefault(name, set()).update((r[1], r[2]) for r in rnd)
        jumps.setdefault(name, []).extend(jump[0])
        xodr_jumps.setdefault(name, []).extend(jump[1])
        boxes.setdefault(name, []).append(box[0] * box[1] / 1e6)
        crossings.setdefault(name, []).append(bridges)
        if again:
            rebuilt[name] = rebuilt.get(name, 0) + 1
        if dense:
            dense_bad[name] = dense_bad.get(name, 0) + 1
            print(f"{name} sample {sample}: same-level conflicts (dense check): "
                  + ", ".join(f"{c.ramp}/{c.other} at {c.s_m:.0f} m ({c.length_m:.1f} m)"
                              for c in dense))
        per_ic.append(secs)
        by_design.setdefault(name, []).append(secs)
        rows += ic_rows
        fits += ic_fits
        print(f"{name} sample {sample}: {sum(f.ok for f in ic_fits)}/"
              f"{len(ic_fits)} ramps ok, {secs:.2f} s", flush=True)
    if pool is not None:
        pool.close()
    if not rows:
        print(f"no interchange built; not built or not exported: {len(failed)}")
        return
    print("\nclass (design)                 ramps  first-try-ok  resampled  ok  infeasible  conflict")
    tot = dict(ramps=0, first_try_ok=0, resampled=0, ok=0, infeasible=0, conflicts=0)
    for s in summary(rows):
        print(f"{s['class_id']} ({names[s['class_id']]:<17}) {s['ramps']:5d}  {s['first_try_ok']:12d}"
              f"  {s['resampled']:9d}  {s['ok']:3d}  {s['infeasible']:10d}  {s['conflicts']:8d}")
        for k in tot:
            tot[k] += s[k]
    print(f"{'total':<31}{tot['ramps']:5d}  {tot['first_try_ok']:12d}  {tot['resampled']:9d}"
          f"  {tot['ok']:3d}  {tot['infeasible']:10d}  {tot['conflicts']:8d}")
    print(f"first try within tolerance: {100 * tot['first_try_ok'] / tot['ramps']:.1f} %; "
          f"ok or recorded infeasible: "
          f"{100 * sum(r['ok'] or bool(r['infeasible']) for r in rows) / len(rows):.1f} %")
    print(f"interchanges with a same-level conflict, dense check (lane centres <= 1 m apart, "
          f"flyover.geometry.check): {sum(dense_bad.values())} of {len(per_ic)} {dense_bad or ''}")
    print(f"interchanges not built or not exported: {len(failed)} of {len(per_ic) + len(failed)}")
    for line in failed:
        print(f"  {line}")
    print(f"interchanges kept from a rebuild with other seeds (a ramp met something at its "
          f"level, or an outer connector went over or under its loop): {sum(rebuilt.values())} of {len(per_ic)} {rebuilt or ''}")
    ramp_s = np.array([r["seconds"] for r in rows])  # all DE runs of the ramp
    print(f"\nper interchange (CPU s): median {np.median(per_ic):.3f}  p95 "
          f"{np.percentile(per_ic, 95):.3f}  (n={len(per_ic)})")
    for name, secs in sorted(by_design.items()):
        print(f"  {name:<17} median {np.median(secs):.3f}  p95 {np.percentile(secs, 95):.3f}  "
              f"max {max(secs):.2f}  (n={len(secs)})")
    print(f"per ramp incl. restarts/lifts/resamples, vectorised DE (wall s): median {np.median(ramp_s):.3f}  p95 "
          f"{np.percentile(ramp_s, 95):.3f}  (n={len(ramp_s)})")
    lengths: dict[str, list[float]] = {}
    for r in rows:
        lengths.setdefault(names[r["class_id"]], []).append(r["length_m"])
    print("ramp length (m):")
    for name, ls in sorted(lengths.items()):
        print(f"  {name:<17} median {np.median(ls):6.0f}  p95 {np.percentile(ls, 95):6.0f}  "
              f"max {max(ls):6.0f}  (n={len(ls)})", end="")
        cid = next(c for c, n in names.items() if n == name)
        if real_by_ramp.get(cid):  # the real interchange's ramps (OSM length_m)
            rl = list(real_by_ramp[cid].values())
            print(f"   real: median {np.median(rl):6.0f}  p95 {np.percentile(rl, 95):6.0f}  "
                  f"max {max(rl):6.0f}  (n={len(rl)})", end="")
        print()
    if args.real_features is not None:
        print_real_comparison(rows, names, real_by_ramp)
    print("ramp length / what it needs (its turn at its radius or its climb at its slope, "
          "and two tapers; benchmarks.geometry.need_m):")
    ratios: dict[str, list[float]] = {}
    for r in rows:
        ratios.setdefault(names[r["class_id"]], []).append(r["stretch"])
    for name, xs in sorted(ratios.items()) + [("total", [r["stretch"] for r in rows])]:
        print(f"  {name:<17} median {np.median(xs):5.2f}  p95 {np.percentile(xs, 95):5.2f}  "
              f"max {max(xs):5.2f}  over 1.5: {sum(x > 1.5 for x in xs)} of {len(xs)}")
    print("ramp length / the least it can be (between its windows at its radius, its turn, "
          "its climb; benchmarks.geometry.least_m; ramps between two windows, within targets):")
    detours: dict[str, list[float]] = {}
    for r in rows:
        if math.isfinite(r["detour"]):
            detours.setdefault(names[r["class_id"]], []).append(r["detour"])
    every = [x for xs in detours.values() for x in xs]
    for name, xs in sorted(detours.items()) + ([("total", every)] if every else []):
        print(f"  {name:<17} median {np.median(xs):5.2f}  p95 {np.percentile(xs, 95):5.2f}  "
              f"max {max(xs):5.2f}  over 1.5: {sum(x > 1.5 for x in xs)}, over 2: "
              f"{sum(x > 2 for x in xs)} of {len(xs)}")
    print(f"ramps longer than their bound (geometry.max_length_ratio, RampFit.max_length_m): "
          f"{sum(r['over_bound'] for r in rows)} of {len(rows)}, of them ok: "
          f"{sum(r['over_bound'] and r['ok'] for r in rows)}")
    print("footprint (bounding box of the ramps, km²):")
    for name, bs in sorted(boxes.items()):
        print(f"  {name:<17} median {np.median(bs):6.2f}  max {max(bs):6.2f}  (n={len(bs)})")
    print("re-measured from the .xodr: ramps within 5 % of the radius target / 0.2 pp of the "
          "slope target / both (of geometry.parquet's targets)")
    by_name: dict[str, list] = {}
    for r in rows:
        by_name.setdefault(names[r["class_id"]], []).append(
            agrees(r, settings.fit.inf_reference_m))
    ref: dict[str, list] = {}
    for r in rows:
        ref.setdefault(names[r["class_id"]], []).append(
            agrees(r, settings.fit.inf_reference_m, "xodr_ref_radius_m")[0])
    circ: dict[str, list] = {}
    for r in rows:
        circ.setdefault(names[r["class_id"]], []).append(
            agrees(r, settings.fit.inf_reference_m, "xodr_3pt_radius_m")[0])
    every = [a for v in by_name.values() for a in v]
    for name, ag in sorted(by_name.items()) + [("total", every)]:
        n = len(ag)
        rf = ref.get(name, [x for v in ref.values() for x in v])
        rc = circ.get(name, [x for v in circ.values() for x in v])
        print(f"  {name:<17} radius {100 * sum(a for a, _ in ag) / n:5.1f} %  slope "
              f"{100 * sum(b for _, b in ag) / n:5.1f} %  both {100 * sum(a and b for a, b in ag) / n:5.1f} %"
              f"  (n={n});  radius of the line width / 2 right of the reference line "
              f"{100 * sum(rf) / n:5.1f} %, by three-point circles {100 * sum(rc) / n:5.1f} %")
    bad = [r for r in rows if not all(agrees(r, settings.fit.inf_reference_m))]
    for r in bad[:args.show_misses]:
        print(f"    miss {names[r['class_id']]} {r['sample']} {r['ramp']}: radius "
              f"{r['target_radius_m']:g} -> {r['xodr_radius_m']:.1f} "
              f"(reference line - width / 2 {r['xodr_ref_radius_m']:.1f}, three-point "
              f"{r['xodr_3pt_radius_m']:.1f}, fit "
              f"{r['min_radius_m']:.1f}),"
              f" slope {r['target_slope_pct']:g} -> {r['xodr_slope_pct']:.2f} "
              f"(fit {r['max_slope_pct']:.2f}) {r['infeasible'][:60]}")
    print("outer connectors that go round their loop (not over or under it, "
          "flyover.geometry.check.ramp_crossings):")
    for name, rs in sorted(rounded.items()):
        if rs:
            pairs = " ".join(f"{a}/{b}" for a, b in sorted(round_named[name]))
            print(f"  {name:<17} {100 * sum(rs) / len(rs):5.1f} %  (n={len(rs)}; {pairs})")
    for name, sample, ramp, loop, r_ramp, r_loop in round_misses[:args.show_rounds]:
        print(f"    over/under {name} {sample} {ramp} (radius target {r_ramp:g}) and its loop "
              f"{loop} ({r_loop:g})")
    print("grade jump where a ramp leaves / joins a ramp (pp; > 0.5 pp counted):")
    for name, js in sorted(jumps.items()):
        if js:
            xs = xodr_jumps.get(name) or [math.nan]
            print(f"  {name:<17} max {max(js):5.2f}  over 0.5 pp: {sum(j > 0.5 for j in js)} of "
                  f"{len(js)};  read back from the .xodr (every road link between two ramps): "
                  f"max {max(xs):5.2f}  over 0.5 pp: {sum(j > 0.5 for j in xs)} of {len(xs)}")
    print("ramps crossing ramps in plan (a bridge each; flyover.geometry.check.ramp_crossings) "
          "per interchange:")
    for name, xs in sorted(crossings.items()):
        print(f"  {name:<17} mean {np.mean(xs):5.2f}  max {max(xs):3d}  (n={len(xs)})")
    rng = np.random.default_rng(0)
    pick = rng.choice(len(fits), size=min(args.plain_ramps, len(fits)), replace=False)
    engines = {"flyover DE (JADE, compiled objective)": settings.fit,
               "scipy DE, vectorised": replace(settings.fit, engine="scipy"),
               "scipy DE, plain (one call per candidate)": replace(settings.fit, engine="scipy",
                                                                    vectorized=False)}
    for label, fit_settings in engines.items() if len(pick) else ():
        secs, ok = [], 0
        for i in pick:
            f = fits[i]
            t0 = time.process_time()
            a = fit_ramp(f.spec, None, fit_settings, seed=7)
            secs.append(time.process_time() - t0)
            ok += a.radius_ok and a.slope_ok
        print(f"same {len(pick)} ramps alone (no obstacles), {label}: median "
              f"{np.median(secs):.3f} p95 {np.percentile(secs, 95):.3f} CPU s, {ok} within tolerance")

if __name__ == "__main__":
    main()
