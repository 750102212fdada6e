"""Read any OpenDRIVE file and evaluate it in 3D: reference lines, lanes, links.

Enough of the standard to check continuity and draw plans of files written by
any tool: plan-view geometries ``line``, ``arc``, ``spiral``, ``poly3`` and
``paramPoly3`` (``arcLength`` or ``normalized``), ``elevation`` records,
``laneOffset`` and lane ``width`` records. Lane ``border`` records and
superelevation are not evaluated (lanes given by borders are skipped).

For ``paramPoly3`` with ``pRange="normalized"``, the curve parameter at
road position ``s`` is ``p = (s - s0) / length``, as in SUMO and esmini.

Example
-------
>>> import io
>>> xodr = b'''<OpenDRIVE><header revMajor="1" revMinor="7"/>
... <road id="1" length="10" junction="-1"><planView>
... <geometry s="0" x="0" y="0" hdg="0" length="10"><line/></geometry></planView>
... <lanes><laneSection s="0"><center><lane id="0" type="none"/></center>
... <right><lane id="-1" type="driving"><width sOffset="0" a="3.5" b="0" c="0" d="0"/></lane>
... </right></laneSection></lanes></road></OpenDRIVE>'''
>>> net = read_xodr(io.BytesIO(xodr))
>>> [round(v, 3) for v in net.roads["1"].lane_point(-1, 10.0)[:3]]
[10.0, -1.75, 0.0]
"""

from __future__ import annotations

from bisect import bisect_right

import math
import os
from dataclasses import dataclass, field
from typing import IO

import numpy as np
from lxml import etree
from scipy.integrate import quad

from flyover.errors import InputFormatError

__all__ = ["PlanGeometry", "Cubic", "Lane", "LaneSection", "XodrRoad", "XodrConnection",
           "XodrJunction", "XodrNetwork", "read_xodr"]


@dataclass(frozen=True)
class Cubic:
    """``a + b·ds + c·ds² + d·ds³`` from ``s`` (elevation, laneOffset, width)."""

    s: float
    a: float
    b: float
    c: float
    d: float

    def __call__(self, s: np.ndarray | float) -> np.ndarray | float:
        ds = np.asarray(s, dtype=float) - self.s
        return self.a + ds * (self.b + ds * (self.c + ds * self.d))


def _piecewise(records: list[Cubic], s: np.ndarray | float) -> np.ndarray:
    s = np.atleast_1d(np.asarray(s, dtype=float))
    if not records:
        return np.zeros_like(s)
    if s.size == 1:  # one station (lane ends, links): no vector machinery
        v = float(s[0])
        i = max(0, min(bisect_right([r.s for r in records], v + 1e-9) - 1, len(records) - 1))
        return np.array([records[i](v)], dtype=float)
    starts = np.array([r.s for r in records])
    idx = np.clip(np.searchsorted(starts, s + 1e-9, side="right") - 1, 0, len(records) - 1)
    out = np.empty_like(s)
    for i in np.unique(idx):
        m = idx == i
        out[m] = records[i](s[m])
    return out


