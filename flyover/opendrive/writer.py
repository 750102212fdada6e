"""Write an interchange (``geometry.json``) as OpenDRIVE 1.8 (or 1.7).

Model
-----
* Every road (straight carriageway) and ramp (Bézier chain) is cut into
  OpenDRIVE roads at its attachments; each OpenDRIVE road's ``name`` is the
  topology element it belongs to (``A1``, ``r3``).
* A diverge (``Out-R``/``Out-L`` inside the parent) is a junction: the parent
  road ends, the junction holds two connecting roads (the parent's next
  ``Lc`` metres and the ramp's first ``Lc`` metres), then parent and ramp go
  on as ordinary roads. Before the diverge the parent carries the ramp's
  lanes as auxiliary lanes that open from zero width (a deceleration lane),
  on the side of the exit (left ones through ``laneOffset``). A merge
  (``In-R``/``In-L``) is the mirror image with an acceleration lane that
  closes to zero width after the junction. The lanes of a two-lane ramp open
  (close) one at a time, each over its own taper, never together at one point.
* ``Out-M``/``In-M`` (a carriageway ending into or beginning from a ramp) is
  a direct road link; lane counts and widths change smoothly on the ramp, the
  carriageway's lanes beyond the ramp's closing (opening) one at a time there too.
* Straight pieces are ``<line>``, Bézier pieces ``<paramPoly3
  pRange="normalized">`` (exact), each cut into parts on which a reader's
  road position s (``p = s/length``) is within 5 cm of arc length
  (:func:`flyover.opendrive.curves.uniform_parts`), heights ``<elevation>``
  cubics of s (exact re-basing of the geometry's profile, along arc length),
  every lane followed by a shoulder.

The local frame is the geometry stage's: metres, x east, y north, z up,
origin at the interchange centre, headings counter-clockwise from +x,
right-hand traffic; it is written into the header as ``userData``.
"""

from __future__ import annotations

import logging
import math
import os
from dataclasses import dataclass, field

import numpy as np
from lxml import etree

from flyover.errors import FlyoverError
from flyover.geometry.model import InterchangeGeometry
from flyover.opendrive.curves import BezierChain, Line, ParamPoly3
from flyover.opendrive.curves import _deriv as _bez_deriv, _point as _bez_point
from flyover.opendrive.reader import Cubic

__all__ = ["ExportError", "ExportOptions", "xodr_bytes", "write_xodr", "FRAME_NOTE"]

log = logging.getLogger(__name__)

FRAME_NOTE = ("local Cartesian frame in metres: x east, y north, z up, origin at the "
              "interchange centre; headings in radians counter-clockwise from +x; "
              "right-hand traffic; no geographic reference")


class ExportError(FlyoverError):
    """The geometry cannot be written as OpenDRIVE."""


@dataclass(frozen=True)
class ExportOptions:
    """Tunables of the export.

    Attributes
    ----------
    connecting_length_m
        Length of the parent's and the ramp's pieces inside a diverge/merge junction.
    taper_length_m
        Length over which an auxiliary lane opens/closes, or lane widths change.
    decel_length_m, accel_length_m
        Full-width (parallel) length of the auxiliary lane before a diverge
        (deceleration lane) and after a merge (acceleration lane), beside its
        taper; shortened in proportion where the parent piece has no room.
        Without them a lane-changing vehicle had ~70 m (mostly taper) to reach
        or leave the ramp's lane, and SUMO jammed at every loop.
    lane_drop_spacing_m
        Where an auxiliary region has several lanes (a two-lane ramp), they close
        (open) one at a time, each over its own ``taper_length_m``, with this much
        full width between one taper's end and the next one's start: the
        outermost lane first after a merge, the innermost first before a diverge.
        So do the lanes of a carriageway beyond a narrower ramp it ends into (begins
        from) straight on, on the ramp's body. Shortened in proportion with the other
        lengths where the piece has no room.
    weave_max_m
        A merge followed on the same side by a diverge, with as many ramp
        lanes, at most this far apart (the parent piece between the two
        junctions) keep one continuous auxiliary lane between them (a weaving
        section, as on a cloverleaf), not two tapers.
    snap_tol_m
        Largest correction of a ramp end onto its attachment before failing.
    opendrive_minor
        The declared OpenDRIVE version 1.<minor>: 8 (default) or 7; the
        document is the same and valid against both schemas.
    """

    connecting_length_m: float = 15.0
    taper_length_m: float = 80.0
    snap_tol_m: float = 0.5
    decel_length_m: float = 120.0
    accel_length_m: float = 200.0
    lane_drop_spacing_m: float = 80.0
    weave_max_m: float = 800.0
    opendrive_minor: int = 8

    def __post_init__(self) -> None:
        if self.opendrive_minor not in (7, 8):
            raise ExportError(f"OpenDRIVE 1.{self.opendrive_minor} not supported (7 or 8)",
                              element="export.opendrive_minor")


# -- elements ---------------------------------------------------------------------------

@dataclass
class _Element:
    id: str
    kind: str  # road | ramp
    lanes: int
    width: float
    length: float
    z0: float = 0.0
    line: tuple[float, float, float] | None = None  # x, y, hdg for roads
    chain: BezierChain | None = None
    elevation: tuple[Cubic, ...] = ()

    def pose(self, s: float) -> tuple[float, float, float]:
        if self.chain is not None:
            return self.chain.pose(s)
        x, y, h = self.line
        return x + s * math.cos(h), y + s * math.sin(h), h

    def z(self, s: float) -> float:
        if not self.elevation:
            return self.z0
        rec = [e for e in self.elevation if e.s <= s + 1e-9][-1] if s > self.elevation[0].s else self.elevation[0]
        return float(rec(s))

    def plan(self, s0: float, s1: float) -> list[Line | ParamPoly3]:
        if self.chain is not None:
            return self.chain.part(s0, s1)
        x, y, h = self.pose(s0)
        return [Line(x, y, h, s1 - s0)]

    def elevation_part(self, s0: float, s1: float) -> list[Cubic]:
        if not self.elevation:
            return [Cubic(0.0, self.z0, 0.0, 0.0, 0.0)]
        out = []
        recs = list(self.elevation)
        for i, r in enumerate(recs):
            end = recs[i + 1].s if i + 1 < len(recs) else math.inf
            if end <= s0 + 1e-9 and i + 1 < len(recs):
                continue
            if r.s >= s1 - 1e-9 and out:
                break
            start = max(r.s, s0)
            dl = start - r.s
            out.append(Cubic(start - s0, r.a + r.b * dl + r.c * dl ** 2 + r.d * dl ** 3,
                             r.b + 2 * r.c * dl + 3 * r.d * dl ** 2, r.c + 3 * r.d * dl, r.d))
        return _merge_same(out)


def _rebase(c: Cubic, s: float) -> Cubic:
    dl = s - c.s
    return Cubic(s, c.a + c.b * dl + c.c * dl ** 2 + c.d * dl ** 3,
                 c.b + 2 * c.c * dl + 3 * c.d * dl ** 2, c.c + 3 * c.d * dl, c.d)


def _merge_same(records: list[Cubic], tol: float = 1e-9) -> list[Cubic]:
    """Drop records that only continue the previous polynomial (redundant in OpenDRIVE)."""
    out: list[Cubic] = []
    for r in records:
        if out:
            p = _rebase(out[-1], r.s)
            if all(abs(x - y) <= tol * max(1.0, abs(x)) for x, y in
                   ((p.a, r.a), (p.b, r.b), (p.c, r.c), (p.d, r.d))):
                continue
        out.append(r)
    return out


