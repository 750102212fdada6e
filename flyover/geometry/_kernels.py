"""Compiled inner loop of the ramp objective (numba): shape terms and same-level conflicts.

:func:`conflicts` counts, per candidate ramp, the lane-centre samples that
meet an obstacle at the same level (closer than ``clearance`` in height):

* a road's driving band, given in its own frame (``lines`` rows
  ``x0, y0, dx, dy, t_lo, t_hi, lat_lo, lat_hi, z``), widened by the ramp's
  half width;
* a sample of an already fitted ramp closer than the two half widths.

Ramp samples sit in a uniform grid (:func:`grid`, with the cells' height
ranges), so a stretch looks only at the cells within the largest reach of its
box whose heights come within the clearance of its own.
Between two samples a candidate's lane centre is a straight stretch (height and
station linear along it), tested exactly against road bands and obstacle ramp
points (which lie at most :data:`STEP_M` apart), so that a crossing cannot slip
between samples. Only the inner points count (``end_zone`` from
either end, where a ramp leaves or joins its parent, is exempt).

A candidate whose heading spans far enough for it to cross itself (over
:data:`SELF_TURN_RAD`: loops, and curves that loop and turn back) is also tested
against its own lane centre (:func:`self_conflicts`), stretch against stretch.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["STEP_M", "SELF_TURN_RAD", "grid", "cell_heights", "conflicts", "self_conflicts"]


def grid(points: np.ndarray, cell: float) -> tuple[np.ndarray, np.ndarray, float, float, int, int]:
    """Bucket ``points`` ``(N, 2)`` into square cells of side ``cell``.

    Returns the point order (by cell), the first index of each cell in that
    order (``nx * ny + 1`` entries), the grid origin and its size in cells.
    See :func:`cell_heights` for the cells' height ranges.
    """
    if len(points) == 0:
        return np.zeros(0, np.int64), np.zeros(2, np.int64), 0.0, 0.0, 1, 1
    x0, y0 = points.min(0) - cell
    nx = int((points[:, 0].max() - x0) // cell) + 2
    ny = int((points[:, 1].max() - y0) // cell) + 2
    key = ((points[:, 0] - x0) // cell).astype(np.int64) * ny + \
        ((points[:, 1] - y0) // cell).astype(np.int64)
    order = np.argsort(key, kind="stable")
    starts = np.searchsorted(key[order], np.arange(nx * ny + 1))
    return order, starts.astype(np.int64), float(x0), float(y0), nx, ny


def cell_heights(z_sorted: np.ndarray, starts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lowest and highest height of the points in each cell (``z_sorted`` in the
    order of :func:`grid`; empty cells get ``+inf``, ``-inf``): a stretch clear of a
    cell's range by the clearance cannot meet any of its points."""
    cells = len(starts) - 1
    lo, hi = np.full(cells, np.inf), np.full(cells, -np.inf)
    full = starts[1:] > starts[:-1]
    if full.any():
        lo[full] = np.minimum.reduceat(z_sorted, starts[:-1][full])
        hi[full] = np.maximum.reduceat(z_sorted, starts[:-1][full])
    return lo, hi


#: longest spacing (m) of an obstacle ramp's lane-centre points (see layout's record)
STEP_M = 2.0
#: a ramp's radius is the tightest one it *holds* over this much arc (m): the mean
#: curvature over every stretch this long (:func:`flyover.geometry.bezier.held_radius`).
#: A curve that is tight only for a few metres (a cubic that meets a small radius
#: target with a kink at its end and is gentle everywhere else) does not turn at that
#: radius, and the exported road (tapers, lane sections) does not show it either.
HOLD_M = 10.0
#: an obstacle ramp's points are STEP_M apart, so a point within the two half widths of
#: its lane centre line may lie up to STEP_M / 2 along it from the nearest one: the
#: reach to a point is widened to cover that (never by more than 0.2 m for one lane)
_ALONG2 = (STEP_M / 2) ** 2


@njit(cache=True, inline="always")
def _clip(v0, dv, lo, hi, tl, th):  # pragma: no cover - compiled
    """The part of ``[tl, th]`` where ``lo < v0 + dv t < hi`` (empty: ``tl > th``)."""
    if dv == 0.0:
        if v0 <= lo or v0 >= hi:
            return 1.0, 0.0
        return tl, th
    t1, t2 = (lo - v0) / dv, (hi - v0) / dv
    if t1 > t2:
        t1, t2 = t2, t1
    return max(tl, t1), min(th, t2)


@njit(cache=True, inline="always")
def _least(c, m, t):  # pragma: no cover - compiled
    """The least of the four linear functions ``c[k] + m[k] t`` at ``t``."""
    return min(min(c[0] + m[0] * t, c[1] + m[1] * t), min(c[2] + m[2] * t, c[3] + m[3] * t))


@njit(cache=True, inline="always")
def _band_depth(xa, ya, za, sa, xb, yb, zb, sb, t0, hw, clearance, row, s_lo,
                s_hi):  # pragma: no cover - compiled
    """How deep the stretch ``a + t (b - a)``, ``t0 <= t <= 1``, gets into a road's band
    ``row`` (0: clear), counting only points with stations in ``(s_lo, s_hi)``.

    Along, across, height and station are linear in ``t``: the points inside the
    band and the end zones' limits form an interval, and the depth (the least of
    the two ways out sideways and the two ways out up/down, a concave piecewise
    linear function) is largest at an end of it or where two of those ways meet.
    """
    dz0 = row[8]
    if (za - dz0 >= clearance and zb - dz0 >= clearance) or \
            (dz0 - za >= clearance and dz0 - zb >= clearance):
        return 0.0
    rxa, rya, rxb, ryb = xa - row[0], ya - row[1], xb - row[0], yb - row[1]
    al_a = rxa * row[2] + rya * row[3]
    al_b = rxb * row[2] + ryb * row[3]
    tl, th = _clip(al_a, al_b - al_a, row[4], row[5], t0, 1.0)
    if tl > th:
        return 0.0
    la = row[2] * rya - row[3] * rxa
    lb = row[2] * ryb - row[3] * rxb
    lo, hi = row[6] - hw, row[7] + hw
    tl, th = _clip(la, lb - la, lo, hi, tl, th)
    if tl > th:
        return 0.0
    tl, th = _clip(sa, sb - sa, s_lo, s_hi, tl, th)
    if tl > th:
        return 0.0
    # the ways out, c[k] + m[k] t: up, down, to either side
    c = (clearance - (za - dz0), clearance + (za - dz0), la - lo, hi - la)
    m = (-(zb - za), zb - za, lb - la, -(lb - la))
    best = max(0.0, _least(c, m, tl), _least(c, m, th))
    for i in range(4):  # where two ways out meet inside the interval
        for j in range(i + 1, 4):
            if m[i] != m[j]:
                t = (c[j] - c[i]) / (m[i] - m[j])
                if tl < t < th:
                    best = max(best, _least(c, m, t))
    return best


