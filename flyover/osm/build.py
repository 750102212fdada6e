"""OSM motorway network → interchanges → topologies.

Steps (each survives messy data with a logged reason):

1. **Directed segments.** Every network way becomes directed node-to-node
   segments: ``oneway=-1`` is reversed, a link tagged ``oneway=no`` is
   oriented by the flow of its neighbours, ways split into many pieces are
   joined again through their shared nodes.
2. **Snapping.** A link end that touches neither the network nor an ordinary
   road and lies within ``snap_tolerance_m`` of a carriageway is joined to it.
3. **Connectors tagged motorway.** A short ``motorway`` stretch without ``ref``
   fed only by links (or feeding only links, or forking off a carriageway), or a
   chain of them that leaves one carriageway and joins another, is treated as a link.
4. **Pruning.** Links not on a carriageway-to-carriageway path (exits to
   ordinary roads) are dropped unless ``keep_exits``.
5. **Stretches.** The network is cut at every diverge and merge; road
   stretches are chained into one-way carriageways (a road node each), link
   stretches are ramps.
6. **Labels** from geometry at each junction: a branch's side relative to its
   parent's direction of travel (right-hand traffic). A carriageway that ends
   into links: the link on the left is ``Out-M``, others ``Out-R``; one that
   begins from links: the left one ``In-M``, others ``In-R``. A ramp that
   splits becomes three ramp nodes (``Out-L``/``Out-R``). A ramp that another
   merges into keeps its node when its OSM way goes on through the merge (the
   merging ramp gets ``In-L``/``In-R``); ramps that all end at a merge feed a
   new ramp node (``In-L``/``In-R``), as in the catalog's stack.
7. **Interchanges.** Link components joining ≥ 2 corridors (by ``ref``,
   falling back to geometry), clustered by :func:`flyover.osm.cluster.cluster_link_groups`:
   sharing two corridors within ``cluster_distance_m``, or one corridor (a system
   interchange of three or more motorways) within half of it; interchanges further
   apart along one motorway stay separate.
"""

from __future__ import annotations

import gc
import logging
import math
from collections import Counter, defaultdict
from dataclasses import dataclass, field

import numpy as np

from flyover.errors import TopologyError
from flyover.osm.check import RING_MARGIN_M, self_check
from flyover.osm.cluster import cluster_link_groups
from flyover.osm.corridors import name_corridors
from flyover.osm.driving_side import driving_side_at
from flyover.osm.geom import (LocalProjection, arclength, bearing_letter, min_radius, point_at, run_beside,
                              segment_distances, signed_turn_deg, turn_deg)
from flyover.osm.reader import OsmNetwork, gc_paused, normalize_ref
from flyover.topology.model import Connection, Label, Ramp, Road, Topology
from flyover.topology.names import MAX_NAME_LENGTH, safe_name

__all__ = ["OsmOptions", "build_topologies", "interchange_name", "split_network", "place_way_ids"]

log = logging.getLogger(__name__)

ROAD, LINK = "road", "link"
_ROAD_KEYS = ("road", "local")  # topology road keys: a motorway carriageway, an ordinary road
_PROBE_M = 60.0
_TURN_BACK_DEG = 90.0  # a carriageway never turns so at one node (Stretches break there)


@dataclass(frozen=True)
class OsmOptions:
    """How an OSM extract is read (the ``osm:`` section of the config).

    Attributes
    ----------
    trunk_as_motorway
        ``highway=trunk`` / ``trunk_link`` count as motorway / motorway_link.
    keep_exits
        Keep links to ordinary roads; each ordinary road they reach becomes
        a one-carriageway road node of its own expressway.
    snap_tolerance_m
        A dangling link end this close to a carriageway is joined to it.
    cluster_distance_m
        Link groups of the same two corridors closer than this form one interchange.
    stem_length_m
        A carriageway that begins from a link (``In-M``) and receives another
        link within this distance downstream (not at the same point) is still
        the stem of a trumpet there: that link merges into the ramp that began
        the carriageway (catalog ``trumpet``), not into the carriageway.
    connector_max_length_m
        A ``motorway`` stretch without ``ref`` between links up to this long is a link.
    driving_side
        ``"auto"`` (a ``driving_side`` tag on the ways, else the country the
        extract lies in), ``"right"`` or ``"left"``. Left-hand traffic mirrors
        the labels: a left-hand interchange reads as its right-hand mirror image.
    bbox
        ``(min_lon, min_lat, max_lon, max_lat)``: only network ways with a node
        inside are read (the city's entry under ``osm.city_bbox`` in the config).
    workers
        Processes that build the places of a large extract (not in the config:
        the workflow passes its rule's threads). Results do not depend on it.
    """

    trunk_as_motorway: bool = False
    keep_exits: bool = False
    snap_tolerance_m: float = 40.0
    cluster_distance_m: float = 600.0
    stem_length_m: float = 250.0
    connector_max_length_m: float = 400.0
    driving_side: str = "auto"
    bbox: tuple[float, float, float, float] | None = None
    workers: int = 1

    @classmethod
    def from_config(cls, config: dict, city: str | None = None) -> "OsmOptions":
        """Options from ``config["osm"]``; ``city`` picks its bbox from ``osm.city_bbox``
        (a section already cut to one city may carry it as ``bbox``)."""
        sec = dict(config.get("osm") or {})
        box = (sec.get("city_bbox") or {}).get(city) if city is not None else sec.get("bbox")
        sec["bbox"] = tuple(float(v) for v in box) if box is not None else None
        if sec["bbox"] is not None and (len(sec["bbox"]) != 4 or not (
                sec["bbox"][0] < sec["bbox"][2] and sec["bbox"][1] < sec["bbox"][3])):
            from flyover.errors import ConfigError  # noqa: PLC0415
            raise ConfigError("bbox must be [min_lon, min_lat, max_lon, max_lat] with min < max",
                              element=f"osm.city_bbox.{city}" if city else "osm.bbox")
        return cls(**{k: sec[k] for k in cls.__dataclass_fields__ if k in sec})

    @property
    def highways(self) -> frozenset[str]:
        base = {"motorway", "motorway_link"}
        if self.trunk_as_motorway:
            base |= {"trunk", "trunk_link"}
        return frozenset(base)


def _cached(st: "_Stretch", key: str, compute):
    """``compute()`` once per stretch geometry (a probe point is asked for at every junction
    label; the cache is void when the stretch's xy is replaced, as when stretches are joined)."""
    hit = st.__dict__.get(key)
    if hit is None or hit[0] is not st.xy:
        hit = (st.xy, compute())
        st.__dict__[key] = hit
    return hit[1]


@dataclass
class _Stretch:
    """A run of segments between junctions, all road or all link."""

    idx: int
    nodes: list[int]
    cls: str
    ways: list[int]
    xy: np.ndarray = field(repr=False, default=None)

    @property
    def start(self) -> int:
        return self.nodes[0]

    @property
    def end(self) -> int:
        return self.nodes[-1]

    @property
    def cum(self) -> np.ndarray:
        """Arclength at each node (computed once per geometry)."""
        return _cached(self, "_cum", lambda: arclength(self.xy))

    @property
    def length(self) -> float:
        return float(self.cum[-1])