@dataclass(frozen=True)
class _Event:
    """A ramp attaching to a parent element at ``s``."""

    parent: str
    ramp: str
    s: float
    out: bool  # diverge (ramp leaves) or merge (ramp joins)
    side: str  # R | L | M


@dataclass
class _Piece:
    element: str
    s0: float
    s1: float
    junction: int | None = None  # junction id when a connecting road
    road_id: int = 0
    #: ("aux", side, k, w) | ("trans", n_from, w_from) | ("drop", n_from, w_from)
    start_region: tuple | None = None
    end_region: tuple | None = None
    pred: tuple | None = None  # ("road", id, contact) | ("junction", id)
    succ: tuple | None = None


@dataclass
class _Junction:
    id: int
    event: _Event | None
    pieces: dict[str, _Piece] = field(default_factory=dict)  # "parent"/"ramp" -> piece
    #: a fork (ramps leave the end of their parent) or a join (they form its start)
    group: tuple[_Event, ...] = ()
    forking: bool = True
    #: the parent's end is free (a stub ramp): the branches lie on its lanes
    free: bool = False


#: a lane that opens from zero width over a taper of length ``T`` reaches its full width (its
#: width stops changing) at ``T * (1 - OPENING_MARGIN)``, not at the taper's very end: its
#: width there is short of full by ``3 * OPENING_MARGIN**2`` of it (1.2e-9 m for 4 m).
#: CommonRoad's converter looks for that place among the roots of the width's derivative no
#: further than the lane section's length, compared exactly; computed from the written
#: coefficients, a root at the very end came out beyond it by 1e-14 to 1e-6 m on some
#: tapers (e.g. 80 m written as sections 79.99999999999999 m apart), and the converter then
#: re-drew the lane over its whole lanelet, whose border ended 1-2 cm off its successor's
#: (cloverleaf, cloverleaf C-D, parclo opposite).
OPENING_MARGIN = 1e-5


def _rising(w: float, T: float) -> Cubic:
    Tm = T * (1.0 - OPENING_MARGIN)
    return Cubic(0.0, 0.0, 0.0, 3 * w / Tm ** 2, -2 * w / Tm ** 3)


def _change(w0: float, w1: float, T: float) -> Cubic:
    if w0 == 0.0 and w1 != 0.0:  # a lane that opens
        return _rising(w1, T)
    return Cubic(0.0, w0, 0.0, 3 * (w1 - w0) / T ** 2, -2 * (w1 - w0) / T ** 3)


def _const(w: float) -> Cubic:
    return Cubic(0.0, w, 0.0, 0.0, 0.0)


def _shifted(c: Cubic, u: float) -> Cubic:
    """The cubic ``c`` (from 0) written from ``u`` on: the same values at ``u + ds``."""
    return Cubic(0.0, c.a + c.b * u + c.c * u * u + c.d * u ** 3,
                 c.b + 2 * c.c * u + 3 * c.d * u * u, c.c + 3 * c.d * u, c.d)


#: in a connecting road, a lane that opens from (closes to) zero width over its whole lane
#: section reaches its full width (begins to close) within this fraction of the section and
#: keeps it for the rest: a second width record. Link-following converters (CommonRoad's)
#: re-draw such a lane up to the first place where its width stops changing; at the
#: section's end that was the link itself, which they then moved by up to 2 m.
JUNCTION_TAPER_FRACTION = 2.0 / 3.0


def _junction_widths(w: Cubic, length: float) -> tuple[Cubic, ...]:
    """``w`` as width records of a connecting road's lane section of ``length`` m.

    A smooth full-section opening (``0 → W``) or closing (``W → 0``) becomes a smooth
    step over :data:`JUNCTION_TAPER_FRACTION` of the section and a constant part (same
    widths at both ends, so links are unchanged); any other width stays one record.

    >>> [(c.s, round(c.a, 3)) for c in _junction_widths(_rising(3.0, 15.0), 15.0)]
    [(0.0, 0.0), (10.0, 3.0)]
    >>> [(c.s, round(c.a, 3)) for c in _junction_widths(_change(3.0, 0.0, 15.0), 15.0)]
    [(0.0, 3.0), (5.0, 3.0)]
    """
    T = JUNCTION_TAPER_FRACTION * length
    if length <= 0 or w.b != 0.0:
        return (w,)
    w_end = float(w(length))
    if abs(w.a) < 1e-9 and abs(w_end) > 1e-9:
        # the width it opens to: where it stops changing (OPENING_MARGIN before the end)
        full = float(w(-2.0 * w.c / (3.0 * w.d))) if w.d != 0.0 else w_end
        step = _rising(full, length)
        if math.isclose(w.c, step.c, rel_tol=1e-9) and math.isclose(w.d, step.d, rel_tol=1e-9):
            r = _rising(full, T)
            return (r, Cubic(T, full, 0.0, 0.0, 0.0))
    if abs(w_end) < 1e-9 and abs(w.a) > 1e-9:
        step = _change(w.a, 0.0, length)
        if math.isclose(w.c, step.c, rel_tol=1e-9) and math.isclose(w.d, step.d, rel_tol=1e-9):
            c = _change(w.a, 0.0, T)
            return (_const(w.a), Cubic(length - T, c.a, c.b, c.c, c.d))
    return (w,)


def _elements(g: InterchangeGeometry, opts: ExportOptions) -> dict[str, _Element]:
    els: dict[str, _Element] = {}
    for r in g.roads:
        els[r.id] = _Element(r.id, "road", r.lanes, g.lane_width_m, r.length_m, z0=r.z_m,
                             line=(r.start[0], r.start[1], r.heading_rad))
    for r in g.ramps:
        pieces = [np.array(p.p, dtype=float) for p in r.plan]
        els[r.id] = _Element(r.id, "ramp", r.lanes, g.ramp_lane_width_m, 0.0,
                             chain=BezierChain(pieces),
                             elevation=tuple(Cubic(e.s_m, e.a, e.b, e.c, e.d) for e in r.elevation))
    return els