@njit(cache=True, inline="always")
def _points_depth(xa, ya, za, sa, xb, yb, zb, sb, t0, hw, clearance, px, py, pz, phw, starts,
                  x0, y0, cell, reach, nx, ny, zlo, zhi, s_lo, s_hi):  # pragma: no cover - compiled
    """How deep the stretch ``a + t (b - a)``, ``t0 <= t <= 1``, gets into the obstacle
    ramps' lanes (0: clear), counting only points with stations in ``(s_lo, s_hi)``.

    An obstacle point is met where the stretch passes closer than the reach (the
    two half widths, widened by half the points' spacing, :data:`_ALONG2`) and
    less than the clearance apart in height: an interval of ``t`` (a quadratic
    and a linear condition), found exactly. The depth there (the lesser of the
    ways out, sideways and up/down) is taken at the closest approach within that
    interval or at its middle, whichever is deeper: always positive inside it.
    """
    tl, th = _clip(sa, sb - sa, s_lo, s_hi, t0, 1.0)
    if tl > th:
        return 0.0
    ex, ey, ez = xb - xa, yb - ya, zb - za
    l2 = ex * ex + ey * ey
    # a point the stretch passes within reach of lies within ``reach`` of its box: only the
    # cells that overlap the box widened by ``reach`` are looked at
    gx0 = max(int(np.floor((min(xa, xb) - reach - x0) / cell)), 0)
    gx1 = min(int(np.floor((max(xa, xb) + reach - x0) / cell)), nx - 1)
    gy0 = max(int(np.floor((min(ya, yb) - reach - y0) / cell)), 0)
    gy1 = min(int(np.floor((max(ya, yb) + reach - y0) / cell)), ny - 1)
    z_lo, z_hi = min(za, zb), max(za, zb)
    deep = 0.0
    for ix in range(gx0, gx1 + 1):
        for iy in range(gy0, gy1 + 1):
            c = ix * ny + iy
            if z_lo - zhi[c] >= clearance or zlo[c] - z_hi >= clearance:
                continue
            for j in range(starts[c], starts[c + 1]):
                if z_lo - pz[j] >= clearance or pz[j] - z_hi >= clearance:
                    continue  # never within the clearance in height (the test below, cheaper)
                dx, dy = xa - px[j], ya - py[j]
                r2 = (hw + phw[j]) ** 2 + _ALONG2
                dd = dx * dx + dy * dy
                de = dx * ex + dy * ey
                if l2 > 0.0:
                    disc = de * de - l2 * (dd - r2)
                    if disc <= 0.0:
                        continue
                    sq = np.sqrt(disc)
                    u1, u2 = max(tl, (-de - sq) / l2), min(th, (-de + sq) / l2)
                    t_near = -de / l2
                else:
                    if dd >= r2:
                        continue
                    u1, u2, t_near = tl, th, th
                u1, u2 = _clip(za - pz[j], ez, -clearance, clearance, u1, u2)
                if u1 > u2:
                    continue
                t_near = min(max(t_near, u1), u2)
                for t in (t_near, 0.5 * (u1 + u2)):
                    qx, qy = dx + t * ex, dy + t * ey
                    d = min(clearance - abs(za - pz[j] + t * ez),
                            np.sqrt(r2) - np.sqrt(qx * qx + qy * qy))
                    deep = max(deep, d)
    return deep


@njit(cache=True, nogil=True)
def conflicts(cx, cy, s, z, length, end_zone, hw, clearance, lines,
              px, py, pz, phw, starts, x0, y0, cell, reach, nx, ny, zlo, zhi):  # pragma: no cover - compiled
    """Conflicting inner samples per candidate ``(P,)`` from samples ``(P, N)``, and
    how deep they are in (``(P,)``, metres summed over the conflicting samples).

    Sample ``i`` stands for the stretch of lane centre from sample ``i - 1`` to it
    (heights and stations linear along it): it conflicts when any point of that
    stretch outside the end zones does, tested exactly against road bands
    (:func:`_band_depth`) and obstacle ramp points (:func:`_points_depth`). A point's depth is the least it would
    have to move to be clear of all it meets: sideways (out of a road's band or a
    ramp's lane) or up/down (to the clearance), whichever is less, the largest over
    what it meets; a sample's depth is the largest over its stretch. It grades the
    penalty inside a conflict, which the count alone leaves flat. ``px, py, pz,
    phw``: obstacle ramp samples sorted by grid cell (``starts`` per cell, see
    :func:`grid`; ``zlo, zhi`` their height range per cell, :func:`cell_heights`);
    they should lie no more than :data:`STEP_M` apart along their ramps. ``reach``:
    at least ``hw + phw + STEP_M / 2`` for every point (the cells within it of a
    stretch are the ones looked at).
    """
    p_count, n = cx.shape
    out = np.zeros(p_count, np.int64)
    depth = np.zeros(p_count)
    for p in range(p_count):
        hi_s = length[p] - end_zone
        for i in range(n):
            a = max(i - 1, 0)  # the stretch's start (sample 0 stands for itself)
            t0 = 0.0 if i > 0 else 1.0
            deep = 0.0
            for k in range(lines.shape[0]):
                deep = max(deep, _band_depth(cx[p, a], cy[p, a], z[p, a], s[p, a], cx[p, i],
                                             cy[p, i], z[p, i], s[p, i], t0, hw, clearance,
                                             lines[k], end_zone, hi_s))
            if px.shape[0] > 0:
                deep = max(deep, _points_depth(cx[p, a], cy[p, a], z[p, a], s[p, a],
                                               cx[p, i], cy[p, i], z[p, i], s[p, i], t0, hw,
                                               clearance, px, py, pz, phw, starts, x0, y0,
                                               cell, reach, nx, ny, zlo, zhi, end_zone, hi_s))
            if deep > 0.0:
                out[p] += 1
                depth[p] += deep
    return out, depth