class _Network:
    """Mutable working state of one extract (segments, stretches, roads)."""

    def __init__(self, net: OsmNetwork, options: OsmOptions):
        self.src = net.source
        self.opt = options
        self.net = net
        self.quirks: list[str] = []
        self.ignored: dict[int, str] = {}  # link way id -> why it is in no interchange
        self.snapped: dict[int, float] = {}  # carriageway node a link was snapped to -> gap (m)
        lat = np.array([c[0] for c in net.coords.values()]) if net.coords else np.zeros(1)
        lon = np.array([c[1] for c in net.coords.values()]) if net.coords else np.zeros(1)
        self.proj = LocalProjection(float(lat.mean()), float(lon.mean()))
        ids = list(net.coords)
        xy = self.proj.xy([net.coords[i][0] for i in ids], [net.coords[i][1] for i in ids]) \
            if ids else np.zeros((0, 2))
        self.side = self._driving_side()
        self.mirror = 1.0
        if self.side == "left":  # left-hand traffic: read in a mirror, labels come out mirrored
            self.mirror = -1.0
            xy = xy * np.array([-1.0, 1.0])
            self.quirk("left-hand traffic: the interchange is read mirrored (labels as its "
                       "right-hand mirror image)")
        self.xy: dict[int, np.ndarray] = {i: xy[k] for k, i in enumerate(ids)}
        self.seg: dict[tuple[int, int], int] = {}   # (a, b) -> way id
        self.cls: dict[int, str] = {}                # way id -> road|link
        self.ref: dict[int, str | None] = {}
        self.succ: dict[int, list[int]] = defaultdict(list)
        self.pred: dict[int, list[int]] = defaultdict(list)
        self._next_virtual = -1

    def _driving_side(self) -> str:
        if self.opt.driving_side in ("left", "right"):
            return self.opt.driving_side
        tagged = Counter(w.tag("driving_side") for w in self.net.ways.values() if w.tag("driving_side"))
        if tagged:
            return tagged.most_common(1)[0][0]
        return driving_side_at(self.proj.lat0, self.proj.lon0)

    def unmirrored(self, xy) -> np.ndarray:
        """Map coordinates as they are on the ground (undo the left-hand-traffic mirror)."""
        return np.asarray(xy, float).reshape(-1, 2) * np.array([self.mirror, 1.0])

    def quirk(self, msg: str, level: int = logging.INFO) -> None:
        self.quirks.append(msg)
        log.log(level, "%s: %s", self.src, msg)

    # -- 1. segments ------------------------------------------------------
    def add_ways(self) -> None:
        undecided = []
        for wid in sorted(self.net.ways):
            w = self.net.ways[wid]
            hw = w.tag("highway")
            cls = LINK if hw.endswith("_link") else ROAD
            self.cls[wid] = cls
            self.ref[wid] = normalize_ref(w.tag("ref"))
            nodes = [n for n in w.nodes if n in self.xy]
            if len(nodes) < len(w.nodes):
                self.quirk(f"way {wid}: {len(w.nodes) - len(nodes)} node(s) outside the extract dropped")
            if len(nodes) < 2:
                continue
            oneway = (w.tag("oneway") or "").lower()
            if oneway == "-1":
                nodes.reverse()
                self.quirk(f"way {wid}: oneway=-1, reversed")
            elif oneway in ("no", "false", "0") or (hw == "trunk" and oneway not in ("yes", "true", "1")):
                if cls == ROAD:
                    self.quirk(f"way {wid}: two-way {hw} is not a carriageway of a dual motorway, ignored")
                    continue
                undecided.append((wid, nodes))
                continue
            self._add_chain(wid, nodes)
        for wid, nodes in undecided:
            # orient like the traffic it meets: a link leaves and joins roughly along its neighbours
            align = self._flow_alignment(nodes[0], nodes[0], nodes[1]) + \
                self._flow_alignment(nodes[-1], nodes[-2], nodes[-1])
            if align < 0:
                nodes = nodes[::-1]
            self.quirk(f"way {wid}: link tagged oneway=no, taken as one-way "
                       f"{'against' if align < 0 else 'along'} its digitised direction "
                       f"(alignment with neighbouring traffic {abs(align):.2f})")
            self._add_chain(wid, nodes)

    def _flow_alignment(self, end: int, a: int, b: int) -> float:
        """Cosine between the link's digitised direction ``a → b`` at ``end`` and the
        one-way traffic already there: +1 along, -1 against, 0 if none."""
        flows = [self.xy[end] - self.xy[p] for p in self.pred[end]] + \
                [self.xy[q] - self.xy[end] for q in self.succ[end]]
        if not flows:
            return 0.0
        mean = _unit(np.sum([_unit(f) for f in flows], axis=0))
        return float(np.dot(mean, _unit(self.xy[b] - self.xy[a])))

    def _add_chain(self, wid: int, nodes: list[int]) -> None:
        seg, succ, pred = self.seg, self.succ, self.pred
        for a, b in zip(nodes, nodes[1:]):
            if a == b or (a, b) in seg:
                continue
            seg[(a, b)] = wid
            succ[a].append(b)
            pred[b].append(a)

    def _remove_seg(self, a: int, b: int) -> None:
        del self.seg[(a, b)]
        self.succ[a].remove(b)
        self.pred[b].remove(a)

    def seg_cls(self, a: int, b: int) -> str:
        return self.cls[self.seg[(a, b)]]

    def _classes_at(self, n: int) -> tuple[set[str], set[str]]:
        return ({self.seg_cls(p, n) for p in self.pred[n]}, {self.seg_cls(n, s) for s in self.succ[n]})

    # -- 2. snapping ------------------------------------------------------
    def snap_dangling_links(self) -> None:
        road = None
        for n in sorted(self.succ.keys() | self.pred.keys()):
            deg = len(self.pred[n]) + len(self.succ[n])  # (cheap test first: most nodes are no end)
            if deg != 1:
                continue
            ins, outs = self._classes_at(n)
            if ROAD in ins | outs or n in self.net.ordinary:
                continue
            if road is None:  # (re)built only after a carriageway segment was split
                road = [(a, b) for (a, b), w in self.seg.items() if self.cls[w] == ROAD]
                pa = np.array([self.xy[a] for a, _ in road]).reshape(-1, 2)
                pb = np.array([self.xy[b] for _, b in road]).reshape(-1, 2)
            if not road:
                return
            d, t = segment_distances(self.xy[n], pa, pb)
            k = int(np.argmin(d))
            if d[k] > self.opt.snap_tolerance_m:
                continue
            a, b = road[k]
            wid_road = self.seg[(a, b)]
            if t[k] <= 1e-6 or t[k] >= 1 - 1e-6:
                v = a if t[k] <= 1e-6 else b
            else:
                v = self._next_virtual
                self._next_virtual -= 1
                self.xy[v] = pa[k] + t[k] * (pb[k] - pa[k])
                self._remove_seg(a, b)
                self._add_chain(wid_road, [a, v, b])
                road = None
            wid_link = self.seg[(self.pred[n][0], n)] if self.pred[n] else self.seg[(n, self.succ[n][0])]
            self._add_chain(wid_link, [n, v] if self.pred[n] else [v, n])
            self.snapped[v] = float(d[k])
            end = "end" if self.pred[n] and self.succ[n] == [v] else "start"
            self.quirk(f"way {wid_link}: link {end} (node {n}) is {d[k]:.1f} m short of carriageway "
                       f"way {wid_road}: snapped", logging.WARNING)

    # -- 5. stretches -----------------------------------------------------
    def _turns_back(self, n: int) -> bool:
        """Whether node ``n`` has one road segment in and one out and the road turns there by
        more than :data:`_TURN_BACK_DEG`: no carriageway does; two carriageways of a road that
        ends at grade, drawn end to start at one node (DC's US 50 stub at 23rd Street), do."""
        p, s = self.pred.get(n), self.succ.get(n)
        if not p or not s or len(p) != 1 or len(s) != 1 \
                or not self.cls[self.seg[(p[0], n)]] == ROAD == self.cls[self.seg[(n, s[0])]]:
            return False
        pa, pn, pb = self.xy[p[0]], self.xy[n], self.xy[s[0]]
        u, v = _unit(pn - pa), _unit(pb - pn)
        return float(np.dot(u, v)) < math.cos(math.radians(_TURN_BACK_DEG))

    def build_stretches(self) -> list[_Stretch]:
        out: list[_Stretch] = []
        succ, pred, seg, wcls, pos = self.succ, self.pred, self.seg, self.cls, self.xy
        breaks = set()  # a node where stretches break: not one in, one out of the same class (runs three times per place)
        for n in succ.keys() | pred.keys():
            p, s = pred.get(n), succ.get(n)
            if not p or not s or len(p) != 1 or len(s) != 1 or wcls[seg[(p[0], n)]] != wcls[seg[(n, s[0])]]:
                breaks.add(n)
            elif self._turns_back(n):
                breaks.add(n)  # one carriageway ends where the other begins (_group_roads)
        starts = sorted(n for n in breaks if succ.get(n))
        limit = len(seg) + 1
        for s0 in starts:
            for nxt in sorted(succ[s0]):
                nodes, ways = [s0, nxt], [seg[(s0, nxt)]]
                cls = wcls[ways[0]]
                b = nxt
                while b not in breaks and len(nodes) <= limit:
                    a = b
                    b = succ[a][0]
                    nodes.append(b)
                    w = seg[(a, b)]
                    if w != ways[-1]:
                        ways.append(w)
                xy = np.array([pos[i] for i in nodes])
                out.append(_Stretch(len(out), nodes, cls, ways, xy))
        return out

    # -- 3. connectors tagged motorway ------------------------------------
    def reclassify_connectors(self) -> None:
        if not any(c == ROAD and not self.ref[w] for w, c in self.cls.items()):
            return  # (only a carriageway way without ref can be a connector: most places)
        for st in self.build_stretches():
            if st.cls != ROAD or any(self.ref[w] for w in st.ways):
                continue
            if st.length > self.opt.connector_max_length_m:
                continue
            ins, _ = self._classes_at(st.start)
            _, outs = self._classes_at(st.end)
            road_outs_at_start = [s for s in self.succ[st.start] if self.seg_cls(st.start, s) == ROAD]
            road_ins_at_end = [p for p in self.pred[st.end] if self.seg_cls(p, st.end) == ROAD]
            joins_road = len(road_ins_at_end) > 1      # merges into another carriageway
            leaves_road = len(road_outs_at_start) > 1  # diverges from another carriageway
            fed_by_links = ins == {LINK} and (joins_road or outs == {LINK})
            feeds_links = outs == {LINK} and leaves_road
            others = [self.seg[(st.start, x)] for x in road_outs_at_start if x != st.nodes[1]] + \
                [self.seg[(x, st.end)] for x in road_ins_at_end if x != st.nodes[-2]]
            fork = (joins_road or leaves_road) and any(self.ref[w] for w in others)
            if fed_by_links or feeds_links or fork:
                for w in st.ways:
                    if self.cls[w] == ROAD:
                        self.cls[w] = LINK
                why = "fed by links" if fed_by_links else "feeding links" if feeds_links else "forking"
                self.quirk(f"way(s) {', '.join(map(str, st.ways))}: tagged motorway without ref, "
                           f"{st.length:.0f} m, {why}: treated as motorway_link")
        self._reclassify_crossovers()

    def _reclassify_crossovers(self) -> None:
        """A ``motorway`` chain without ref that leaves one carriageway where that one goes on
        (a diverge) and joins another where that one goes on (a merge), up to
        ``connector_max_length_m`` long, is a connector between two roads: a link (Sydney's
        Cahill Expressway → Western Distributor roadway tagged ``motorway``). The chain may pass
        nodes where only links branch off."""
        if not any(len(ss) > 1 and sum(self.seg_cls(n, x) == ROAD for x in ss) > 1 for n, ss in self.succ.items()):
            return  # (no carriageway splits without a link)
        by_start: dict[int, list[_Stretch]] = defaultdict(list)
        stretches = self.build_stretches()
        for st in stretches:
            by_start[st.start].append(st)

        def road_outs(n):
            return [s for s in self.succ[n] if self.seg_cls(n, s) == ROAD]

        def road_ins(n):
            return [p for p in self.pred[n] if self.seg_cls(p, n) == ROAD]

        for st in stretches:
            if st.cls != ROAD or len(road_outs(st.start)) < 2 or not road_ins(st.start):
                continue
            chain, length, cur = [st], st.length, st
            while len(road_ins(cur.end)) == 1 and len(road_outs(cur.end)) == 1:
                nxt = [s for s in by_start[cur.end] if s.cls == ROAD]
                if len(nxt) != 1 or nxt[0] in chain:
                    break
                cur = nxt[0]
                chain.append(cur)
                length += cur.length
                if length > self.opt.connector_max_length_m:
                    break
            ways = list(dict.fromkeys(w for c in chain for w in c.ways if self.cls[w] == ROAD))
            if (length > self.opt.connector_max_length_m or len(road_ins(cur.end)) < 2
                    or not road_outs(cur.end) or any(self.ref[w] for w in ways)):
                continue
            for w in ways:
                self.cls[w] = LINK
            self.quirk(f"way(s) {', '.join(map(str, ways))}: tagged motorway without ref, {length:.0f} m, "
                       "leaves one carriageway and joins another: treated as motorway_link")

    def extend_cut_carriageways(self) -> None:
        """A carriageway tagged ``motorway_link`` past the interchange that leaves the extract
        (Sydney's Cahill Expressway): a link chain whose free end lies at the extract edge
        (no ordinary road there) is, from that end on, a carriageway while its ways carry
        the name of a motorway carriageway of the network and run straight (turn < 90°)."""
        names = {self.net.ways[w].tag("name") for w, c in self.cls.items() if c == ROAD} - {None}
        if not any(c == LINK and self.net.ways[w].tag("name") in names for w, c in self.cls.items()):
            return  # (no link is named like a carriageway)
        for st in self.build_stretches():
            if st.cls != LINK:
                continue
            for free, order in ((st.start, st.ways), (st.end, st.ways[::-1])):
                if self.pred[free] if free == st.start else self.succ[free]:
                    continue
                if free in self.net.ordinary:
                    continue
                changed = []
                for w in order:
                    way = self.net.ways[w]
                    if way.tag("name") not in names or _turn_deg(self, way.nodes) >= 90.0:
                        break
                    self.cls[w] = ROAD
                    changed.append(w)
                if changed:
                    self.quirk(f"link way(s) {', '.join(map(str, changed))} named like a carriageway "
                               f"({self.net.ways[changed[0]].tag('name')}) leave the extract: read as "
                               "that carriageway")

    def note_dead_ends(self) -> None:
        """The nodes where the network as read (before pruning) begins or ends: nothing comes
        in (``dead_in``) or goes on (``dead_out``); a motorway that ends there ends on the map
        (at ordinary roads or the extract's edge), not into links. For the self-check."""
        self.dead_in = {n for n, s in self.succ.items() if s and not self.pred.get(n)}
        self.dead_out = {n for n, p in self.pred.items() if p and not self.succ.get(n)}
        back = {n for n in self.pred if self._turns_back(n)}
        self.dead_in |= back  # one carriageway ends there, the other begins (build_stretches)
        self.dead_out |= back

    # -- 4. pruning -------------------------------------------------------
    def prune_links(self) -> None:
        on_road = {n for (a, b), w in self.seg.items() if self.cls[w] == ROAD for n in (a, b)}
        link = [(a, b) for (a, b), w in self.seg.items() if self.cls[w] == LINK]
        fwd_adj, bwd_adj = defaultdict(list), defaultdict(list)
        for a, b in link:
            fwd_adj[a].append(b)
            bwd_adj[b].append(a)

        def reach(adj):  # (the search starts only from road nodes where links are)
            seen, stack = set(on_road), [n for n in on_road if n in adj]
            while stack:
                for m in adj[stack.pop()]:
                    if m not in seen:
                        seen.add(m)
                        stack.append(m)
            return seen

        fwd, bwd = reach(fwd_adj), reach(bwd_adj)
        dropped = sorted({self.seg[(a, b)] for a, b in link if not (a in fwd and b in bwd)})
        for a, b in link:
            if not (a in fwd and b in bwd):
                self._remove_seg(a, b)
        for w in dropped:
            self.ignored.setdefault(w, "exit to an ordinary road or cut at the extract edge")
        if dropped:
            self.quirk(f"link way(s) {', '.join(map(str, dropped))} not between carriageways "
                       "(exits to ordinary roads or cut at the extract edge): ignored")