def _snap_ramps(g: InterchangeGeometry, els: dict[str, _Element], opts: ExportOptions) -> None:
    """Move each ramp's end control points exactly onto its attachment (by ≤ snap_tol_m)."""
    free_end, free_start = _free_ends(g)
    for r in g.ramps:
        el = els[r.id]
        pieces = [p.copy() for p in el.chain.pieces]
        for att, at_start in ((r.start, True), (r.end, False)):
            if not att.parent:
                continue  # a free end (fork/join): the children attach to it
            par = els.get(att.parent)
            if par is None:
                raise ExportError(f"attaches to unknown parent {att.parent!r}", element=r.id)
            side = att.label[-1]
            # within 0.5 m of its parent's end (start) a diverge (merge) is written as a fork
            # (join) at that end: the ramp meets it exactly there, not up to 0.5 m off
            s_att = att.s_m
            if at_start and abs(s_att - par.length) <= 0.5:
                s_att = par.length
            elif not at_start and abs(s_att) <= 0.5:
                s_att = 0.0
            x, y, h = par.pose(s_att)
            # a diverge from a ramp with a free end is a fork there (a merge into one with a
            # free start a join); a merge along the body of a stub adds a lane beside it
            fork = (att.parent in free_end and at_start) or \
                (att.parent in free_start and not at_start)
            if side == "M":
                off = 0.0
            elif fork:
                off = 0.0 if side == "L" else -(par.lanes * par.width - el.lanes * el.width)
            elif side == "R":
                off = -par.lanes * par.width
            else:
                off = el.lanes * el.width
            if abs(off - att.offset_m) > 0.01:
                raise ExportError(f"offset {att.offset_m:.3f} m on {att.parent} is not the lane "
                                  f"layout's {off:.3f} m", element=r.id)
            px, py = x - math.sin(h) * off, y + math.cos(h) * off
            q = pieces[0] if at_start else pieces[-1]
            i0, i1 = (0, 1) if at_start else (3, 2)
            d = math.hypot(q[i0][0] - px, q[i0][1] - py)
            if d > opts.snap_tol_m:
                raise ExportError(f"{'start' if at_start else 'end'} is {d:.3f} m from its "
                                  f"attachment on {att.parent} at s={att.s_m:.2f}", element=r.id)
            arm = float(np.linalg.norm(q[i1] - q[i0]))
            sgn = 1.0 if at_start else -1.0
            q[i0] = (px, py)
            q[i1] = (px + sgn * arm * math.cos(h), py + sgn * arm * math.sin(h))
        el.chain = BezierChain(pieces)
        el.length = el.chain.length
        # the elevation profile covers 0..length_m of the geometry stage; re-check the ends
        for s, att in ((0.0, r.start), (el.length, r.end)):
            if not att.parent:
                continue
            dz = abs(el.z(s) - els[att.parent].z(att.s_m))
            if dz > 0.01:
                log.warning("%s: ramp height %.3f m off its attachment on %s", r.id, dz, att.parent)


def _events(g: InterchangeGeometry) -> list[_Event]:
    ev = []
    for r in g.ramps:
        if r.start.parent:
            ev.append(_Event(r.start.parent, r.id, r.start.s_m, True, r.start.label[-1]))
        if r.end.parent:
            ev.append(_Event(r.end.parent, r.id, r.end.s_m, False, r.end.label[-1]))
    return ev


def _free_ends(g: InterchangeGeometry) -> tuple[set[str], set[str]]:
    """Ramps with a free end (they fork into others) and with a free start (others join)."""
    return ({r.id for r in g.ramps if not r.end.parent},
            {r.id for r in g.ramps if not r.start.parent})


def _plan_pieces(g: InterchangeGeometry, els: dict[str, _Element], opts: ExportOptions
                 ) -> tuple[dict[str, list[_Piece]], list[_Junction]]:
    events = _events(g)
    free_end, free_start = _free_ends(g)
    junctions: list[_Junction] = []
    cuts: dict[str, list[tuple[float, float, _Junction, str]]] = {k: [] for k in els}
    for pid in sorted(els):
        el = els[pid]
        for forking in (True, False):
            free = pid in (free_end if forking else free_start)
            at_end = [e for e in events if e.parent == pid and e.out == forking
                      and (free or (e.s >= el.length - 0.5 if forking else e.s <= 0.5))]
            if free and not at_end:
                raise ExportError(f"free {'end' if forking else 'start'} without ramps attached",
                                  element=pid)
            if not free and not (len(at_end) > 1 or (at_end and at_end[0].side != "M")):
                continue
            group = tuple(sorted(at_end, key=lambda e: e.ramp))
            j = _Junction(1000 + len(junctions), None, group=group, forking=forking, free=free)
            junctions.append(j)
            for e in group:
                ramp = els[e.ramp]
                other = [x.s for x in events if x.parent == e.ramp and x.side != "M"]
                ramp_s = 0.0 if e.out else ramp.length
                lc = min([opts.connecting_length_m, ramp.length / 3]
                         + [abs(x - ramp_s) / 3 for x in other if abs(x - ramp_s) > 1e-6])
                span = (0.0, lc) if e.out else (ramp.length - lc, ramp.length)
                cuts[e.ramp].append((*span, j, f"ramp:{e.ramp}"))
    grouped = {(e.parent, e.ramp, e.out) for j in junctions for e in j.group}
    for e in sorted(events, key=lambda e: (e.parent, e.s, e.ramp)):
        if e.side == "M" or (e.parent, e.ramp, e.out) in grouped:
            continue
        par, ramp = els[e.parent], els[e.ramp]
        same = sorted(x.s for x in events if x.parent == e.parent and x.side != "M")
        gaps = [abs(x - e.s) for x in same if abs(x - e.s) > 1e-9]
        gaps += [e.s, par.length - e.s]
        other = [x.s for x in events if x.parent == e.ramp and x.side != "M"]
        ramp_s = 0.0 if e.out else ramp.length
        gaps += [abs(x - ramp_s) for x in other] + [ramp.length / 2]
        lc = min([opts.connecting_length_m] + [gp / 3 for gp in gaps])
        if lc < 0.5:
            raise ExportError(f"attachment at s={e.s:.2f} of {e.parent} leaves no room "
                              f"for a junction ({lc:.2f} m)", element=e.ramp)
        j = _Junction(1000 + len(junctions), e)
        junctions.append(j)
        if e.out:
            cuts[e.parent].append((e.s, e.s + lc, j, "parent"))
            cuts[e.ramp].append((0.0, lc, j, "ramp"))
        else:
            cuts[e.parent].append((e.s - lc, e.s, j, "parent"))
            cuts[e.ramp].append((ramp.length - lc, ramp.length, j, "ramp"))
    pieces: dict[str, list[_Piece]] = {}
    for k, el in els.items():
        out, s = [], 0.0
        for a, b, j, role in sorted(cuts[k], key=lambda c: c[0]):
            if a > s + 1e-6:
                out.append(_Piece(k, s, a))
            elif a < s - 1e-6:
                raise ExportError(f"junctions overlap at s={a:.2f}", element=k)
            p = _Piece(k, a, b, junction=j.id)
            j.pieces[role] = p
            out.append(p)
            s = b
        if s < el.length - 1e-6:
            out.append(_Piece(k, s, el.length))
        pieces[k] = out
    return pieces, junctions