#: a candidate whose lane centre's heading spans more than this (rad) is tested against
#: itself (:func:`self_conflicts`): between two points where a curve crosses itself its
#: heading turns by at least half a turn (the loop it closes: 2 pi less the crossing's
#: angle); 0.9 pi leaves a margin for coming within the lane's width of itself short of
#: crossing. Not the ramp's intended turn: a ramp turning 123 degrees net can loop
#: over itself and turn back (catalog j1)
SELF_TURN_RAD = 0.9 * np.pi
#: stretches per block of :func:`self_conflicts` (blocks whose boxes are apart skip their pairs)
_SELF_BLOCK = 8


@njit(cache=True, inline="always")
def _segment_params(ax, ay, bx, by, cx, cy, dx, dy):  # pragma: no cover - compiled
    """Parameters ``t, u`` in ``[0, 1]`` of the closest points of segments ``a-b`` and
    ``c-d`` (Ericson, Real-Time Collision Detection, 5.1.9)."""
    d1x, d1y, d2x, d2y = bx - ax, by - ay, dx - cx, dy - cy
    rx, ry = ax - cx, ay - cy
    a = d1x * d1x + d1y * d1y
    e = d2x * d2x + d2y * d2y
    f = d2x * rx + d2y * ry
    if a <= 1e-12 and e <= 1e-12:
        return 0.0, 0.0
    if a <= 1e-12:
        return 0.0, min(max(f / e, 0.0), 1.0)
    c = d1x * rx + d1y * ry
    if e <= 1e-12:
        return min(max(-c / a, 0.0), 1.0), 0.0
    b = d1x * d2x + d1y * d2y
    den = a * e - b * b
    t = min(max((b * f - c * e) / den, 0.0), 1.0) if den > 1e-12 else 0.0
    u = (b * t + f) / e
    if u < 0.0:
        u = 0.0
        t = min(max(-c / a, 0.0), 1.0)
    elif u > 1.0:
        u = 1.0
        t = min(max((b - c) / a, 0.0), 1.0)
    return t, u


@njit(cache=True)
def self_conflicts(cx, cy, s, z, length, end_zone, hw, clearance, gap):  # pragma: no cover
    """Where each candidate's lane centre ``(P, N)`` meets itself at one level: pairs of
    stretches (sample ``i - 1`` to ``i``, heights and stations linear) more than ``gap``
    apart along it (station of the later one's start less the earlier one's end) whose
    closest points are within the two half widths ``2 hw`` in plan and less than
    ``clearance`` apart in height, both outside the end zones. Returns the count
    ``(P,)`` and depth (the least move clear, sideways or up/down, summed) ``(P,)``.
    Only candidates whose heading spans more than :data:`SELF_TURN_RAD` can meet
    themselves (the others cost one pass over their samples). Stretches are grouped in
    blocks of :data:`_SELF_BLOCK`; two blocks whose boxes are more than ``2 hw`` apart in
    plan, or a clearance apart in height, are skipped."""
    p_count, n = cx.shape
    out = np.zeros(p_count, np.int64)
    depth = np.zeros(p_count)
    if gap <= 0.0 or n < 3:
        return out, depth
    reach = 2.0 * hw
    nb = (n - 2) // _SELF_BLOCK + 1  # blocks of stretches 1 .. n - 1
    bx0, bx1 = np.empty(nb), np.empty(nb)
    by0, by1 = np.empty(nb), np.empty(nb)
    bz0, bz1 = np.empty(nb), np.empty(nb)
    for p in range(p_count):
        # the span of the heading along the lane centre's stretches
        h = h_lo = h_hi = 0.0
        for i in range(2, n):
            ux, uy = cx[p, i - 1] - cx[p, i - 2], cy[p, i - 1] - cy[p, i - 2]
            vx, vy = cx[p, i] - cx[p, i - 1], cy[p, i] - cy[p, i - 1]
            h += _step_angle(ux * vy - uy * vx, ux * vx + uy * vy)
            h_lo, h_hi = min(h_lo, h), max(h_hi, h)
        if h_hi - h_lo <= SELF_TURN_RAD:
            continue
        hi_s = length[p] - end_zone
        for k in range(nb):
            i0 = 1 + k * _SELF_BLOCK
            i1 = min(i0 + _SELF_BLOCK, n)
            bx0[k] = bx1[k] = cx[p, i0 - 1]
            by0[k] = by1[k] = cy[p, i0 - 1]
            bz0[k] = bz1[k] = z[p, i0 - 1]
            for i in range(i0, i1):
                bx0[k] = min(bx0[k], cx[p, i])
                bx1[k] = max(bx1[k], cx[p, i])
                by0[k] = min(by0[k], cy[p, i])
                by1[k] = max(by1[k], cy[p, i])
                bz0[k] = min(bz0[k], z[p, i])
                bz1[k] = max(bz1[k], z[p, i])
        for k in range(nb):
            ka = 1 + k * _SELF_BLOCK
            if s[p, min(ka + _SELF_BLOCK, n) - 1] <= end_zone or s[p, ka - 1] >= hi_s:
                continue
            for q in range(k, nb):
                kb = 1 + q * _SELF_BLOCK
                if s[p, min(kb + _SELF_BLOCK, n) - 1] - s[p, ka - 1] <= gap:
                    continue  # nothing in these blocks is gap apart
                if s[p, min(kb + _SELF_BLOCK, n) - 1] <= end_zone or s[p, kb - 1] >= hi_s:
                    continue
                if bx0[q] - bx1[k] >= reach or bx0[k] - bx1[q] >= reach or \
                        by0[q] - by1[k] >= reach or by0[k] - by1[q] >= reach:
                    continue
                if bz0[q] - bz1[k] >= clearance or bz0[k] - bz1[q] >= clearance:
                    continue
                for i in range(ka, min(ka + _SELF_BLOCK, n)):
                    for j in range(max(kb, i + 1), min(kb + _SELF_BLOCK, n)):
                        if s[p, j - 1] - s[p, i] <= gap:
                            continue
                        t, u = _segment_params(cx[p, i - 1], cy[p, i - 1], cx[p, i], cy[p, i],
                                               cx[p, j - 1], cy[p, j - 1], cx[p, j], cy[p, j])
                        ex = (cx[p, i - 1] + t * (cx[p, i] - cx[p, i - 1])
                              - cx[p, j - 1] - u * (cx[p, j] - cx[p, j - 1]))
                        ey = (cy[p, i - 1] + t * (cy[p, i] - cy[p, i - 1])
                              - cy[p, j - 1] - u * (cy[p, j] - cy[p, j - 1]))
                        d = np.sqrt(ex * ex + ey * ey)
                        if d >= reach:
                            continue
                        dz = abs(z[p, i - 1] + t * (z[p, i] - z[p, i - 1])
                                 - z[p, j - 1] - u * (z[p, j] - z[p, j - 1]))
                        if dz >= clearance:
                            continue
                        sa = s[p, i - 1] + t * (s[p, i] - s[p, i - 1])
                        sb = s[p, j - 1] + u * (s[p, j] - s[p, j - 1])
                        if sa <= end_zone or sa >= hi_s or sb <= end_zone or sb >= hi_s:
                            continue
                        out[p] += 1
                        depth[p] += min(reach - d, clearance - dz)
    return out, depth


