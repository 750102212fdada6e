"""The ``truck_fuel`` plugin object (entry point ``flyover.plugins: truck_fuel``).

One row per ramp of an interchange (table ``fuel``)::

    class_id, sample, ramp, direction (up|down|level), length_m, min_radius_m,
    max_slope_pct, climb_m, target_speed_mps, mean_speed_mps, duration_s,
    fuel_ml, fuel_ml_per_km, max_lateral_error_m, max_lateral_accel_mps2,
    completed, reason

``length_m``, ``min_radius_m``, ``max_slope_pct`` and ``climb_m`` are of the
lane centre line the truck follows; ``max_lateral_error_m`` is the largest
distance between the truck and its plan on the ramp; a ramp the truck cannot
drive within its limits has ``completed = False`` and the ``reason`` (the
figures then cover the part driven).
"""

from __future__ import annotations

import logging
from typing import Any, Mapping

from flyover_truck_fuel import __version__
from flyover_truck_fuel.params import Settings, config_schema, settings

__all__ = ["TruckFuelPlugin", "COLUMNS", "fuel_schema", "evaluate_ramp", "direction"]

log = logging.getLogger(__name__)

COLUMNS = ("class_id", "sample", "ramp", "direction", "length_m", "min_radius_m",
           "max_slope_pct", "climb_m", "target_speed_mps", "mean_speed_mps", "duration_s",
           "fuel_ml", "fuel_ml_per_km", "max_lateral_error_m", "max_lateral_accel_mps2",
           "completed", "reason")


def fuel_schema():
    """The :class:`pyarrow.Schema` of the rows."""
    import pyarrow as pa  # noqa: PLC0415

    types = {"class_id": pa.string(), "sample": pa.int64(), "ramp": pa.string(),
             "direction": pa.string(), "completed": pa.bool_(), "reason": pa.string()}
    return pa.schema([(c, types.get(c, pa.float64())) for c in COLUMNS])


def direction(climb_m: float, tolerance_m: float) -> str:
    """``up``, ``down`` or ``level`` for a net height change ``climb_m``.

    >>> direction(6.5, 0.5), direction(-0.2, 0.5)
    ('up', 'level')
    """
    if climb_m > tolerance_m:
        return "up"
    if climb_m < -tolerance_m:
        return "down"
    return "level"


def evaluate_ramp(geometry, ramp, st: Settings) -> dict[str, Any]:
    """The row of one ramp (never raises for a ramp the truck cannot drive)."""
    from flyover_truck_fuel.route import ramp_route  # noqa: PLC0415
    from flyover_truck_fuel.simulate import drive, ramp_summary  # noqa: PLC0415

    row: dict[str, Any] = {"class_id": geometry.class_id, "sample": int(geometry.sample),
                           "ramp": ramp.id,
                           "target_speed_mps": st.planner.preferred_speed_mps}
    try:
        route = ramp_route(geometry, ramp, st.route)
    except Exception as exc:  # noqa: BLE001 - a malformed ramp is a row, not a crash
        log.warning("%s/%s ramp %s: no route: %s", geometry.class_id, geometry.sample,
                    ramp.id, exc)
        row.update(direction=None, length_m=ramp.length_m, completed=False,
                   reason=f"no route: {type(exc).__name__}: {exc}")
        return row
    row.update(direction=direction(route.climb_m, st.route.level_tolerance_m),
               length_m=route.ramp_length_m, min_radius_m=route.min_radius_m,
               max_slope_pct=route.max_slope_pct, climb_m=route.climb_m)
    try:
        s = ramp_summary(route, drive(route, st))
    except Exception as exc:  # noqa: BLE001
        log.exception("%s/%s ramp %s: simulation failed", geometry.class_id,
                      geometry.sample, ramp.id)
        row.update(completed=False, reason=f"simulation failed: {type(exc).__name__}: {exc}")
        return row
    row.update(mean_speed_mps=s.mean_speed_mps, duration_s=s.duration_s, fuel_ml=s.fuel_ml,
               fuel_ml_per_km=s.fuel_ml_per_km, max_lateral_error_m=s.max_lateral_error_m,
               max_lateral_accel_mps2=s.max_lateral_accel_mps2, completed=s.completed,
               reason=s.reason)
    if not s.completed:
        log.info("%s/%s ramp %s not completed: %s", geometry.class_id, geometry.sample,
                 ramp.id, s.reason)
    return row


class TruckFuelPlugin:
    """Fuel of a 40 t articulated truck on every ramp (see the package README)."""

    name = "truck_fuel"
    version = __version__
    table = "fuel"

    def config_schema(self) -> Mapping[str, Any]:
        return config_schema()

    def schema(self):
        return fuel_schema()

    def evaluate(self, geometry, config: Mapping[str, Any]) -> list[dict[str, Any]]:
        """One row per ramp of ``geometry`` (an :class:`~flyover.geometry.model.InterchangeGeometry`)."""
        st = settings(config)
        return [evaluate_ramp(geometry, ramp, st) for ramp in geometry.ramps]

    def failure_rows(self, class_id: str, sample: int, reason: str) -> list[dict[str, Any]]:
        """The row recording an interchange that could not be evaluated at all."""
        return [{"class_id": class_id, "sample": int(sample), "ramp": "", "direction": None,
                 "completed": False, "reason": reason}]
