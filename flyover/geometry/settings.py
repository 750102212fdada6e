"""What the layout is told: its settings (config ``geometry``) and one ramp's targets.

Decides nothing; every other layout module reads these values.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

from flyover.errors import FlyoverError
from flyover.geometry.fit import FitSettings

__all__ = ["GeometryError", "LayoutSettings", "RampFeatures", "Z_MARGIN"]

#: m kept beyond the clearance where levels are planned
Z_MARGIN = 0.5


class GeometryError(FlyoverError):
    """A topology cannot be laid out (e.g. a ramp with neither start nor end)."""


@dataclass(frozen=True)
class LayoutSettings:
    """Layout settings (config ``geometry``)."""

    lane_width_m: float = 3.75
    shoulder_width_m: float = 2.5
    ramp_lane_width_m: float = 4.0
    median_m: float = 4.0
    level_height_m: float = 6.5
    levels: int = 4
    default_lanes: int = 2
    crossing_margin_m: float = 15.0
    gap_m: float = 40.0
    reach_m: float = 1500.0
    terminal_m: float = 120.0
    road_margin_m: float = 100.0
    cd_clear_m: float = 350.0
    #: a collector-distributor road runs this far (m) beside its carriageway's edge
    cd_offset_m: float = 10.0
    stub_window_m: float = 200.0
    turn_room: float = 2.0
    leads: bool = True
    lead_min_m: float = 60.0
    max_resamples: int = 3
    restarts: int = 5
    #: whole-interchange rebuilds with other DE seeds while a ramp still meets something
    #: or an outer connector goes over or under its loop
    rebuilds: int = 3
    #: a ramp attaches to a road no farther beyond the room it keeps from the crossing
    #: than (1 + length_margin) × what it needs (:meth:`RampSpecs.need_m`: its turn at its
    #: radius or its climb at its slope, and its two tapers); ``None``: anywhere within
    #: ``reach_m`` (ramps then wander: a long detour costs the search less than a conflict)
    length_margin: float | None = 0.5
    #: the longest ramp a feature set may ask for (m; real ramps: median ~570 m, longest
    #: ~1.6 km in ../shared/osm): a (radius, slope) whose turn or climb needs more is no
    #: combination sampling offers that ramp (:func:`flyover.geometry.feasibility.forbidden_features`)
    max_ramp_length_m: float = 1500.0
    #: a fitted ramp is no longer than this many times the least it needs (its plan between
    #: its windows at its radius, its turn, its climb to its crest and down at its slope),
    #: and its two tapers (``gap_m`` each); longer is not ok (resampled or recorded, never
    #: stretched; :meth:`flyover.geometry.specs.RampSpecs.least_m`); ``None``: unbounded
    max_length_ratio: float | None = 2.5
    #: a loop an outer connector goes round is an obstacle at every height except within
    #: this far (m) of its ends, where both run beside their shared road
    keep_out_trim_m: float = 40.0
    fit: FitSettings = field(default_factory=FitSettings)

    @classmethod
    def from_config(cls, cfg: Mapping) -> "LayoutSettings":
        """From the ``geometry`` section of the workflow config."""
        de = dict(cfg.get("de", {}))
        fit = FitSettings(**{k: v for k, v in de.items() if k in FitSettings.__dataclass_fields__},
                          clearance_m=float(cfg.get("clearance_m", 5.5)))
        keys = set(cls.__dataclass_fields__) - {"fit"}
        return cls(**{k: v for k, v in cfg.items() if k in keys}, fit=fit)

    @property
    def levels_m(self) -> tuple[float, ...]:
        return tuple(i * self.level_height_m for i in range(self.levels))


@dataclass(frozen=True)
class RampFeatures:
    """Targets of one ramp: minimum radius (may be ``inf``) and maximum slope."""

    radius_m: float
    slope_pct: float