@njit(cache=True, inline="always")
def _climb(s, h, grade, transition):  # pragma: no cover - compiled
    """Height gained after ``s`` metres of a climb of total ``h`` (see profile._climb)."""
    if h <= 0.0:
        return 0.0
    t = max(min(transition, h / grade), 1e-9)
    d = h / grade + t
    s = max(s, 0.0)
    if s >= d:
        return h
    if s < t:
        return grade * s * s / (2.0 * t)
    if s <= d - t:
        return grade * t / 2.0 + grade * (s - t)
    return h - grade * (d - s) ** 2 / (2.0 * t)


@njit(cache=True, inline="always")
def _step_angle(c, d):  # pragma: no cover - compiled
    """``arctan2(c, d)``: the heading change between two tangents (``c`` their cross,
    ``d`` their dot product). Steps between samples are mostly small: there the odd
    series to x^9 (error below 1e-10 rad for |x| <= 0.1) replaces the library call."""
    if d > 0.0 and abs(c) <= 0.1 * d:
        x = c / d
        x2 = x * x
        return x * (1.0 - x2 * (1.0 / 3.0 - x2 * (0.2 - x2 * (1.0 / 7.0 - x2 / 9.0))))
    return np.arctan2(c, d)


@njit(cache=True, inline="always")
def _shape(ctrl, m, width, t, xs, ys, tx, ty, sp, ss, kap):  # pragma: no cover - compiled
    """What :func:`spline_terms` measures on one candidate's pieces ``ctrl`` ``(n, 4, 2)``
    without the conflicts: length, minimum lane radius (held over :data:`HOLD_M`),
    turning, curvature variance, mean squared curvature, joint jumps, and the pointwise
    minimum lane radius (at any sample: the ends and joints are samples). Fills the samples (``m`` per piece at
    parameters ``t``) the conflicts are counted on: reference line ``xs, ys``,
    tangent ``tx, ty``, speed ``sp``, station ``ss`` (see :func:`_lane`); ``kap``
    is scratch."""
    n_p = ctrl.shape[0]
    n = n_p * m
    off = 0.0
    for k in range(n_p):
        q = ctrl[k]
        for i in range(m):
            u = t[i]
            v = 1.0 - u
            b0, b1, b2, b3 = v * v * v, 3 * v * v * u, 3 * v * u * u, u * u * u
            d0, d1, d2, d3 = -3 * v * v, 3 * v * v - 6 * v * u, 6 * v * u - 3 * u * u, 3 * u * u
            e0, e1, e2, e3 = 6 * v, -12 * v + 6 * u, 6 * v - 12 * u, 6 * u
            j = k * m + i
            xs[j] = b0 * q[0, 0] + b1 * q[1, 0] + b2 * q[2, 0] + b3 * q[3, 0]
            ys[j] = b0 * q[0, 1] + b1 * q[1, 1] + b2 * q[2, 1] + b3 * q[3, 1]
            dx = d0 * q[0, 0] + d1 * q[1, 0] + d2 * q[2, 0] + d3 * q[3, 0]
            dy = d0 * q[0, 1] + d1 * q[1, 1] + d2 * q[2, 1] + d3 * q[3, 1]
            ex = e0 * q[0, 0] + e1 * q[1, 0] + e2 * q[2, 0] + e3 * q[3, 0]
            ey = e0 * q[0, 1] + e1 * q[1, 1] + e2 * q[2, 1] + e3 * q[3, 1]
            tx[j], ty[j] = dx, dy
            speed = np.sqrt(dx * dx + dy * dy)
            sp[j] = speed
            sm = max(speed, 1e-9)
            kap[j] = (dx * ey - dy * ex) / (sm * sm * sm)
            if i > 0:
                off += 0.5 * (speed + sp[j - 1]) / (m - 1)
            ss[j] = off
    g2 = 0.0
    for k in range(1, n_p):
        g2 += (kap[k * m] - kap[k * m - 1]) ** 2
    turn = 0.0
    mean = 0.0
    k2 = 0.0
    rpt = np.inf  # the tightest lane-centre radius at any sample (pointwise)
    for j in range(n):
        kj = kap[j]
        if kj != 0.0:
            rpt = min(rpt, abs(1.0 / kj + 0.5 * width))
        mean += kj
        k2 += kj * kj
        if j > 0:  # the heading change from the previous sample
            turn += _step_angle(tx[j - 1] * ty[j] - ty[j - 1] * tx[j],
                                tx[j - 1] * tx[j] + ty[j - 1] * ty[j])
        kap[j] = turn  # from here on: the heading change up to sample j
    mean /= n
    k2 /= n
    # the tightest radius held over HOLD_M (or the whole ramp, if shorter): mean curvature
    # between each sample and the first one at least HOLD_M further on
    hold = min(HOLD_M, 0.999 * off)
    rmin = np.inf
    k = 0
    for j in range(n):
        while k < n and ss[k] - ss[j] < hold:
            k += 1
        if k == n:
            break
        kj = (kap[k] - kap[j]) / (ss[k] - ss[j])
        r = np.inf if kj == 0.0 else abs(1.0 / kj + 0.5 * width)
        if r < rmin:
            rmin = r
    return off, rmin, turn, max(k2 - mean * mean, 0.0), k2, g2, rpt


