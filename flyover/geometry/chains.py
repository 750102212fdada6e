"""What each ramp is, read from the topology: its ends, the roads its chain connects,
its movement (turn between those roads) and its kind (loop, stub, collector-distributor
road, connector between ramps).

Decides the *kind* of a ramp; reads the topology and the road layout (headings).

* The movement of a ramp is that of the roads its chain connects.
* A loop is a left movement that leaves its parent on the right (``Out-R``),
  unless its exit ``pos`` is below 0.4 (then it is a semi-directional flyover) and the
  real ramp, where the topology has it (``turn_deg``, measured by the OSM reader), turns
  right by no more than 180° (Bangor's ``r7`` leaves at 0.35 and really turns -267°);
  it turns 270° to the right. It is decided from the roads the chain connects,
  not from the parents' local headings: a collector-distributor road with a
  small radius wiggles.
* A stub has no end (it splits into other ramps) or no start (formed by merging).
* Two expressways that both end here *continue one another* (:func:`continuations`)
  when traffic runs from each straight on to the other: in both directions a ramp
  leaves a carriageway that ends here and joins one that begins here, with ``Out-M``
  or ``In-M`` at one end (a freeway whose name changes at a junction: DC's I-66 and
  the Potomac Freeway).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import numpy as np

from flyover.topology.model import Kind, Label, Topology

__all__ = ["wrap", "ends", "road_of", "terminal", "Continuation", "continuations", "Movements"]


def wrap(a: float) -> float:
    """An angle wrapped to -π..π."""
    return (a + np.pi) % (2 * np.pi) - np.pi


def ends(topo: Topology, ramp: str) -> tuple[tuple[str, Label] | None, tuple[str, Label] | None]:
    """``(parent, label)`` of the ramp's start (an ``Out-*`` edge) and end (``In-*``);
    read once per topology (:meth:`Topology.derived`)."""
    memo = topo.derived("ends")
    if ramp not in memo:
        g = topo.graph
        starts = sorted((u, d["label"]) for u, _, d in g.in_edges(ramp, data=True)
                        if d["label"].is_out)
        end = sorted((v, d["label"]) for _, v, d in g.out_edges(ramp, data=True)
                     if not d["label"].is_out)
        memo[ramp] = (starts[0] if starts else None), (end[0] if end else None)
    return memo[ramp]


def road_of(topo: Topology, node: str, forward: bool) -> str | None:
    """The road a chain of ramps leads to (forward) or comes from; followed once per
    topology (:meth:`Topology.derived`)."""
    memo = topo.derived("road_of")
    if (node, forward) not in memo:
        memo[node, forward] = _road_of(topo, node, forward, set())
    return memo[node, forward]


def _road_of(topo: Topology, node: str, forward: bool, seen: set[str]) -> str | None:
    if topo.graph.nodes[node]["kind"] is Kind.ROAD:
        return node
    if node in seen:
        return None
    seen.add(node)
    start, end = ends(topo, node)
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


def terminal(topo: Topology, road: str) -> str | None:
    """``end`` if the carriageway ends here (Out-M), ``start`` if it begins (In-M)."""
    g = topo.graph
    if any(d["label"] is Label.OUT_M for _, _, d in g.out_edges(road, data=True)):
        return "end"
    if any(d["label"] is Label.IN_M for _, _, d in g.in_edges(road, data=True)):
        return "start"
    return None


@dataclass(frozen=True)
class Continuation:
    """Two expressways ending here that continue one another (:func:`continuations`).

    ``kept`` keeps its terminal: it also ends into (begins from) a ramp to a third road,
    which needs the room there to climb; ``through`` runs on past the centre to it
    (``meets``), unless it too has such a ramp. ``ramps``: the ramp from ``through``
    to ``kept`` and the one from ``kept`` to ``through``."""

    kept: str
    through: str
    ramps: tuple[str, str]
    meets: bool


def continuations(topo: Topology) -> list[Continuation]:
    """The pairs of expressways ending here that continue one another on one line: in
    both directions a ramp runs from a carriageway of one that ends here to one of the
    other that begins here, straight on at one of its ends (``Out-M`` or ``In-M``)."""
    exp = {r: e for e, rs in topo.expressways.items() for r in rs}
    link: dict[tuple[str, str], str] = {}
    for ramp in sorted(topo.ramps):
        start, end = ends(topo, ramp)
        if start is None or end is None or start[0] not in exp or end[0] not in exp:
            continue
        a, b = start[0], end[0]
        if exp[a] != exp[b] and terminal(topo, a) == "end" and terminal(topo, b) == "start" \
                and (start[1] is Label.OUT_M or end[1] is Label.IN_M):
            link.setdefault((exp[a], exp[b]), ramp)

    def third(e: str, pair: set[str]) -> bool:
        """Whether ``e`` ends into (begins from) a ramp to a road outside ``pair``."""
        g = topo.graph
        for r in topo.expressways[e]:
            for _, v, d in g.out_edges(r, data=True):
                if d["label"] is Label.OUT_M and exp.get(road_of(topo, v, True)) not in pair:
                    return True
            for u, _, d in g.in_edges(r, data=True):
                if d["label"] is Label.IN_M and exp.get(road_of(topo, u, False)) not in pair:
                    return True
        return False

    out, used = [], set()
    for e, f in sorted(link):
        if e < f and (f, e) in link and not {e, f} & used:
            used |= {e, f}
            kept, through = (f, e) if third(f, {e, f}) and not third(e, {e, f}) else (e, f)
            out.append(Continuation(kept, through, (link[(through, kept)], link[(kept, through)]),
                                    not third(through, {e, f})))
    return out


class Movements:
    """The kind and movement of every ramp of ``topo`` on the laid-out ``roads``."""

    def __init__(self, topo: Topology, roads: Mapping):
        self.topo, self.roads, self.g = topo, roads, topo.graph
        self.continuing = frozenset(r for c in continuations(topo) for r in c.ramps)
        #: whether :meth:`round_by_collector` holds where it may (the build's last resort
        #: turns it off: ``build.build_interchange``)
        self.quadrant = True

    def ends(self, ramp: str):
        return ends(self.topo, ramp)

    def road_of(self, node: str, forward: bool) -> str | None:
        return road_of(self.topo, node, forward)

    def movement(self, ramp: str) -> float | None:
        """The turn between the roads the ramp's chain connects (``None`` if unknown)."""
        a, b = road_of(self.topo, ramp, False), road_of(self.topo, ramp, True)
        if not a or not b:
            return None
        return float(wrap(self.roads[b].heading - self.roads[a].heading))

    def is_loop(self, ramp: str) -> bool:
        """A left movement between the roads, leaving its parent on the right and not
        joining its road on the left (DC's ``r13``, E Street Expressway to I-66 South, leaves
        the stub ``r11`` on the right and joins I-66 on its left: a direct left turn, which
        a loop, turning right by 270°, cannot be)."""
        start, end = ends(self.topo, ramp)
        if start is None or end is None:
            return False
        if start[1] is not Label.OUT_R or end[1] is Label.IN_L:
            return False
        raw = self.movement(ramp)
        if raw is None or not (abs(raw - np.pi / 2) < 0.2):
            return False
        pos = self.g.edges[start[0], ramp].get("pos")
        return pos is None or pos >= 0.4 or self.g.nodes[ramp].get("turn_deg", 0.0) < -180.0

    def is_stub(self, ramp: str) -> bool:
        start, end = ends(self.topo, ramp)
        return start is None or end is None

    def same_road(self, ramp: str) -> bool:
        """A collector-distributor road: leaves a road and rejoins the same one."""
        start, end = ends(self.topo, ramp)
        return bool(start and end and start[0] == end[0] and start[0] in self.roads)

    def kids(self, ramp: str) -> list[str]:
        """The ramps leaving ``ramp`` or joining it (a stub's children, a C-D road's
        exits and entrances)."""
        g = self.g
        return [v for _, v, d in g.out_edges(ramp, data=True) if d["label"].is_out] + \
            [u for u, _, d in g.in_edges(ramp, data=True) if not d["label"].is_out]

    def lanes(self, ramp: str) -> int:
        """Lanes of a ramp: a stub has one per ramp it splits into (is formed from)."""
        start, end = ends(self.topo, ramp)
        if end is None:
            return max(1, sum(self.lanes(v) for _, v, d in self.g.out_edges(ramp, data=True)
                              if d["label"].is_out))
        if start is None:
            return max(1, sum(self.lanes(u) for u, _, d in self.g.in_edges(ramp, data=True)
                              if not d["label"].is_out))
        return 1

    def round_gap(self, connector: str, loop: str, lane_width_m: float) -> float:
        """Room (m) an outer connector keeps between its lane centre and its loop's centre
        line: its own lanes and half the loop's, and 1 m."""
        return (self.lanes(connector) + self.lanes(loop) / 2) * lane_width_m + 1.0

    def other_road(self, ramp: str, road: str) -> str | None:
        """The road at the other end of ``ramp``'s chain from ``road``."""
        start, _ = ends(self.topo, ramp)
        return road_of(self.topo, ramp, start is not None and start[0] == road)

    def goes_round_loop(self, ramp: str, other: str, road: str) -> bool:
        """Whether ``ramp`` and the loop ``other``, both on ``road``, join the same two
        roads the other way round: a cloverleaf's outer connector round its loop."""
        return self.is_loop(other) and not self.is_loop(ramp) and \
            self.other_road(ramp, road) == self.other_road(other, road)

    def through_stubs(self, ramp: str, forward: bool, collectors: bool = False
                      ) -> str | None:
        """The road ``ramp``'s chain reaches forward (backward) through stubs alone: the
        ramp's end (start), else that of the stub it joins (leaves), and so on (Columbus's
        loop ``r6`` comes from I-270 North through the stubs ``r13`` and ``r8``); a
        collector-distributor road it joins (leaves) counts as the road it runs beside
        (``cloverleaf_cd``'s ``oA1`` from ``cA1``, beside A1, to ``cB1``, beside B1).
        ``None`` if the chain passes any other ramp with both ends (a connector) or a
        stub with no end that way (it splits: which road is open); with ``collectors``,
        forward, a collector road (:meth:`collects`) counts as the road it collects for: a
        loop joining it goes to that road."""
        node, seen = ramp, {ramp}
        while True:
            nxt = ends(self.topo, node)[1 if forward else 0]
            if nxt is None:
                return self.collects(node) if collectors and forward and node != ramp \
                    else None
            node = nxt[0]
            if node in self.roads:
                return node
            if self.same_road(node):  # a C-D road: the carriageway it leaves and rejoins
                return ends(self.topo, node)[0][0]
            if node in seen or not self.is_stub(node):
                return None
            seen.add(node)

    def collects(self, stub: str) -> str | None:
        """The road a splitting stub collects for: the one its chain comes from through
        stubs, if one of its branches leads back onto it (Columbus's ``r13``, from I-270
        North through ``r8``, splits into ``r12``, on through ``r11`` to I-270 North, and the
        loop ``r6``; the loop ``r5`` from I-70 East joins it, a loop to I-270 North).
        ``None`` for any other ramp."""
        start, end = ends(self.topo, stub)
        if start is None or end is not None:
            return None
        back = self.through_stubs(stub, False)
        if back is None or not any(road_of(self.topo, k, True) == back
                                   for k in self.kids(stub)):
            return None
        return back

    def goes_round(self, ramp: str, loop: str, collectors: bool = False) -> bool:
        """Whether ``ramp`` is the outer connector of ``loop`` by their chains: it joins the
        two roads the loop joins the other way round, each reached directly or through
        stubs (:meth:`through_stubs`; Columbus's ``r11`` from I-70 West through the stub
        ``r1`` to I-270 North, round the loop ``r6`` from I-270 North through ``r8`` and
        ``r13`` to I-70 West; ``cloverleaf_cd``'s ``oA1`` round ``lB1``, both between
        collector-distributor roads). Unlike :meth:`goes_round_loop` it needs no road both
        attach to themselves. ``collectors``: as :meth:`through_stubs`."""
        if ramp == loop or not self.is_loop(loop) or self.is_loop(ramp):
            return False
        a, b = self.through_stubs(ramp, False), self.through_stubs(ramp, True, collectors)
        return a is not None and b is not None and a != b and (b, a) == (
            self.through_stubs(loop, False), self.through_stubs(loop, True, collectors))

    def round_by_collector(self, ramp: str, loop: str) -> bool:
        """Whether ``ramp`` is the outer connector of ``loop`` only where a loop joining a
        collector road counts as joining the road it collects for (:meth:`goes_round` with
        ``collectors``; Columbus's ``r2`` round ``r5``, which joins ``r13``): the layout
        then fits the loop first, in the corner of its quadrant
        (:meth:`flyover.geometry.quadrant.CollectorQuadrant.window`), keeps the stubs the
        connector leaves and joins beyond its reach
        (:meth:`flyover.geometry.quadrant.CollectorQuadrant.fences`) and fits the
        connector round it."""
        return self.quadrant and self.goes_round(ramp, loop, True) \
            and not self.goes_round(ramp, loop)

    def is_outer_connector(self, ramp: str, loop: str, collectors: bool = False) -> bool:
        """Whether ``ramp`` goes round the loop ``loop`` as its outer connector: on a road
        both attach to (:meth:`goes_round_loop`) or by their chains through stubs
        (:meth:`goes_round`; Columbus's ``r11`` round ``r6``). The one rule the layout
        (:meth:`flyover.geometry.loop_room.LoopRoom.round_loops`) and sampling
        (:func:`flyover.geometry.feasibility.round_loops`) share, but sampling also
        counts a loop joining a collector road (``collectors``, :meth:`collects`:
        Columbus's ``r2`` round ``r5``), which the layout fits round it with its own
        rules (:meth:`round_by_collector`)."""
        if self.goes_round(ramp, loop, collectors):
            return True
        on = [{e[0] for e in ends(self.topo, r) if e is not None and e[0] in self.roads}
              for r in (ramp, loop)]
        return any(self.goes_round_loop(ramp, loop, road) for road in sorted(on[0] & on[1]))

    def crosses_loop_exit(self, ramp: str, other: str, road: str) -> bool:
        """Whether ``ramp``, joining ``road`` after the loop ``other`` leaves it, has to pass
        over the loop's exit branch: it does unless it comes from the road the loop goes
        to (then it goes round the loop, as a cloverleaf's outer connector: a trumpet's
        ramps pass over)."""
        start, end = ends(self.topo, ramp)
        if not self.is_loop(other) or end is None or end[0] != road:
            return False
        return road_of(self.topo, ramp, False) != road_of(self.topo, other, True)
