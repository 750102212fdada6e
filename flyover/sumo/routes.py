"""Routability of entrance → exit movements in a SUMO network (sumolib).

netconvert names the edges of OpenDRIVE road ``N`` ``-N`` (or ``-N#k`` when
lane sections split it); :func:`road_edges` maps them back.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass

import sumolib

__all__ = ["Movement", "road_edges", "check_routes", "generic_routes"]

_EDGE = re.compile(r"^-?(?P<road>[^#]+?)(?:#(?P<k>\d+))?$")


@dataclass(frozen=True)
class Movement:
    """Enter at the start of OpenDRIVE road ``from_road``, leave at the end of ``to_road``."""

    name: str
    from_road: str
    to_road: str


def _net(path: str | os.PathLike):
    return sumolib.net.readNet(str(path), withInternal=False)


def road_edges(net) -> dict[str, list]:
    """OpenDRIVE road id → its SUMO edges in travel order."""
    out: dict[str, list] = {}
    for e in net.getEdges():
        m = _EDGE.match(e.getID())
        if m:
            out.setdefault(m["road"], []).append((int(m["k"] or 0), e))
    return {k: [e for _, e in sorted(v, key=lambda t: t[0])] for k, v in out.items()}


def check_routes(net_path: str | os.PathLike, movements: list[Movement]) -> tuple[bool, str, list[str]]:
    """``(ok, detail, failed movement names)``: is every movement routable?"""
    net = _net(net_path)
    edges = road_edges(net)
    failed = []
    for m in movements:
        a, b = edges.get(m.from_road), edges.get(m.to_road)
        if not a or not b:
            failed.append(m.name)
            continue
        path, _ = net.getShortestPath(a[0], b[-1])
        if path is None:
            failed.append(m.name)
    detail = f"{len(movements) - len(failed)}/{len(movements)} movements routable"
    if failed:
        detail += "; not: " + ", ".join(failed[:8])
    return not failed, detail, failed


def generic_routes(net_path: str | os.PathLike) -> tuple[bool, str]:
    """For any network: every source edge reaches some sink edge and vice versa."""
    net = _net(net_path)
    es = net.getEdges()
    sources = [e for e in es if not e.getIncoming()]
    sinks = [e for e in es if not e.getOutgoing()]
    reach = {e.getID(): net.getReachable(e) for e in sources}
    bad_src = [s.getID() for s in sources if not any(t in reach[s.getID()] for t in sinks)]
    bad_sink = [t.getID() for t in sinks if not any(t in r for r in reach.values())]
    ok = not bad_src and not bad_sink and bool(es)
    detail = (f"{len(sources)} entry and {len(sinks)} exit edges; "
              f"{len(bad_src)} entries reach no exit, {len(bad_sink)} exits unreachable")
    return ok, detail
