"""Demand: one flow of passenger cars per entrance → exit movement.

The movements are the topology's (:func:`flyover.opendrive.validate.movements`,
the same ones the ``routes`` validation routes), found on the SUMO network
through the OpenDRIVE file it was converted from (road ``name`` = topology
element; :func:`flyover.sumo.routes.road_edges`). U-turns back onto the
entrance's own expressway are left out unless asked for. Going straight on
follows the road's own edges (the shortest path could take a collector-
distributor road that leaves and rejoins it); a turn takes the shortest path.
A movement without a
route in the network is a :class:`DemandError`: the experiment is never
silently smaller than the topology.

Without a ``geometry.json`` (any SUMO network), every entry edge (no incoming
edge) is paired with every exit edge (no outgoing edge) it reaches.
"""

from __future__ import annotations

import logging
import os
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import quoteattr

from flyover.errors import FlyoverError
from flyover.traffic.settings import Arrivals, ThroughputSettings

__all__ = ["DemandError", "Flow", "interchange_flows", "network_flows", "interchange_or_network_flows",
           "routes_xml"]

log = logging.getLogger(__name__)


class DemandError(FlyoverError):
    """The demand cannot be built: a movement without a route, or no movement at all."""


@dataclass(frozen=True)
class Flow:
    """One movement's flow: a name (``A1->B2``) and its SUMO route (edge ids)."""

    movement: str
    edges: tuple[str, ...]


def _net(path: str | os.PathLike):
    import sumolib  # noqa: PLC0415

    try:
        return sumolib.net.readNet(str(path), withInternal=False)
    except Exception as exc:  # sumolib raises whatever its XML parser does
        raise DemandError(f"cannot read SUMO network: {exc}", source=str(path)) from None


def interchange_flows(net_path: str | os.PathLike, geometry, xodr_path: str | os.PathLike, *,
                      uturns: bool = False) -> list[Flow]:
    """One flow per movement of the interchange ``geometry`` (an ``InterchangeGeometry``).

    ``xodr_path`` is the OpenDRIVE file the network was converted from. Raises
    :class:`DemandError` naming every movement without a route.
    """
    from flyover.opendrive.reader import read_xodr  # noqa: PLC0415
    from flyover.opendrive.validate import movements  # noqa: PLC0415
    from flyover.sumo.routes import road_edges  # noqa: PLC0415

    moves = movements(geometry)
    if not uturns:
        way = {r.id: r.expressway for r in geometry.roads}
        moves = [(u, v) for u, v in moves if u == v or way[u] != way[v]]
    if not moves:
        raise DemandError("the interchange allows no movement", source=str(net_path))
    xodr = read_xodr(xodr_path)
    first = {r.name: r.id for r in xodr.roads.values() if r.junction == "-1" and r.predecessor is None}
    last = {r.name: r.id for r in xodr.roads.values() if r.junction == "-1" and r.successor is None}
    name = {r.id: r.name for r in xodr.roads.values()}
    net = _net(net_path)
    edges = road_edges(net)
    element = {e.getID(): name.get(rid) for rid, es in edges.items() for e in es}
    flows, missing = [], []
    for u, v in moves:
        a, b = edges.get(first.get(u, "?")), edges.get(last.get(v, "?"))
        if not (a and b):
            path = None
        elif u == v:  # straight on: along the road itself, never round a ramp that rejoins it
            path = _along(a[0], b[-1], u, element)
        else:
            path = net.getShortestPath(a[0], b[-1])[0]
        if path is None:
            missing.append(f"{u}->{v}")
            continue
        flows.append(Flow(f"{u}->{v}", tuple(e.getID() for e in path)))
    if missing:
        raise DemandError(f"{len(missing)} of {len(moves)} movements have no route in the "
                          f"network: {', '.join(missing)}", source=str(net_path),
                          element=missing[0])
    return flows


def _along(start, end, road: str, element: dict[str, str | None]):
    """The edges from ``start`` to ``end`` that stay on the topology element ``road``."""
    path, e, seen = [start], start, {start.getID()}
    while e is not end:
        nxt = sorted((x for x in e.getOutgoing() if element.get(x.getID()) == road
                      and x.getID() not in seen), key=lambda x: x.getID())
        if not nxt:
            return None
        e = nxt[0]
        seen.add(e.getID())
        path.append(e)
    return path


def network_flows(net_path: str | os.PathLike) -> list[Flow]:
    """Any SUMO network: one flow from every entry edge to every exit edge it reaches."""
    net = _net(net_path)
    es = sorted(net.getEdges(), key=lambda e: e.getID())
    sources = [e for e in es if not e.getIncoming()]
    sinks = [e for e in es if not e.getOutgoing()]
    flows = []
    for s in sources:
        for t in sinks:
            path = net.getShortestPath(s, t)[0]
            if path is not None:
                flows.append(Flow(f"{s.getID()}->{t.getID()}", tuple(e.getID() for e in path)))
    if not flows:
        raise DemandError("no entry edge reaches an exit edge", source=str(net_path))
    return flows


def interchange_or_network_flows(net_path: str | os.PathLike, *, uturns: bool = False
                                 ) -> tuple[list[Flow], str]:
    """Flows of the interchange beside ``net_path`` (``geometry.json`` and
    ``interchange.xodr`` in its folder), else of the bare network; and which it was."""
    from flyover.geometry.model import read_geometry  # noqa: PLC0415

    folder = Path(net_path).parent
    geo, xodr = folder / "geometry.json", folder / "interchange.xodr"
    if geo.exists() and xodr.exists():
        return interchange_flows(net_path, read_geometry(geo), xodr, uturns=uturns), "topology"
    log.info("%s: no geometry.json and interchange.xodr beside it: every entry to every exit",
             net_path)
    return network_flows(net_path), "network"


def routes_xml(flows: list[Flow], density: float, settings: ThroughputSettings) -> str:
    """A SUMO route file: one ``<flow>`` of ``density`` veh/h per movement for the whole run.

    Passenger cars (SUMO's default ``passenger`` class, 1 pcu), inserted on
    ``settings.depart_lane`` at ``settings.depart_speed``.
    """
    rate = float(density) / 3600.0
    spacing = (f'period="exp({rate!r})"' if settings.arrivals is Arrivals.POISSON
               else f'vehsPerHour="{float(density)!r}"')
    lines = ['<routes xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance">',
             '    <vType id="car" vClass="passenger"/>']
    for i, f in enumerate(flows):
        lines.append(f'    <route id="m{i}" edges="{" ".join(f.edges)}"/>')
    for i, f in enumerate(flows):
        lines.append(f'    <flow id="m{i}" name={quoteattr(f.movement)} type="car" route="m{i}" '
                     f'begin="0" end="{float(settings.duration_s)!r}" {spacing} '
                     f'departLane="{settings.depart_lane.value}" '
                     f'departSpeed="{settings.depart_speed}"/>')
    lines.append("</routes>")
    return "\n".join(lines) + "\n"
