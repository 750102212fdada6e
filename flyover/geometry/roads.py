"""Road layout: where the expressways' carriageways run and at which level.

Decides each carriageway's line (origin, heading), extent and height; reads the
topology (expressways, T terminals, which side ramps leave and join on) and the
settings.

* Expressways are straight lines through the centre: the first through
  expressway runs north–south (carriageway 1 northbound), the second east–west;
  its direction is chosen so that the ramps between two roads turn as the real ones
  do, where the topology comes with their real turns (``turn_deg``, measured by the OSM
  reader; a cloverleaf's ends are all on the right, so nothing else tells its two
  orientations apart: Bangor's was laid out mirrored), then so that as many ramps as
  possible leave and join on the side they turn to (right exits turning right); catalog
  specs and GraphML without coordinates carry no turns. Further expressways are
  placed at 45° steps, each where its legs are farthest from those placed
  (a 5-leg interchange's half lines spread round the centre). An expressway
  that ends here (``Out-M``/``In-M``, a T) is a half line: its carriageways
  end/begin ``terminal_m`` from the centre on the side the topology implies,
  farther by the room a ramp at that terminal needs to climb one level there: at the
  lowest slope of the ramps between that expressway and a road on another level or
  flying over between two on its level (``slopes``, ``climbing``;
  :func:`terminal_room`), not of every ramp of the interchange (DC's I-66: r1 and r2,
  not the E Street Expressway's flyovers). Each through expressway is on its
  own level (0, 1, ...); the terminating ones, which never meet, share the level above
  them (a T's terminating expressway above the through one).
* Two expressways ending here that continue one another
  (:func:`flyover.geometry.chains.continuations`: DC's I-66 and Potomac Freeway) are
  one line, placed as a through expressway is: the one with ramps to a third road at
  its terminal (the *kept* one) keeps it; its partner runs on past the centre, in the
  kept one's median just left of its lanes (the median wide enough for it), to
  ``CONTINUATION_GAP_M`` short of that terminal, so the ramps between them are short
  and move over by about a lane, as a merge from the left does.
* A T whose ramps all run to or from one such pair's line (:func:`tee_junctions`: DC's
  E Street Expressway, to the I-66 / Potomac Freeway line) meets that line square at a
  junction of its own on the kept one's leg, as on the map, not at the centre: beyond the
  kept one's terminal by ``terminal_m``, the other roads' half width and the room its
  flyovers leaving it need to descend to the line; its own terminal is out from that
  junction by the room those into it need to descend two levels (they fly over those
  leaving it: :class:`flyover.geometry.levels.LevelPlan`) or those leaving it to climb
  one; it lies on the side where most ramp ends lie on the side their ramp turns to. Its
  roads record the junction (:attr:`RoadLine.junction`), the origin of their stations;
  the ramps between it and the line keep their room from it
  (:meth:`flyover.geometry.rails.RoadWindows.crossing_s`); its ramps do not size the
  kept one's terminal.
* A carriageway's reference line is its left (median) edge, ``median_m / 2``
  from the axis; where ramps leave or join a carriageway on its left (they run
  in the median) the median is wider by two ramp lanes and shoulders.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Mapping

import numpy as np

from flyover.geometry.chains import Continuation, continuations, ends, road_of, terminal, wrap
from flyover.geometry.settings import LayoutSettings
from flyover.topology.model import Label, Topology

__all__ = ["RoadLine", "layout_roads", "road_bands", "tee_junctions", "terminal_room",
           "CONTINUATION_GAP_M", "CONTINUATION_SIDE_M"]

#: how far short of its partner's terminal an expressway that continues it ends (m;
#: :func:`flyover.geometry.chains.continuations`): room for the ramps there to move aside
CONTINUATION_GAP_M = 40.0
#: how far left of its partner's lanes it runs, in that one's median (m)
CONTINUATION_SIDE_M = 1.0
#: a real ramp turning within this of straight on or of a U-turn (degrees, its ``turn_deg``
#: wrapped) tells no orientation (:func:`layout_roads`)
REAL_TURN_MIN_DEG = 20.0


@dataclass(frozen=True)
class RoadLine:
    """One carriageway as laid out: its reference line (median edge) and level."""

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
    #: where a T meeting a line at its own junction (:func:`tee_junctions`) meets it (x, y):
    #: the origin of its stations; ``None`` for the roads meeting at the centre
    junction: tuple[float, float] | None = None


def terminal_room(topo: Topology, level: Mapping[str, int], slopes: Mapping[str, float],
                  st: LayoutSettings, climbing: frozenset[str] = frozenset(),
                  skip: frozenset[str] = frozenset()) -> dict[str, float]:
    """The room beyond ``terminal_m`` at each expressway's terminal (expressway → m): a
    climb of one level at the lowest slope target (``slopes``: ramp → %) of the ramps
    whose chain joins a carriageway of that expressway to a road on another level
    (``level``: expressway → level) or that climb over others between two roads on one
    level (``climbing``: the planned crests of :class:`flyover.geometry.levels.LevelPlan`),
    and a grade transition; 0 where none does. The ramps of ``skip`` size nothing."""
    exp = {r: e for e, rs in topo.expressways.items() for r in rs}
    low: dict[str, float] = {}
    for ramp in topo.ramps:
        g = slopes.get(ramp, 0.0)
        ea, eb = (exp.get(road_of(topo, ramp, f)) for f in (False, True))
        if g <= 0 or ea is None or eb is None or ramp in skip or (level[ea] == level[eb]
                                                                  and ramp not in climbing):
            continue
        for e in (ea, eb):
            low[e] = min(low.get(e, g), g)
    return {e: st.level_height_m / (g / 100) + st.fit.transition_m for e, g in low.items()}


def layout_roads(topo: Topology, lanes: Mapping[str, int], st: LayoutSettings,
                 slopes: Mapping[str, float] | None = None,
                 climbing: frozenset[str] = frozenset()) -> dict[str, RoadLine]:
    """Every carriageway of ``topo`` laid out (see the module doc); ``slopes`` (ramp →
    slope target, %) and ``climbing`` size the room at a T's terminals
    (:func:`terminal_room`), none without them."""
    plan = _Placement.of(topo, lanes, st, slopes or {}, climbing)
    units = [e for e in plan.order if e not in plan.through_of and e not in plan.tees]
    base = {e: np.pi / 2 - k * np.pi / 2 for k, e in enumerate(units[:2])}
    best, best_score = None, (-1e9, -1e9)
    for flip, side in itertools.product([False, True] if len(units) > 1 else [False],
                                        [1.0, -1.0] if plan.tees else [0.0]):
        opts = dict(base)
        if flip:
            opts[units[1]] += np.pi
        roads = plan.place(plan.square(plan.spread(opts, units), side))
        # the real turns first (0 on every orientation of a topology without them)
        score = (_real_turn_score(topo, roads), _turn_side_score(topo, roads))
        if score > best_score:
            best, best_score = roads, score
    return best


def _cross_section(topo: Topology, lanes: Mapping[str, int], st: LayoutSettings,
                   conts: list[Continuation]) -> tuple[dict[str, float], dict[str, float]]:
    """Across each expressway: each carriageway's reference line (median edge) from the
    axis (carriageway → m) and the expressway's half width (expressway → m), the median
    wide enough for ramps running in it and for a continuing partner beside the lanes."""
    exps = topo.expressways
    g = topo.graph
    # ramps leaving or joining a carriageway on its left run in the median: widen it
    left = {e: any(d["label"] in (Label.OUT_L, Label.IN_L) and (u in rs or v in rs)
                   for u, v, d in g.edges(data=True)) for e, rs in exps.items()}
    wide = 2 * (st.ramp_lane_width_m + st.shoulder_width_m)
    median = {e: st.median_m + (wide if left[e] else 0.0) for e in exps}
    for c in conts:  # the through one runs in the kept one's median, beside its lanes
        room = max(lanes.get(r, st.default_lanes) for r in exps[c.through]) * st.lane_width_m
        median[c.kept] = max(median[c.kept], st.median_m + 2 * (room + CONTINUATION_SIDE_M))
    ref = {r: median[e] / 2 for e, rs in exps.items() for r in rs}  # median edge from the axis
    for c in conts:
        for r in exps[c.through]:
            ref[r] = median[c.kept] / 2 - lanes.get(r, st.default_lanes) * st.lane_width_m \
                - CONTINUATION_SIDE_M
    half = {e: max(ref[r] for r in rs) + max(lanes.get(r, st.default_lanes) for r in rs)
            * st.lane_width_m + st.shoulder_width_m for e, rs in exps.items()}
    return ref, half


def _real_turn_score(topo: Topology, roads: Mapping[str, RoadLine]) -> int:
    """How well an orientation keeps the real turns of the ramps between two roads: +1 for
    each ramp turning to the side its real one turns to, -1 for one turning to the other.
    A real turn is the ramp node's ``turn_deg`` (the OSM reader's measurement of the real
    ramp: its heading change, left positive, a loop about -270), wrapped; ramps without one
    (catalog specs, GraphML without coordinates), ramps of a chain (their own turn is not
    their chain's) and turns within :data:`REAL_TURN_MIN_DEG` of straight on or of a U-turn
    (really or as laid) count nothing."""
    score = 0
    g = topo.graph
    for ramp in topo.ramps:
        real = g.nodes[ramp].get("turn_deg")
        start, end = ends(topo, ramp)
        if real is None or start is None or end is None or start[0] not in roads \
                or end[0] not in roads or start[0] == end[0]:
            continue
        real = wrap(math.radians(float(real)))
        laid = wrap(roads[end[0]].heading - roads[start[0]].heading)
        if not _telling(real, math.radians(REAL_TURN_MIN_DEG)) or not _telling(laid, 0.2):
            continue
        score += 1 if (real > 0) == (laid > 0) else -1
    return score


def _telling(turn: float, margin: float) -> bool:
    """A turn (rad, wrapped) that is a left or a right one: more than ``margin`` from
    straight on and from a U-turn."""
    return margin < abs(turn) < np.pi - margin


def _turn_side_score(topo: Topology, roads: Mapping[str, RoadLine]) -> int:
    """How well an orientation suits the ramps between square roads: +1 for each end on
    the side its ramp turns to, -1 for a left end on a right turn."""
    score = 0
    for ramp in topo.ramps:
        a = road_of(topo, ramp, False)
        b = road_of(topo, ramp, True)
        if not a or not b:
            continue
        raw = wrap(roads[b].heading - roads[a].heading)
        if abs(abs(raw) - np.pi / 2) > 0.1:
            continue
        turn = "left" if raw > 0 else "right"
        for end in ends(topo, ramp):
            if end is None or end[1].side == "middle":
                continue
            score += 1 if end[1].side == turn else (-1 if end[1].side == "left" else 0)
    return score


@dataclass(frozen=True)
class _Placement:
    """What places the carriageways once their expressways' headings are chosen: the
    order, levels, cross sections and terminal rooms of :func:`layout_roads`."""

    topo: Topology
    st: LayoutSettings
    lanes: Mapping[str, int]
    order: list[str]
    term_of: dict[str, bool]
    conts: list[Continuation]
    tees: dict[str, Continuation]
    level: dict[str, int]
    ref: dict[str, float]
    half: dict[str, float]
    room: dict[str, float]  # beyond ``terminal_m`` at each terminal
    down: dict[str, float]  # a T at its own junction: room before it (:func:`_tee_rooms`)
    up: dict[str, float]  # and after it

    @classmethod
    def of(cls, topo: Topology, lanes: Mapping[str, int], st: LayoutSettings,
           slopes: Mapping[str, float], climbing: frozenset[str]) -> _Placement:
        exps = topo.expressways
        term_of = {e: any(terminal(topo, r) for r in rs) for e, rs in exps.items()}
        conts = continuations(topo)
        tees = tee_junctions(topo)  # T → the pair whose line it meets at a junction of its own
        kept = {c.kept for c in conts}  # a pair is placed by its kept expressway
        order = sorted(exps, key=lambda e: (term_of[e], e not in kept, e))
        ref, half = _cross_section(topo, lanes, st, conts)
        # each through expressway on its own level; the terminating ones (half lines in
        # directions of their own: they never meet) on the one above them all
        n_through = sum(not term_of[e] for e in exps)
        level = {e: (n_through if term_of[e] else k) for k, e in enumerate(order)}
        room = terminal_room(topo, level, slopes, st, climbing)
        down: dict[str, float] = {}
        up: dict[str, float] = {}
        if tees:  # a T at a junction of its own: its ramps climb there, not at the line's terminal
            exp = {r: e for e, rs in exps.items() for r in rs}
            own = frozenset(x for x in topo.ramps if tees.keys() & {
                exp.get(road_of(topo, x, f)) for f in (False, True)})
            room = terminal_room(topo, level, slopes, st, climbing, own)
            down, up = _tee_rooms(topo, tees, slopes, st, climbing)
        return cls(topo, st, lanes, order, term_of, conts, tees, level, ref, half, room, down, up)

    @property
    def through_of(self) -> dict[str, Continuation]:
        return {c.through: c for c in self.conts}

    def _other(self, e: str) -> float:
        """The widest half width of the expressways ``e`` crosses at the centre."""
        pair = {x: {c.kept, c.through} for c in self.conts for x in (c.kept, c.through)}
        exps = self.topo.expressways
        return max([self.half[x] for x in exps if x != e and x not in pair.get(e, ())] or [0.0])

    def inner(self, e: str) -> float:
        """How far from the centre (a T's own junction) along its leg ``e`` begins."""
        return self._other(e) + self.st.terminal_m + self.room.get(e, 0.0)

    def leg(self, e: str, h: float) -> float:
        """The direction from the centre in which ``e``, ending here, runs (heading ``h``)."""
        return h if terminal(self.topo, self.topo.expressways[e][0]) == "start" else h + np.pi

    def legs(self, e: str, h: float) -> list[float]:
        """The directions from the centre in which expressway ``e`` (heading ``h``) runs:
        both for a through one or a pair that continue one another, one for a T's
        terminating one (a half line)."""
        if not self.term_of[e]:
            return [h, h + np.pi]
        kept = any(c.kept == e for c in self.conts)
        return [self.leg(e, h)] + ([self.leg(e, h) + np.pi] if kept else [])

    def spread(self, opts: dict[str, float], units: list[str]) -> dict[str, float]:
        """Headings of the third and further expressways, at 45° steps: each where its
        legs are farthest from those already placed (a half line needs one free
        direction, a through expressway two opposite ones); a pair's through one
        opposite its kept one."""
        taken = [a for e in units[:2] for a in self.legs(e, opts[e])]
        for e in units[2:]:
            cands = [np.pi / 2 - j * np.pi / 4 for j in range(8)]
            gap = [min((abs(wrap(a - b)) for a in self.legs(e, h) for b in taken), default=np.pi)
                   for h in cands]
            opts[e] = cands[int(np.argmax(gap))]
            taken += self.legs(e, opts[e])
        for c in self.conts:
            b = c.through
            opts[b] = self.leg(c.kept, opts[c.kept]) + np.pi - self.leg(b, 0.0)
        return opts

    def square(self, opts: dict[str, float], side: float) -> dict[str, float]:
        """A T meeting a pair's line at its own junction: square to the kept one's leg,
        on its left (``side`` +1) or right (-1)."""
        for e, c in self.tees.items():
            a = self.leg(c.kept, opts[c.kept]) + side * np.pi / 2
            starts = terminal(self.topo, self.topo.expressways[e][0]) == "start"
            opts[e] = a if starts else a + np.pi
        return opts

    def place(self, options: dict[str, float]) -> dict[str, RoadLine]:
        """Every carriageway on its line, its expressway heading ``options[e]``."""
        topo, st = self.topo, self.st
        through_of = self.through_of
        roads = {}
        for e in self.order:
            k = self.level[e]
            inner = self.inner(e)  # from the centre along its leg
            if e in through_of and through_of[e].meets:  # on past the centre to its partner
                inner = -(self._other(e) + st.terminal_m + self.room.get(through_of[e].kept, 0.0)
                          - CONTINUATION_GAP_M)
            at, junction = np.zeros(2), None
            if e in self.tees:  # its own junction on the kept one's leg, beyond that one's terminal
                kept = self.tees[e].kept
                a = self.leg(kept, options[kept])
                at = (self.inner(kept) + inner + self.down[e]) * np.array([np.cos(a), np.sin(a)])
                junction = (float(at[0]), float(at[1]))
                inner += self.up[e]
            for i, r in enumerate(topo.expressways[e]):
                h = options[e] if i == 0 else options[e] + np.pi
                o = at + self.ref[r] * np.array([np.sin(h), -np.cos(h)])
                term = terminal(topo, r)
                t_lo, t_hi = -np.inf, np.inf
                if term == "end":
                    t_hi = -inner
                elif term == "start":
                    t_lo = inner
                n = self.lanes.get(r, st.default_lanes)
                roads[r] = RoadLine(r, e, int(n), k, k * st.level_height_m,
                                    (float(o[0]), float(o[1])), float(wrap(h)), t_lo, t_hi,
                                    self.half[e], junction)
        return roads


def _tee_rooms(topo: Topology, tees: Mapping[str, Continuation], slopes: Mapping[str, float],
               st: LayoutSettings, climbing: frozenset[str]
               ) -> tuple[dict[str, float], dict[str, float]]:
    """The room (m) a T meeting a line at a junction of its own keeps for its flyovers
    (``climbing``): between the line's terminal and the junction (``down``: one level at the
    lowest slope of those leaving it, which descend to the line there), and between the
    junction and its own terminal (``up``: one level at that slope, or two at the lowest
    slope of those into it, which fly a level higher where left turns run both ways:
    :class:`flyover.geometry.levels.LevelPlan`), each with a grade transition; 0 for none."""
    exp = {r: e for e, rs in topo.expressways.items() for r in rs}
    down, up = {}, {}
    for e in tees:
        leave = [slopes.get(x, 0.0) for x in climbing if exp.get(road_of(topo, x, False)) == e]
        into = [slopes.get(x, 0.0) for x in climbing if exp.get(road_of(topo, x, True)) == e]
        leave, into = [g for g in leave if g > 0], [g for g in into if g > 0]
        h, tr = st.level_height_m, st.fit.transition_m
        down[e] = h / (min(leave) / 100) + tr if leave else 0.0
        n = 2 if leave else 1
        up[e] = max([down[e]] + ([n * h / (min(into) / 100) + tr] if into else []))
    return down, up


def tee_junctions(topo: Topology) -> dict[str, Continuation]:
    """The expressways ending here (a T's, not one of a pair that continue one another)
    whose every ramp runs to or from the line of one such pair, each with that pair
    (:func:`flyover.geometry.chains.continuations`): such a T meets the line at a junction
    of its own, as DC's E Street Expressway meets the I-66 / Potomac Freeway line about
    330 m north of US 50, not the centre where the line crosses the other roads."""
    conts = continuations(topo)
    paired = {e: c for c in conts for e in (c.kept, c.through)}
    exp = {r: e for e, rs in topo.expressways.items() for r in rs}
    out = {}
    for e, rs in topo.expressways.items():
        if e in paired or not any(terminal(topo, r) for r in rs):
            continue
        lines = set()
        for ramp in topo.ramps:
            a, b = (exp.get(road_of(topo, ramp, f)) for f in (False, True))
            if a is None or b is None or (a == e) == (b == e):
                continue
            c = paired.get(b if a == e else a)
            lines.add(None if c is None else c.kept)
        if len(lines) == 1 and None not in lines:
            out[e] = next(c for c in conts if c.kept in lines)
    return out


def road_bands(roads: Mapping[str, RoadLine], st: LayoutSettings) -> np.ndarray:
    """The roads' driving bands as :attr:`flyover.geometry.fit.Obstacles.lines` rows
    (in ``roads`` order)."""
    rows = []
    for r in roads.values():
        d = (math.cos(r.heading), math.sin(r.heading))
        rows.append([r.origin[0], r.origin[1], d[0], d[1], max(r.t_lo, -1e5),
                     min(r.t_hi, 1e5), -r.lanes * st.lane_width_m, 0.0, r.z])
    return np.array(rows)
