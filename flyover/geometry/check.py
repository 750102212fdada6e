"""An independent check of a built interchange: same-level conflicts, densely.

The search counts conflicts on 64 samples per Bézier piece (pieces can be
hundreds of metres long). This check reads only the ``geometry.json`` value and
samples every ramp's lane centre line at most ``spacing_m`` apart, so a crossing
that slips between the search's samples is still found.

Rule (the fitter's, made symmetric): a lane-centre sample of ramp A, outside
``end_zone_m`` of A's ends, conflicts with

* a road when it lies on the road's driving lanes widened by A's half width
  (less ``margin_m``) and is less than ``clearance_m`` above or below it;
* a ramp B when a lane-centre sample of B, outside B's end zones, is closer
  than the two half widths (less ``margin_m`` each) and less than
  ``clearance_m`` apart in height;
* itself, the same way, at a sample of its own lane centre more than ``2 x`` its
  width further along it (a loop that turns far enough passes over or under its
  own earlier part; samples closer along it are neighbours on one stretch of lane,
  never a crossing: within the two half widths in plan only if the lane turned
  back within a few metres).

Distances and heights are compared to ``tolerance_m`` (5 cm): the search
follows the lane centre and the profile in straight steps between its samples.

Example
-------
>>> from flyover.geometry.model import InterchangeGeometry
>>> same_level_conflicts(InterchangeGeometry(class_id="c0", sample=0, seed=1))
()
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Collection

import numpy as np
from scipy.spatial import cKDTree

from flyover.geometry.bezier import lane_centre, sample_spline
from flyover.geometry.model import InterchangeGeometry, RampGeometry
from flyover.geometry.profile import evaluate_polys

__all__ = ["Conflict", "Crossing", "ramp_crossings", "same_level_conflicts"]


@dataclass(frozen=True)
class Conflict:
    """Ramp ``ramp`` meets ``other`` (a road or ramp) at one level around station
    ``s_m`` (the first conflicting sample; ``length_m`` of its stations conflict)."""

    ramp: str
    other: str
    s_m: float
    length_m: float
    dz_m: float


@dataclass(frozen=True)
class Crossing:
    """Ramp ``ramp`` passes over or under ``other`` (a ramp) at its station ``s_m``,
    ``dz_m`` apart in height (signed: ``ramp`` above ``other`` when positive)."""

    ramp: str
    other: str
    s_m: float
    dz_m: float


def _lane_centre(ramp: RampGeometry, width: float, spacing: float):
    ctrl = np.array([p.p for p in ramp.plan], float)
    m = max(8, math.ceil(2.0 * max(p.length_m for p in ramp.plan) / spacing))
    smp = sample_spline(ctrl, m)
    xy = np.stack(lane_centre(smp.xy, smp.tangent, width), axis=-1)
    z, _ = evaluate_polys(ramp.elevation, smp.s)
    return xy, z, smp.s, float(smp.length)


def _runs(ramp: str, other: str, s: np.ndarray, hit: np.ndarray, dz: np.ndarray,
          spacing: float) -> list[Conflict]:
    out = []
    idx = np.flatnonzero(hit)
    if not len(idx):
        return out
    breaks = np.flatnonzero(np.diff(s[idx]) > 2.0 * spacing) + 1
    for part in np.split(idx, breaks):
        out.append(Conflict(ramp, other, float(s[part[0]]), float(s[part[-1]] - s[part[0]]),
                            float(np.min(np.abs(dz[part])))))
    return out


def _self_conflicts(rid: str, xy: np.ndarray, z: np.ndarray, s: np.ndarray, hw: float,
                    gap: float, clearance: float, spacing: float) -> list[Conflict]:
    """Where ramp ``rid``'s lane centre (inner samples) comes within its two half widths
    ``hw`` of itself more than ``gap`` further along, less than ``clearance`` apart in
    height: marked at the earlier station of each such pair."""
    if len(s) < 2:
        return []
    pairs = cKDTree(xy).query_pairs(2.0 * hw, output_type="ndarray")
    if not len(pairs):
        return []
    i, j = pairs.min(axis=1), pairs.max(axis=1)
    far = np.abs(s[j] - s[i]) > gap
    i, j = i[far], j[far]
    dz = np.full(len(s), np.inf)
    np.minimum.at(dz, i, np.abs(z[i] - z[j]))
    return _runs(rid, rid, s, dz < clearance, dz, spacing)


def same_level_conflicts(geometry: InterchangeGeometry, *, spacing_m: float = 1.0,
                         clearance_m: float = 5.5, end_zone_m: float = 15.0,
                         margin_m: float = 0.5, tolerance_m: float = 0.05
                         ) -> tuple[Conflict, ...]:
    """Every same-level conflict of ``geometry``, one :class:`Conflict` per run of
    conflicting stations (ramp-ramp pairs reported once, by the first ramp id; a ramp
    meeting itself once, ``other`` its own id, at the earlier of its two stations)."""
    clearance_m -= tolerance_m
    lanes, gaps = {}, {}
    for r in geometry.ramps:
        width = r.lanes * geometry.ramp_lane_width_m
        xy, z, s, length = _lane_centre(r, width, spacing_m)
        inner = (s > end_zone_m) & (s < length - end_zone_m)
        # one sample per quarter spacing (a piece is sampled as finely as the longest one:
        # up to ten per metre, which made the pair searches quadratic in that density)
        inner &= np.diff(np.floor(4.0 * s / spacing_m), prepend=-1.0) > 0
        lanes[r.id] = (xy[inner], z[inner], s[inner], 0.5 * width - margin_m - tolerance_m / 2)
        gaps[r.id] = 2.0 * width
    out: list[Conflict] = []
    for rid, (xy, z, s, hw) in sorted(lanes.items()):
        out += _self_conflicts(rid, xy, z, s, hw, gaps[rid], clearance_m, spacing_m)
        for road in geometry.roads:
            d = np.array([math.cos(road.heading_rad), math.sin(road.heading_rad)])
            rel = xy - np.asarray(road.start)
            along = rel @ d
            lat = d[0] * rel[:, 1] - d[1] * rel[:, 0]
            dz = z - road.z_m
            hit = ((np.abs(dz) < clearance_m) & (along > 0.0) & (along < road.length_m)
                   & (lat > -road.lanes * geometry.lane_width_m - hw) & (lat < hw))
            out += _runs(rid, road.id, s, hit, dz, spacing_m)
    ids = sorted(lanes)
    trees = {i: cKDTree(lanes[i][0]) for i in ids if len(lanes[i][0])}
    for a_i, a in enumerate(ids):
        if a not in trees:
            continue
        xy, z, s, hw = lanes[a]
        for b in ids[a_i + 1:]:
            if b not in trees:
                continue
            zb, hwb = lanes[b][1], lanes[b][3]
            near = trees[a].query_ball_tree(trees[b], hw + hwb)
            hit = np.zeros(len(s), bool)
            dz = np.full(len(s), np.inf)
            for i, js in enumerate(near):
                if js:
                    d = np.abs(z[i] - zb[js]).min()
                    dz[i] = d
                    hit[i] = d < clearance_m
            out += _runs(a, b, s, hit, dz, spacing_m)
    return tuple(out)


def ramp_crossings(geometry: InterchangeGeometry, *, spacing_m: float = 2.0,
                   end_zone_m: float = 15.0,
                   pairs: Collection[frozenset[str]] | None = None) -> tuple[Crossing, ...]:
    """Where two ramps cross in plan (their lane centres intersect, outside their end
    zones): each is a ramp bridge, and none is at one level when
    :func:`same_level_conflicts` finds nothing. Pairs attached to each other are
    skipped (they meet where one leaves or joins the other); each pair is reported
    once, by the first ramp id. ``pairs``: only these pairs of ramp ids (every pair if
    ``None``).

    Example
    -------
    >>> from flyover.geometry.model import InterchangeGeometry
    >>> ramp_crossings(InterchangeGeometry(class_id="c0", sample=0, seed=1))
    ()
    """
    lanes = {}
    wanted = None if pairs is None else set().union(*pairs)
    for r in geometry.ramps:
        if wanted is not None and r.id not in wanted:
            continue
        xy, z, s, length = _lane_centre(r, r.lanes * geometry.ramp_lane_width_m, spacing_m)
        inner = (s > end_zone_m) & (s < length - end_zone_m)
        lanes[r.id] = (xy[inner], z[inner], s[inner])
    attached = {frozenset((r.id, a.parent)) for r in geometry.ramps
                for a in (r.start, r.end) if a is not None}
    out: list[Crossing] = []
    ids = sorted(i for i in lanes if len(lanes[i][0]) > 1)
    trees = {i: cKDTree(0.5 * (lanes[i][0][1:] + lanes[i][0][:-1])) for i in ids}
    reach = {i: float(np.linalg.norm(np.diff(lanes[i][0], axis=0), axis=1).max()) for i in ids}
    for a_i, a in enumerate(ids):
        pa, za, sa = lanes[a]
        for b in ids[a_i + 1:]:
            if frozenset((a, b)) in attached or (pairs is not None
                                                 and frozenset((a, b)) not in pairs):
                continue
            pb, zb, sb = lanes[b]
            # segments that intersect have midpoints within half their lengths' sum
            near = trees[a].query_ball_tree(trees[b], 0.5 * (reach[a] + reach[b]) + 1e-9)
            hits = []
            for i, js in enumerate(near):
                if not js:
                    continue
                j = np.asarray(js)
                p0, p1, q0, q1 = pa[i], pa[i + 1], pb[j], pb[j + 1]
                d1 = _orient(p0, p1, q0)
                d2 = _orient(p0, p1, q1)
                d3 = _orient(q0, q1, p0)
                d4 = _orient(q0, q1, p1)
                for k in j[(d1 * d2 < 0) & (d3 * d4 < 0)]:
                    hits.append((float(sa[i]), float(za[i] - zb[k])))
            hits.sort()
            last = -np.inf
            for s_m, dz in hits:
                if s_m - last > 2.0 * spacing_m:  # one crossing, not its neighbouring segments
                    out.append(Crossing(a, b, s_m, dz))
                last = s_m
    return tuple(out)


def _orient(u: np.ndarray, v: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Twice the signed area of triangles (u, v, w): > 0 when w is left of u → v."""
    return ((v[..., 0] - u[..., 0]) * (w[..., 1] - u[..., 1])
            - (v[..., 1] - u[..., 1]) * (w[..., 0] - u[..., 0]))
