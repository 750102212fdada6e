"""The ramps fitted so far: their fits, stations and attachments, as later ramps see them.

Decides what a later ramp must avoid (:meth:`FittedRamps.obstacles`), where the
ramps already attached to a parent are (:attr:`FittedRamps.attached`) and where a
ramp's end nominally lies on the ramp it leaves or joins (:meth:`FittedRamps.start_s`,
:meth:`FittedRamps.end_s`, :meth:`FittedRamps.start_pose`, :meth:`FittedRamps.end_z`,
:meth:`FittedRamps.heading_at`); reads the road layout, the ramps' kinds and the fits
recorded by the build loop.
"""

from __future__ import annotations

import math
from typing import Mapping

import numpy as np

from flyover.geometry import _kernels
from flyover.geometry.bezier import sample_spline
from flyover.geometry.chains import Movements, ends
from flyover.geometry.fit import Obstacles, RampFit
from flyover.geometry.profile import evaluate_polys
from flyover.geometry.roads import road_bands
from flyover.geometry.settings import LayoutSettings

__all__ = ["FittedRamps", "stations"]


def stations(fit: RampFit, m: int, right_m: float = 0.0) -> dict[str, np.ndarray]:
    """Stations of a fitted ramp's reference line (or of the line ``right_m`` to its right),
    ``m`` samples per Bézier piece: arc length ``s``, ``xy``, unwrapped ``heading``, ``z``."""
    dense = sample_spline(fit.ctrl, m)
    tang = dense.tangent
    speed = np.maximum(np.hypot(tang[:, 0], tang[:, 1]), 1e-9)[:, None]
    xy = dense.xy + right_m * np.stack([tang[:, 1], -tang[:, 0]], axis=-1) / speed
    z, _ = evaluate_polys(fit.elevation, dense.s)
    keep = np.concatenate([[True], np.diff(dense.s) > 1e-9])
    head = np.unwrap(np.arctan2(tang[:, 1], tang[:, 0]))
    return {"s": dense.s[keep], "xy": xy[keep], "heading": head[keep], "z": z[keep]}


