"""Road layout and ramp assembly: a topology + a feature set → :class:`InterchangeGeometry`.

Layout
------
* Expressways are straight lines through the centre: the first through
  expressway runs north–south (carriageway 1 northbound), the second east–west;
  its direction is chosen so that as many ramps as possible leave and join on
  the side they turn to (right exits turning right). Further expressways are
  placed at 45° steps. An expressway that ends here (``Out-M``/``In-M``, a T)
  is a half line: its carriageways end/begin ``terminal_m`` from the centre on
  the side the topology implies. Each expressway is on its own level
  (0, 1, ...), the terminating one of a T above the through one.
* A carriageway's reference line is its left (median) edge, ``median_m / 2``
  from the axis; where ramps leave or join a carriageway on its left (they run
  in the median) the median is wider by two ramp lanes and shoulders.
* Ramps attach along their parents; *which side of the centre* follows from
  the movement (right turns and direct left turns exit before the crossing and
  merge after it; loops do the opposite; stubs that split exit before, those
  that merge join after), and the order of attachments on one parent follows
  ``pos`` (attachments placed later keep ``gap_m`` from earlier ones, from the
  whole length a stub runs along the road or a loop reaches along it). A
  cloverleaf's outer connector, which goes round the loop joining the same
  two roads, attaches where an arc of its target radius clears every point
  of the loop, and is fitted with the loop as an obstacle at every height: it
  goes round the loop, not over or under it (if it cannot meet its targets
  that way, it is fitted as any other ramp). A ramp joining a road after a loop leaves it, and not coming
  from the road the loop goes to (it cannot go round the loop: a trumpet),
  passes over the loop's exit branch and keeps room after it to descend. A
  ramp leaving (joining) a loop does so before (after) the loop turns. A ramp
  attached on the side of a parent that faces a road (J1's r2 joins r3 on the
  left where r3 runs along R4's edge) attaches only where its lane is clear
  of that road.
* The movement of a ramp is that of the roads its chain connects. A loop is
  a left movement that leaves its parent on the right (``Out-R``), unless its
  exit ``pos`` is below 0.4 (then it is a semi-directional flyover); it turns
  270° to the right. A ramp attached to other ramps (e.g. a loop on
  collector-distributor roads) turns by the parents' local heading
  difference, on the branch nearest that movement. Direct left turns are
  splines of three pieces (climb along the road, turn, descend along it),
  loops and straight-on ramps of two, other ramps one.
* A stub ramp with no end (it splits into other ramps) or no start (formed
  by merging ramps) gets a free end; it climbs a third of the height between
  its road and its children's roads, so every ramp of a chain climbs, over a
  free end far enough out to reach that height at its slope. It attaches
  within ``stub_window_m`` beyond the room it leaves toward the crossing: for
  its planned children to climb to their crest, for its turning children to
  turn at their radius.
* Level plan (fixed up front): a direct left turn crosses the through
  expressways, so its crest is the lowest level ``clearance_m`` above the
  highest of them. Where left turns run both ways between two expressways
  they cross each other: those leaving the second expressway (a T's
  terminating one) go one level higher — the two flyover levels of a
  four-level stack, the three levels of a directional T. A stub feeding or
  fed by such a ramp ends ``clearance_m`` from its road toward that crest;
  if its other children (right turns) go on to a road (a turbine), no higher
  than ``clearance_m`` (and 0.5 m) under the lowest planned crest, so that
  they pass under every flyover; a planned
  ramp's road ends, and those of a ramp it leaves or joins, keep room from
  the crossing to climb to (descend from) the crest at the ramp's slope.
* Ramps are fitted parents first; in one round, a low connector between two
  ramps (a stack's right turn, fixed at both ends) before the flyovers.

Ramps are fitted one by one (parents first) by :func:`flyover.geometry.fit.fit_ramp`,
avoiding same-level conflicts with roads and the ramps already fitted:

1. a ramp that still conflicts is lifted to the next level (a flyover);
2. one that misses its targets is fitted again with straight leads (a ramp
   that climbs may first run along its parent's heading, as long as the climb
   from that end takes: up beside its road before it turns over the other
   carriageway), then also with one more Bézier piece, then with one more
   piece but no leads, then with other seeds (``restarts`` fits in all);
3. one that still meets fitted ramps at its level makes way (rip-up and
   reroute): each ramp it meets, if nothing is attached to it yet and it is
   not its parent, is fitted again on its own targets with the new ramp's
   curve as an obstacle and kept only if it meets them without conflict;
   then the new ramp is counted again and, if it still conflicts, refitted;
4. a ramp that misses its targets after all that is resampled (Algorithm 1)
   through ``resampler``; what still misses is recorded with the reason;
5. an interchange in which a ramp still meets something at its level is
   built again from scratch with other seeds (``rebuilds`` times at most),
   and the build with the fewest conflicting ramps is kept.

Steps 1–3 of the first build are "the first try" as long as the targets are the sampled ones.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field, replace
from typing import Callable, Mapping

import numpy as np

from flyover.errors import FlyoverError
from flyover.geometry import _kernels
from flyover.geometry.bezier import sample_spline
from flyover.geometry.fit import (
    FitSettings, FreeEnd, Obstacles, Rail, RampFit, RampSpec, conflicts_with, fit_ramp,
    measure_spline, recount,
)
from flyover.geometry.model import (
    Attachment, InterchangeGeometry, RampGeometry, RoadGeometry,
)
from flyover.geometry.profile import climb_distance, evaluate_polys
from flyover.topology.model import Kind, Label, Topology

__all__ = ["GeometryError", "LayoutSettings", "RampFeatures", "RampOutcome", "Interchange",
           "build_interchange"]

log = logging.getLogger(__name__)


_Z_MARGIN = 0.5  # m kept beyond the clearance where levels are planned


class GeometryError(FlyoverError):
    """A topology cannot be laid out (e.g. a ramp with neither start nor end)."""


@dataclass(frozen=True)
class LayoutSettings:
    """Layout settings (config ``geometry``)."""

    lane_width_m: float = 3.75
    shoulder_width_m: float = 2.5
    ramp_lane_width_m: float = 4.0
    median_m: float = 4.0
    level_height_m: float = 6.5
    levels: int = 4
    default_lanes: int = 2
    crossing_margin_m: float = 15.0
    gap_m: float = 40.0
    reach_m: float = 1500.0
    terminal_m: float = 120.0
    road_margin_m: float = 100.0
    cd_clear_m: float = 350.0
    #: a collector-distributor road runs this far (m) beside its carriageway's edge
    cd_offset_m: float = 10.0
    stub_window_m: float = 200.0
    turn_room: float = 2.0
    leads: bool = True
    lead_min_m: float = 60.0
    max_resamples: int = 3
    restarts: int = 5
    #: whole-interchange rebuilds with other DE seeds while a ramp still meets something
    rebuilds: int = 3
    inf_min_radius_m: float = 30.0
    fit: FitSettings = field(default_factory=FitSettings)

    @classmethod
    def from_config(cls, cfg: Mapping) -> "LayoutSettings":
        """From the ``geometry`` section of the workflow config."""
        de = dict(cfg.get("de", {}))
        fit = FitSettings(**{k: v for k, v in de.items() if k in FitSettings.__dataclass_fields__},
                          clearance_m=float(cfg.get("clearance_m", 5.5)))
        keys = set(cls.__dataclass_fields__) - {"fit"}
        return cls(**{k: v for k, v in cfg.items() if k in keys}, fit=fit)

    @property
    def levels_m(self) -> tuple[float, ...]:
        return tuple(i * self.level_height_m for i in range(self.levels))


@dataclass(frozen=True)
class RampFeatures:
    """Targets of one ramp: minimum radius (may be ``inf``) and maximum slope."""

    radius_m: float
    slope_pct: float


@dataclass(frozen=True)
class RampOutcome:
    """How one ramp came out: the fit, first-try success and resamples."""

    ramp: str
    fit: RampFit
    first_try_ok: bool
    resamples: int
    infeasible: str
    evaluations: int
    seconds: float
    #: the targets of the feature set (the fit's may be resampled ones)
    first_targets: RampFeatures


@dataclass(frozen=True)
class Interchange:
    """A built interchange: the geometry.json value and per-ramp outcomes."""

    geometry: InterchangeGeometry
    outcomes: tuple[RampOutcome, ...]


# -- roads ----------------------------------------------------------------------

@dataclass(frozen=True)
class _Road:
    id: str
    expressway: str
    lanes: int
    level: int
    z: float
    origin: tuple[float, float]
    heading: float
    t_lo: float  # extent of the carriageway along its line (-inf .. inf for through roads)
    t_hi: float
    half_width: float  # of its expressway, median to outer edge


def _wrap(a: float) -> float:
    return (a + np.pi) % (2 * np.pi) - np.pi


def _ends(topo: Topology, ramp: str) -> tuple[tuple[str, Label] | None, tuple[str, Label] | None]:
    g = topo.graph
    starts = sorted((u, d["label"]) for u, _, d in g.in_edges(ramp, data=True) if d["label"].is_out)
    ends = sorted((v, d["label"]) for _, v, d in g.out_edges(ramp, data=True)
                  if not d["label"].is_out)
    return (starts[0] if starts else None), (ends[0] if ends else None)


def _road_of(topo: Topology, node: str, forward: bool, seen=None) -> str | None:
    """The road a chain of ramps leads to (forward) or comes from."""
    seen = seen or set()
    if topo.graph.nodes[node]["kind"] is Kind.ROAD:
        return node
    if node in seen:
        return None
    seen.add(node)
    start, end = _ends(topo, node)
    nxt = end if forward else start
    if nxt is not None:
        return _road_of(topo, nxt[0], forward, seen)
    g = topo.graph
    others = sorted(v for _, v, d in g.out_edges(node, data=True)) if forward else \
        sorted(u for u, _, d in g.in_edges(node, data=True))
    for o in others:
        r = _road_of(topo, o, forward, seen)
        if r:
            return r
    return None


def _terminal(topo: Topology, road: str) -> str | None:
    """``end`` if the carriageway ends here (Out-M), ``start`` if it begins (In-M)."""
    g = topo.graph
    if any(d["label"] is Label.OUT_M for _, _, d in g.out_edges(road, data=True)):
        return "end"
    if any(d["label"] is Label.IN_M for _, _, d in g.in_edges(road, data=True)):
        return "start"
    return None


def _layout_roads(topo: Topology, lanes: Mapping[str, int], st: LayoutSettings,
                  terminal_extra: float = 0.0) -> dict[str, _Road]:
    exps = topo.expressways
    terminal = {e: any(_terminal(topo, r) for r in rs) for e, rs in exps.items()}
    order = sorted(exps, key=lambda e: (terminal[e], e))
    g = topo.graph
    # ramps leaving or joining a carriageway on its left run in the median: widen it
    left = {e: any(d["label"] in (Label.OUT_L, Label.IN_L) and (u in rs or v in rs)
                   for u, v, d in g.edges(data=True)) for e, rs in exps.items()}
    wide = 2 * (st.ramp_lane_width_m + st.shoulder_width_m)
    median = {e: st.median_m + (wide if left[e] else 0.0) for e in exps}
    half = {e: median[e] / 2 + max(lanes.get(r, st.default_lanes) for r in rs) * st.lane_width_m
            + st.shoulder_width_m for e, rs in exps.items()}

    def place(options: dict[str, float]) -> dict[str, _Road]:
        roads = {}
        for k, e in enumerate(order):
            rs = exps[e]
            h1 = options[e]
            for i, r in enumerate(rs):
                h = h1 if i == 0 else h1 + np.pi
                o = (median[e] / 2) * np.array([np.sin(h), -np.cos(h)])
                other = max([half[x] for x in exps if x != e] or [0.0])
                term = _terminal(topo, r)
                t_lo, t_hi = -np.inf, np.inf
                if term == "end":
                    t_hi = -(other + st.terminal_m + terminal_extra)
                elif term == "start":
                    t_lo = other + st.terminal_m + terminal_extra
                n = lanes.get(r, st.default_lanes)
                roads[r] = _Road(r, e, int(n), k, k * st.level_height_m, (float(o[0]), float(o[1])),
                                 float(_wrap(h)), t_lo, t_hi, half[e])
        return roads

    base = {e: np.pi / 2 - k * np.pi / 2 if k < 2 else np.pi / 2 - k * np.pi / 4
            for k, e in enumerate(order)}
    best, best_score = None, -1e9
    for flip in ([False, True] if len(order) > 1 else [False]):
        opts = dict(base)
        if flip:
            opts[order[1]] += np.pi
        roads = place(opts)
        score = 0
        for ramp in topo.ramps:
            a = _road_of(topo, ramp, False)
            b = _road_of(topo, ramp, True)
            if not a or not b:
                continue
            raw = _wrap(roads[b].heading - roads[a].heading)
            if abs(abs(raw) - np.pi / 2) > 0.1:
                continue
            turn = "left" if raw > 0 else "right"
            for end in _ends(topo, ramp):
                if end is None or end[1].side == "middle":
                    continue
                score += 1 if end[1].side == turn else (-1 if end[1].side == "left" else 0)
        if score > best_score:
            best, best_score = roads, score
    return best


# -- ramps -------------------------------------------------------------------------

class _Builder:
    def __init__(self, topo: Topology, lanes: Mapping[str, int],
                 features: Mapping[str, RampFeatures], st: LayoutSettings, seed: int):
        self.topo, self.st, self.seed = topo, st, seed
        self.features = dict(features)
        # a T's terminal is far enough out for a ramp to climb one level there
        slopes = [f.slope_pct for f in features.values() if f.slope_pct > 0]
        extra = st.level_height_m / (min(slopes) / 100) + st.fit.transition_m if slopes else 0.0
        self.roads = _layout_roads(topo, lanes, st, extra)
        self.g = topo.graph
        self.fits: dict[str, RampFit] = {}
        self.rails: dict[str, dict] = {}  # fitted ramp → stations
        # parent (road or ramp) → (pos, extent along it, ramp, station) of the ramps
        # attached to it with a ``pos``
        self.attached: dict[str, list[tuple[float, float, float, str, float]]] = {}
        self.width = {r: self._lanes(r) * st.ramp_lane_width_m for r in topo.ramps}
        self.plan = self._level_plan()

    def _level_plan(self) -> dict[str, float]:
        """Crest heights fixed up front: the direct left turns.

        A direct left turn crosses the through expressways, so it passes over
        the highest of them by the clearance. Where left turns run both ways
        between two expressways they cross each other: those leaving the
        second expressway (a T's terminating one) go one level higher. Four
        legs: the two flyover levels of a four-level stack; a T: the three
        levels of a directional T.
        """
        topo, st = self.topo, self.st
        through = [r for r in self.roads.values() if np.isinf(r.t_lo) and np.isinf(r.t_hi)]
        top = max(r.z for r in through or self.roads.values())
        levels = [z for z in st.levels_m if z >= top + st.fit.clearance_m - 1e-6]
        if not levels:
            return {}
        lefts = {}
        for ramp in topo.ramps:
            start, end = _ends(topo, ramp)
            a, b = _road_of(topo, ramp, False), _road_of(topo, ramp, True)
            if start is None or end is None or not a or not b:
                continue
            raw = _wrap(self.roads[b].heading - self.roads[a].heading)
            if raw > 1.0 and not self._is_loop(ramp):
                lefts[ramp] = (self.roads[a].expressway, self.roads[b].expressway)
        plan = {}
        for ramp, (ea, eb) in lefts.items():
            both_ways = (eb, ea) in lefts.values()
            k = self.roads[_road_of(topo, ramp, False)].level if both_ways else 0
            plan[ramp] = float(levels[min(k, len(levels) - 1)])
        return plan

    def _stub_kids(self, ramp: str) -> list[str]:
        """The ramps leaving ``ramp`` or joining it (a stub's children, a C-D road's
        exits and entrances)."""
        g = self.g
        return [v for _, v, d in g.out_edges(ramp, data=True) if d["label"].is_out] + \
            [u for u, _, d in g.in_edges(ramp, data=True) if not d["label"].is_out]

    def _stub_z(self, ramp: str, z_road: float, zf: float) -> float:
        """Height of a stub's free end: the clearance toward its planned children's crest
        (so that they clear the roads near the stub), else ``zf``. If its unplanned
        children (right turns) go on to a road, they are fitted after the flyovers: then
        no higher than the clearance (and a margin) under the lowest planned crest, so
        that they pass under every flyover. (Right turns between two stubs are fitted
        before the flyovers, which pass round or over them.)"""
        crests = [self.plan[k] for k in self._stub_kids(ramp) if k in self.plan]
        if not crests:
            return zf
        c = max(crests)
        if c <= z_road:
            return zf
        clear = self.st.fit.clearance_m
        z = min(c, z_road + clear)
        if any(k not in self.plan and not self._low_connector(k) for k in self._stub_kids(ramp)):
            # they are fitted after the flyovers (they go on to a road): keep them under
            z = min(z, min(self.plan.values()) - clear - _Z_MARGIN)
        return float(z) if z > z_road + 0.25 else float(min(c, z_road + clear))

    def _kids_room(self, kids: list[str], z: float, turning: bool = True) -> float:
        """Room a ramp leaves toward the crossing for the ramps leaving or joining it
        (``kids``, at height ``z``): for the planned ones to climb to their crest, and
        (``turning``) for the turning ones to turn at their radius (``turn_room`` times
        it: the turn, and its straight leads and transitions; ``inf_reference_m`` for an
        ``inf`` target)."""
        extra = 0.0
        for k in kids:
            if k not in self.features:
                continue
            if k in self.plan:
                gk = max(self.features[k].slope_pct, 0.5) / 100.0
                extra = max(extra, abs(self.plan[k] - z) / gk + self.st.fit.transition_m)
            mov = self._movement(k)
            if turning and mov is not None and abs(mov) > 1.0:
                r = self.features[k].radius_m
                extra = max(extra, self.st.turn_room * r if math.isfinite(r)
                            else self.st.fit.inf_reference_m)
        return extra

    def _lanes(self, ramp: str) -> int:
        start, end = _ends(self.topo, ramp)
        if end is None:
            return max(1, sum(1 for _, _, d in self.g.out_edges(ramp, data=True) if d["label"].is_out))
        if start is None:
            return max(1, sum(1 for _, _, d in self.g.in_edges(ramp, data=True)
                              if not d["label"].is_out))
        return 1

    # movement classification
    def _heading_at(self, node: str, s: float | None = None) -> float:
        if node in self.roads:
            return self.roads[node].heading
        fit = self.fits[node]
        if s is None:
            return fit.end_pose[2]
        st = self.rails[node]
        return float(np.interp(s, st["s"], st["heading"]))

    def _movement(self, ramp: str) -> float | None:
        """The turn between the roads the ramp's chain connects (``None`` if unknown)."""
        a, b = _road_of(self.topo, ramp, False), _road_of(self.topo, ramp, True)
        if not a or not b:
            return None
        return float(_wrap(self.roads[b].heading - self.roads[a].heading))

    def _is_loop(self, ramp: str) -> bool:
        """A left movement between the roads, leaving its parent on the right (see module doc).

        Decided from the roads the chain connects, not from the parents' local
        headings: a collector-distributor road with a small radius wiggles.
        """
        start, end = _ends(self.topo, ramp)
        if start is None or end is None:
            return False
        if start[1] is not Label.OUT_R:
            return False
        raw = self._movement(ramp)
        if raw is None or not (abs(raw - np.pi / 2) < 0.2):
            return False
        pos = self.g.edges[start[0], ramp].get("pos")
        return pos is None or pos >= 0.4

    def _road_rail(self, road: str, ramp: str, label: Label, is_start: bool, loop: bool,
                   pos: float | None, width: float, extra: float = 0.0) -> Rail:
        r, st = self.roads[road], self.st
        if label in (Label.OUT_M, Label.IN_M):
            off = 0.0
        elif label.side == "right":
            off = -r.lanes * st.lane_width_m
        else:
            off = width
        other = max([x.half_width for x in self.roads.values() if x.expressway != r.expressway]
                    or [0.0])
        tz = other + st.crossing_margin_m + extra
        if self._same_road(ramp):  # collector-distributor: leave room for what attaches to it
            tz += st.cd_clear_m
        if label is Label.OUT_M or (pos is not None and pos >= 0.99 and np.isfinite(r.t_hi)):
            lo = hi = r.t_hi
        elif label is Label.IN_M or (pos is not None and pos <= 0.01 and np.isfinite(r.t_lo)):
            lo = hi = r.t_lo
        else:
            before = is_start != loop
            reach = max(st.reach_m, tz + st.gap_m)
            if self._is_stub(ramp):  # a stub attaches just beyond the room it leaves
                reach = tz + st.stub_window_m
            lo, hi = (-reach, -tz) if before else (tz, reach)
            lo, hi = max(lo, r.t_lo + st.gap_m), min(hi, r.t_hi - st.gap_m)
            if pos is not None:
                for p, t_min, t_max, other, t_other in self.attached.get(road, []):
                    round_loop = self._goes_round_loop(ramp, other, road)
                    if p < pos:
                        lo = max(lo, t_max + st.gap_m)
                        if self._crosses_loop_exit(ramp, other, road):
                            # it passes over the loop's exit branch, then descends
                            g = max(self._feat.slope_pct, 0.5) / 100.0
                            lo = max(lo, t_other + st.fit.clearance_m / g
                                     + st.fit.transition_m + st.gap_m)
                        if round_loop:
                            lo = max(lo, self._round_loop(other, road, width, +1))
                    elif p > pos:
                        hi = min(hi, t_min - st.gap_m)
                        if round_loop:
                            hi = min(hi, self._round_loop(other, road, width, -1))
            if lo > hi - 1.0:  # no room left between the others: keep the side's order
                lo, hi = (hi - st.stub_window_m, hi) if before else (lo, lo + st.stub_window_m)
        if hi - lo < 1e-3:
            hi = lo + 1e-3
        return Rail.line(road, label.value, r.origin, r.heading, r.z, off, lo, hi)

    def _low_connector(self, ramp: str) -> bool:
        """A ramp between two other ramps, without a planned crest."""
        ends = _ends(self.topo, ramp)
        return ramp not in self.plan and all(e is not None and e[0] not in self.roads
                                             for e in ends)

    def _other_road(self, ramp: str, road: str) -> str | None:
        """The road at the other end of ``ramp``'s chain from ``road``."""
        start, _ = _ends(self.topo, ramp)
        return _road_of(self.topo, ramp, start is not None and start[0] == road)

    def _goes_round_loop(self, ramp: str, other: str, road: str) -> bool:
        """Whether ``ramp`` and the loop ``other``, both on ``road``, join the same two
        roads the other way round: a cloverleaf's outer connector round its loop."""
        return self._is_loop(other) and not self._is_loop(ramp) and \
            self._other_road(ramp, road) == self._other_road(other, road)

    def round_loops(self, ramp: str) -> frozenset[str]:
        """The fitted loops ``ramp`` goes round (a cloverleaf's outer connector: the loop
        joining the same two roads the other way round, on the road they share)."""
        out = set()
        for end in _ends(self.topo, ramp):
            if end is None or end[0] not in self.roads:
                continue
            for other in self.fits:
                if any(e is not None and e[0] == end[0] for e in _ends(self.topo, other)) \
                        and self._goes_round_loop(ramp, other, end[0]):
                    out.add(other)
        return frozenset(out)

    def _round_loop(self, loop: str, road: str, width: float, side: int) -> float:
        """Where along ``road`` a ramp turning at its target radius must attach to go round
        the fitted ``loop``: after (``side`` +1) or before (-1) every point of it, by the
        distance an arc of that radius needs to get as far from the road."""
        r, st = self.roads[road], self.st
        d = np.array([math.cos(r.heading), math.sin(r.heading)])
        rel = self.rails[loop]["centre"] - np.array(r.origin)
        t = rel @ d
        lat = np.clip(-(rel @ np.array([-d[1], d[0]])) - r.lanes * st.lane_width_m, 0.0, None)
        rad = self._feat.radius_m if math.isfinite(self._feat.radius_m) else \
            st.fit.inf_reference_m
        c = width + self.width[loop] / 2 + 1.0
        need = np.where(lat + c < rad, np.sqrt(np.clip(rad**2 - (rad - lat - c) ** 2, 0, None)),
                        rad + c)
        return float(np.max(t + need)) if side > 0 else float(np.min(t - need))

    def _crosses_loop_exit(self, ramp: str, other: str, road: str) -> bool:
        """Whether ``ramp``, joining ``road`` after the loop ``other`` leaves it, has to pass
        over the loop's exit branch: it does unless it comes from the road the loop goes
        to (then it goes round the loop, as a cloverleaf's outer connector)."""
        start, end = _ends(self.topo, ramp)
        if not self._is_loop(other) or end is None or end[0] != road:
            return False
        return _road_of(self.topo, ramp, False) != _road_of(self.topo, other, True)

    def _is_stub(self, ramp: str) -> bool:
        start, end = _ends(self.topo, ramp)
        return start is None or end is None

    def _same_road(self, ramp: str) -> bool:
        start, end = _ends(self.topo, ramp)
        return bool(start and end and start[0] == end[0] and start[0] in self.roads)

    def _ramp_rail(self, parent: str, label: Label, is_start: bool, width: float) -> Rail:
        st = self.rails[parent]
        length = st["s"][-1]
        pw = self.width[parent]
        p_start, p_end = _ends(self.topo, parent)
        if label.side == "right":
            off = -pw if (p_end is not None and p_start is not None) else -(pw - width)
        else:
            off = width if (p_end is not None and p_start is not None) else 0.0
        if is_start and p_end is None:
            lo = hi = length
        elif not is_start and p_start is None:
            lo = hi = 0.0
        else:
            key = (parent, self._current) if is_start else (self._current, parent)
            pos = self.g.edges[key].get("pos")
            if pos is not None:
                lo, hi = max(0.05, pos - 0.15) * length, min(0.95, pos + 0.15) * length
                # diverges and merges keep the order ``pos`` gives them on this parent, a
                # gap apart from those already attached (a merge just before a diverge
                # leaves no room for lane changes: movements become unroutable)
                gap = min(self.st.gap_m, 0.05 * length)
                wlo, whi = lo, hi
                for p_other, _, _, _, t_other in self.attached.get(parent, []):
                    if p_other < pos:
                        lo = max(lo, t_other + gap)
                    elif p_other > pos:
                        hi = min(hi, t_other - gap)
                if lo > hi - 1.0:
                    lo, hi = wlo, whi
            elif self._is_loop(parent):  # leave a loop before it turns, join it after
                head = st["heading"]
                if is_start:
                    turned = np.abs(head - head[0]) > 0.35
                    lo, hi = 0.05 * length, float(st["s"][np.argmax(turned)]) if turned.any() \
                        else 0.6 * length
                else:
                    turned = np.abs(head - head[-1]) > 0.35
                    last = len(head) - 1 - np.argmax(turned[::-1])
                    lo = float(st["s"][last]) if turned.any() else 0.4 * length
                    hi = 0.95 * length
                lo, hi = min(lo, hi), max(lo, hi)
            elif is_start:
                lo, hi = 0.15 * length, 0.6 * length
            else:
                lo, hi = 0.4 * length, 0.85 * length
            lo, hi = self._room_beside(parent, off, width, lo, hi)
        if hi - lo < 1e-3:
            hi = lo + 1e-3
        return Rail(parent, label.value, st["s"], st["xy"], st["heading"], st["z"], off, lo, hi)

    def _room_beside(self, parent: str, off: float, width: float, lo: float,
                     hi: float) -> tuple[float, float]:
        """The part of ``lo..hi`` on a fitted parent where a child ``width`` wide, beside it
        at ``off``, is clear of the roads at its level.

        A ramp that joins a road runs along its edge for a while (and one that leaves a
        road starts along it): a child on the side facing that road has no room there,
        whatever its shape (J1's r2 joins r3 on the left, between r3 and R4). When some
        stations of ``lo..hi`` lack that room, the window becomes the run of stations
        with room (within 5..95 % of the parent) that overlaps it most, else the longest;
        unchanged when every station has room or none has."""
        st = self.rails[parent]
        s, xy, head, z = st["s"], st["xy"], st["heading"], st["z"]
        left = np.stack([-np.sin(head), np.cos(head)], -1)
        clear = np.ones(len(s), bool)
        for k in np.linspace(off - width + 0.5, off + 1.0, 5):  # across the child's lane
            q = xy + k * left
            for x0, y0, dx, dy, t_lo, t_hi, lat_lo, lat_hi, zr in self._road_lines():
                rel = q - (x0, y0)
                along, lat = rel @ (dx, dy), rel @ (-dy, dx)
                clear &= ~((along >= t_lo) & (along <= t_hi) & (lat >= lat_lo) & (lat <= lat_hi)
                           & (np.abs(z - zr) < self.st.fit.clearance_m))
        inside = (s >= lo) & (s <= hi)
        if clear[inside].all() or not clear.any():
            return lo, hi
        length = s[-1]
        ok = clear & (s >= 0.05 * length) & (s <= 0.95 * length)
        edges = np.flatnonzero(np.diff(np.concatenate([[0], ok.astype(int), [0]])))
        runs = [(s[a], s[b - 1]) for a, b in zip(edges[::2], edges[1::2]) if b - 1 > a]
        if not runs:
            return lo, hi
        a, b = max(runs, key=lambda r: (max(0.0, min(hi, r[1]) - max(lo, r[0])), r[1] - r[0]))
        return float(a), float(b)

    def _goal_z(self, ramp: str, forward: bool) -> float:
        g = self.g
        if forward:
            kids = [v for _, v, d in g.out_edges(ramp, data=True) if d["label"].is_out]
        else:
            kids = [u for u, _, d in g.in_edges(ramp, data=True) if not d["label"].is_out]
        zs = [self.roads[r].z for r in (_road_of(self.topo, k, forward) for k in kids) if r]
        return float(np.mean(zs)) if zs else 0.0

    def spec(self, ramp: str, feat: RampFeatures) -> RampSpec:
        self._current, self._feat = ramp, feat
        start, end = _ends(self.topo, ramp)
        width = self.width[ramp]
        st = self.st
        if start is None and end is None:
            raise GeometryError("ramp has neither a start nor an end", source=self.topo.source,
                                element=ramp)
        # headings of the ends (nominal) → raw turn
        h_a = self._nominal_heading(start, True) if start else None
        h_b = self._nominal_heading(end, False) if end else None
        free = None
        if start is None or end is None:
            raw, loop = 0.0, False
            fixed = start or end
            side = fixed[1].side
            sgn = -1.0 if side == "right" else (1.0 if side == "left" else 0.0)
            lat = (sorted((sgn * 3.0, sgn * 40.0)) if sgn else (-10.0, 10.0))
            if end is None:  # split stub: free end
                z0 = self._end_z(start)
                zf = self._stub_z(ramp, z0, z0 + (self._goal_z(ramp, True) - z0) / 3.0)
            else:
                z1 = self._end_z(end)
                zf = self._stub_z(ramp, z1, z1 + (self._goal_z(ramp, False) - z1) / 3.0)
            # the free end is far enough out for the stub to climb to it at its slope
            z_fix = self._end_z(start or end)
            g = max(feat.slope_pct, 0.5) / 100.0
            climb = float(climb_distance(zf - z_fix, g, st.fit.transition_m)) + 60.0
            free = FreeEnd((60.0, max(400.0, climb)), lat, (-np.pi / 4, np.pi / 4), zf)
            stub_extra = self._kids_room(self._stub_kids(ramp), zf)
            if stub_extra > 0:  # the free end keeps that room from the crossing
                free = replace(free, forward=(60.0, max(250.0, climb)))
                stub_extra += free.forward[1]
        else:
            raw = _wrap(h_b - h_a)
            loop = self._is_loop(ramp)
            mov = self._movement(ramp)
            if mov is not None:  # the branch of the local turn nearest the roads' movement
                if loop:
                    mov -= 2 * np.pi
                raw = mov + _wrap(raw - mov)
        turn = raw
        pieces = 2 if (abs(turn) > 2.2 or abs(turn) < 0.3) else 1
        if start is not None and end is not None and not loop and turn > 1.0:
            pieces = 3  # a left turn over the roads: climb along its road, turn, descend along
        # a direct left turn crosses the other roads: leave room to climb / descend a level
        extra = stub_extra if free is not None else 0.0
        extra_b = extra
        if start is not None and end is not None and not loop and turn > 1.0:
            g = max(feat.slope_pct, 0.5) / 100.0
            crest = self.plan.get(ramp)
            if crest is not None:  # the whole climb before the crossing, descent after
                extra, extra_b = (max(st.level_height_m, crest - self._end_z(e)) / g
                                  + st.fit.transition_m for e in (start, end))
            else:
                extra = extra_b = st.level_height_m / g + st.fit.transition_m
        if free is None:  # room for the planned ramps leaving / joining this one
            g_ = self.g
            outs = [v for _, v, d in g_.out_edges(ramp, data=True) if d["label"].is_out]
            ins = [u for u, _, d in g_.in_edges(ramp, data=True) if not d["label"].is_out]
            extra = max(extra, self._kids_room(outs, self._end_z(start), turning=False))
            extra_b = max(extra_b, self._kids_room(ins, self._end_z(end), turning=False))
        a = self._rail(ramp, start, True, loop, width, extra) if start else None
        b = self._rail(ramp, end, False, loop, width, extra_b) if end else None
        crest = self.plan.get(ramp)
        return RampSpec(ramp, a, b, free, float(turn), pieces, width, float(feat.radius_m),
                        float(feat.slope_pct), crest, self._leads(start, end, crest, free, feat),
                        inf_floor_m=float(st.inf_min_radius_m))

    def _leads(self, start, end, crest, free, feat: RampFeatures) -> tuple:
        """Longest straight leads of a ramp that climbs: each attached end may run
        straight along its parent's heading for as long as it takes to climb from
        that end to the ramp's top at its slope (at least ``lead_min_m``), so that
        a flyover can gain height beside its road before it turns over what it
        crosses. Level ramps get none (their geometry is as without leads)."""
        st = self.st
        if not st.leads:
            return (None, None)
        g = max(feat.slope_pct, 0.5) / 100.0
        za = self._end_z(start) if start else None
        zb = self._end_z(end) if end else None
        top = max(z for z in (crest, za, zb, free.z if free else None) if z is not None)
        climbs = [float(climb_distance(top - z, g, st.fit.transition_m)) if z is not None
                  else 0.0 for z in (za, zb)]
        if max(climbs) <= 0:
            return (None, None)
        return tuple(max(st.lead_min_m, c) for c in climbs)

    def _nominal_heading(self, end, is_start) -> float:
        node, label = end
        if node in self.roads:
            return self.roads[node].heading
        st = self.rails[node]
        p_start, p_end = _ends(self.topo, node)
        pos = self.g.edges[(node, self._current) if is_start else (self._current, node)].get("pos")
        if is_start:
            s = st["s"][-1] if p_end is None else (0.4 if pos is None else pos) * st["s"][-1]
        else:
            s = 0.0 if p_start is None else (0.6 if pos is None else pos) * st["s"][-1]
        return float(np.interp(s, st["s"], st["heading"]))

    def _end_z(self, end) -> float:
        node, _ = end
        if node in self.roads:
            return self.roads[node].z
        st = self.rails[node]
        return float(np.mean(st["z"]))  # refined per candidate by the rail

    def _rail(self, ramp, end, is_start, loop, width, extra=0.0) -> Rail:
        node, label = end
        if node in self.roads:
            pos = self.g.edges[(node, ramp) if is_start else (ramp, node)].get("pos")
            return self._road_rail(node, ramp, label, is_start, loop, pos, width, extra)
        return self._ramp_rail(node, label, is_start, width)

    def _road_lines(self) -> np.ndarray:
        """The roads' driving bands as :attr:`Obstacles.lines` rows (in ``roads`` order)."""
        rows = []
        for r in self.roads.values():
            d = (math.cos(r.heading), math.sin(r.heading))
            rows.append([r.origin[0], r.origin[1], d[0], d[1], max(r.t_lo, -1e5),
                         min(r.t_hi, 1e5), -r.lanes * self.st.lane_width_m, 0.0, r.z])
        return np.array(rows)

    def obstacles(self, keep_out: frozenset[str] = frozenset()) -> Obstacles:
        """Roads and fitted ramps; the fitted ramps in ``keep_out`` at every height (a
        ramp must not cross them in plan at all)."""
        st = self.st
        lines = self._road_lines()
        names = [r.id for r in self.roads.values()]
        pts, zs, hw, owner = [], [], [], []
        for rid, s in self.rails.items():
            pts.append(s["centre"])
            zs.append(s["centre_z"])
            hw.append(np.full(len(s["centre_z"]), self.width[rid] / 2))
            owner += [rid] * len(s["centre_z"])
        # a keep-out loop, copied at heights less than the clearance apart over every level:
        # no height of the ramp clears it
        step = st.fit.clearance_m
        heights = np.arange(-step, st.levels_m[-1] + 2 * step, step)
        for rid in sorted(keep_out & set(self.rails)):
            s = self.rails[rid]
            n = len(s["centre_z"])
            for h in heights:
                pts.append(s["centre"])
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
        self.rails.pop(ramp, None)
        for parent, items in self.attached.items():
            self.attached[parent] = [a for a in items if a[3] != ramp]

    def record(self, ramp: str, fit: RampFit) -> None:
        self.fits[ramp] = fit
        # stations ~1 m apart: a ramp attaching to this one is placed on them by linear
        # interpolation (chord error < 1 cm down to 30 m radius); the lane centre, an
        # obstacle for later ramps, is sampled as the search samples candidates
        per_piece = math.ceil(fit.length_m / len(fit.ctrl))
        stations = _stations(fit, int(min(4000, max(64, per_piece))))
        # the lane centre as an obstacle: points no more than the search's step apart
        # (a piece's control polygon is at least as long as the piece)
        polygon = float(np.linalg.norm(np.diff(fit.ctrl, axis=1), axis=-1).sum(-1).max())
        dense = int(math.ceil(1.2 * polygon / _kernels.STEP_M))
        centre = _stations(fit, max(64, dense), self.width[ramp] / 2)
        self.rails[ramp] = {**stations, "centre": centre["xy"], "centre_z": centre["z"]}
        for end, t, is_start in ((fit.spec.start, fit.start_s, True), (fit.spec.end, fit.end_s, False)):
            if end is None:
                continue
            key = (end.parent, ramp) if is_start else (ramp, end.parent)
            pos = self.g.edges[key].get("pos")
            if pos is None:
                continue
            lo_t = hi_t = float(t)
            if end.parent in self.roads and (fit.spec.free is not None or self._is_loop(ramp)):
                # a stub runs along its road up to its free end, a loop's circle reaches
                # along it: the next attachments keep their gap from all of it
                road = self.roads[end.parent]
                d = np.array([math.cos(road.heading), math.sin(road.heading)])
                along = (stations["xy"] - np.array(road.origin)) @ d
                lo_t, hi_t = float(min(t, along.min())), float(max(t, along.max()))
            self.attached.setdefault(end.parent, []).append((pos, lo_t, hi_t, ramp, float(t)))

    def order(self) -> list[str]:
        done: set[str] = set()
        out = []
        todo = list(self.topo.ramps)
        while todo:
            ready = []
            for r in todo:
                start, end = _ends(self.topo, r)
                deps = [e[0] for e in (start, end) if e and e[0] not in self.roads]
                if all(d in done for d in deps):
                    ready.append(r)
            if not ready:
                raise GeometryError("ramps attach to each other in a cycle", source=self.topo.source,
                                    element=", ".join(todo))
            # stubs and road-to-road ramps first, in id order; in a round, a low connector
            # between two ramps (e.g. a stack's right turn: no freedom where it attaches)
            # goes before the flyovers, which then pass over it
            for r in sorted(ready, key=lambda r: not self._low_connector(r)):
                done.add(r)
                out.append(r)
                todo.remove(r)
        return out


def _stations(fit: RampFit, m: int, right_m: float = 0.0) -> dict[str, np.ndarray]:
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


def _arc(p: np.ndarray, heading: float, turn: float, radius: float) -> tuple[np.ndarray,
                                                                         np.ndarray, float]:
    """A circular arc from ``p`` at ``heading`` turning ``turn`` rad (left positive) at
    ``radius`` as one cubic (tangents 4/3 tan(|turn| / 4) r long); its end and heading."""
    k = 4.0 / 3.0 * radius * math.tan(abs(turn) / 4.0)
    chord = 2.0 * radius * math.sin(abs(turn) / 2.0)
    h1 = heading + turn
    q = p + chord * np.array([math.cos(heading + turn / 2), math.sin(heading + turn / 2)])
    ctrl = np.stack([p, p + k * np.array([math.cos(heading), math.sin(heading)]),
                     q - k * np.array([math.cos(h1), math.sin(h1)]), q])
    return ctrl, q, h1


def _cd_fit(b: _Builder, ramp: str, spec: RampSpec) -> RampFit | None:
    """A collector-distributor road built as real ones are: it leaves its carriageway on
    a reverse curve, runs straight beside it ``cd_offset_m`` from its edge, and rejoins
    it on a reverse curve (plan: two pairs of circular arcs at the target radius on the
    lane centre, or ``inf_reference_m`` for an ``inf`` target, and a straight). It
    reaches from the crossing's room (the rails' inner ends) far enough for the ramps
    attached to it to turn at their radii. ``None`` when the rails leave no room for it."""
    st = b.st
    a, e = spec.start, spec.end
    r_lane = spec.target_radius_m
    if math.isinf(r_lane):
        r_lane = st.fit.inf_reference_m
    half = 0.5 * spec.width_m
    d = st.cd_offset_m
    theta = math.acos(max(-1.0, 1.0 - d / (2.0 * r_lane)))
    s_curve = 2.0 * r_lane * math.sin(theta)  # along the carriageway
    r_kids = max([min(b.features[k].radius_m, st.fit.inf_reference_m)
                  for k in b._stub_kids(ramp) if k in b.features] or [0.0])
    room = s_curve + 2.0 * (r_kids + st.gap_m)
    sa = float(np.clip(a.hi - room, a.lo, a.hi))
    sb = float(np.clip(e.lo + room, e.lo, e.hi))
    (pa, ha, _), (pb, hb, _) = a.at(np.array([sa])), e.at(np.array([sb]))
    pa, pb, h = pa[0], pb[0], float(ha[0])
    along = float(np.dot(pb - pa, [math.cos(h), math.sin(h)]))
    straight = along - 2.0 * s_curve
    if straight < 1.0 or abs(_wrap(float(hb[0]) - h)) > 1e-6:
        return None
    pieces = []
    p, head = np.asarray(pa, float), h
    # right arcs have the lane centre inside (its radius r - half), left arcs outside
    for turn in (-theta, theta):
        c, p, head = _arc(p, head, turn, r_lane + (half if turn < 0 else -half))
        pieces.append(c)
    q = p + straight * np.array([math.cos(head), math.sin(head)])
    pieces.append(np.stack([p + (q - p) * f for f in (0.0, 1 / 3, 2 / 3, 1.0)]))
    p = q
    for turn in (theta, -theta):
        c, p, head = _arc(p, head, turn, r_lane + (half if turn < 0 else -half))
        pieces.append(c)
    return measure_spline(spec, np.stack(pieces), sa, sb, b.obstacles(), st.fit)


def _fit_with_levels(b: _Builder, spec: RampSpec, seed: int) -> tuple[RampFit, int, float]:
    """Fit; while the ramp meets something at its level, lift its crest one level.

    The first fits have no leads; a ramp that still misses its targets is fitted
    again (``restarts`` times in all) with its straight leads
    (:meth:`_Builder._leads`), then also with one more Bézier piece (a turn one
    cubic cannot bend evenly enough for its radius), then with one more piece
    but no leads, then with other seeds."""
    st = b.st
    evals, secs = 0, 0.0
    obst = b.obstacles()
    tried = []
    more = replace(spec, pieces=spec.pieces + 1)
    plain_more = replace(more, lead_m=(None, None))
    restarts = [spec, more, plain_more] if any(spec.leads()) else [more]
    spec = replace(spec, lead_m=(None, None))
    while True:
        fit = fit_ramp(spec, obst, st.fit, seed=seed)
        evals += fit.evaluations
        secs += fit.seconds
        tried.append(fit)
        if fit.conflicts == 0:
            break
        higher = [z for z in st.levels_m if z > fit.z_crest + 1e-6]
        if not higher or (len(tried) > 1 and fit.conflicts >= tried[-2].conflicts):
            break  # lifting does not help: the conflict is not a crossing
        spec = replace(spec, z_crest=higher[0])
    best = min(tried, key=lambda f: (f.conflicts, not f.ok, not f.slope_ok))
    restarts += [spec] * st.restarts
    for k, again in enumerate(restarts[:st.restarts]):  # same targets, other shapes/seeds
        if best.ok or _systematic(best):
            break
        fit = fit_ramp(replace(again, z_crest=best.spec.z_crest), obst, st.fit,
                       seed=seed + 104_729 * (k + 1))
        evals += fit.evaluations
        secs += fit.seconds
        best = min([best, fit], key=lambda f: (not f.ok, f.conflicts, not f.slope_ok))
    return best, evals, secs


def build_interchange(topology: Topology, lanes: Mapping[str, int],
                      features: Mapping[str, RampFeatures], *, class_id: str = "",
                      sample: int = 0, seed: int = 0, settings: LayoutSettings | None = None,
                      resampler: Callable[[str, int], RampFeatures | None] | None = None
                      ) -> Interchange:
    """Lay out the roads and fit every ramp of one feature set.

    Parameters
    ----------
    topology
        The interchange topology.
    lanes
        Road id → number of lanes (missing roads get ``default_lanes``).
    features
        Ramp id → :class:`RampFeatures` (targets).
    resampler
        ``(ramp, attempt) → RampFeatures`` drawing new targets for a ramp that
        misses its targets (Algorithm 1); ``None`` disables resampling. If it
        also has a method ``clearing(ramp, attempt)`` (as
        :class:`flyover.geometry.tables.DomainResampler`), a ramp that still meets
        something at its level after that is resampled with its draws (the
        steepest slope), up to ``max_resamples`` times more.

    While a ramp still meets something at its level, the interchange is built
    again with seeds derived from ``seed`` (``settings.rebuilds`` times at most);
    the build with the fewest conflicting ramps is returned, with first-try
    success from the first build and the effort of all builds.

    Raises
    ------
    GeometryError
        When the topology cannot be laid out (naming the element).
    """
    st = settings or LayoutSettings()
    best = None
    effort: dict[str, tuple[int, float]] = {}
    first: dict[str, bool] = {}
    for k in range(st.rebuilds + 1):
        # a ramp meeting something at its level is never kept if it can be helped: the
        # whole interchange is built again with other seeds (every ramp's shape, hence
        # where the later ones find room, changes); the build with the fewest conflicts
        # wins, its effort includes the discarded builds'
        ks = seed if k == 0 else (seed * 2_654_435_761 + 97 * k) % (2**32)
        ic = _build_once(topology, lanes, features, class_id, sample, ks, st, resampler)
        for o in ic.outcomes:
            e, t = effort.get(o.ramp, (0, 0.0))
            effort[o.ramp] = (e + o.evaluations, t + o.seconds)
            first.setdefault(o.ramp, o.first_try_ok)
        rank = (sum(o.fit.conflicts > 0 for o in ic.outcomes),
                sum(o.fit.conflicts for o in ic.outcomes), sum(not o.fit.ok for o in ic.outcomes))
        if best is None or rank < best[0]:
            best = (rank, ic)
        if rank[0] == 0:
            break
    ic = best[1]
    outs = tuple(replace(o, first_try_ok=first[o.ramp], evaluations=effort[o.ramp][0],
                         seconds=effort[o.ramp][1]) for o in ic.outcomes)
    return Interchange(ic.geometry, outs)


def _build_once(topology: Topology, lanes: Mapping[str, int],
                features: Mapping[str, RampFeatures], class_id: str, sample: int, seed: int,
                st: LayoutSettings, resampler) -> Interchange:
    """One build of :func:`build_interchange` with one seed."""
    b = _Builder(topology, lanes, features, st, seed)
    outcomes = []
    for k, ramp in enumerate(b.order()):
        if ramp not in features:
            raise GeometryError("no features for ramp", source=topology.source, element=ramp)
        feat = features[ramp]
        rseed = (seed * 1_000_003 + k * 7919) % (2**32)
        spec = b.spec(ramp, feat)
        built = _cd_fit(b, ramp, spec) if b._same_road(ramp) else None
        fit, evals, secs = None, 0, 0.0
        if built is not None and built.ok:
            fit = built
        elif loops := b.round_loops(ramp):
            # a cloverleaf's outer connector goes round its loop, not over or under it:
            # fitted with the loop as an obstacle at every height and one more Bézier piece
            # to bow out with (without, then with its leads); if it cannot meet its targets
            # that way, it is fitted as any other ramp
            more = replace(spec, pieces=spec.pieces + 1)
            for n, again in enumerate((replace(more, lead_m=(None, None)), more)):
                kept = fit_ramp(again, b.obstacles(loops), st.fit, seed=rseed + n)
                evals, secs = evals + kept.evaluations, secs + kept.seconds
                if kept.ok and kept.conflicts == 0:
                    fit = kept
                    break
        if fit is None:
            fit, e2, s2 = _fit_with_levels(b, spec, rseed)
            evals, secs = evals + e2, secs + s2
        if fit.conflicts:  # make way: refit the ramps it meets, then it again
            fit, e2, s2 = _reroute(b, ramp, fit, rseed, outcomes)
            evals, secs = evals + e2, secs + s2
        first_ok = fit.ok
        attempts, tried = 0, [fit]
        while (not fit.ok and resampler is not None and attempts < st.max_resamples
               and not _systematic(fit)):
            attempts += 1
            new = resampler(ramp, attempts)
            if new is None:
                break
            fit2, e2, s2 = _fit_with_levels(b, b.spec(ramp, new), rseed + attempts)
            evals += e2
            secs += s2
            tried.append(fit2)
            fit = fit2
        if not fit.ok:
            fit = min(tried, key=lambda f: (f.conflicts, not f.slope_ok, not f.radius_ok))
        if fit.conflicts and attempts:  # on the last targets too
            fit, e2, s2 = _reroute(b, ramp, fit, rseed + attempts, outcomes)
            evals, secs = evals + e2, secs + s2
        # still crossing something at its level: a crossing is never acceptable, so draw
        # targets that clear it soonest (the steepest slope of the domain)
        clearing = getattr(resampler, "clearing", None)
        k = 0
        while fit.conflicts and clearing is not None and k < st.max_resamples:
            k += 1
            new = clearing(ramp, k)
            if new is None:
                break
            fit2, e2, s2 = _fit_with_levels(b, b.spec(ramp, new), rseed + 7 * k + 101)
            evals, secs = evals + e2, secs + s2
            if fit2.conflicts:
                fit2, e2, s2 = _reroute(b, ramp, fit2, rseed + 7 * k + 102, outcomes)
                evals, secs = evals + e2, secs + s2
            attempts += 1
            fit = min([fit, fit2], key=lambda f: (f.conflicts, not f.ok))
        met = conflicts_with(fit, b.obstacles(), st.fit) if fit.conflicts else {}
        reason = "" if fit.ok else _reason(fit, met)
        b.record(ramp, fit)
        outcomes.append(RampOutcome(ramp, fit, first_ok, attempts, reason, evals, secs, feat))
    return Interchange(_assemble(b, class_id, sample, seed, outcomes), tuple(outcomes))


def _reroute(b: _Builder, ramp: str, fit: RampFit, seed: int,
             outcomes: list[RampOutcome]) -> tuple[RampFit, int, float]:
    """Rip up and reroute: ``ramp`` still meets fitted ramps at its level, so each of
    them (one nothing is attached to yet, and not ``ramp``'s parent) is fitted again
    on its own targets with ``ramp``'s curve as an obstacle; a refit is kept only when
    it meets its targets with no conflict. Then ``ramp`` is measured against the new
    obstacles, and fitted again if it still meets something. Returns ``ramp``'s
    fit and the effort spent."""
    st = b.st
    evals, secs = 0, 0.0
    parents = {r.parent for r in (fit.spec.start, fit.spec.end) if r is not None}
    used = {r.parent for f in b.fits.values() for r in (f.spec.start, f.spec.end) if r is not None}
    met = conflicts_with(fit, b.obstacles(), st.fit)
    movable = [m for m in met if m in b.fits and m not in parents and m not in used]
    if not movable:
        return fit, evals, secs
    by_ramp = {o.ramp: i for i, o in enumerate(outcomes)}
    for k, other in enumerate(movable):
        old = b.fits[other]
        b.unrecord(other)
        b.record(ramp, fit)  # an obstacle while the other one is refitted
        spec = b.spec(other, RampFeatures(old.spec.target_radius_m, old.spec.target_slope_pct))
        new, e, t = _fit_with_levels(b, spec, seed + 7_368_787 * (k + 1))
        evals, secs = evals + e, secs + t
        b.unrecord(ramp)
        keep = new if (new.ok and new.conflicts == 0) else old
        b.record(other, keep)
        if keep is new:
            o = outcomes[by_ramp[other]]
            outcomes[by_ramp[other]] = replace(o, fit=new, infeasible="",
                                               evaluations=o.evaluations + e,
                                               seconds=o.seconds + t)
    fit = recount(fit, b.obstacles(), st.fit)
    if fit.conflicts:
        again, e, t = _fit_with_levels(b, replace(fit.spec, z_crest=b.plan.get(ramp)), seed + 1)
        evals, secs = evals + e, secs + t
        fit = min([fit, again], key=lambda f: (f.conflicts, not f.ok))
    return fit, evals, secs


def _systematic(fit: RampFit) -> bool:
    """A level ramp (ends at one height, nothing to pass over) cannot have any slope:
    resampling cannot help, the feature set is systematically infeasible."""
    za, zb = fit.start_pose[3], fit.end_pose[3]
    level = abs(za - zb) < 1e-6 and fit.z_crest <= max(za, zb) + 1e-6
    return level and fit.radius_ok and fit.conflicts == 0 and not fit.slope_ok


def _reason(fit: RampFit, met: Mapping[str, int] | None = None) -> str:
    parts = []
    sp = fit.spec
    za, zb = fit.start_pose[3], fit.end_pose[3]
    if not fit.slope_ok:
        if abs(za - zb) < 1e-6 and fit.z_crest <= max(za, zb) + 1e-6:
            parts.append(f"slope: level ramp (both ends at z={za:.1f} m) cannot have a "
                         f"{sp.target_slope_pct:g} % slope")
        else:
            parts.append(f"slope: {fit.max_slope_pct:.2f} % instead of {sp.target_slope_pct:g} %")
    if not fit.radius_ok and math.isinf(sp.target_radius_m):
        parts.append(f"radius: {fit.min_radius_m:.1f} m, tighter than the {sp.inf_floor_m:g} m "
                     f"an inf target allows")
    elif not fit.radius_ok:
        parts.append(f"radius: {fit.min_radius_m:.1f} m instead of {sp.target_radius_m:g} m")
    if fit.conflicts:
        with_ = ", ".join(f"{k} ({n})" for k, n in sorted((met or {}).items()))
        parts.append(f"same-level conflict ({fit.conflicts} samples)"
                     + (f" with {with_}" if with_ else ""))
    return "; ".join(parts)


def _assemble(b: _Builder, class_id: str, sample: int, seed: int,
              outcomes: list[RampOutcome]) -> InterchangeGeometry:
    st = b.st
    # road extents: cover every attachment and ramp with a margin
    ts: dict[str, list[float]] = {r: [] for r in b.roads}
    for o in outcomes:
        f = o.fit
        for rail, t in ((f.spec.start, f.start_s), (f.spec.end, f.end_s)):
            if rail is not None and rail.parent in b.roads:
                ts[rail.parent].append(t)
    extent = max([abs(t) for v in ts.values() for t in v] or [st.reach_m / 3])
    extent += st.road_margin_m
    t0: dict[str, float] = {}
    roads = []
    for r in sorted(b.roads.values(), key=lambda r: r.id):
        lo = r.t_lo if np.isfinite(r.t_lo) else -extent
        hi = r.t_hi if np.isfinite(r.t_hi) else extent
        t0[r.id] = lo
        start = np.array(r.origin) + lo * np.array([math.cos(r.heading), math.sin(r.heading)])
        roads.append(RoadGeometry(r.id, r.expressway, r.lanes, r.level, r.z,
                                  (float(start[0]), float(start[1])), r.heading, float(hi - lo)))
    ramps = []
    for o in sorted(outcomes, key=lambda o: o.ramp):
        f = o.fit
        atts = []
        for rail, s, pose in ((f.spec.start, f.start_s, f.start_pose),
                              (f.spec.end, f.end_s, f.end_pose)):
            if rail is None:
                atts.append(Attachment("", "", 0.0, 0.0, _wrap(pose[2]), pose[3]))
                continue
            s_m = s - t0[rail.parent] if rail.parent in b.roads else s
            atts.append(Attachment(rail.parent, rail.label, float(s_m), float(rail.offset_m),
                                   float(_wrap(pose[2])), float(pose[3])))
        ramps.append(RampGeometry(
            id=o.ramp, lanes=int(round(b.width[o.ramp] / st.ramp_lane_width_m)),
            plan=f.pieces(), elevation=f.elevation, start=atts[0], end=atts[1],
            target_radius_m=f.spec.target_radius_m, target_slope_pct=f.spec.target_slope_pct,
            min_radius_m=f.min_radius_m, max_slope_pct=f.max_slope_pct, length_m=f.length_m,
            ok=f.ok, resamples=o.resamples, infeasible=o.infeasible))
    return InterchangeGeometry(class_id, int(sample), int(seed), st.lane_width_m,
                               st.shoulder_width_m, st.ramp_lane_width_m, st.levels_m,
                               tuple(roads), tuple(ramps))
