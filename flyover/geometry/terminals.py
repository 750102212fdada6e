"""Room at a T's terminal: where the two branches a carriageway ends (begins) in keep apart.

A T's terminating carriageway ends by splitting into a ramp straight on (Out-M, a left
turn that flies over) and one on its right at its very end (Out-R at ``pos`` 1, the right
turn); the carriageway of the other direction begins where they merge (In-M and In-R at
``pos`` 0). Both branches start at the carriageway's height, side by side: until they are
a clearance apart in height, neither may swing across to the other's side of the
carriageway's right edge (a left turn wiggling out to the right to gain height leaves its
sibling right turn, fitted after it, no room to leave; a right turn first bulging left
runs into the left turn's lanes), and the straight one not across the median either (the
other carriageway's terminal lies beyond it: directional_t's rA2, coming into B2 along its
axis, swung across into rL's and rR's way). :func:`terminal_fences` gives each branch
fences on those sides for that distance (:attr:`flyover.geometry.fit.Obstacles.lines` rows
without their height; the layout keeps them out at every height, and the build loop
drops them when the ramp cannot meet its targets within them, as the loop fences of
:mod:`flyover.geometry.loop_room`).
"""

from __future__ import annotations

import math
from typing import Mapping

import numpy as np

from flyover.geometry.chains import Movements, ends
from flyover.geometry.profile import parting_distance
from flyover.geometry.settings import LayoutSettings, RampFeatures
from flyover.topology.model import Label

__all__ = ["terminal_fences"]


def _branches(moves: Movements, road: str, leaving: bool) -> dict[str, Label]:
    """The ramps a carriageway ends in (``leaving``) or begins from, at its terminal:
    straight on, or on its right at its very end (start)."""
    g = moves.g
    edges = g.out_edges(road, data=True) if leaving else g.in_edges(road, data=True)
    out = {}
    for u, v, d in edges:
        label, pos = d["label"], d.get("pos")
        at_end = pos is not None and (pos >= 0.99 if leaving else pos <= 0.01)
        if label in (Label.OUT_M, Label.IN_M) or (label in (Label.OUT_R, Label.IN_R) and at_end):
            out[v if leaving else u] = label
    return out


def terminal_fences(moves: Movements, features: Mapping[str, RampFeatures],
                    st: LayoutSettings, ramp: str) -> list[tuple[float, ...]]:
    """Fences (road-frame bands ``x0, y0, dx, dy, t_lo, t_hi, lat_lo, lat_hi``) keeping
    ``ramp``, one branch of a T's terminal, off its sibling's side of the carriageway's
    right edge (the straight branch also off the median side of its left edge) for as far
    beyond (before) the terminal as the two need to be a clearance apart in height at
    their slope targets (:attr:`FitSettings.clearance_m` over the sum of their grades, and
    a grade transition). Empty for any other ramp."""
    out = []
    for end, leaving in zip(ends(moves.topo, ramp), (True, False)):
        if end is None or end[0] not in moves.roads:
            continue
        road = moves.roads[end[0]]
        t_end = road.t_hi if leaving else road.t_lo
        if not np.isfinite(t_end):
            continue
        branches = _branches(moves, end[0], leaving)
        if ramp not in branches or len(branches) < 2:
            continue
        siblings = [k for k in branches if k != ramp and k in features]
        if not siblings or ramp not in features:
            continue
        g = (features[ramp].slope_pct + min(features[k].slope_pct for k in siblings)) / 100.0
        reach = parting_distance(g, st.fit.clearance_m, st.fit.transition_m)
        edge = road.lanes * st.lane_width_m
        straight = branches[ramp] in (Label.OUT_M, Label.IN_M)
        # the straight one keeps within the carriageway's edges (off the median: the
        # other carriageway's terminal lies across it), the right one right of them
        lats = [(-1e4, -edge - 0.5), (0.5, 1e4)] if straight else [(-edge + 0.5, 1e4)]
        along = (t_end, t_end + reach) if leaving else (t_end - reach, t_end)
        out += [(road.origin[0], road.origin[1], math.cos(road.heading),
                 math.sin(road.heading), *along, *lat) for lat in lats]
    return out