@njit(cache=True, inline="always")
def _lane(xs, ys, tx, ty, sp, ss, length, width, za, zc, zb, grade, transition, cx, cy,
          zz):  # pragma: no cover - compiled
    """A candidate's lane centre (``cx, cy`` row 0) and heights on its grade line
    (``zz`` row 0) at the samples of :func:`_shape`."""
    hr, hf = abs(zc - za), abs(zc - zb)
    sr = 1.0 if zc > za else (-1.0 if zc < za else 0.0)
    sf = 1.0 if zb > zc else (-1.0 if zb < zc else 0.0)
    for j in range(xs.shape[0]):
        half = 0.5 * width / max(sp[j], 1e-9)
        cx[0, j] = xs[j] + half * ty[j]
        cy[0, j] = ys[j] - half * tx[j]
        zz[0, j] = (za + sr * _climb(ss[j], hr, grade, transition)
                    + sf * (hf - _climb(length - ss[j], hf, grade, transition)))


@njit(cache=True)
def _scratch(m, n):  # pragma: no cover - compiled
    """Per-candidate work arrays for ``n`` samples, ``m`` per piece: the parameters
    ``t``, then what :func:`_shape` fills (``xs, ys, tx, ty, sp, kap``, stations ``ss``
    as row 0) and what :func:`_lane_conflicts` fills (``cx, cy, zz`` row 0, ``ln``)."""
    return (np.linspace(0.0, 1.0, m), np.empty(n), np.empty(n), np.empty(n), np.empty(n),
            np.empty(n), np.empty(n), np.empty((1, n)), np.empty((1, n)), np.empty((1, n)),
            np.empty((1, n)), np.empty(1))


@njit(cache=True, nogil=True)
def _lane_conflicts(xs, ys, tx, ty, sp, ss, length, width, za, zc, zb, grade, transition,
                    cx, cy, zz, ln, end_zone, hw, clearance, lines, px, py, pz, phw, starts,
                    x0, y0, cell, reach, nx, ny, zlo, zhi, gap):  # pragma: no cover - compiled
    """One candidate's conflicting samples and their depth (:func:`conflicts`) on its
    lane centre (:func:`_lane`; ``ss`` its stations as row 0), with its conflicts with
    itself (:func:`self_conflicts`) when ``gap`` > 0."""
    _lane(xs, ys, tx, ty, sp, ss[0], length, width, za, zc, zb, grade, transition, cx, cy, zz)
    ln[0] = length
    c, d = conflicts(cx, cy, ss, zz, ln, end_zone, hw, clearance, lines, px, py, pz, phw,
                     starts, x0, y0, cell, reach, nx, ny, zlo, zhi)
    if gap > 0.0:
        c2, d2 = self_conflicts(cx, cy, ss, zz, ln, end_zone, hw, clearance, gap)
        return c[0] + c2[0], d[0] + d2[0]
    return c[0], d[0]


@njit(cache=True, nogil=True)
def spline_terms(ctrl, m, width, za, zc, zb, grade, transition, end_zone, hw, clearance,
                 lines, px, py, pz, phw, starts, x0, y0, cell, reach, nx, ny, zlo, zhi,
                 gap=0.0):  # pragma: no cover
    """Everything the ramp objective measures on candidate splines ``ctrl`` ``(P, n, 4, 2)``.

    Samples each cubic piece at ``m`` parameter values (as
    :func:`flyover.geometry.bezier.sample_spline`) and returns per candidate:
    length, minimum lane-centre radius, total turning, curvature variance,
    mean squared curvature, squared curvature jumps at joints, the number
    of conflicting samples and their depth (:func:`conflicts`; heights from the grade line of
    :func:`flyover.geometry.profile.heights` between ``za``, ``zc``, ``zb``; with
    :func:`self_conflicts` when ``gap`` > 0).
    """
    p_count = ctrl.shape[0]
    out = np.zeros((6, p_count))
    conf = np.zeros(p_count, np.int64)
    deep = np.zeros(p_count)
    t, xs, ys, tx, ty, sp, kap, ss, cx, cy, zz, ln = _scratch(m, ctrl.shape[1] * m)
    for p in range(p_count):
        r = _shape(ctrl[p], m, width, t, xs, ys, tx, ty, sp, ss[0], kap)
        for k in range(6):
            out[k, p] = r[k]
        conf[p], deep[p] = _lane_conflicts(xs, ys, tx, ty, sp, ss, r[0], width, za[p], zc[p],
                                           zb[p], grade, transition, cx, cy, zz, ln, end_zone,
                                           hw, clearance, lines, px, py, pz, phw, starts, x0,
                                           y0, cell, reach, nx, ny, zlo, zhi, gap)
    return out[0], out[1], out[2], out[3], out[4], out[5], conf, deep


@njit(cache=True, inline="always")
def _rail_at(s, rs, rx, ry, rh, rz, offset):  # pragma: no cover - compiled
    """Point (offset to the left), heading and height of a rail at station ``s``."""
    x = np.interp(s, rs, rx)
    y = np.interp(s, rs, ry)
    h = np.interp(s, rs, rh)
    z = np.interp(s, rs, rz)
    return x - offset * np.sin(h), y + offset * np.cos(h), h, z