def _link_fork(j: _Junction, pieces: dict[str, list[_Piece]], els: dict[str, _Element]) -> None:
    """Road links and lane regions of a fork (ramps leave their parent's end) or join."""
    stub = j.group[0].parent
    par = els[stub]
    end_piece = pieces[stub][-1] if j.forking else pieces[stub][0]
    if end_piece.junction is not None:
        raise ExportError("another junction too close to where ramps fork/join", element=stub)
    sides = [e for e in j.group if e.side != "M"]
    if not j.free and sides:
        if len(sides) > 1:
            raise ExportError("more than one ramp beside the straight-on one at a carriageway end",
                              element=stub)
        e = sides[0]
        region = ("aux", e.side, els[e.ramp].lanes, els[e.ramp].width)
        if j.forking:
            end_piece.end_region = region
        else:
            end_piece.start_region = region
    for e in j.group:
        rp = j.pieces[f"ramp:{e.ramp}"]
        rlist = pieces[e.ramp]
        ri = rlist.index(rp)
        if e.side == "M":
            # the carriageway's lanes beyond the ramp's end (begin) on the connecting road;
            # the ramp's own lanes change width over a taper on its body, where a 15 m
            # change bent their centre line (a 2-lane ramp: 0.25 m sideways, a 210 m ramp
            # read back as 184 m); where two lanes or more end (begin) beyond the ramp's,
            # they do so on the body too, one at a time (the connecting road has no room
            # for their tapers), and the connecting road keeps them at full width
            ramp = els[e.ramp]
            body = rlist[ri + 1] if j.forking else rlist[ri - 1]
            room = (body.junction is None
                    and (body.start_region if j.forking else body.end_region) is None)
            taper = abs(par.width - ramp.width) > 1e-9 and room
            if room and par.lanes - ramp.lanes > 1:
                region, body_region = ("keep", par.lanes, par.width), ("trans", par.lanes, par.width)
            else:
                region = ("drop" if taper else "trans", par.lanes, par.width)
                body_region = ("trans", ramp.lanes, par.width) if taper else None
            if j.forking:
                rp.start_region = region
                if body_region is not None:
                    body.start_region = body_region
            else:
                rp.end_region = region
                if body_region is not None:
                    body.end_region = body_region
        if e.out:
            body = rlist[ri + 1]
            end_piece.succ, body.pred = ("junction", j.id), ("junction", j.id)
            rp.pred, rp.succ = ("road", end_piece.road_id, "end"), ("road", body.road_id, "start")
        else:
            body = rlist[ri - 1]
            end_piece.pred, body.succ = ("junction", j.id), ("junction", j.id)
            rp.pred, rp.succ = ("road", body.road_id, "end"), ("road", end_piece.road_id, "start")


def _branch_map(j: _Junction, e: _Event, els: dict[str, _Element], inverse: bool = False):
    """Lane keys at the parent's end → lane keys of one branch of a fork (inverse: join)."""
    stub, ramp = els[e.parent], els[e.ramp]
    if j.free:
        return _fork_map(stub, ramp, e.side, inverse)
    right_side = any(x.side == "R" for x in j.group)
    if e.side == "M":
        pairs = {("b", i): (("b", i) if i <= ramp.lanes else ("x", i))
                 for i in range(1, max(stub.lanes, ramp.lanes) + 1)}
        if not right_side:
            pairs[("sh",)] = ("sh",)
    else:
        pairs = {("aux", k): ("b", k) for k in range(1, ramp.lanes + 1)}
        if e.side == "R":
            pairs[("sh",)] = ("sh",)
    if inverse:
        pairs = {v: k for k, v in pairs.items()}
    return lambda k: pairs.get(k)


def _fork_map(stub: _Element, ramp: _Element, side: str, inverse: bool = False):
    """Lane keys of the stub → lane keys of a ramp that forks from (joins) it, by position.

    The ramp's lanes lie on the stub's: left-aligned for ``L``, right-aligned
    for ``R``; a lane maps to the one whose centre it shares (within 1 cm).
    """
    off = 0.0 if side == "L" else -(stub.lanes * stub.width - ramp.lanes * ramp.width)
    pairs = {}
    for j in range(1, ramp.lanes + 1):
        tc = off - (j - 0.5) * ramp.width
        for i in range(1, stub.lanes + 1):
            if abs(tc + (i - 0.5) * stub.width) < 0.01:
                pairs[("b", i)] = ("b", j)
    if abs(off - ramp.lanes * ramp.width + stub.lanes * stub.width) < 0.01:
        pairs[("sh",)] = ("sh",)
    if inverse:
        pairs = {v: k for k, v in pairs.items()}
    return lambda k: pairs.get(k)


#: share of a piece the auxiliary lanes of its regions may take at most (the rest is plain:
#: an auxiliary lane that closes right at the next junction made netconvert cut the
#: joining ramp short)
_FILL = 0.8


def _weaves(piece: _Piece, L: float, opts: ExportOptions) -> bool:
    """Does one auxiliary lane run from the merge at the piece's start to the diverge at its end?"""
    r0, r1 = piece.start_region, piece.end_region
    return (r0 is not None and r1 is not None and r0[0] == r1[0] == "aux" and r0[1:] == r1[1:]
            and L <= opts.weave_max_m)


def _taper_count(el: _Element, region: tuple | None) -> int:
    """Tapers a region of a normal piece takes, one after the other (at least 1 if any).

    An auxiliary region closes (opens) each of its lanes over its own taper; a width
    transition toward (from) a carriageway of ``n`` lanes, where ``|n - lanes|`` lanes
    end (begin), does the same (the first taper from the link also changes the widths
    of the lanes that go on).
    """
    if region is None:
        return 0
    if region[0] == "aux":
        return max(1, region[2])
    if region[0] == "trans":
        return max(1, abs(region[1] - el.lanes))
    return 1


def _region_lengths(el: _Element, piece: _Piece, L: float, opts: ExportOptions
                    ) -> tuple[float, float, float, float, float, bool]:
    """``(T0, T1, P0, P1, G, weave)``: taper, full-width and spacing lengths of a normal piece.

    An auxiliary lane runs full width for ``accel_length_m`` after a merge (start region)
    and ``decel_length_m`` before a diverge (end region), beside its taper; a width
    transition has the taper alone. A region of ``k`` auxiliary lanes, or a transition
    where ``k`` lanes end (begin), has ``k`` tapers ``G`` = ``lane_drop_spacing_m`` apart
    (each lane closes, or opens, over its own).
    Where the piece is shorter than what its regions ask for, every length shrinks in
    the same proportion (without full-width parts this is the former
    ``min(taper, L / regions)``).
    """
    r0, r1 = piece.start_region, piece.end_region
    if _weaves(piece, L, opts):
        return 0.0, 0.0, 0.0, 0.0, 0.0, True
    T, G = opts.taper_length_m, opts.lane_drop_spacing_m
    T0, T1 = (T if r0 else 0.0), (T if r1 else 0.0)
    P0 = opts.accel_length_m if r0 is not None and r0[0] == "aux" else 0.0
    P1 = opts.decel_length_m if r1 is not None and r1[0] == "aux" else 0.0
    k0, k1 = max(1, _taper_count(el, r0)), max(1, _taper_count(el, r1))
    want = k0 * T0 + k1 * T1 + P0 + P1 + ((k0 - 1) + (k1 - 1)) * G
    # full lengths where they fit with a plain stretch beside them; else in proportion
    f = min(1.0, L / want, _FILL * L / want if P0 or P1 else 1.0) if want > 0 else 1.0
    return T0 * f, T1 * f, P0 * f, P1 * f, G * f, False


def _region_span(el: _Element, region: tuple | None, T: float, P: float, G: float,
                 one_taper: bool = False) -> float:
    """Length a region's lane sections take: its full-width part, tapers and the spacing between."""
    if region is None:
        return 0.0
    k = 1 if one_taper else _taper_count(el, region)
    return P + k * T + (k - 1) * G


