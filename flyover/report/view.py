"""The interactive plan view of one interchange, drawn from its ``geometry.json``.

The view is an SVG made here (no JavaScript is needed to see it): every
carriageway is a band as wide as its lanes, every ramp a stroke along its lane
centre as wide as its lanes, cut into pieces of about :data:`PIECE_M` metres
that each take the colour of their mean height (viridis, as ``plan.png``);
higher pieces are drawn over lower ones, so flyovers read at a glance. The
report's ``viewer.js`` adds pan, zoom and the hover box from the ``info`` of
each element.

Example
-------
>>> from flyover.geometry.model import InterchangeGeometry, RoadGeometry
>>> g = InterchangeGeometry("c0000000000", 0, 1, roads=(RoadGeometry(
...     "A1", "A", 2, 0, 0.0, (0.0, 0.0), 0.0, 100.0),))
>>> v = plan_view(g)
>>> [e.element for e in v.shapes], v.height_range_m
(['A1'], (0.0, 1.0))
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from flyover.geometry.bezier import lane_centre, sample_spline
from flyover.geometry.model import InterchangeGeometry
from flyover.geometry.profile import evaluate_polys

__all__ = ["PIECE_M", "Shape", "PlanView", "plan_view", "viridis_hex"]

#: length of the pieces a ramp is cut into for its colours (metres)
PIECE_M = 20.0


@dataclass(frozen=True)
class Shape:
    """One drawn piece: a road band (``polygon``) or a piece of ramp (``polyline``).

    ``points`` is the SVG ``points`` text in view coordinates (x east, y south:
    the plan's y negated), ``width`` the stroke width of a polyline (metres).
    """

    element: str
    kind: str
    tag: str
    points: str
    z_m: float
    colour: str
    width: float = 0.0


@dataclass(frozen=True)
class PlanView:
    """What the template draws: shapes in drawing order, hover lines, labels, extent.

    ``hits`` are the whole lane centre lines of the ramps, drawn on top without
    colour, wider than the ramp, so that a ramp is easy to point at at any zoom.
    ``info`` maps each element to the facts the hover box shows.
    """

    view_box: tuple[float, float, float, float]
    shapes: tuple[Shape, ...]
    hits: tuple[tuple[str, str], ...]
    labels: tuple[tuple[str, float, float], ...]
    height_range_m: tuple[float, float]
    legend: tuple[str, ...]
    info: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)


#: viridis at 9 stops (matplotlib's), interpolated linearly
_VIRIDIS = np.array([
    (0x44, 0x01, 0x54), (0x47, 0x2d, 0x7b), (0x3b, 0x52, 0x8b), (0x2c, 0x72, 0x8e),
    (0x21, 0x91, 0x8c), (0x28, 0xae, 0x80), (0x5e, 0xc9, 0x62), (0xad, 0xdc, 0x30),
    (0xfd, 0xe7, 0x25)], float)


def viridis_hex(t: float) -> str:
    """The viridis colour at ``t`` in 0..1 as ``#rrggbb``.

    >>> viridis_hex(0.0), viridis_hex(1.0)
    ('#440154', '#fde725')
    """
    t = min(max(float(t), 0.0), 1.0) * (len(_VIRIDIS) - 1)
    i = min(int(t), len(_VIRIDIS) - 2)
    rgb = _VIRIDIS[i] + (t - i) * (_VIRIDIS[i + 1] - _VIRIDIS[i])
    return "#" + "".join(f"{int(round(c)):02x}" for c in rgb)


def _points(x, y) -> str:
    """SVG points ``x,-y`` to 0.1 m (one C-level format of the whole list)."""
    xy = np.empty(2 * len(x))
    xy[0::2], xy[1::2] = x, -np.asarray(y, dtype=float)
    return " ".join(["%.1f,%.1f"] * len(x)) % tuple(xy.tolist())


def _ramp_centre(ramp, width: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Lane-centre x, y, height z and station s of a ramp, about every 4 m (the chord of
    4 m departs from a 30 m radius by 7 cm: invisible at any zoom that shows the lane)."""
    ctrl = np.array([p.p for p in ramp.plan], float)
    m = max(8, math.ceil(max(p.length_m for p in ramp.plan) / 4.0))
    smp = sample_spline(ctrl, m)
    x, y = lane_centre(smp.xy, smp.tangent, width)
    z, _ = evaluate_polys(ramp.elevation, smp.s) if ramp.elevation else (np.zeros_like(smp.s), None)
    return x, y, z, smp.s


def _entry(x: float, y: float, ux: float, uy: float, length: float,
           frame: tuple[float, float, float, float]) -> float | None:
    """Where (station) the segment from (x, y) along (ux, uy) for ``length`` enters the
    rectangle ``frame`` (x0, x1, y0, y1), ``None`` if it misses it (Liang–Barsky)."""
    lo, hi = 0.0, length
    for p, d, a, b in ((x, ux, frame[0], frame[1]), (y, uy, frame[2], frame[3])):
        if abs(d) < 1e-12:
            if not a <= p <= b:
                return None
            continue
        t0, t1 = sorted(((a - p) / d, (b - p) / d))
        lo, hi = max(lo, t0), min(hi, t1)
    return lo if lo <= hi else None


def plan_view(geometry: InterchangeGeometry, extra: Mapping[str, Mapping[str, Any]] | None = None
              ) -> PlanView:
    """The plan view of ``geometry``; ``extra`` adds facts per element to the hover box
    (e.g. the truck's fuel on each ramp)."""
    extra = extra or {}
    pieces: list[tuple[float, str, str, str, str, float]] = []  # z, element, kind, tag, pts, w
    hits: list[tuple[str, str]] = []
    labels: list[tuple[str, float, float]] = []
    info: dict[str, dict[str, Any]] = {}
    xs: list[float] = []
    ys: list[float] = []
    rxs: list[float] = []  # the ramps' extent: what the view frames first
    rys: list[float] = []
    centre: list[tuple[str, float, float, float, float, float]] = []
    for road in geometry.roads:
        width = road.lanes * geometry.lane_width_m
        h = road.heading_rad
        ux, uy = math.cos(h), math.sin(h)
        nx, ny = uy, -ux  # to the right of the reference line (its left edge)
        x0, y0 = road.start
        x1, y1 = x0 + ux * road.length_m, y0 + uy * road.length_m
        px = np.array([x0, x1, x1 + nx * width, x0 + nx * width])
        py = np.array([y0, y1, y1 + ny * width, y0 + ny * width])
        xs += list(px)
        ys += list(py)
        pieces.append((road.z_m, road.id, "road", "polygon", _points(px, py), 0.0))
        centre.append((road.id, x0 + nx * width / 2, y0 + ny * width / 2, ux, uy, road.length_m))
        info[road.id] = {"kind": "road", "name": road.id, "expressway": road.expressway,
                         "lanes": road.lanes, "height_m": road.z_m, "length_m": road.length_m}
    for ramp in geometry.ramps:
        if not ramp.plan:
            continue
        width = ramp.lanes * geometry.ramp_lane_width_m
        x, y, z, s = _ramp_centre(ramp, width)
        rxs += [float(x.min()) - width, float(x.max()) + width]
        rys += [float(y.min()) - width, float(y.max()) + width]
        n = max(1, math.ceil(float(s[-1]) / PIECE_M))
        cuts = np.searchsorted(s, np.linspace(0.0, float(s[-1]), n + 1)[1:-1])
        bounds = [0, *cuts.tolist(), len(s) - 1]
        for a, b in zip(bounds[:-1], bounds[1:]):
            if b <= a:
                continue
            sl = slice(a, b + 1)  # pieces share their end points: no gaps
            pieces.append((float(z[sl].mean()), ramp.id, "ramp", "polyline",
                           _points(x[sl], y[sl]), width))
        hits.append((ramp.id, _points(x[::2].tolist() + [x[-1]], y[::2].tolist() + [y[-1]])
                     if len(x) > 3 else _points(x, y)))
        mid = len(x) // 2
        labels.append((ramp.id, float(x[mid]), -float(y[mid])))
        info[ramp.id] = {
            "kind": "ramp", "name": ramp.id, "lanes": ramp.lanes,
            "from": f"{ramp.start.parent} ({ramp.start.label})" if ramp.start.parent
            else "the ramps that merge into it",
            "to": f"{ramp.end.parent} ({ramp.end.label})" if ramp.end.parent
            else "the ramps it splits into",
            "target_radius_m": ramp.target_radius_m, "min_radius_m": ramp.min_radius_m,
            "target_slope_pct": ramp.target_slope_pct, "max_slope_pct": ramp.max_slope_pct,
            "length_m": ramp.length_m, "height_m": [float(z.min()), float(z.max())],
            "ok": ramp.ok, "resamples": ramp.resamples, "infeasible": ramp.infeasible}
    for element, facts in extra.items():
        if element in info:
            info[element].update(facts)
    zs = [p[0] for p in pieces] or [0.0]
    zmin, zmax = min(zs), max(max(zs), min(zs) + 1.0)
    shapes = tuple(
        Shape(element, kind, tag, pts, zp, viridis_hex((zp - zmin) / (zmax - zmin)), w)
        # higher on top; at one height roads under ramps; stable order otherwise
        for zp, element, kind, tag, pts, w in sorted(pieces, key=lambda p: (round(p[0], 3),
                                                                             p[2] == "ramp")))
    # frame the ramps (the carriageways run on beyond, a zoom out away), else everything
    fx, fy = (rxs, rys) if rxs else (xs, ys)
    if fx:
        pad = max(30.0, 0.06 * max(max(fx) - min(fx), max(fy) - min(fy)))
        x0, x1, y0, y1 = min(fx) - pad, max(fx) + pad, min(fy) - pad, max(fy) + pad
    else:
        x0, x1, y0, y1 = -100.0, 100.0, -100.0, 100.0
    for road_id, cx, cy, ux, uy, length in centre:
        s_in = _entry(cx, cy, ux, uy, length, (x0, x1, y0, y1))
        s_label = min(s_in + 0.04 * (x1 - x0), length) if s_in is not None else length / 2
        labels.insert(0, (road_id, cx + ux * s_label, -(cy + uy * s_label)))
    x0, x1, y0, y1 = x0, x1, -y1, -y0  # view coordinates: y south
    legend = tuple(viridis_hex(i / 8) for i in range(9))
    return PlanView((round(x0, 1), round(y0, 1), round(x1 - x0, 1), round(y1 - y0, 1)),
                    shapes, tuple(hits), tuple(labels), (zmin, zmax), legend, info)