# -- roads, labels, interchanges ------------------------------------------------

@dataclass
class _RoadGroup:
    """A one-way carriageway: a chain of road stretches."""

    gid: int
    stretches: list[int]
    xy: np.ndarray
    s_of: dict[int, float]
    corridor: str | None
    ways: list[int]


def _turn_deg(nw: "_Network", nodes) -> float:
    """Total heading change along a way's nodes (degrees, absolute)."""
    return turn_deg([nw.xy[n] for n in nodes if n in nw.xy])


def _unit(v: np.ndarray) -> np.ndarray:
    n = float(np.hypot(*v))
    return v / n if n > 0 else v


def _cross(a: np.ndarray, b: np.ndarray) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


class _Builder:
    def __init__(self, nw: _Network):
        self.nw = nw
        self.st = nw.build_stretches()
        self.ends: dict[int, list[_Stretch]] = defaultdict(list)
        self.starts: dict[int, list[_Stretch]] = defaultdict(list)
        for s in self.st:
            self.ends[s.end].append(s)
            self.starts[s.start].append(s)
        self.groups: list[_RoadGroup] = []
        self.group_of: dict[int, int] = {}
        self.continuations: list[tuple[int, int]] = []  # (ramp, its continuation past a merge)
        self._group_roads()

    # -- carriageways -----------------------------------------------------
    def _stretch_ref(self, s: _Stretch) -> str | None:
        refs = [self.nw.ref[w] for w in s.ways if self.nw.ref[w]]
        return refs[0] if refs else None

    def _ref_match(self, a: _Stretch, b: _Stretch) -> int:
        """2: same ref; 1: a ref missing, or routes in common (concurrency ``I 81;US 322``
        beside ``I 81``); 0: different routes."""
        ra, rb = self._stretch_ref(a), self._stretch_ref(b)
        if ra is None or rb is None:
            return 1
        if ra == rb:
            return 2
        return 1 if set(ra.split(";")) & set(rb.split(";")) else 0

    def _group_roads(self) -> None:
        nxt: dict[int, int] = {}
        prv: dict[int, int] = {}
        nodes = sorted(set(self.ends) | set(self.starts))
        for n in nodes:
            ins = [s for s in self.ends[n] if s.cls == ROAD]
            outs = [s for s in self.starts[n] if s.cls == ROAD]
            if not ins or not outs:
                continue
            # carriageways go on by continuity: the best ref match first, then the straightest;
            # a ref change on a plain continuation (one in, one out) still goes on
            scored = []
            for i in ins:
                d_in = _unit(i.xy[-1] - i.xy[-2])
                for o in outs:
                    match = self._ref_match(i, o)
                    if match == 0 and not (len(ins) == 1 and len(outs) == 1):
                        continue
                    align = float(np.dot(d_in, _unit(o.xy[1] - o.xy[0])))
                    if align < math.cos(math.radians(_TURN_BACK_DEG)):
                        continue  # it turns back: another carriageway (Stretches break here)
                    scored.append((-match, -align, i.idx, o.idx))
            for _, _, i, o in sorted(scored):
                if i not in nxt and o not in prv:
                    nxt[i], prv[o] = o, i
            if len(outs) > 1 or len(ins) > 1:
                unpaired = [s.idx for s in outs if s.idx not in prv] + [s.idx for s in ins if s.idx not in nxt]
                if unpaired:
                    self.nw.quirk(f"node {n}: carriageways meet without a link (stretches {unpaired}): "
                                  "joined by a direct ramp")
        seen: set[int] = set()
        road_idx = [s.idx for s in self.st if s.cls == ROAD]
        heads = [i for i in road_idx if i not in prv] + road_idx  # cycles last
        for h in heads:
            if h in seen:
                continue
            chain, cur = [], h
            while cur is not None and cur not in seen:
                seen.add(cur)
                chain.append(cur)
                cur = nxt.get(cur)
            xy = np.concatenate([self.st[chain[0]].xy] + [self.st[c].xy[1:] for c in chain[1:]])
            nodes = self.st[chain[0]].nodes + [n for c in chain[1:] for n in self.st[c].nodes[1:]]
            cum = arclength(xy)
            s_of = {n: float(s) for n, s in zip(nodes, cum)}
            lengths = Counter()
            ways = []
            for c in chain:
                st = self.st[c]
                for w in st.ways:
                    ways.append(w)
                    if self.nw.ref[w]:
                        lengths[self.nw.ref[w]] += st.length / len(st.ways)
            corridor = lengths.most_common(1)[0][0] if lengths else None
            g = _RoadGroup(len(self.groups), chain, xy, s_of, corridor, list(dict.fromkeys(ways)))
            self.groups.append(g)
            for c in chain:
                self.group_of[c] = g.gid
        name_corridors(self)

    # -- junction labels ----------------------------------------------------
    def _probe_out(self, s: _Stretch) -> np.ndarray:
        if s.start in self.nw.snapped and len(s.xy) > 1:
            return s.xy[1]  # the link's real start: which side of the carriageway it lies on
        return _cached(s, "_probe_out", lambda: point_at(s.xy, min(_PROBE_M, 0.5 * s.length), s.cum))

    def _probe_in(self, s: _Stretch) -> np.ndarray:
        if s.end in self.nw.snapped and len(s.xy) > 1:
            return s.xy[-2]
        return _cached(s, "_probe_in", lambda: point_at(s.xy[::-1], min(_PROBE_M, 0.5 * s.length)))

    def _lanes(self, gid: int) -> int:
        vals = [self.nw.net.ways[w].tag("lanes") for w in self.groups[gid].ways]
        vals = [int(v) for v in vals if v and v.isdigit()]
        return max(vals) if vals else 0

    def _direct_edges(self, n: int, ri: list[_Stretch], ro: list[_Stretch]) -> list:
        """Carriageways meeting without a link: a carriageway that begins at a diverge (ends at
        a merge) of another is joined to it by a ramp ``("direct", n)`` (its geometry: the branch
        where it runs beside the through carriageway, :func:`_direct_ramp_line`): the
        through carriageway ``Out-R``/``Out-L`` → ramp → ``In-M`` the branch (branch ``Out-M``
        → ramp → ``In-R``/``In-L`` the through carriageway)."""
        p = self.nw.xy[n]
        edges = []
        through = [(i, o) for i in ri for o in ro if self.group_of[i.idx] == self.group_of[o.idx]]
        ramp = ("direct", n)
        if not through and len(ro) >= 2 and not ri or len(ri) >= 2 and not ro:
            # carriageways split (merge) right at the extract edge: the main one goes on
            group = ro or ri
            main = max(group, key=lambda s: (self._lanes(self.group_of[s.idx]),
                                              len(self.groups[self.group_of[s.idx]].xy) and
                                              float(arclength(self.groups[self.group_of[s.idx]].xy)[-1]), -s.idx))
            g = ("road", self.group_of[main.idx])
            b = next(s for s in group if s is not main)
            if ro:
                d = _unit(self._probe_out(main) - p)
                side = "left" if _cross(d, _unit(self._probe_out(b) - p)) > 0 else "right"
                edges += [(g, ramp, Label.of(True, side), n), (ramp, ("road", self.group_of[b.idx]), Label.IN_M, n)]
            else:
                d = _unit(p - self._probe_in(main))
                side = "left" if _cross(d, _unit(self._probe_in(b) - p)) > 0 else "right"
                edges += [(("road", self.group_of[b.idx]), ramp, Label.OUT_M, n), (ramp, g, Label.of(False, side), n)]
            self.nw.quirk(f"node {n}: carriageways split or merge at the extract edge: "
                          f"way {b.ways[0]} joined to way {main.ways[0]} by a direct ramp")
            return edges
        if not through:
            return edges
        i, o = through[0]
        g = ("road", self.group_of[i.idx])
        branches_out = [s for s in ro if s is not o]
        branches_in = [s for s in ri if s is not i]
        if branches_out:
            d_out = _unit(p - self._probe_in(i))
            ref = _cross(d_out, _unit(self._probe_out(o) - p))
            b = branches_out[0]
            side = "left" if _cross(d_out, _unit(self._probe_out(b) - p)) > ref else "right"
            edges += [(g, ramp, Label.of(True, side), n), (ramp, ("road", self.group_of[b.idx]), Label.IN_M, n)]
        elif branches_in:
            d_in = _unit(self._probe_out(o) - p)
            ref = _cross(d_in, _unit(self._probe_in(i) - p))
            b = branches_in[0]
            side = "left" if _cross(d_in, _unit(self._probe_in(b) - p)) > ref else "right"
            edges += [(("road", self.group_of[b.idx]), ramp, Label.OUT_M, n), (ramp, g, Label.of(False, side), n)]
        return edges

    def junction_edges(self, n: int) -> list[tuple[tuple[str, int], tuple[str, int], Label, int]]:
        """Edges (source key, target key, label, junction node) at node ``n``."""
        ins, outs = self.ends[n], self.starts[n]
        ri = [s for s in ins if s.cls == ROAD]
        ro = [s for s in outs if s.cls == ROAD]
        li = [s for s in ins if s.cls == LINK]
        lo = [s for s in outs if s.cls == LINK]
        p = self.nw.xy[n]
        edges = []
        if not li and not lo:
            return self._direct_edges(n, ri, ro)

        def lateral_out(d_ref, s):
            return _cross(d_ref, _unit(self._probe_out(s) - p))

        def lateral_in(d_ref, s):
            return _cross(d_ref, _unit(self._probe_in(s) - p))

        through = [(i, o) for i in ri for o in ro if self.group_of[i.idx] == self.group_of[o.idx]]
        if through:
            i, o = through[0]
            g = ("road", self.group_of[i.idx])
            d_out = _unit(p - self._probe_in(i))
            d_in = _unit(self._probe_out(o) - p)
            ref_out, ref_in = lateral_out(d_out, o), lateral_in(d_in, i)
            for s in lo:
                side = "left" if lateral_out(d_out, s) > ref_out else "right"
                edges.append((g, ("ramp", s.idx), Label.of(True, side), n))
            for s in li:
                side = "left" if lateral_in(d_in, s) > ref_in else "right"
                edges.append((("ramp", s.idx), g, Label.of(False, side), n))
            return edges
        if ri and lo:
            g = ("road", self.group_of[ri[0].idx])
            d_out = _unit(p - self._probe_in(ri[0]))
            ranked = sorted(lo, key=lambda s: -lateral_out(d_out, s))
            for k, s in enumerate(ranked):
                edges.append((g, ("ramp", s.idx), Label.OUT_M if k == 0 else Label.OUT_R, n))
        if ro and li:
            g = ("road", self.group_of[ro[0].idx])
            d_in = _unit(self._probe_out(ro[0]) - p)
            ranked = sorted(li, key=lambda s: -lateral_in(d_in, s))
            for k, s in enumerate(ranked):
                edges.append((("ramp", s.idx), g, Label.IN_M if k == 0 else Label.IN_R, n))
        if ro and lo and not ri:  # carriageway cut at the extract edge right at a diverge
            g = ("road", self.group_of[ro[0].idx])
            d_out = _unit(self._probe_out(ro[0]) - p)
            for s in lo:
                side = "left" if lateral_out(d_out, s) > lateral_out(d_out, ro[0]) else "right"
                edges.append((g, ("ramp", s.idx), Label.of(True, side), n))
            self.nw.quirk(f"node {n}: carriageway begins at the extract edge where a link leaves it")
        if ri and li and not ro:  # carriageway cut at the extract edge right at a merge
            g = ("road", self.group_of[ri[0].idx])
            d_in = _unit(p - self._probe_in(ri[0]))
            for s in li:
                side = "left" if lateral_in(d_in, s) > lateral_in(d_in, ri[0]) else "right"
                edges.append((("ramp", s.idx), g, Label.of(False, side), n))
            self.nw.quirk(f"node {n}: carriageway ends at the extract edge where a link joins it")
        if ri or ro:
            return edges
        # links only: splits, merges, or both (through a junction ramp)
        if len(li) == 1 and len(lo) == 1:
            return [(("ramp", li[0].idx), ("ramp", lo[0].idx), Label.OUT_M, n)]  # not expected
        parent = ("ramp", li[0].idx) if len(li) == 1 else ("junction", n)
        child = ("ramp", lo[0].idx) if len(lo) == 1 else ("junction", n)
        if len(lo) >= 2:
            base = li[0] if len(li) == 1 else None
            d_out = _unit(p - self._probe_in(base)) if base is not None else \
                _unit(np.mean([_unit(self._probe_out(s) - p) for s in lo], axis=0))
            ranked = sorted(lo, key=lambda s: -lateral_out(d_out, s))
            for k, s in enumerate(ranked):
                edges.append((parent, ("ramp", s.idx), Label.OUT_L if k == 0 else Label.OUT_R, n))
        if len(li) >= 2:
            base = lo[0] if len(lo) == 1 else None
            d_in = _unit(self._probe_out(base) - p) if base is not None else \
                _unit(np.mean([_unit(p - self._probe_in(s)) for s in li], axis=0))
            main = [s for s in li if base is not None and s.ways[-1] == base.ways[0]]
            if len(main) == 1:  # a ramp merged into: its way goes on, it keeps its node
                self.continuations.append((main[0].idx, base.idx))
                ref = lateral_in(d_in, main[0])
                for s in li:
                    if s is not main[0]:
                        side = "left" if lateral_in(d_in, s) > ref else "right"
                        edges.append((("ramp", s.idx), child, Label.of(False, side), n))
                return edges
            ranked = sorted(li, key=lambda s: -lateral_in(d_in, s))
            for k, s in enumerate(ranked):
                edges.append((("ramp", s.idx), child, Label.IN_L if k == 0 else Label.IN_R, n))
        if len(li) >= 2 and len(lo) >= 2:
            self.nw.quirk(f"node {n}: links merge and split at one point: a junction ramp is added")
        return edges