def _lanes_layout(el: _Element, piece: _Piece, T0: float, T1: float, sh: float,
                  P0: float = 0.0, P1: float = 0.0, weave: bool = False, G: float = 0.0,
                  one_taper: bool = False):
    """Lane sections of a normal piece: list of (s, laneOffset cubic, [(key, width cubic)]).

    A region's auxiliary lanes run full width for ``P0`` (after the start) or ``P1``
    (before the end) beside their tapers ``T0``/``T1``, one taper per lane, ``G`` apart,
    and so do the lanes a width transition ends (begins); ``weave``: one full-width
    auxiliary lane over the whole piece; ``one_taper``: every region is one lane section
    (a connecting road's).
    """
    L = piece.s1 - piece.s0
    base = [(("b", i), _const(el.width)) for i in range(1, el.lanes + 1)]
    r0, r1 = piece.start_region, piece.end_region
    if weave:
        return [(0.0, _region_lanes(el, r0, 0.0, opening=False, sh=sh, full=True))]
    secs = []
    P0 = P0 if r0 else 0.0
    P1 = P1 if r1 else 0.0
    s_plain0 = _region_span(el, r0, T0, P0, G, one_taper)
    s_plain1 = L - _region_span(el, r1, T1, P1, G, one_taper)
    if r0:
        if r0[0] == "aux":
            secs += _aux_sections(el, r0, 0.0, T0, P0, G, opening=False, sh=sh)
        elif r0[0] == "trans" and not one_taper and _taper_count(el, r0) > 1:
            secs += _trans_sections(el, r0, 0.0, T0, G, opening=False, sh=sh)
        else:
            secs.append((0.0, _region_lanes(el, r0, T0, opening=False, sh=sh)))
    if s_plain1 - s_plain0 > 1e-6 or not (r0 or r1):
        secs.append((s_plain0, (_const(0.0), base + [(("sh",), _const(sh))])))
    if r1:
        if r1[0] == "aux":
            secs += _aux_sections(el, r1, s_plain1, T1, P1, G, opening=True, sh=sh)
        elif r1[0] == "trans" and not one_taper and _taper_count(el, r1) > 1:
            secs += _trans_sections(el, r1, s_plain1, T1, G, opening=True, sh=sh)
        else:
            secs.append((s_plain1, _region_lanes(el, r1, T1, opening=True, sh=sh)))
    return secs


def _aux_sections(el: _Element, region: tuple, s0: float, T: float, P: float, G: float,
                  opening: bool, sh: float) -> list:
    """Lane sections of an auxiliary region from ``s0``: its lanes close (open) one at a time.

    After a merge (``opening=False``) every lane runs full width for ``P``, then the
    outermost closes over ``T``, the others keep their width for ``G``, the next
    closes, and so on; before a diverge (``opening=True``) the mirror image, the
    innermost opening first. Successive lane drops are separated, never at one point
    (two lanes ending together also read to CommonRoad's verifier as one place).

    >>> el = _Element("A1", "road", 2, 3.5, 500.0)
    >>> secs = _aux_sections(el, ("aux", "R", 2, 4.0), 0.0, 80.0, 200.0, 80.0, False, 3.0)
    >>> [(s, [k for k, _ in lanes if k[0] == "aux"]) for s, (_, lanes) in secs]
    [(0.0, [('aux', 1), ('aux', 2)]), (200.0, [('aux', 1), ('aux', 2)]), (280.0, [('aux', 1)]), (360.0, [('aux', 1)])]
    """
    _, side, k, w = region
    outer_first = list(range(k, 0, -1)) if side == "R" else list(range(1, k + 1))
    order = outer_first if not opening else outer_first[::-1]
    steps: list[dict[int, Cubic]] = []  # per section: aux lane -> width
    live = set(range(1, k + 1)) if not opening else set()
    if P > 1e-6 and not opening:
        steps.append(("P", {j: _const(w) for j in live}))
    for n, j in enumerate(order):
        cub = _rising(w, T) if opening else _change(w, 0.0, T)
        steps.append(("T", {**{i: _const(w) for i in live if i != j}, j: cub}))
        live = live | {j} if opening else live - {j}
        if n < k - 1 and G > 1e-6:
            steps.append(("G", {i: _const(w) for i in live}))
    if P > 1e-6 and opening:
        steps.append(("P", {j: _const(w) for j in live}))
    secs, s = [], s0
    for kind, widths in steps:
        secs.append((s, _aux_lanes(el, side, widths, sh)))
        s += {"P": P, "T": T, "G": G}[kind]
    return secs


def _trans_sections(el: _Element, region: tuple, s0: float, T: float, G: float,
                    opening: bool, sh: float) -> list:
    """Lane sections of a width transition where several lanes end (begin), one at a time.

    ``region = ("trans", n, w)``: at the piece's end nearest the link (its start if
    ``opening`` is false) the lanes are the carriageway's ``n`` of width ``w``. Going
    away from the link, the outermost lane that ends closes over ``T``, the others keep
    width ``w`` for ``G``, the next closes, and so on; before the link (``opening``) the
    mirror image, the innermost opening first. The lanes that go on change their width
    over the whole transition, one cubic cut at the sections: over the first taper alone
    (about 29 m on DC's 86 m `r4`, 4 → 3.75 m) the change bent their centre line, and
    a 276 m radius on the reference line read back as 239 m on the lane centre.

    >>> el = _Element("r1", "ramp", 1, 4.0, 500.0)
    >>> secs = _trans_sections(el, ("trans", 3, 3.75), 0.0, 80.0, 80.0, False, 3.0)
    >>> [(s, [k for k, _ in lanes if k[0] != "sh"]) for s, (_, lanes) in secs]
    [(0.0, [('b', 1), ('x', 2), ('x', 3)]), (80.0, [('b', 1), ('x', 2)]), (160.0, [('b', 1), ('x', 2)])]
    """
    _, n, w = region
    lo, hi = min(n, el.lanes), max(n, el.lanes)
    link = {i: (w if i <= n else 0.0) for i in range(1, hi + 1)}  # widths at the link
    far = {i: (el.width if i <= el.lanes else 0.0) for i in range(1, hi + 1)}
    # from the link outward: the outermost of the lanes there ends first (the innermost of
    # those not there begins first, where the ramp has more lanes than the carriageway)
    order = list(range(hi, lo, -1)) if n > el.lanes else list(range(lo + 1, hi + 1))
    steps = []  # from the link outward: (length, {lane: "link" | "far" | "change"})
    for m, c in enumerate(order):
        state = {i: ("change" if m == 0 else "far") for i in range(1, lo + 1)}
        state.update({i: "far" for i in order[:m]})
        state.update({i: "link" for i in order[m + 1:]})
        state[c] = "change"
        steps.append((T, state))
        if m + 1 < len(order) and G > 1e-6:
            steps.append((G, {i: ("link" if i in order[m + 1:] else "far") for i in state}))
    if opening:
        steps = steps[::-1]

    span = sum(length for length, _ in steps)
    going_on = _change(far[1], link[1], span) if opening else _change(link[1], far[1], span)

    def width(i: int, how: str, u: float) -> Cubic:
        if i <= lo:  # a lane that goes on, ``u`` into the transition
            return _shifted(going_on, u)
        if how == "link":
            return _const(link[i])
        if how == "far":
            return _const(far[i])
        return _change(far[i], link[i], T) if opening else _change(link[i], far[i], T)

    secs, s = [], s0
    for length, state in steps:
        lanes = []
        for i in sorted(state):
            cub = width(i, state[i], s - s0)
            if state[i] != "change" and abs(cub.a) < 1e-12:
                continue  # closed (not yet open)
            lanes.append((("b", i) if i <= el.lanes else ("x", i), cub))
        secs.append((s, (_const(0.0), lanes + [(("sh",), _const(sh))])))
        s += length
    return secs


