"""Assembly: the fitted ramps and the laid-out roads as the ``geometry.json`` value.

Decides each road's extent (every attachment and ramp covered, with
``road_margin_m``) and each ramp's attachment stations measured from its road's
start (an attachment off its road is a :class:`GeometryError`); reads the layout
state and the build loop's outcomes.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Sequence

import numpy as np

from flyover.geometry.chains import wrap as _wrap
from flyover.geometry.model import Attachment, InterchangeGeometry, RampGeometry, RoadGeometry
from flyover.geometry.settings import GeometryError

if TYPE_CHECKING:
    from flyover.geometry.build import RampOutcome
    from flyover.geometry.state import LayoutState

__all__ = ["assemble"]


def assemble(b: "LayoutState", class_id: str, sample: int, seed: int,
             outcomes: Sequence["RampOutcome"]) -> InterchangeGeometry:
    """The ``geometry.json`` value of one build."""
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
    length: dict[str, float] = {}
    roads = []
    for r in sorted(b.roads.values(), key=lambda r: r.id):
        lo = r.t_lo if np.isfinite(r.t_lo) else -extent
        hi = r.t_hi if np.isfinite(r.t_hi) else extent
        t0[r.id], length[r.id] = lo, hi - lo
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
            if rail.parent in b.roads and not -0.01 <= s_m <= length[rail.parent] + 0.01:
                raise GeometryError(f"attachment at s={s_m:.2f} m is off {rail.parent} "
                                    f"(0..{length[rail.parent]:.2f} m)",
                                    source=b.topo.source, element=o.ramp)
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