@dataclass(frozen=True)
class PlanGeometry:
    """One ``<geometry>`` record of a plan view."""

    s: float
    x: float
    y: float
    hdg: float
    length: float
    kind: str
    params: tuple[tuple[str, float], ...] = ()

    def _p(self, name: str, default: float = 0.0) -> float:
        return dict(self.params).get(name, default)

    def local(self, ds: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Local (u, v, heading) at distances ``ds`` from the start, before rotation."""
        ds = np.asarray(ds, dtype=float)
        if self.kind == "line":
            return ds, np.zeros_like(ds), np.zeros_like(ds)
        if self.kind == "arc":
            k = self._p("curvature")
            if abs(k) < 1e-12:
                return ds, np.zeros_like(ds), np.zeros_like(ds)
            return np.sin(k * ds) / k, (1 - np.cos(k * ds)) / k, k * ds
        if self.kind == "spiral":
            k0, k1 = self._p("curvStart"), self._p("curvEnd")
            dk = (k1 - k0) / self.length if self.length > 0 else 0.0
            th = lambda t: k0 * t + 0.5 * dk * t * t  # noqa: E731
            u = np.array([quad(lambda t: math.cos(th(t)), 0, d)[0] for d in ds.ravel()])
            v = np.array([quad(lambda t: math.sin(th(t)), 0, d)[0] for d in ds.ravel()])
            return u.reshape(ds.shape), v.reshape(ds.shape), th(ds)
        if self.kind == "poly3":
            a, b, c, d = (self._p(n) for n in "abcd")
            # u is the local x; approximate s -> u by the chord (standard practice)
            u = ds
            v = a + b * u + c * u ** 2 + d * u ** 3
            return u, v, np.arctan(b + 2 * c * u + 3 * d * u ** 2)
        if self.kind == "paramPoly3":
            p = ds / self.length if self._p("normalized", 1.0) else ds
            cu = [self._p(f"{k}U") for k in "abcd"]
            cv = [self._p(f"{k}V") for k in "abcd"]
            u = cu[0] + p * (cu[1] + p * (cu[2] + p * cu[3]))
            v = cv[0] + p * (cv[1] + p * (cv[2] + p * cv[3]))
            du = cu[1] + p * (2 * cu[2] + 3 * p * cu[3])
            dv = cv[1] + p * (2 * cv[2] + 3 * p * cv[3])
            return u, v, np.arctan2(dv, du)
        raise InputFormatError(f"unsupported plan-view geometry <{self.kind}>")

    def evaluate(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Global (x, y, heading) at road positions ``s`` inside this record."""
        u, v, h = self.local(np.asarray(s, dtype=float) - self.s)
        c, sn = math.cos(self.hdg), math.sin(self.hdg)
        return self.x + c * u - sn * v, self.y + sn * u + c * v, self.hdg + h


@dataclass(frozen=True)
class Lane:
    """One lane of a lane section (width records relative to the section start)."""

    id: int
    type: str
    widths: tuple[Cubic, ...]
    predecessors: tuple[int, ...]
    successors: tuple[int, ...]

    def width(self, ds: np.ndarray | float) -> np.ndarray:
        return _piecewise(list(self.widths), ds)


@dataclass(frozen=True)
class LaneSection:
    """A ``<laneSection>``: its start and lanes by id (centre lane excluded)."""

    s: float
    lanes: dict[int, Lane]


def _offset(x: float, y: float, z: float, heading: float, t: float) -> tuple[float, float, float]:
    return x - math.sin(heading) * t, y + math.cos(heading) * t, z


@dataclass
class XodrRoad:
    """A road: plan view, elevation, lane offset, lane sections and links."""

    id: str
    name: str
    length: float
    junction: str
    geometry: list[PlanGeometry]
    elevation: list[Cubic]
    lane_offset: list[Cubic]
    sections: list[LaneSection]
    predecessor: tuple[str, str, str] | None = None  # (elementType, elementId, contactPoint)
    successor: tuple[str, str, str] | None = None

    def reference(self, s: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(x, y, z, heading) of the reference line at ``s``."""
        s = np.clip(np.atleast_1d(np.asarray(s, dtype=float)), 0.0, self.length)
        starts = np.array([g.s for g in self.geometry])
        idx = np.clip(np.searchsorted(starts, s + 1e-9, side="right") - 1, 0, len(self.geometry) - 1)
        x, y, h = np.empty_like(s), np.empty_like(s), np.empty_like(s)
        for i in np.unique(idx):
            m = idx == i
            x[m], y[m], h[m] = self.geometry[i].evaluate(s[m])
        return x, y, _piecewise(self.elevation, s), h

    def section_at(self, s: float, at_end: bool = False) -> LaneSection:
        """The lane section holding ``s`` (the one ending there when ``at_end``)."""
        best = self.sections[0]
        for sec in self.sections:
            if sec.s < s - 1e-9 or (not at_end and abs(sec.s - s) <= 1e-9):
                best = sec
        return best

    def lane_t(self, lane_id: int, s: float, at_end: bool = False) -> tuple[float, float] | None:
        """Lateral (inner, outer) border offsets of a lane at ``s``; ``None`` if absent."""
        sec = self.section_at(s, at_end)
        if lane_id not in sec.lanes:
            return None
        ds = s - sec.s
        sign = 1 if lane_id > 0 else -1
        t = float(_piecewise(self.lane_offset, s)[0])
        inner = t
        for k in range(1, abs(lane_id) + 1):
            lane = sec.lanes.get(sign * k)
            if lane is None:
                return None
            w = float(lane.width(ds)[0])
            inner, t = t, t + sign * w
        return inner, t

    def lane_point(self, lane_id: int, s: float, at_end: bool = False
                   ) -> tuple[float, float, float, float] | None:
        """(x, y, z, heading) of a lane's centre line at ``s``."""
        # tangent by a one-sided three-point difference (exact for quadratics):
        # a two-point difference reads the mean slope over the step and errs by
        # ~0.5 deg where inner lanes taper with cubic widths up to the link
        h = min(0.02, self.length / 8)
        step = -h if at_end or s >= self.length - 1e-9 else h
        stations = [s] + [min(max(s + k * step, 0.0), self.length) for k in (1, 2)]
        borders = [self.lane_t(lane_id, si, at_end) for si in stations]
        if borders[0] is None:
            return None
        x, y, z, hd = self.reference(np.array(stations))  # the three stations in one evaluation
        pts = [None if bt is None else _offset(float(x[i]), float(y[i]), float(z[i]), float(hd[i]),
                                               0.5 * (bt[0] + bt[1]))
               for i, bt in enumerate(borders)]
        p, a, b = pts
        if a is None or b is None:
            return (*p, float("nan"))
        dx = (-3 * p[0] + 4 * a[0] - b[0]) * math.copysign(1, step)
        dy = (-3 * p[1] + 4 * a[1] - b[1]) * math.copysign(1, step)
        return (*p, math.atan2(dy, dx))


@dataclass(frozen=True)
class XodrConnection:
    """A junction connection with its lane links ``(from, to)``."""

    id: str
    incoming: str
    connecting: str
    contact_point: str
    lane_links: tuple[tuple[int, int], ...]


@dataclass(frozen=True)
class XodrJunction:
    id: str
    type: str
    connections: tuple[XodrConnection, ...]


@dataclass
class XodrNetwork:
    """A parsed OpenDRIVE file."""

    version: tuple[int, int]
    header: dict[str, str]
    roads: dict[str, XodrRoad] = field(default_factory=dict)
    junctions: dict[str, XodrJunction] = field(default_factory=dict)
    source: str | None = None


def _number(text: str, name: str) -> float:
    """A finite number from an attribute (``nan``/``inf`` have no place in a road network)."""
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f"{name}={text!r} is not a finite number")
    return value


def _f(el, name: str, default: float = 0.0) -> float:
    v = el.get(name)
    return _number(v, name) if v is not None else default


def _cubic(el, s_attr: str = "s") -> Cubic:
    return Cubic(_f(el, s_attr), _f(el, "a"), _f(el, "b"), _f(el, "c"), _f(el, "d"))


def _link(el) -> tuple[str, str, str] | None:
    if el is None:
        return None
    return (el.get("elementType", "road"), el.get("elementId", ""), el.get("contactPoint", ""))


def _strip_ns(root) -> None:
    for el in root.iter():
        if isinstance(el.tag, str) and "}" in el.tag:
            el.tag = el.tag.split("}", 1)[1]


def _road(el) -> XodrRoad:
    geoms = []
    for g in el.findall("planView/geometry"):
        child = next(iter(g), None)
        if child is None:
            continue
        params = {k: _number(v, k) for k, v in child.attrib.items() if k != "pRange"}
        if child.tag == "paramPoly3":
            params["normalized"] = 0.0 if child.get("pRange") == "arcLength" else 1.0
        geoms.append(PlanGeometry(_f(g, "s"), _f(g, "x"), _f(g, "y"), _f(g, "hdg"), _f(g, "length"),
                                  child.tag, tuple(sorted(params.items()))))
    elevation = sorted((_cubic(e) for e in el.findall("elevationProfile/elevation")), key=lambda c: c.s)
    offsets = sorted((_cubic(e) for e in el.findall("lanes/laneOffset")), key=lambda c: c.s)
    sections = []
    for ls in el.findall("lanes/laneSection"):
        lanes = {}
        for ln in ls.findall("left/lane") + ls.findall("right/lane"):
            lid = int(ln.get("id"))
            widths = tuple(sorted((_cubic(w, "sOffset") for w in ln.findall("width")), key=lambda c: c.s))
            lanes[lid] = Lane(lid, ln.get("type", ""), widths,
                              tuple(int(p.get("id")) for p in ln.findall("link/predecessor")),
                              tuple(int(p.get("id")) for p in ln.findall("link/successor")))
        sections.append(LaneSection(_f(ls, "s"), lanes))
    sections.sort(key=lambda x: x.s)
    road = XodrRoad(el.get("id"), el.get("name", ""), _f(el, "length"), el.get("junction", "-1"),
                    sorted(geoms, key=lambda g: g.s), elevation, offsets, sections,
                    _link(el.find("link/predecessor")), _link(el.find("link/successor")))
    if not road.geometry or not road.sections:
        raise InputFormatError("road without plan view or lane sections", element=f"road {road.id}")
    return road


def _parser() -> etree.XMLParser:
    """An XML parser for files from anyone: no DTD loading, no entity expansion, no network,
    libxml2's default limits on depth and size (no ``huge_tree``)."""
    return etree.XMLParser(resolve_entities=False, load_dtd=False, no_network=True, huge_tree=False)


def _junction(j) -> XodrJunction:
    conns = []
    for c in j.findall("connection"):
        conns.append(XodrConnection(
            c.get("id", ""), c.get("incomingRoad", ""),
            c.get("connectingRoad") or c.get("linkedRoad") or "", c.get("contactPoint", "start"),
            tuple((int(ll.get("from")), int(ll.get("to"))) for ll in c.findall("laneLink"))))
    return XodrJunction(j.get("id"), j.get("type", "default"), tuple(conns))


def read_xodr(path: str | os.PathLike | IO[bytes]) -> XodrNetwork:
    """Parse an OpenDRIVE file.

    Entities are not expanded and no DTD or other file is fetched, whatever the
    file declares.

    Raises
    ------
    InputFormatError
        Naming the file (and road or junction) when it is not readable OpenDRIVE.
    """
    src = None if hasattr(path, "read") else str(path)
    try:
        root = etree.parse(path, _parser()).getroot()
    except (OSError, etree.XMLSyntaxError) as exc:
        raise InputFormatError(f"not readable XML: {str(exc)[:300]}", source=src) from None
    if root is None:
        raise InputFormatError("not readable XML: no root element", source=src)
    _strip_ns(root)
    if root.tag != "OpenDRIVE" or root.find("header") is None:
        raise InputFormatError("not an OpenDRIVE file (root <OpenDRIVE> with <header>)", source=src)
    head = root.find("header")
    try:
        version = (int(head.get("revMajor", 1)), int(head.get("revMinor", 0)))
    except ValueError as exc:
        raise InputFormatError(f"malformed header version: {str(exc)[:200]}", source=src,
                               element="header") from None
    net = XodrNetwork(version, dict(head.attrib), source=src)
    element = None
    try:
        for el in root.findall("road"):
            element = f"road {el.get('id')}"
            r = _road(el)
            net.roads[r.id] = r
        for j in root.findall("junction"):
            element = f"junction {j.get('id')}"
            junction = _junction(j)
            net.junctions[junction.id] = junction
    except InputFormatError as exc:
        raise exc.located(src or "<memory>") from None
    except (TypeError, ValueError, OverflowError) as exc:
        raise InputFormatError(f"malformed {element.split()[0]}: {str(exc)[:200]}", source=src,
                               element=element[:200]) from None
    return net
