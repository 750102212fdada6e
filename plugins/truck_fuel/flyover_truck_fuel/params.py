"""Parameters of the truck, its engine and its driver, from the plugin's config section.

The single source of default values (and of each one's source) is
``config.schema.yaml`` beside this module; :func:`settings` validates a config
section against it and returns frozen values.

Example
-------
>>> s = settings({})
>>> s.truck.mass_kg, s.planner.preferred_speed_mps
(40000.0, 10.0)
>>> round(s.truck.lf_m + s.truck.lr_m, 3) == s.truck.wheelbase_m
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from functools import lru_cache
from pathlib import Path
from typing import Any, Mapping

import yaml

__all__ = ["G", "TruckParams", "EngineParams", "PlannerParams", "ControlParams",
           "RouteParams", "Settings", "config_schema", "settings"]

#: standard gravity (m/s²)
G = 9.81


@lru_cache(maxsize=1)
def config_schema() -> dict[str, Any]:
    """The JSON schema of the ``plugins.truck_fuel`` config section (with defaults)."""
    return yaml.safe_load((Path(__file__).parent / "config.schema.yaml").read_text("utf-8"))


def _build(cls, d: Mapping[str, Any]):
    names = {f.name for f in fields(cls)}
    return cls(**{k: (tuple(v) if isinstance(v, list) else v) for k, v in d.items() if k in names})


@dataclass(frozen=True)
class TruckParams:
    """40 t articulated truck: longitudinal resistances, a lumped single-track model and
    its steering actuator (first-order lag)."""

    mass_kg: float
    rotating_mass_factor: float
    cd_a_m2: float
    rolling_resistance: float
    air_density_kg_m3: float
    driveline_efficiency: float
    max_power_kw: float
    drive_axle_load_kg: float
    max_brake_decel_mps2: float
    wheelbase_m: float
    front_axle_load_kg: float
    cornering_coefficient_per_rad: float
    tyre_friction: float
    max_steer_rad: float
    steer_lag_s: float
    min_turn_radius_m: float

    @property
    def lf_m(self) -> float:
        """Distance centre of gravity → front axle (from the front axle's load share)."""
        return self.wheelbase_m * (1.0 - self.front_axle_load_kg / self.mass_kg)

    @property
    def lr_m(self) -> float:
        """Distance centre of gravity → (lumped) rear axle."""
        return self.wheelbase_m * self.front_axle_load_kg / self.mass_kg

    @property
    def yaw_inertia_kgm2(self) -> float:
        """Yaw inertia with a dynamic index of one (``m·lf·lr``)."""
        return self.mass_kg * self.lf_m * self.lr_m

    @property
    def front_load_n(self) -> float:
        return self.mass_kg * G * self.lr_m / self.wheelbase_m

    @property
    def rear_load_n(self) -> float:
        return self.mass_kg * G * self.lf_m / self.wheelbase_m

    @property
    def cf_n_per_rad(self) -> float:
        """Front-axle cornering stiffness."""
        return self.cornering_coefficient_per_rad * self.front_load_n

    @property
    def cr_n_per_rad(self) -> float:
        """Lumped rear cornering stiffness."""
        return self.cornering_coefficient_per_rad * self.rear_load_n

    @property
    def max_traction_n(self) -> float:
        """Adhesion limit of the drive axle."""
        return self.tyre_friction * self.drive_axle_load_kg * G

    def resistance_n(self, v: float, grade: float = 0.0) -> float:
        """Rolling + air + grade resistance at speed ``v`` and grade ``grade`` (rise/run)."""
        th = math.atan(grade)
        return (self.rolling_resistance * self.mass_kg * G * math.cos(th)
                + 0.5 * self.air_density_kg_m3 * self.cd_a_m2 * v * v
                + self.mass_kg * G * math.sin(th))


@dataclass(frozen=True)
class EngineParams:
    """Willans-line diesel engine with idle consumption and overrun fuel cut-off."""

    willans_efficiency: float
    friction_mep_bar: float
    displacement_l: float
    engine_speed_rpm: float
    aux_power_kw: float
    idle_fuel_l_per_h: float
    cutoff_speed_mps: float
    lhv_mj_per_kg: float
    fuel_density_kg_per_l: float

    @property
    def friction_power_w(self) -> float:
        """Willans offset ``P_0 = p_me0 · V_d · n / 2`` (four-stroke) at the cruise speed."""
        return (self.friction_mep_bar * 1e5 * self.displacement_l * 1e-3
                * self.engine_speed_rpm / 60.0 / 2.0)

    @property
    def ml_per_joule(self) -> float:
        """Millilitres of fuel per joule of fuel energy."""
        return 1.0 / (self.lhv_mj_per_kg * 1e6) / self.fuel_density_kg_per_l * 1e3

    @property
    def idle_ml_per_s(self) -> float:
        return self.idle_fuel_l_per_h * 1000.0 / 3600.0


@dataclass(frozen=True)
class PlannerParams:
    """Lattice planner: preferred speed, hard limits, sampled end states, cost weights."""

    preferred_speed_mps: float
    max_lateral_accel_mps2: float
    max_accel_mps2: float
    max_decel_mps2: float
    min_speed_mps: float
    lateral_offsets_m: tuple[float, ...]
    speed_fractions: tuple[float, ...]
    horizons_s: tuple[float, ...]
    replan_s: float
    weight_deviation: float
    weight_lateral_jerk: float
    weight_longitudinal_jerk: float
    weight_speed: float


@dataclass(frozen=True)
class ControlParams:
    """LQR weights and the control period."""

    step_s: float
    lateral_q: tuple[float, ...]
    lateral_r: float
    speed_q: tuple[float, ...]
    speed_r: float


@dataclass(frozen=True)
class RouteParams:
    """How a ramp becomes a route: leads on the parent roads and sampling."""

    lead_in_m: float
    lane_change_by_m: float
    lead_out_m: float
    spacing_m: float
    level_tolerance_m: float
    max_tracking_error_m: float


@dataclass(frozen=True)
class Settings:
    """Everything the plugin reads from its config section."""

    truck: TruckParams
    engine: EngineParams
    planner: PlannerParams
    control: ControlParams
    route: RouteParams


def settings(section: Mapping[str, Any] | None = None) -> Settings:
    """Validate a ``plugins.truck_fuel`` section (defaults filled) into :class:`Settings`.

    Raises
    ------
    flyover.errors.ConfigError
        Naming the key that breaks the schema.
    """
    from flyover.plugins.api import plugin_config  # noqa: PLC0415

    cfg = plugin_config(config_schema(), section, plugin="truck_fuel")
    return Settings(truck=_build(TruckParams, cfg["truck"]),
                    engine=_build(EngineParams, cfg["engine"]),
                    planner=_build(PlannerParams, cfg["planner"]),
                    control=_build(ControlParams, cfg["control"]),
                    route=_build(RouteParams, cfg["route"]))