def _components(keys: list, pairs: list[tuple]) -> list[list]:
    parent = {k: k for k in keys}

    def find(k):
        while parent[k] != k:
            parent[k] = parent[parent[k]]
            k = parent[k]
        return k

    for a, b in pairs:
        ra, rb = find(a), find(b)
        if ra != rb:
            parent[max(ra, rb, key=str)] = min(ra, rb, key=str)
    out = defaultdict(list)
    for k in keys:
        out[find(k)].append(k)
    return [sorted(v, key=str) for _, v in sorted(out.items(), key=lambda kv: str(kv[0]))]


def _stem_merges(nw: _Network, b: _Builder, edges: list) -> list:
    """Links merging onto a trumpet stem that OSM tags as the carriageway (see ``stem_length_m``)."""
    out = list(edges)
    for src, dst, label, n0 in edges:
        if label is not Label.IN_M:
            continue
        grp = b.groups[dst[1]]
        s0 = grp.s_of[n0]
        diverges = [grp.s_of[e[3]] for e in edges if e[0] == dst and e[2].is_out]
        for k, e in enumerate(out):
            if e[1] != dst or e[2] in (Label.IN_M,) or e[3] == n0:
                continue
            ds = grp.s_of[e[3]] - s0
            if 0 < ds <= nw.opt.stem_length_m and not any(s0 < s <= grp.s_of[e[3]] for s in diverges):
                out[k] = (e[0], src, e[2], e[3])
                nw.quirk(f"node {e[3]}: link merges {ds:.0f} m after the carriageway began from a link "
                         "(node {n0}): merged into that ramp (trumpet stem)".replace("{n0}", str(n0)))
    return out