def _aux_lanes(el: _Element, side: str, widths: dict[int, Cubic], sh: float):
    """``(laneOffset, lanes)`` of a section with auxiliary lanes ``widths`` beside the carriageway."""
    aux = [(("aux", j), widths[j]) for j in sorted(widths)]
    base = [(("b", i), _const(el.width)) for i in range(1, el.lanes + 1)]
    if side == "R":
        return _const(0.0), base + aux + [(("sh",), _const(sh))]
    off = Cubic(0.0, *(sum(getattr(c, a) for c in widths.values()) for a in "abcd"))
    return off, aux + base + [(("sh",), _const(sh))]


def _region_lanes(el: _Element, region: tuple, T: float, opening: bool, sh: float,
                  full: bool = False):
    kind = region[0]
    if kind == "aux":  # the full-width lanes of a weave (tapers: _aux_sections)
        _, side, k, w = region
        return _aux_lanes(el, side, {j: _const(w) for j in range(1, k + 1)}, sh)
    if kind == "keep":  # a connecting road carries a carriageway's n lanes of width w on to
        _, n, w = region  # (from) the ramp's body, where those beyond the ramp's close (open)
        lanes = [(("b", i) if i <= el.lanes else ("x", i), _const(w))
                 for i in range(1, max(n, el.lanes) + 1)]
        return _const(0.0), lanes + [(("sh",), _const(sh))]
    # width transition toward/from a carriageway of n lanes of width w (Out-M / In-M);
    # "drop": only its lanes beyond the ramp's close (open), the ramp's keep width w
    kind, n, w = region
    lanes = []
    for i in range(1, max(n, el.lanes) + 1):
        mine = (w if kind == "drop" else el.width) if i <= el.lanes else 0.0
        theirs = w if i <= n else 0.0
        cub = _change(mine, theirs, T) if opening else _change(theirs, mine, T)
        lanes.append((("b", i) if i <= el.lanes else ("x", i), cub))
    return _const(0.0), lanes + [(("sh",), _const(sh))]


def _f(x: float) -> str:
    x = float(x)
    if abs(x) < 5e-13:
        x = 0.0
    return repr(round(x, 12))


def _coef(x: float) -> str:
    """A polynomial coefficient to 15 significant digits: :func:`_f`'s 12 decimals kept a
    3.75 m lane closing over 80 m (``d`` = 1.46484375e-05) 2.56e-7 m wide at its end, above
    CommonRoad's 1e-8 m test for a lane that ends (it left the lane as it was, with bounds
    that cross: ``polylines_intersection``)."""
    x = float(x)
    return "0.0" if abs(x) < 1e-16 else repr(float(f"{x:.15g}"))


def _cubic_attrs(c: Cubic, s_name: str = "s") -> dict[str, str]:
    return {s_name: _f(c.s), "a": _f(c.a), "b": _coef(c.b), "c": _coef(c.c), "d": _coef(c.d)}