class FittedRamps:
    """Fits (``fits``), stations (``stations``: ramp → ``s``, ``xy``, ``heading``, ``z``,
    lane ``centre``, ``centre_z``) and, per parent, the ramps attached to it with a
    ``pos`` (``attached``: parent → ``(pos, extent along it, ramp, station)``)."""

    def __init__(self, moves: Movements, width: Mapping[str, float], st: LayoutSettings):
        self.moves, self.roads, self.g, self.st = moves, moves.roads, moves.g, st
        self.width = width
        self.fits: dict[str, RampFit] = {}
        self.stations: dict[str, dict] = {}
        self.attached: dict[str, list[tuple[float, float, float, str, float]]] = {}
        #: ramp → how far (m) along its road its run beside the road lies beyond where
        #: :func:`flyover.geometry.beside.beside_run` first puts it (moved for a child
        #: that missed its targets joining it there: ``build._moved_run``)
        self.run_shift: dict[str, float] = {}
        self.bands = road_bands(self.roads, st)

    def obstacles(self, keep_out: frozenset[str] = frozenset(),
                  fences: tuple = (), approaches: tuple = ()) -> Obstacles:
        """Roads and fitted ramps; the fitted ramps in ``keep_out`` at every height (a
        ramp must not cross them in plan at all), and so the ``fences`` (road-frame bands
        ``x0, y0, dx, dy, t_lo, t_hi, lat_lo, lat_hi``, named ``fence``); the
        ``approaches`` of ramps not fitted yet
        (:class:`flyover.geometry.approaches.Approach`) at their heights, named after
        their ramp."""
        st = self.st
        lines = self.bands
        names = [r.id for r in self.roads.values()]
        step = st.fit.clearance_m
        heights = np.arange(-step, st.levels_m[-1] + 2 * step, step)
        if fences:
            lines = np.vstack([lines] + [np.array([[*f, h] for h in heights]) for f in fences])
            names += ["fence"] * (len(lines) - len(names))
        pts, zs, hw, owner = [], [], [], []
        for rid, s in self.stations.items():
            pts.append(s["centre"])
            zs.append(s["centre_z"])
            hw.append(np.full(len(s["centre_z"]), self.width[rid] / 2))
            owner += [rid] * len(s["centre_z"])
        for a in approaches:
            pts.append(a.xy)
            zs.append(a.z)
            hw.append(np.full(len(a.z), a.half_width_m))
            owner += [a.ramp] * len(a.z)
        # a keep-out loop, copied at heights less than the clearance apart over every level:
        # no height of the ramp clears it
        for rid in sorted(keep_out & set(self.stations)):
            s = self.stations[rid]
            # not where it leaves or joins its roads (within keep_out_trim_m of its ends):
            # there it runs beside the road the other ramp also runs beside (its copy at its
            # own height still counts)
            c = s["centre"]
            along = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(c, axis=0).T))])
            inner = (along > st.keep_out_trim_m) & (along < along[-1] - st.keep_out_trim_m)
            n = int(inner.sum())
            for h in heights:
                pts.append(c[inner])
                zs.append(np.full(n, h))
                hw.append(np.full(n, self.width[rid] / 2))
                owner += [rid] * n
        if pts:
            return Obstacles(lines, np.concatenate(pts), np.concatenate(zs),
                             np.concatenate(hw), tuple(owner), tuple(names))
        return Obstacles(lines, line_names=tuple(names))

    def unrecord(self, ramp: str) -> None:
        """Forget a fitted ramp (to fit it again): its fit, stations and attachments."""
        self.fits.pop(ramp, None)
        self.stations.pop(ramp, None)
        for parent, items in self.attached.items():
            self.attached[parent] = [a for a in items if a[3] != ramp]

    def saved(self) -> tuple:
        """The fits, stations, attachments and run shifts as they are now, for
        :meth:`restore`."""
        return (dict(self.fits), dict(self.stations),
                {k: list(v) for k, v in self.attached.items()}, dict(self.run_shift))

    def restore(self, saved: tuple) -> None:
        """Put back what :meth:`saved` returned, in its order (a ramp recorded again with
        :meth:`record` would be attached last, and later ramps read attachments in order)."""
        fits, stations, attached, shifts = saved
        for now, then in ((self.fits, fits), (self.stations, stations),
                          (self.run_shift, shifts)):
            now.clear()
            now.update(then)
        self.attached.clear()
        self.attached.update({k: list(v) for k, v in attached.items()})

    def record(self, ramp: str, fit: RampFit) -> None:
        """Keep a fitted ramp: later ramps attach to its stations and avoid its lane."""
        self.fits[ramp] = fit
        # stations ~1 m apart: a ramp attaching to this one is placed on them by linear
        # interpolation (chord error < 1 cm down to 30 m radius); the lane centre, an
        # obstacle for later ramps, is sampled as the search samples candidates
        per_piece = math.ceil(fit.length_m / len(fit.ctrl))
        stn = stations(fit, int(min(4000, max(64, per_piece))))
        # the lane centre as an obstacle: points no more than the search's step apart
        # (a piece's control polygon is at least as long as the piece)
        polygon = float(np.linalg.norm(np.diff(fit.ctrl, axis=1), axis=-1).sum(-1).max())
        dense = int(math.ceil(1.2 * polygon / _kernels.STEP_M))
        centre = stations(fit, max(64, dense), self.width[ramp] / 2)
        self.stations[ramp] = {**stn, "centre": centre["xy"], "centre_z": centre["z"]}
        for end, t, is_start in ((fit.spec.start, fit.start_s, True),
                                 (fit.spec.end, fit.end_s, False)):
            if end is None:
                continue
            key = (end.parent, ramp) if is_start else (ramp, end.parent)
            pos = self.g.edges[key].get("pos")
            if pos is None:
                continue
            lo_t = hi_t = float(t)
            if end.parent in self.roads and (fit.spec.free is not None
                                             or self.moves.is_loop(ramp)):
                # a stub runs along its road up to its free end, a loop's circle reaches
                # along it: the next attachments keep their gap from all of it
                road = self.roads[end.parent]
                d = np.array([math.cos(road.heading), math.sin(road.heading)])
                along = (stn["xy"] - np.array(road.origin)) @ d
                lo_t, hi_t = float(min(t, along.min())), float(max(t, along.max()))
            self.attached.setdefault(end.parent, []).append((pos, lo_t, hi_t, ramp, float(t)))

    def end_z(self, end) -> float:
        """Height of an end ``(parent, label)``: its road's, or the mean of the fitted
        ramp's (refined per candidate by the rail)."""
        node, _ = end
        if node in self.roads:
            return self.roads[node].z
        st = self.stations[node]
        return float(np.mean(st["z"]))

    def start_s(self, ramp: str, start) -> float:
        """Nominal station of ``ramp``'s start on the fitted ramp it leaves."""
        node = start[0]
        length = self.stations[node]["s"][-1]
        pos = self.g.edges[(node, ramp)].get("pos")
        return length if ends(self.moves.topo, node)[1] is None else \
            (0.4 if pos is None else pos) * length

    def end_s(self, ramp: str, end) -> float:
        """Nominal station of ``ramp``'s end on the fitted ramp it joins."""
        node = end[0]
        length = self.stations[node]["s"][-1]
        pos = self.g.edges[(ramp, node)].get("pos")
        return 0.0 if ends(self.moves.topo, node)[0] is None else \
            (0.6 if pos is None else pos) * length

    def start_pose(self, ramp: str, start) -> tuple[np.ndarray, float]:
        """Nominal point and heading of ``ramp``'s start on the fitted ramp it leaves."""
        st = self.stations[start[0]]
        s = self.start_s(ramp, start)
        xy = np.array([np.interp(s, st["s"], st["xy"][:, k]) for k in (0, 1)])
        return xy, float(np.interp(s, st["s"], st["heading"]))

    def heading_at(self, ramp: str, end, is_start: bool) -> float:
        """Nominal heading of ``ramp``'s start (end) ``end``: its road's, or the fitted
        parent's at :meth:`start_s` (:meth:`end_s`)."""
        node, _ = end
        if node in self.roads:
            return self.roads[node].heading
        st = self.stations[node]
        s = self.start_s(ramp, end) if is_start else self.end_s(ramp, end)
        return float(np.interp(s, st["s"], st["heading"]))
