"""The paper's Table IV: fuel on single ramps over radius × slope, up and down.

Each grid ramp is a 90° curve of lane-centre radius ``R`` entered and left
through clothoids of length ``R/3`` (parameter ``A = R/√3``, within the
``R/3 ≤ A ≤ R`` of road design guidelines such as the German RAL) at a
constant grade ``±slope`` (its length is ``πR/2 + R/3``, so a larger radius
is a longer ramp),
between straight leads at the same grade; the truck enters at the preferred
speed (10 m/s). Both the fuel per ramp and per kilometre are reported: the
first grows with the radius because the ramp does, the second isolates
what the curve itself costs (slowing down where the lateral-acceleration
limit binds, tyre slip drag).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from flyover_truck_fuel.params import Settings
from flyover_truck_fuel.route import straight_route
from flyover_truck_fuel.simulate import drive, ramp_summary

__all__ = ["PAPER_RADII_M", "PAPER_SLOPES_PCT", "GridCell", "fuel_grid", "plot_grid"]

#: radii and slopes of the paper's Table IV
PAPER_RADII_M = (30.0, 40.0, 60.0, 100.0, 150.0, 210.0, 280.0)
PAPER_SLOPES_PCT = (1.0, 2.0, 3.0, 4.0)


@dataclass(frozen=True)
class GridCell:
    """One grid ramp's result."""

    radius_m: float
    slope_pct: float
    direction: str
    length_m: float
    fuel_ml: float
    fuel_ml_per_km: float
    mean_speed_mps: float
    max_lateral_accel_mps2: float
    max_lateral_error_m: float
    completed: bool
    reason: str


def fuel_grid(st: Settings, radii=PAPER_RADII_M, slopes=PAPER_SLOPES_PCT,
              turn_rad: float = 0.5 * math.pi) -> list[GridCell]:
    """Drive every grid ramp (up and down) and return one :class:`GridCell` each."""
    out = []
    for sign, direction in ((1.0, "up"), (-1.0, "down")):
        for r in radii:
            for sl in slopes:
                route = straight_route(r * turn_rad + r / 3.0, sign * sl / 100.0, st.route,
                                       radius_m=r, transition_m=r / 3.0)
                s = ramp_summary(route, drive(route, st))
                out.append(GridCell(r, sl, direction, route.ramp_length_m, s.fuel_ml,
                                    s.fuel_ml_per_km, s.mean_speed_mps,
                                    s.max_lateral_accel_mps2, s.max_lateral_error_m,
                                    s.completed, s.reason))
    return out


def plot_grid(cells: list[GridCell], path) -> None:
    """Heatmaps (rows: up, down; columns: ml per ramp, ml/km) of a grid, as PNG."""
    import matplotlib  # noqa: PLC0415

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415
    import numpy as np  # noqa: PLC0415

    radii = sorted({c.radius_m for c in cells})
    slopes = sorted({c.slope_pct for c in cells})
    fig, axes = plt.subplots(2, 2, figsize=(11, 7), constrained_layout=True)
    for i, direction in enumerate(("up", "down")):
        for j, (attr, unit) in enumerate((("fuel_ml", "ml per ramp"),
                                          ("fuel_ml_per_km", "ml/km"))):
            m = np.full((len(slopes), len(radii)), np.nan)
            for c in cells:
                if c.direction == direction:
                    m[slopes.index(c.slope_pct), radii.index(c.radius_m)] = getattr(c, attr)
            ax = axes[i, j]
            im = ax.imshow(m, origin="lower", aspect="auto", cmap="viridis")
            ax.set_xticks(range(len(radii)), [f"{r:g}" for r in radii])
            ax.set_yticks(range(len(slopes)), [f"{s:g}" for s in slopes])
            ax.set_xlabel("radius (m)")
            ax.set_ylabel("slope (%)")
            ax.set_title(f"{direction}: {unit}")
            for (yy, xx), v in np.ndenumerate(m):
                ax.text(xx, yy, f"{v:.0f}", ha="center", va="center", color="w", fontsize=8)
            fig.colorbar(im, ax=ax, shrink=0.8)
    fig.suptitle("40 t truck at 10 m/s on a 90° ramp: fuel by radius and slope")
    fig.savefig(path, dpi=110)
    plt.close(fig)