def _join_continuations(b: _Builder, edges: list) -> list:
    """A ramp merged into keeps one node: join it with its stretch past the merge."""
    rep: dict[int, int] = {}

    def find(i):
        while i in rep:
            i = rep[i]
        return i

    for main, nxt in b.continuations:
        m, tail = b.st[find(main)], b.st[nxt]
        m.nodes = m.nodes + tail.nodes[1:]
        m.xy = np.concatenate([m.xy, tail.xy[1:]])
        m.ways = m.ways + [w for k, w in enumerate(tail.ways) if k or w != m.ways[-1]]
        rep[nxt] = m.idx

    def key(k):
        return ("ramp", find(k[1])) if k[0] == "ramp" else k

    return [(key(u), key(v), lab, n) for u, v, lab, n in edges]


def _exit_edges(nw: _Network, b: _Builder) -> list:
    """With ``keep_exits``: a link ending (beginning) off the network ends in (begins from)
    an ordinary road of its own, ``In-M`` (``Out-M``)."""
    out = []
    for s in b.st:
        if s.cls != LINK:
            continue
        if not b.starts[s.end] and len(b.ends[s.end]) == 1:
            out.append((("ramp", s.idx), ("local", s.end), Label.IN_M, s.end))
        if not b.ends[s.start] and len(b.starts[s.start]) == 1:
            out.append((("local", s.start), ("ramp", s.idx), Label.OUT_M, s.start))
    return out