def xodr_bytes(g: InterchangeGeometry, options: ExportOptions | None = None,
               name: str | None = None) -> bytes:
    """The OpenDRIVE document of an interchange (byte-reproducible)."""
    opts = options or ExportOptions()
    els = _elements(g, opts)
    _snap_ramps(g, els, opts)
    pieces, junctions = _plan_pieces(g, els, opts)
    sh = g.shoulder_width_m
    # ids
    rid = 1
    for k in sorted(els, key=lambda k: (els[k].kind != "road", k)):
        for p in pieces[k]:
            p.road_id = rid
            rid += 1
    # regions (aux lanes, width transitions) and links
    for j in junctions:
        if j.group:
            _link_fork(j, pieces, els)
            continue
        e = j.event
        par, ramp = els[e.parent], els[e.ramp]
        pp, rp = j.pieces["parent"], j.pieces["ramp"]
        plist, rlist = pieces[e.parent], pieces[e.ramp]
        pi, ri = plist.index(pp), rlist.index(rp)
        # the parent runs through the junction (up → pp → down); the ramp's body leaves
        # it after rp (a diverge, with an auxiliary lane before) or joins it before rp
        # (a merge, with the auxiliary lane after)
        up, down = plist[pi - 1], plist[pi + 1]
        up.succ = down.pred = ("junction", j.id)
        pp.pred, pp.succ = ("road", up.road_id, "end"), ("road", down.road_id, "start")
        aux = ("aux", e.side, ramp.lanes, ramp.width)
        if e.out:
            rbody = rlist[ri + 1]
            up.end_region, rbody.pred = aux, ("junction", j.id)
            rp.pred, rp.succ = ("road", up.road_id, "end"), ("road", rbody.road_id, "start")
        else:
            rbody = rlist[ri - 1]
            down.start_region, rbody.succ = aux, ("junction", j.id)
            rp.pred, rp.succ = ("road", rbody.road_id, "end"), ("road", down.road_id, "start")
    grouped = {(e.parent, e.ramp, e.out) for j in junctions for e in j.group}
    for e in _events(g):
        if e.side != "M" or (e.parent, e.ramp, e.out) in grouped:
            continue
        par, ramp = els[e.parent], els[e.ramp]
        if e.out:  # parent ends, ramp begins
            a, b = pieces[e.parent][-1], pieces[e.ramp][0]
            b.start_region = ("trans", par.lanes, par.width)
        else:  # ramp ends, parent begins
            a, b = pieces[e.ramp][-1], pieces[e.parent][0]
            a.end_region = ("trans", par.lanes, par.width)
        if a.junction is not None or b.junction is not None:
            raise ExportError(f"straight-on link {e.parent}/{e.ramp} too close to a junction",
                              element=e.ramp)
        a.succ, b.pred = ("road", b.road_id, "start"), ("road", a.road_id, "end")
    # lane sections of every piece
    layouts: dict[int, list] = {}
    for k, plist in pieces.items():
        el = els[k]
        for p in plist:
            L = p.s1 - p.s0
            if p.junction is not None and (p.start_region or p.end_region):
                layouts[p.road_id] = _lanes_layout(el, p, L, L, sh, one_taper=True)
                continue
            if p.junction is not None:
                layouts[p.road_id] = [(0.0, (_const(0.0), [(("b", i), _const(el.width))
                                                          for i in range(1, el.lanes + 1)]
                                             + [(("sh",), _const(sh))]))]
                continue
            T0, T1, P0, P1, G, weave = _region_lengths(el, p, L, opts)
            layouts[p.road_id] = _lanes_layout(el, p, T0, T1, sh, P0, P1, weave, G)

    def ids(rid_: int, which: int) -> dict[tuple, int]:
        secs = layouts[rid_]
        _, (_, lanes) = secs[which]
        return {key: -(i + 1) for i, (key, _) in enumerate(lanes)}

    # lane links across roads: (road_id, 'first'|'last') -> {key: other lane id}
    by_id = {p.road_id: p for plist in pieces.values() for p in plist}
    pred_links: dict[int, dict[tuple, int]] = {}
    succ_links: dict[int, dict[tuple, int]] = {}
    conn_links: list[tuple[int, int, int, list[tuple[int, int]]]] = []  # junction, incoming, connecting, links

    def keymap(src: dict[tuple, int], dst: dict[tuple, int], mapping) -> list[tuple[int, int]]:
        out = []
        for key, lid in src.items():
            k2 = mapping(key)
            if k2 is not None and k2 in dst:
                out.append((lid, dst[k2]))
        return out

    same = lambda k: k if k[0] in ("b", "sh") else None  # noqa: E731
    same_x = lambda k: k if k[0] in ("b", "x", "sh") else None  # noqa: E731  (keep regions)
    for j in junctions:
        if j.group:
            for e in j.group:
                rp = j.pieces[f"ramp:{e.ramp}"]
                if e.out:
                    up = by_id[rp.pred[1]]
                    links = keymap(ids(up.road_id, -1), ids(rp.road_id, 0), _branch_map(j, e, els))
                    conn_links.append((j.id, up.road_id, rp.road_id, links))
                    pred_links[rp.road_id] = dict((b, a) for a, b in links)
                    succ_links[rp.road_id] = dict(keymap(ids(rp.road_id, -1),
                                                         ids(rp.succ[1], 0), same_x))
                else:
                    body, down = by_id[rp.pred[1]], by_id[rp.succ[1]]
                    links = keymap(ids(body.road_id, -1), ids(rp.road_id, 0), same_x)
                    conn_links.append((j.id, body.road_id, rp.road_id, links))
                    pred_links[rp.road_id] = dict((b, a) for a, b in links)
                    inv = _branch_map(j, e, els, inverse=True)
                    succ_links[rp.road_id] = dict(keymap(ids(rp.road_id, -1),
                                                         ids(down.road_id, 0), inv))
            continue
        e = j.event
        pp, rp = j.pieces["parent"], j.pieces["ramp"]
        up = by_id[pp.pred[1]]
        up_ids = ids(up.road_id, -1)
        pp_ids, rp_ids = ids(pp.road_id, 0), ids(rp.road_id, 0)
        if e.out:
            side = e.side
            to_ramp = lambda k: ("b", k[1]) if k[0] == "aux" else (k if (k[0] == "sh" and side == "R") else None)  # noqa: E731
            to_par = lambda k: k if (k[0] == "b" or (k[0] == "sh" and side == "L")) else None  # noqa: E731
            conn_links.append((j.id, up.road_id, pp.road_id, keymap(up_ids, pp_ids, to_par)))
            conn_links.append((j.id, up.road_id, rp.road_id, keymap(up_ids, rp_ids, to_ramp)))
            down, rbody = by_id[pp.succ[1]], by_id[rp.succ[1]]
            succ_links[pp.road_id] = dict(keymap(pp_ids, ids(down.road_id, 0), same))
            succ_links[rp.road_id] = dict(keymap(rp_ids, ids(rbody.road_id, 0), same))
            pred_links[pp.road_id] = dict((b, a) for a, b in conn_links[-2][3])
            pred_links[rp.road_id] = dict((b, a) for a, b in conn_links[-1][3])
        else:
            side = e.side
            rbody = by_id[rp.pred[1]]
            down = by_id[pp.succ[1]]
            down_ids = ids(down.road_id, 0)
            conn_links.append((j.id, up.road_id, pp.road_id, keymap(up_ids, pp_ids, same)))
            conn_links.append((j.id, rbody.road_id, rp.road_id, keymap(ids(rbody.road_id, -1), rp_ids, same)))
            from_par = lambda k: k if (k[0] == "b" or (k[0] == "sh" and side == "L")) else None  # noqa: E731
            from_ramp = lambda k: ("aux", k[1]) if k[0] == "b" else (k if (k[0] == "sh" and side == "R") else None)  # noqa: E731
            succ_links[pp.road_id] = dict(keymap(pp_ids, down_ids, from_par))
            succ_links[rp.road_id] = dict(keymap(rp_ids, down_ids, from_ramp))
            pred_links[pp.road_id] = dict((b, a) for a, b in conn_links[-2][3])
            pred_links[rp.road_id] = dict((b, a) for a, b in conn_links[-1][3])
    for e in _events(g):
        if e.side != "M" or (e.parent, e.ramp, e.out) in grouped:
            continue
        a, b = ((pieces[e.parent][-1], pieces[e.ramp][0]) if e.out
                else (pieces[e.ramp][-1], pieces[e.parent][0]))
        a_ids, b_ids = ids(a.road_id, -1), ids(b.road_id, 0)
        if e.out:  # ramp b's first section holds keys b/x for parent lanes 1..n
            fwd = lambda k: k if k[0] == "sh" else (("b", k[1]) if ("b", k[1]) in b_ids else ("x", k[1]))  # noqa: E731
        else:  # ramp a's last section holds b/x keys that become parent lanes
            fwd = lambda k: k if k[0] == "sh" else ("b", k[1])  # noqa: E731
        links = keymap(a_ids, b_ids, fwd)
        succ_links[a.road_id] = dict(links)
        pred_links[b.road_id] = dict((y, x) for x, y in links)

    _close_gore_shoulders(pieces, layouts, pred_links, succ_links)

    # -- XML ------------------------------------------------------------------------
    root = etree.Element("OpenDRIVE")
    allpts = []
    for k, el in sorted(els.items()):
        if el.chain is not None:  # sample by Bézier parameter (no arc-length inversion)
            t = np.linspace(0.0, 1.0, 33)
            xy = np.concatenate([_bez_point(p, t) for p in el.chain.pieces])
            d = np.concatenate([_bez_deriv(p, t) for p in el.chain.pieces])
            h = np.arctan2(d[:, 1], d[:, 0])
        else:
            s_ = np.linspace(0.0, el.length, 2)
            x0, y0, h0 = el.line
            xy = np.stack([x0 + s_ * math.cos(h0), y0 + s_ * math.sin(h0)], 1)
            h = np.full(2, h0)
        wdt = el.lanes * el.width + sh + 2 * el.width
        for sg in (-1.0, 1.0):
            allpts += list(zip(xy[:, 0] + sg * wdt * np.sin(h), xy[:, 1] - sg * wdt * np.cos(h)))
    pts = np.array(allpts)
    head = etree.SubElement(root, "header", revMajor="1", revMinor=str(opts.opendrive_minor),
                            name=name or f"{g.class_id}/{g.sample}", version="1",
                            north=_f(pts[:, 1].max()), south=_f(pts[:, 1].min()),
                            east=_f(pts[:, 0].max()), west=_f(pts[:, 0].min()), vendor="flyover")
    etree.SubElement(head, "userData", code="flyover:frame", value=FRAME_NOTE)
    etree.SubElement(head, "userData", code="flyover:source",
                     value=f"class_id={g.class_id} sample={g.sample} seed={g.seed}")
    for k in sorted(els, key=lambda k: (els[k].kind != "road", k)):
        el = els[k]
        for p in pieces[k]:
            _write_road(root, el, p, layouts[p.road_id], pred_links.get(p.road_id, {}),
                        succ_links.get(p.road_id, {}))
    for j in junctions:
        jname = (f"{j.group[0].parent} {'fork' if j.forking else 'join'}" if j.group
                 else f"{j.event.parent}/{j.event.ramp}")
        je = etree.SubElement(root, "junction", id=str(j.id), name=jname, type="default")
        cid = 0
        for jid, inc, con, links in conn_links:
            if jid != j.id:
                continue
            c = etree.SubElement(je, "connection", id=str(cid), incomingRoad=str(inc),
                                 connectingRoad=str(con), contactPoint="start")
            for a, b in sorted(links, key=lambda t: -t[0]):
                etree.SubElement(c, "laneLink", **{"from": str(a), "to": str(b)})
            cid += 1
    return etree.tostring(root, xml_declaration=True, encoding="UTF-8", pretty_print=True)