@njit(cache=True, nogil=True)
def decode(x, pieces, turn_rad, a_rail, a_off, b_rail, b_off, free_mode, free_z,
           leads):  # pragma: no cover
    """Control points of candidate ramps ``x`` ``(D, P)`` (see ``flyover.geometry.fit``).

    ``a_rail``/``b_rail``: ``(5, K)`` stations, x, y, heading, z of the start
    and end rails (``K = 0`` when that end is free). ``free_mode``: 0 none,
    1 free end, 2 free start. Returns ``ctrl (P, n, 4, 2)``, the stations on
    the rails ``(2, P)``, the end poses ``(2, 4, P)`` (x, y, heading, z) and
    the intended total turn ``(P,)``. ``leads``: 1 when every attached end has
    a straight lead (its length a decision variable, after the stations): the
    chain then runs between the ends of the leads, which become one straight
    piece each at the start / end of ``ctrl``.
    """
    d_count, p_count = x.shape
    lead_a = 1 if (leads and a_rail.shape[1] > 0) else 0
    lead_b = 1 if (leads and b_rail.shape[1] > 0) else 0
    ctrl = np.empty((p_count, pieces + lead_a + lead_b, 4, 2))
    stations = np.zeros((2, p_count))
    poses = np.zeros((2, 4, p_count))
    turn = np.empty(p_count)
    jx = np.empty(pieces + 1)
    jy = np.empty(pieces + 1)
    jh = np.empty(pieces + 1)
    lam_in = np.empty(pieces)
    lam_out = np.empty(pieces)
    for p in range(p_count):
        i = 0
        xa = ya = ha = za = xb = yb = hb = zb = 0.0
        if a_rail.shape[1] > 0:
            stations[0, p] = x[i, p]
            xa, ya, ha, za = _rail_at(x[i, p], a_rail[0], a_rail[1], a_rail[2], a_rail[3],
                                      a_rail[4], a_off)
            i += 1
        if b_rail.shape[1] > 0:
            stations[1, p] = x[i, p]
            xb, yb, hb, zb = _rail_at(x[i, p], b_rail[0], b_rail[1], b_rail[2], b_rail[3],
                                      b_rail[4], b_off)
            i += 1
        la = lb = 0.0
        if lead_a:
            la = x[i, p]
            i += 1
        if lead_b:
            lb = x[i, p]
            i += 1
        if free_mode > 0:
            d, e, phi = x[i, p], x[i + 1, p], x[i + 2, p]
            i += 3
            if free_mode == 1:  # free end, placed from the start
                c, s = np.cos(ha), np.sin(ha)
                xb, yb = xa + d * c - e * s, ya + d * s + e * c
                hb, zb = ha + turn_rad + phi, free_z
            else:  # free start, placed from the end
                c, s = np.cos(hb), np.sin(hb)
                xa, ya = xb - d * c - e * s, yb - d * s + e * c
                ha, za = hb - turn_rad - phi, free_z
        lam_out[0] = x[i, p]
        lam_in[pieces - 1] = x[i + 1, p]
        i += 2
        raw = hb - ha
        tr = turn_rad + ((raw - turn_rad + np.pi) % (2 * np.pi) - np.pi)
        turn[p] = tr
        # the chain runs from the end of the start lead to the start of the end lead
        ca, sa, cb, sb = np.cos(ha), np.sin(ha), np.cos(hb), np.sin(hb)
        xa2, ya2 = xa + la * ca, ya + la * sa
        xb2, yb2 = xb - lb * cb, yb - lb * sb
        if lead_a:
            for q in range(4):
                ctrl[p, 0, q, 0] = xa + la * q / 3.0 * ca
                ctrl[p, 0, q, 1] = ya + la * q / 3.0 * sa
        if lead_b:
            last = pieces + lead_a
            for q in range(4):
                ctrl[p, last, q, 0] = xb2 + lb * q / 3.0 * cb
                ctrl[p, last, q, 1] = yb2 + lb * q / 3.0 * sb
        cx, cy = xb2 - xa2, yb2 - ya2
        dist = max(np.hypot(cx, cy), 1.0)
        ux, uy = cx / dist, cy / dist
        jx[0], jy[0], jh[0] = xa2, ya2, ha
        for k in range(1, pieces):
            u, v, dh = x[i, p], x[i + 1, p], x[i + 2, p]
            lam_in[k - 1] = x[i + 3, p]
            lam_out[k] = x[i + 4, p]
            i += 5
            f = k / pieces
            jx[k] = xa2 + f * cx + u * dist * ux - v * dist * uy
            jy[k] = ya2 + f * cy + u * dist * uy + v * dist * ux
            jh[k] = ha + tr * f + dh
        jx[pieces], jy[pieces], jh[pieces] = xb2, yb2, ha + tr
        for k in range(pieces):
            span = np.hypot(jx[k + 1] - jx[k], jy[k + 1] - jy[k])
            o = k + lead_a
            ctrl[p, o, 0, 0], ctrl[p, o, 0, 1] = jx[k], jy[k]
            ctrl[p, o, 1, 0] = jx[k] + lam_out[k] * span * np.cos(jh[k])
            ctrl[p, o, 1, 1] = jy[k] + lam_out[k] * span * np.sin(jh[k])
            ctrl[p, o, 2, 0] = jx[k + 1] - lam_in[k] * span * np.cos(jh[k + 1])
            ctrl[p, o, 2, 1] = jy[k + 1] - lam_in[k] * span * np.sin(jh[k + 1])
            ctrl[p, o, 3, 0], ctrl[p, o, 3, 1] = jx[k + 1], jy[k + 1]
        poses[0, 0, p], poses[0, 1, p], poses[0, 2, p], poses[0, 3, p] = xa, ya, ha, za
        poses[1, 0, p], poses[1, 1, p], poses[1, 2, p], poses[1, 3, p] = xb, yb, hb, zb
    return ctrl, stations, poses, turn


#: the search holds a ramp's lane centre nowhere tighter (pointwise, at its samples) than
#: its radius target (``inf``: the floor) less this share: 4.5 %, within the 5 % tolerance,
#: so that the final dense measurement (points between the search's samples) stays
#: within it too
POINT_MARGIN = 0.045
#: weight of the pointwise term (``spike``: the share the tightest point falls short)
SPIKE_WEIGHT = 10.0

#: the search holds a ramp this much (relative) under its length bound, so that the final
#: dense measurement (a little longer than the search's samples) stays within it too
LENGTH_MARGIN = 0.005
#: weight of the length term (``over``: the share a candidate is longer than its bound)
OVER_WEIGHT = 10.0

#: rows of :func:`objective_terms` (the penalty terms of the ramp objective)
TERMS = ("rad_err", "smooth", "shortfall", "excess", "spread", "turn_err", "g2", "conflicts",
         "depth", "spike", "over")