def _compact(ref: str) -> str:
    return "".join(ch for ch in ref.replace(";", "-") if ch.isalnum() or ch == "-")


def interchange_name(corridors: list[str], first_node: int) -> tuple[str, dict]:
    """The interchange's name ``{refs}_{first OSM node id}`` as a safe name, and what it
    was made from (corridor ref → its part of the name; the OSM node).

    Refs are data (``"I 70;US 40"``, ``"A 1/E 20"``, any script): each becomes a safe
    part by :func:`flyover.topology.names.safe_name` (``;`` and other unsafe
    characters → ``-``); a name longer than the limit is cut and ends in a hash.

    >>> interchange_name(["I70;US40", "A1/E20"], 42)
    ('I70-US40_A1-E20_42', {'refs': {'I70;US40': 'I70-US40', 'A1/E20': 'A1-E20'}, 'osm_node': 42})
    """
    parts = {c: safe_name(c, max_length=40) for c in corridors}
    name = safe_name("_".join(parts.values()) + f"_{first_node}", max_length=MAX_NAME_LENGTH)
    return name, {"refs": parts, "osm_node": first_node}


def build_topologies(net: OsmNetwork, options: OsmOptions, workers: int = 1) -> list[Topology]:
    """Every motorway-to-motorway interchange of ``net`` as a topology.

    An interchange that breaks a model rule is logged and left out; the
    others are still returned.

    The network is read place by place (:func:`split_network`); ``workers`` > 1
    reads places in that many forked processes (same result, in the same order).

    Raises
    ------
    TopologyError
        Every interchange found breaks a model rule (the first one's reason).
    """
    out, failed = [], []
    with gc_paused():
        places = place_way_ids(net, options)
    if workers > 1 and len(places) > 1:
        import multiprocessing  # noqa: PLC0415

        global _PLACES  # noqa: PLW0603 (inherited by the forked workers, not pickled to them)
        _PLACES = (net, places, options)
        # the workers inherit the whole network: frozen, their garbage collector does not walk
        # it again and again (that made the build grow faster than the extract); the parent
        # only collects results meanwhile. Each worker cuts its places out of the network.
        gc.freeze()
        try:
            with gc_paused(), multiprocessing.get_context("fork").Pool(workers, initializer=gc.enable) as pool:
                results = pool.map(_build_inherited_place, range(len(places)),
                                   chunksize=max(1, len(places) // (32 * workers)))
        finally:
            _PLACES = None
            gc.unfreeze()
    else:
        # the network read so far is not garbage: frozen, the collector's passes while building
        # do not walk it again and again (as in the forked workers)
        gc.freeze()
        try:
            results = [_build_part_safe(_place(net, ids) if len(places) > 1 else net, options)
                       for ids in places]
        finally:
            gc.unfreeze()
    for found, exc in results:
        out += found
        if exc is not None:
            failed.append(exc)
    if failed and not out:  # nothing usable: the file is rejected with the first reason
        raise failed[0]
    names = Counter(t.name for t in out)
    for name in sorted(n for n, k in names.items() if k > 1):
        log.warning("%s: duplicate interchange name %s", net.source, name)
    return sorted(out, key=lambda t: t.name)


#: how far (m) beyond its first and last junction a carriageway is kept for the self-check
_CHECK_REACH_M = 1500.0

#: parts of a network closer than this (m) are read together (snapping, opposite carriageways)
_PART_GAP_M = 250.0


def split_network(net: OsmNetwork, options: OsmOptions) -> list[OsmNetwork]:
    """The network cut into places read independently: ways connected through shared
    nodes, joined when their bounding boxes come within ``_PART_GAP_M`` (plus the snap
    tolerance). A metro extract is read place by place, so the work grows with its size.

    Parameters
    ----------
    net
        The network of one extract.
    options
        Its options (the snap tolerance widens the gap between places).

    Returns
    -------
    list of OsmNetwork
        One network per place (``[net]`` itself when it is one place), in the order of
        their least way id.
    """
    places = place_way_ids(net, options)
    return [_place(net, ids) for ids in places] if len(places) > 1 else [net]


def place_way_ids(net: OsmNetwork, options: OsmOptions) -> list[list[int]]:
    """The way ids of each place of :func:`split_network` (each sorted), in the order of their
    least way id, without cutting the network (the places are cut where they are built)."""
    ids = sorted(net.ways)
    if len(ids) < 2:
        return [ids]
    parent = list(range(len(ids)))

    def find(k):
        while parent[k] != k:
            parent[k] = parent[parent[k]]
            k = parent[k]
        return k

    first_way: dict[int, int] = {}
    for k, wid in enumerate(ids):
        for n in net.ways[wid].nodes:
            j = first_way.setdefault(n, k)
            if j != k:
                ra, rb = find(j), find(k)
                if ra != rb:
                    parent[max(ra, rb)] = min(ra, rb)
    groups: dict[int, list[int]] = defaultdict(list)
    for k in range(len(ids)):
        groups[find(k)].append(k)
    roots = sorted(groups)
    boxes = np.full((len(roots), 4), np.nan)
    for r, root in enumerate(roots):
        pts = np.array([net.coords[n] for k in groups[root] for n in net.ways[ids[k]].nodes
                        if n in net.coords]).reshape(-1, 2)
        if len(pts):
            boxes[r] = [pts[:, 0].min(), pts[:, 1].min(), pts[:, 0].max(), pts[:, 1].max()]
    gap_deg = (_PART_GAP_M + options.snap_tolerance_m) / 111_000.0
    lat = np.nan_to_num(np.abs(boxes[:, [0, 2]]).max(axis=1), nan=0.0)
    gap_lon = gap_deg / np.maximum(np.cos(np.radians(np.minimum(lat, 89.0))), 1e-3)
    merge = list(range(len(roots)))

    def find_part(k):
        while merge[k] != k:
            merge[k] = merge[merge[k]]
            k = merge[k]
        return k

    order = np.argsort(np.nan_to_num(boxes[:, 0], nan=1e9))
    active: list[int] = []  # sweep along latitude: only boxes overlapping in latitude are compared
    for r in order:
        if np.isnan(boxes[r, 0]):
            continue
        active = [a for a in active if boxes[a, 2] + gap_deg >= boxes[r, 0]]
        for a in active:
            g = max(gap_lon[a], gap_lon[r])
            if boxes[a, 1] - g <= boxes[r, 3] and boxes[r, 1] - g <= boxes[a, 3]:
                ra, rb = find_part(a), find_part(r)
                if ra != rb:
                    merge[max(ra, rb)] = min(ra, rb)
        active.append(int(r))
    parts: dict[int, list[int]] = defaultdict(list)
    for r, root in enumerate(roots):
        parts[find_part(r)].extend(groups[root])
    return [sorted(ids[k] for k in parts[key]) for key in sorted(parts)]


def _place(net: OsmNetwork, way_ids: list[int]) -> OsmNetwork:
    """The network of one place: its ways, and the coordinates, ele and ordinary roads of
    their nodes (in node id order)."""
    sub = OsmNetwork(source=net.source, ways={w: net.ways[w] for w in way_ids})
    nodes = {n for w in way_ids for n in net.ways[w].nodes}
    sub.coords = {n: net.coords[n] for n in sorted(nodes) if n in net.coords}
    sub.elevation = {n: net.elevation[n] for n in sub.coords if n in net.elevation}
    sub.ordinary = {n: net.ordinary[n] for n in sub.coords if n in net.ordinary}
    return sub


#: (network, way ids of each place, options) while forked workers build the places
_PLACES: tuple[OsmNetwork, list[list[int]], OsmOptions] | None = None


def _build_inherited_place(k: int) -> tuple[list[Topology], TopologyError | None]:
    net, places, options = _PLACES
    return _build_part_safe(_place(net, places[k]) if len(places) > 1 else net, options)


def _build_part_safe(net: OsmNetwork, options: OsmOptions) -> tuple[list[Topology], TopologyError | None]:
    try:
        return _build_part(net, options), None
    except TopologyError as exc:
        return [], exc


def _build_part(net: OsmNetwork, options: OsmOptions) -> list[Topology]:
    nw = _Network(net, options)
    nw.add_ways()
    nw.snap_dangling_links()
    nw.extend_cut_carriageways()
    nw.reclassify_connectors()
    nw.note_dead_ends()
    if not options.keep_exits:
        nw.prune_links()
    b = _Builder(nw)
    edges = [e for n in sorted(set(b.ends) | set(b.starts)) for e in b.junction_edges(n)]
    edges = _stem_merges(nw, b, edges)
    if options.keep_exits:
        edges += _exit_edges(nw, b)
    edges = _join_continuations(b, edges)
    ramp_keys = sorted({k for e in edges for k in e[:2] if k[0] not in _ROAD_KEYS}, key=str)
    pairs = [(e[0], e[1]) for e in edges if e[0][0] not in _ROAD_KEYS and e[1][0] not in _ROAD_KEYS]
    comps = _components(ramp_keys, pairs)
    comp_of = {k: ci for ci, comp in enumerate(comps) for k in comp}
    comp_edges: dict[int, list] = defaultdict(list)
    for e in edges:
        k = e[0] if e[0][0] not in _ROAD_KEYS else e[1]
        comp_edges[comp_of[k]].append(e)

    corridor_sets = [{b.groups[k[1]].corridor for e in comp_edges[ci] for k in e[:2] if k[0] == "road"}
                     for ci in range(len(comps))]
    point_sets: dict[int, np.ndarray] = {}
    group_sets = [{k[1] for e in comp_edges[ci] for k in e[:2] if k[0] == "road"} for ci in range(len(comps))]

    def groups(ci):
        return group_sets[ci]

    def corridors(ci):
        return corridor_sets[ci]

    def points(ci):
        if ci not in point_sets:
            point_sets[ci] = np.array([nw.xy[e[3]] for e in comp_edges[ci]] +
                                      [p for k in comps[ci] if k[0] == "ramp" for p in b.st[k[1]].xy])
        return point_sets[ci]

    multi = [ci for ci in range(len(comps)) if len(corridors(ci)) >= 2]
    attached: dict[int, list[int]] = defaultdict(list)
    if options.keep_exits:  # an exit joins the nearest interchange on its corridor
        for ci in range(len(comps)):
            if ci in multi or not corridors(ci):
                continue
            near = [(float(np.sqrt(((points(ci)[:, None] - points(cj)[None]) ** 2).sum(-1)).min()), cj)
                    for cj in multi if corridors(ci) <= corridors(cj)]
            near = [x for x in near if x[0] <= options.cluster_distance_m]
            if near:
                attached[min(near)[1]].append(ci)
    for ci in range(len(comps)):
        if ci not in multi and not any(ci in v for v in attached.values()):
            ways = sorted({w for k in comps[ci] if k[0] == "ramp" for w in b.st[k[1]].ways})
            for w in ways:
                nw.ignored.setdefault(w, f"joins only corridor {sorted(map(str, corridors(ci)))}")
            nw.quirk(f"link way(s) {ways} join only corridor {sorted(map(str, corridors(ci)))}: "
                     "not a motorway-to-motorway interchange")
    clusters = [[multi[k] for k in cl] for cl in cluster_link_groups(
        [corridors(ci) for ci in multi], [groups(ci) for ci in multi], [points(ci) for ci in multi],
        options.cluster_distance_m)]
    out, failed = [], []
    for cl in clusters:
        cl_edges = [e for ci in cl for cj in [ci, *attached[ci]] for e in comp_edges[cj]]
        try:
            t = _topology(nw, b, cl_edges)
            t.attrs["osm"]["self_check"] = self_check(t)
            for row in t.attrs["osm"]["self_check"]:
                log.warning("%s: %s: self-check %s: %s", nw.src, t.name, row["check"], row["detail"])
            out.append(t)
        except TopologyError as exc:
            exc.located(nw.src)
            failed.append(exc)
            log.warning("interchange rejected: %s", exc.one_line())
    if failed and not out:
        raise failed[0]
    return out


#: a carriageway splitting from (merging into) another without a link: its ramp is where it
#: runs within this distance (m) of the other, at most ``_DIRECT_MAX_M`` long
_DIRECT_SEPARATION_M = 10.0
_DIRECT_MAX_M = 300.0


def _direct_ramp_line(b: _Builder, edges: list, key: tuple) -> np.ndarray:
    """The geometry of a ramp ``("direct", node)`` (a carriageway splitting from or merging into
    another without a link), in the direction of travel: the branch carriageway from (to) the
    junction while it runs beside the through one (:func:`flyover.osm.geom.run_beside`)."""
    n = key[1]
    ends = [(e[0] if e[1] == key else e[1], e[2]) for e in edges if key in e[:2]]
    branch = next((r for r, lab in ends if lab in (Label.IN_M, Label.OUT_M) and r[0] == "road"), None)
    through = next((r for r, lab in ends if r != branch and r[0] == "road"), None)
    if branch is None or through is None:
        return b.nw.xy[n].reshape(1, 2)
    grp, other = b.groups[branch[1]], b.groups[through[1]].xy
    k = int(np.searchsorted(arclength(grp.xy), grp.s_of[n] - 1e-6))
    splits = any(e[0] == through and e[1] == key for e in edges)
    if splits:  # the branch from the junction on
        return run_beside(grp.xy[k:], other, _DIRECT_SEPARATION_M, _DIRECT_MAX_M)
    return run_beside(grp.xy[:k + 1][::-1], other, _DIRECT_SEPARATION_M, _DIRECT_MAX_M)[::-1]


def _topology(nw: _Network, b: _Builder, edges: list) -> Topology:
    net = nw.net
    road_gids = sorted({k[1] for e in edges for k in e[:2] if k[0] == "road"})
    local_nodes = sorted({k[1] for e in edges for k in e[:2] if k[0] == "local"})
    ramp_keys = sorted({k for e in edges for k in e[:2] if k[0] not in _ROAD_KEYS},
                       key=lambda k: (min(b.st[k[1]].ways) if k[0] == "ramp" else 0, k[1]))
    junction_nodes = sorted({e[3] for e in edges})
    corridors = sorted({b.groups[g].corridor for g in road_gids})
    first_node = min((n for n in junction_nodes if n > 0), default=abs(min(junction_nodes)))
    name, name_from = interchange_name(corridors, first_node)

    # roads: window along each carriageway, heading, expressway pairing
    window, heading, cums = {}, {}, {}
    for g in road_gids:
        grp = b.groups[g]
        s = [grp.s_of[e[3]] for e in edges if ("road", g) in e[:2]]
        cums[g] = arclength(grp.xy)  # (once per carriageway: point_at would redo it each time)
        total = float(cums[g][-1])
        lo, hi = max(0.0, min(s) - 300.0), min(total, max(s) + 300.0)
        window[g] = (lo, hi)
        heading[g] = _unit(point_at(grp.xy, hi, cums[g]) - point_at(grp.xy, lo, cums[g]))
    exp_of: dict[int, str] = {}
    for c in corridors:
        gs = [g for g in road_gids if b.groups[g].corridor == c]
        pairs_left, k = list(gs), 0
        while pairs_left:
            g = pairs_left.pop(0)
            partner = min((h for h in pairs_left if float(np.dot(heading[g], heading[h])) < -0.3),
                          key=lambda h: float(np.dot(heading[g], heading[h])), default=None)
            exp = _compact(c) + ("" if k == 0 else chr(ord("a") + k))
            exp_of[g] = exp
            if partner is not None:
                pairs_left.remove(partner)
                exp_of[partner] = exp
            elif len(gs) > 1:
                nw.quirk(f"{name}: carriageway of {c} without an opposite partner: expressway {exp}")
            k += 1
    road_id: dict[int, str] = {}
    for g in road_gids:
        base = exp_of[g] + bearing_letter(heading[g] * np.array([nw.mirror, 1.0]))
        rid, k = base, 2
        while rid in road_id.values():
            rid, k = f"{base}{k}", k + 1
        road_id[g] = rid
    ramp_id = {k: f"r{i + 1}" for i, k in enumerate(ramp_keys)}
    local_id = {n: f"X{i + 1}" for i, n in enumerate(local_nodes)}

    def nid(k):
        return road_id[k[1]] if k[0] == "road" else local_id[k[1]] if k[0] == "local" else ramp_id[k]

    def lanes_of(ways):
        vals = [net.ways[w].tag("lanes") for w in ways]
        vals = [int(v) for v in vals if v and v.isdigit() and int(v) > 0]
        return Counter(vals).most_common(1)[0][0] if vals else None

    conns = []
    for src, dst, label, n in edges:
        pos = None
        road = src if src[0] == "road" else dst if dst[0] == "road" else None
        if road is not None:
            lo, hi = window[road[1]]
            pos = round(float(np.clip((b.groups[road[1]].s_of[n] - lo) / max(hi - lo, 1e-9), 0, 1)), 4)
        conns.append(Connection(nid(src), nid(dst), label, pos))
    roads, node_attrs, lines, carriageways, dead_ends = [], {}, {}, {}, {}
    junction_xy = np.array([nw.xy[n] for n in junction_nodes])
    ring_centre = junction_xy.mean(axis=0)
    ring_radius = float(np.hypot(*(junction_xy - ring_centre).T).max()) + RING_MARGIN_M + 50.0
    for g in road_gids:
        grp = b.groups[g]
        lo, hi = window[g]
        cum = cums[g]
        inside = (cum >= lo) & (cum <= hi)
        ways_in = list(dict.fromkeys(w for c in grp.stretches for w in b.st[c].ways
                                     if lo <= grp.s_of[b.st[c].end] and grp.s_of[b.st[c].start] <= hi))
        roads.append(Road(road_id[g], exp_of[g], lanes_of(ways_in)))
        node_attrs[road_id[g]] = {"osm_ways": " ".join(map(str, ways_in)), "ref": grp.corridor}
        lines[road_id[g]] = grp.xy[inside].tolist()
        s_j = [grp.s_of[e[3]] for e in edges if ("road", g) in e[:2]]
        reach = (cum >= min(s_j) - _CHECK_REACH_M) & (cum <= max(s_j) + _CHECK_REACH_M)
        # only what the self-check's ring can meet: points inside it and their neighbours
        near = np.hypot(*(grp.xy - ring_centre).T) <= ring_radius
        near = near | np.concatenate([near[1:], [False]]) | np.concatenate([[False], near[:-1]])
        carriageways[road_id[g]] = nw.unmirrored(grp.xy[reach & near]).round(1).tolist()
        first, last = b.st[grp.stretches[0]].start, b.st[grp.stretches[-1]].end
        # where nothing goes on on the map (a stub ending at ordinary roads, the extract's edge)
        total = float(cum[-1])
        for n, kind, dead, s_in in ((first, "in", nw.dead_in, min(_PROBE_M, total)),
                                    (last, "out", nw.dead_out, max(total - _PROBE_M, 0.0))):
            if n in dead:  # with the way the road would go on, outward
                out = _unit(nw.xy[n] - point_at(grp.xy, s_in, cum))
                dead_ends[(n, kind)] = [*nw.unmirrored(nw.xy[n])[0].round(1).tolist(),
                                        *nw.unmirrored(out)[0].round(4).tolist(), kind]
    for n in local_nodes:
        tags = net.ordinary.get(n, {})
        label = tags.get("ref") or tags.get("name") or ("extract edge" if not tags else tags.get("highway"))
        roads.append(Road(local_id[n], f"{local_id[n]} {label} (node {n})"))
        node_attrs[local_id[n]] = {"osm_ways": "", "ref": label}
        lines[local_id[n]] = [nw.xy[n].tolist()]
    ramps = []
    for k in ramp_keys:
        rid = ramp_id[k]
        ramps.append(Ramp(rid))
        if k[0] == "direct":
            real = _direct_ramp_line(b, edges, k)
            node_attrs[rid] = {"length_m": round(float(arclength(real)[-1]), 1),
                               "min_radius_m": round(min_radius(real), 1),
                               "turn_deg": round(signed_turn_deg(real), 1), "osm_ways": ""}
            lines[rid] = real.tolist()
            continue
        if k[0] != "ramp":
            node_attrs[rid] = {"length_m": 0.0, "min_radius_m": float("inf"), "osm_ways": ""}
            lines[rid] = [nw.xy[k[1]].tolist()]
            continue
        st = b.st[k[1]]
        real = st.xy[(1 if st.start in nw.snapped else 0):(-1 if st.end in nw.snapped else None)]
        attrs = {"length_m": round(float(arclength(real)[-1]), 1), "min_radius_m": round(min_radius(real), 1),
                 "turn_deg": round(signed_turn_deg(real), 1), "osm_ways": " ".join(map(str, st.ways))}
        gap = sum(nw.snapped.get(x, 0.0) for x in (st.start, st.end))
        if gap:
            attrs["snapped_m"] = round(gap, 1)
        ele = net.elevation
        if st.start in ele and st.end in ele and st.length > 0:
            attrs["grade_pct"] = round(100.0 * (ele[st.end] - ele[st.start]) / st.length, 2)
        lanes = lanes_of(st.ways)
        if lanes:
            attrs["lanes"] = lanes
        node_attrs[rid] = attrs
        lines[rid] = st.xy.tolist()
    osm = {
        "origin": (nw.proj.lat0, nw.proj.lon0),
        "lines": {k: nw.unmirrored(v).tolist() for k, v in lines.items()},
        "junctions": [(nw.unmirrored(nw.xy[n])[0].tolist(), nid(src), nid(dst), label.value)
                      for src, dst, label, n in edges],
        "driving_side": nw.side,
        "carriageways": carriageways,
        "dead_ends": [dead_ends[k] for k in sorted(dead_ends)],
        "quirks": list(nw.quirks),
        "ignored_links": {str(w): why for w, why in sorted(nw.ignored.items())},
    }
    return Topology.build(name, roads, ramps, conns, source=nw.src, node_attrs=node_attrs,
                          attrs={"format": "osm", "osm": osm, "osm_nodes": junction_nodes,
                                 "name_from": name_from})