def _close_gore_shoulders(pieces: dict[str, list[_Piece]], layouts: dict[int, list],
                          pred_links: dict[int, dict], succ_links: dict[int, dict]) -> None:
    """A connecting road's shoulder that no lane feeds (leads on) opens from (closes to) zero width.

    At a diverge the branch whose shoulder is not the parent's begins beside a
    driving lane (the gore), at a merge it ends beside one; at full width it
    was a lane that continued nowhere: link-following clients (CommonRoad's
    converter) met a dangling lane there. Over the connecting road it now
    opens (closes) like an auxiliary lane, so every lane of nonzero width at
    a road end is linked, and no link joins lanes that do not meet.
    """
    for plist in pieces.values():
        for p in plist:
            if p.junction is None:
                continue
            secs = layouts[p.road_id]
            L = p.s1 - p.s0
            for first, links, end in ((True, pred_links, p.pred), (False, succ_links, p.succ)):
                if end is None or end[0] != "road":
                    continue
                idx = 0 if first else len(secs) - 1
                s0, (off, lanes) = secs[idx]
                keys = [k for k, _ in lanes]
                if ("sh",) not in keys:
                    continue
                lid = -(keys.index(("sh",)) + 1)
                if lid in links.get(p.road_id, {}):
                    continue
                span = (secs[1][0] if len(secs) > 1 else L) - s0 if first else L - s0
                w = lanes[keys.index(("sh",))][1]
                new = _rising(w.a, span) if first else _change(w.a, 0.0, span)
                lanes = [(k, new if k == ("sh",) else c) for k, c in lanes]
                secs[idx] = (s0, (off, lanes))


def _write_road(root, el: _Element, p: _Piece, layout, preds: dict, succs: dict) -> None:
    """One ``<road>``: links, plan view, elevation, lane offset and lane sections."""
    L = p.s1 - p.s0
    road = etree.SubElement(root, "road", name=el.id, length=_f(L), id=str(p.road_id),
                            junction=str(p.junction if p.junction is not None else -1), rule="RHT")
    if p.pred or p.succ:
        link = etree.SubElement(road, "link")
        for tag, val in (("predecessor", p.pred), ("successor", p.succ)):
            if val is None:
                continue
            if val[0] == "junction":
                etree.SubElement(link, tag, elementType="junction", elementId=str(val[1]))
            else:
                etree.SubElement(link, tag, elementType="road", elementId=str(val[1]),
                                 contactPoint=val[2])
    etree.SubElement(road, "type", s="0.0", type="motorway")
    pv = etree.SubElement(road, "planView")
    s = 0.0
    for rec in el.plan(p.s0, p.s1):
        ge = etree.SubElement(pv, "geometry", s=_f(s), x=_f(rec.x), y=_f(rec.y), hdg=_f(rec.hdg),
                              length=_f(rec.length))
        if isinstance(rec, Line):
            etree.SubElement(ge, "line")
        else:
            etree.SubElement(ge, "paramPoly3", aU=_f(rec.u[0]), bU=_f(rec.u[1]), cU=_f(rec.u[2]),
                             dU=_f(rec.u[3]), aV=_f(rec.v[0]), bV=_f(rec.v[1]), cV=_f(rec.v[2]),
                             dV=_f(rec.v[3]), pRange="normalized")
        s += rec.length
    if abs(s - L) > 1e-3:
        log.debug("%s road %d: plan length %.6f vs %.6f", el.id, p.road_id, s, L)
    road.set("length", _f(s))
    ep = etree.SubElement(road, "elevationProfile")
    for c in el.elevation_part(p.s0, p.s1):
        etree.SubElement(ep, "elevation", **_cubic_attrs(c))
    etree.SubElement(road, "lateralProfile")
    lanes_el = etree.SubElement(road, "lanes")
    offsets, prev = [], None
    for s0, (off, _) in layout:
        c = Cubic(s0, off.a, off.b, off.c, off.d)
        if prev is None or (c.a, c.b, c.c, c.d) != (prev.a, prev.b, prev.c, prev.d) or prev.b or prev.c or prev.d:
            if not (prev is None and c.a == 0 and c.b == 0 and c.c == 0 and c.d == 0):
                offsets.append(c)
            prev = c
    if offsets and offsets[0].s > 0:
        offsets.insert(0, Cubic(0.0, 0.0, 0.0, 0.0, 0.0))
    for c in offsets:
        etree.SubElement(lanes_el, "laneOffset", **_cubic_attrs(c))
    for idx, (s0, (_, lanes)) in enumerate(layout):
        sec = etree.SubElement(lanes_el, "laneSection", s=_f(s0))
        ctr = etree.SubElement(sec, "center")
        cl = etree.SubElement(ctr, "lane", id="0", type="none", level="false")
        etree.SubElement(cl, "roadMark", sOffset="0.0", type="solid", weight="standard",
                         color="yellow", width="0.15", laneChange="none")
        right = etree.SubElement(sec, "right")
        prev_keys = {key: -(i + 1) for i, (key, _) in enumerate(layout[idx - 1][1][1])} if idx > 0 else {}
        next_keys = ({key: -(i + 1) for i, (key, _) in enumerate(layout[idx + 1][1][1])}
                     if idx + 1 < len(layout) else {})
        for i, (key, w) in enumerate(lanes):
            lid = -(i + 1)
            lane = etree.SubElement(right, "lane", id=str(lid),
                                    type="shoulder" if key[0] == "sh" else "driving", level="false")
            pred = prev_keys.get(key) if idx > 0 else preds.get(lid)
            succ = next_keys.get(key) if idx + 1 < len(layout) else succs.get(lid)
            # a lane that starts (ends) at zero width has no predecessor (successor)
            if abs(w.a) < 1e-9:
                pred = None
            sec_len = (layout[idx + 1][0] if idx + 1 < len(layout) else float(road.get("length"))) - s0
            wend = float(w(sec_len))
            if abs(wend) < 1e-9:
                succ = None
            if pred is not None or succ is not None:
                ln = etree.SubElement(lane, "link")
                if pred is not None:
                    etree.SubElement(ln, "predecessor", id=str(pred))
                if succ is not None:
                    etree.SubElement(ln, "successor", id=str(succ))
            for rec in (_junction_widths(w, sec_len) if p.junction is not None else (w,)):
                etree.SubElement(lane, "width", **_cubic_attrs(rec, "sOffset"))
            etree.SubElement(lane, "roadMark", sOffset="0.0",
                             type="solid" if key[0] == "sh" or i == len(lanes) - 2 else "broken",
                             weight="standard", color="white", width="0.15",
                             laneChange="none" if key[0] == "sh" else "both")
            if key[0] != "sh":
                etree.SubElement(lane, "speed", sOffset="0.0", max="22.22" if el.kind == "ramp" else "33.33",
                                 unit="m/s")


def write_xodr(g: InterchangeGeometry, path: str | os.PathLike,
               options: ExportOptions | None = None) -> None:
    """Write ``interchange.xodr`` atomically."""
    from flyover.topology.io import atomic_write  # noqa: PLC0415

    atomic_write(path, xodr_bytes(g, options))
