"""Cross-check against an outside model: SUMO's HBEFA4 heavy-truck class.

The same speed and grade profile the truck drove is written as a SUMO
driving cycle (1 s steps: time; speed; acceleration; slope in degrees) and
run through ``emissionsDrivingCycle`` (from the eclipse-sumo wheel); its fuel
column is mg/s, turned into ml with the diesel density 0.836 kg/l.
"""

from __future__ import annotations

import math
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flyover_truck_fuel.params import Settings
from flyover_truck_fuel.route import Route, straight_route
from flyover_truck_fuel.simulate import Drive, drive, ramp_summary

__all__ = ["HBEFA_CLASS", "DIESEL_KG_PER_L", "CrossCheck", "hbefa_fuel_ml", "drive_cycle",
           "crosscheck"]

HBEFA_CLASS = "HBEFA4/TT_AT_gt34-40t_Euro-VI_A-C"
DIESEL_KG_PER_L = 0.836


@dataclass(frozen=True)
class CrossCheck:
    """Ours beside HBEFA4 on one route (fuel over the ramp part)."""

    case: str
    grade_pct: float
    length_m: float
    ours_ml_per_km: float
    hbefa_ml_per_km: float

    @property
    def ratio(self) -> float:
        return self.ours_ml_per_km / self.hbefa_ml_per_km if self.hbefa_ml_per_km else math.nan


def hbefa_fuel_ml(t: np.ndarray, v: np.ndarray, a: np.ndarray, grade: np.ndarray,
                  emission_class: str = HBEFA_CLASS) -> float:
    """Fuel (ml) of a driving cycle sampled every second, by ``emissionsDrivingCycle``."""
    import sumolib  # noqa: PLC0415

    binary = sumolib.checkBinary("emissionsDrivingCycle")
    with tempfile.TemporaryDirectory() as d:
        cyc, out = Path(d) / "cycle.csv", Path(d) / "out.csv"
        slope = np.degrees(np.arctan(grade))
        cyc.write_text("".join(f"{ti:.0f};{vi:.4f};{ai:.4f};{si:.4f}\n"
                               for ti, vi, ai, si in zip(t, v, a, slope)))
        subprocess.run([binary, "-t", str(cyc), "--have-slope", "-e", emission_class,
                        "-o", str(out)], check=True, capture_output=True)
        rows = [line.split(";") for line in out.read_text().splitlines() if line.strip()]
    fuel_mg_s = np.array([float(r[9]) for r in rows])
    return float(fuel_mg_s.sum() / DIESEL_KG_PER_L / 1000.0)  # 1 s steps: mg → ml


def drive_cycle(route: Route, run: Drive) -> tuple[np.ndarray, ...]:
    """The ramp part of a drive as a 1 Hz cycle ``(t, v, a, grade)`` (t from 0)."""
    s, t, v = run.x[0], run.x[8], run.x[5]
    t0, t1 = np.interp(0.0, s, t), np.interp(route.ramp_length_m, s, t)
    tt = np.arange(math.floor(t0), math.floor(t1))
    vv = np.interp(tt + 0.5, t, v)  # speed at the middle of each second
    aa = np.gradient(vv) if len(vv) > 1 else np.zeros_like(vv)
    gg = np.interp(np.interp(tt + 0.5, t, s), route.s, route.grade)
    return tt - tt[0] if len(tt) else tt, vv, aa, gg


def crosscheck(st: Settings, length_m: float = 1000.0,
               grades_pct=(0.0, 2.0, 4.0, -2.0, -4.0), routes=()) -> list[CrossCheck]:
    """Ours beside HBEFA4 on straight ramps of each grade, and on ``routes``
    (``(name, Route)`` pairs, e.g. catalog ramps)."""
    cases = [(f"straight {g:+g} %", g, straight_route(length_m, g / 100.0, st.route))
             for g in grades_pct]
    cases += [(name, math.nan, r) for name, r in routes]
    out = []
    for name, g, route in cases:
        run = drive(route, st)
        ours = ramp_summary(route, run)
        t, v, a, gr = drive_cycle(route, run)
        dist = float(np.sum(v))  # metres covered by the 1 s cycle
        hb = hbefa_fuel_ml(t, v, a, gr)
        if math.isnan(g):
            g = 100.0 * route.climb_m / route.ramp_length_m
        out.append(CrossCheck(name, g, route.ramp_length_m, ours.fuel_ml_per_km,
                              hb / (dist / 1000.0)))
    return out