@njit(cache=True, inline="always")
def length_bound(least_plan, climb, ratio, tapers):  # pragma: no cover - compiled
    """The longest a ramp may be (see :meth:`flyover.geometry.fit.RampSpec.max_length_m`):
    ``ratio`` × the longer of what its plan needs and its ``climb``, and its ``tapers``
    (``ratio`` ``inf``: no bound)."""
    if ratio == np.inf:
        return np.inf
    return ratio * max(least_plan, climb) + tapers


@njit(cache=True, inline="always")
def _climb_distance(h, grade, transition):  # pragma: no cover - compiled
    """Horizontal distance to climb ``|h|`` (see profile.climb_distance)."""
    h = abs(h)
    if h <= 0.0:
        return 0.0
    return h / grade + min(transition, h / grade)


@njit(cache=True, inline="always")
def _energy1(t, p, conflict_weight, depth_weight, compact_weight):  # pragma: no cover
    """The ramp objective of candidate ``p`` from its terms ``t`` (rows :data:`TERMS`)."""
    return (100.0 * t[0, p] ** 2 + 0.05 * t[1, p] + 20.0 * t[2, p] ** 2
            + 10.0 * max(t[5, p] - 0.05, 0.0)
            + conflict_weight * (t[7, p] + depth_weight * t[8, p])
            + 0.01 * min(t[6, p], 10.0) + 2.0 * t[3, p] ** 2
            + compact_weight * t[4, p] + SPIKE_WEIGHT * (t[9, p] + 10.0 * t[9, p] ** 2)
            + OVER_WEIGHT * (t[10, p] + 10.0 * t[10, p] ** 2))


@njit(cache=True, nogil=True)
def objective_terms(x, pieces, turn_rad, a_rail, a_off, b_rail, b_off, free_mode, free_z, leads,
                    z_crest, end_first, m, width, grade, transition, r_target, inf_ref,
                    inf_floor, compact_m, spread_a, spread_b, end_zone, hw, clearance, lines,
                    px, py, pz, phw, starts, x0, y0, cell, reach, nx, ny, zlo, zhi, weights,
                    bound, gap, least_plan, length_ratio, tapers):  # pragma: no cover - compiled
    """The ramp objective's terms (rows :data:`TERMS`, ``(11, P)``) of decision vectors ``x``.

    :func:`decode` then :func:`spline_terms`, then per candidate: radius error
    (relative; for an ``inf`` target, how far it falls short of ``inf_floor``,
    relative, else 0), smoothness (curvature variance times
    the target radius², or mean curvature² times ``inf_ref``² for ``inf``),
    the slope shortfall (length missing to climb at ``grade``, relative; for a
    level ramp (``grade`` 0) 1 when its ends differ in height), excess length
    over a reference, the pull of stubs toward the centre (``spread_a/b``: the
    start / end station counts), the turn error, the curvature jumps at joints
    (scaled like smoothness), conflicting samples and their depth, and the spike: how
    far (relative) the tightest lane-centre radius at any sample falls short of the
    target (``inf``: ``inf_floor``) less :data:`POINT_MARGIN` (0: nowhere tighter), and
    ``over``: how far (relative) the candidate is longer than its length bound
    (:func:`length_bound` of ``least_plan`` and its climb to its crest and down, less
    :data:`LENGTH_MARGIN`; ``length_ratio`` ``inf``: none). The crest is
    the higher end or ``z_crest`` (``-inf``: none); with ``end_first`` 1 the end's height
    (it reaches it as early as it can: :attr:`flyover.geometry.fit.RampSpec.end_z_first`).

    ``bound`` ``(P,)``: a candidate whose energy (:func:`energy` with ``weights``)
    without its conflicts already exceeds its bound is not searched for conflicts
    (the costly part): its conflicts are ``inf`` (depth 0), so it is never acceptable
    and its energy is ``inf``. With its conflicts the energy could only be higher (rounded
    sums are monotone), so a DE trial beaten this way loses to its parent exactly
    as it would have. ``gap`` > 0: candidates are tested against themselves too
    (:func:`self_conflicts`).
    """
    ctrl, st, poses, turn = decode(x, pieces, turn_rad, a_rail, a_off, b_rail, b_off,
                                   free_mode, free_z, leads)
    p_count = x.shape[1]
    za = poses[0, 3].copy()
    zb = poses[1, 3].copy()
    zc = zb.copy() if end_first > 0 else np.maximum(np.maximum(za, zb), z_crest)
    g = grade if grade > 0 else 1.0
    t, xs, ys, tx, ty, sp, kap, ss, cx, cy, zz, ln = _scratch(m, ctrl.shape[1] * m)
    out = np.empty((11, p_count))
    inf_target = np.isinf(r_target)
    # nowhere tighter than this (pointwise): the target (inf: the floor) less the margin
    r_point = (inf_floor if inf_target else r_target) * (1.0 - POINT_MARGIN)
    r_eff = min(r_target, inf_ref)
    for p in range(p_count):
        length, rmin, turned, kvar, k2, g2, rpt = _shape(ctrl[p], m, width, t, xs, ys, tx, ty,
                                                         sp, ss[0], kap)
        if grade > 0:
            need = _climb_distance(zc[p] - za[p], grade, transition) + \
                _climb_distance(zc[p] - zb[p], grade, transition)
            shortfall = max(need - length, 0.0) / max(need, 1.0)
        else:
            need = 0.0
            shortfall = 1.0 if abs(za[p] - zb[p]) > 1e-6 else 0.0
        if inf_target:
            out[0, p] = min(rmin - inf_floor, 0.0) / inf_floor
            out[1, p] = k2 * inf_ref ** 2
            out[6, p] = g2 * inf_ref ** 2
        else:
            out[0, p] = (rmin - r_target) / r_target
            out[1, p] = kvar * r_target ** 2
            out[6, p] = g2 * r_target ** 2
        chord = 0.0
        if abs(turn[p]) < 0.3:  # straight-on ramps only
            chord = np.hypot(poses[1, 0, p] - poses[0, 0, p], poses[1, 1, p] - poses[0, 1, p])
        l_ref = 1.2 * max(max(need, chord), r_eff * abs(turn[p]) + 2 * transition)
        out[2, p] = shortfall
        out[3, p] = max(length / l_ref - 1.0, 0.0)
        out[4, p] = spread_a * (st[0, p] / compact_m) ** 2 + spread_b * (st[1, p] / compact_m) ** 2
        out[5, p] = abs(turned - turn[p])
        out[9, p] = max(r_point - rpt, 0.0) / r_point
        longest = length_bound(least_plan, need, length_ratio, tapers) * (1.0 - LENGTH_MARGIN)
        out[10, p] = max(length / longest - 1.0, 0.0)
        out[7, p] = 0.0
        out[8, p] = 0.0
        if _energy1(out, p, weights[0], weights[1], weights[2]) > bound[p]:
            out[7, p] = np.inf
            continue
        out[7, p], out[8, p] = _lane_conflicts(xs, ys, tx, ty, sp, ss, length, width, za[p],
                                               zc[p], zb[p], g, transition, cx, cy, zz, ln,
                                               end_zone, hw, clearance, lines, px, py, pz, phw,
                                               starts, x0, y0, cell, reach, nx, ny, zlo, zhi,
                                               gap)
    return out


@njit(cache=True, nogil=True)
def energy(terms, conflict_weight, depth_weight, compact_weight):  # pragma: no cover
    """The ramp objective ``(P,)`` from its terms (rows :data:`TERMS`)."""
    p_count = terms.shape[1]
    out = np.empty(p_count)
    for p in range(p_count):
        out[p] = _energy1(terms, p, conflict_weight, depth_weight, compact_weight)
    return out


@njit(cache=True, nogil=True)
def acceptable(terms, accept_radius):  # pragma: no cover - compiled
    """Candidates meeting the targets on these samples: radius, length, turn, no conflict,
    excess under 30 %, nowhere tighter than the target less :data:`POINT_MARGIN`, within
    the length bound less :data:`LENGTH_MARGIN`."""
    p_count = terms.shape[1]
    out = np.zeros(p_count, np.bool_)
    for p in range(p_count):
        out[p] = (abs(terms[0, p]) < accept_radius and terms[2, p] == 0.0
                  and terms[5, p] < 0.05 and terms[7, p] == 0.0 and terms[3, p] < 0.3
                  and terms[9, p] == 0.0 and terms[10, p] == 0.0)
    return out


@njit(cache=True, nogil=True)
def jade_trial(pop, energy, archive, n_arch, u, mu_cr, mu_f, n_best, lo, hi):  # pragma: no cover
    """One generation's trial vectors of JADE (current-to-pbest/1/bin with an archive).

    ``u``: uniforms ``(n, d + 9)`` of this generation: CR (Box-Muller, 2), F
    (Cauchy, twice), p-best, r1, r2, the forced crossover dimension, the
    crossover mask (``d``), the archive slot (see :func:`jade_select`).
    Returns the trials ``(n, d)``, their CR ``(n,)`` and F ``(n,)``. A trial
    leaving the bounds is put halfway between its parent and the bound.
    """
    n, d = pop.shape
    order = np.argsort(energy, kind="mergesort")
    trial = np.empty((n, d))
    cr = np.empty(n)
    fm = np.empty(n)
    n_union = n + n_arch
    for i in range(n):
        c = mu_cr + 0.1 * np.sqrt(-2.0 * np.log1p(-u[i, 0])) * np.cos(2 * np.pi * u[i, 1])
        cr[i] = min(max(c, 0.0), 1.0)
        f = mu_f + 0.1 * np.tan(np.pi * (u[i, 2] - 0.5))
        if f <= 0.0:
            f = mu_f + 0.1 * np.tan(np.pi * (u[i, 3] - 0.5))
        f = min(max(f, 0.05), 1.0)
        fm[i] = f
        best = order[int(u[i, 4] * n_best)]
        r1 = (i + 1 + int(u[i, 5] * (n - 1))) % n
        r2 = int(u[i, 6] * n_union)
        for _ in range(2):  # r2 differs from i and r1
            if r2 == i or r2 == r1:
                r2 = (r2 + 1) % n_union
        forced = int(u[i, 7] * d)
        for k in range(d):
            if u[i, 8 + k] < cr[i] or k == forced:
                other = pop[r2, k] if r2 < n else archive[r2 - n, k]
                v = pop[i, k] + f * (pop[best, k] - pop[i, k]) + f * (pop[r1, k] - other)
                if v < lo[k]:
                    v = (pop[i, k] + lo[k]) / 2
                elif v > hi[k]:
                    v = (pop[i, k] + hi[k]) / 2
                trial[i, k] = v
            else:
                trial[i, k] = pop[i, k]
    return trial, cr, fm


@njit(cache=True, nogil=True)
def jade_select(pop, energy, trial, e_trial, cr, fm, archive, n_arch, u_slot, mu_cr, mu_f,
                c):  # pragma: no cover - compiled
    """Selection and adaptation of one JADE generation (in place on ``pop``, ``energy``,
    ``archive``).

    A trial at least as good replaces its parent; a parent beaten strictly goes to
    the archive (a random slot, ``u_slot``, once it holds ``n``). ``CR`` and ``F``
    move toward the gain-weighted mean / Lehmer mean of the successful ones.
    Returns the archive's size and the new ``mu_cr``, ``mu_f``.
    """
    n, d = pop.shape
    gain_sum = 0.0
    count = 0
    for i in range(n):
        if e_trial[i] < energy[i]:
            gain_sum += energy[i] - e_trial[i]
            count += 1
    if count > 0:
        s_cr = 0.0
        s_f = 0.0
        s_f2 = 0.0
        for i in range(n):
            if e_trial[i] < energy[i]:
                w = (energy[i] - e_trial[i]) / gain_sum if gain_sum > 0 else 1.0 / count
                s_cr += w * cr[i]
                s_f += w * fm[i]
                s_f2 += w * fm[i] * fm[i]
                slot = n_arch if n_arch < n else int(u_slot[i] * n)
                archive[slot] = pop[i]
                if n_arch < n:
                    n_arch += 1
        mu_cr = (1 - c) * mu_cr + c * s_cr
        mu_f = (1 - c) * mu_f + c * s_f2 / max(s_f, 1e-12)
    for i in range(n):
        if e_trial[i] <= energy[i]:
            pop[i] = trial[i]
            energy[i] = e_trial[i]
    return n_arch, mu_cr, mu_f
