"""The ``throughput:`` section of the configuration, and the seeds derived from ``seed``.

Example
-------
>>> s = ThroughputSettings.from_config({"seed": 7, "throughput": {"densities": [450]}})
>>> s.densities, s.duration_s
((450.0,), 2000.0)
>>> run_seed(7, "c0123456789", 0, 450.0) == run_seed(7, "c0123456789", 0, 450)
True
"""

from __future__ import annotations

import enum
import zlib
from dataclasses import dataclass
from typing import Any, Mapping

from flyover.errors import ConfigError

__all__ = ["Arrivals", "DepartLane", "ThroughputSettings", "run_seed", "selection_seed"]


class Arrivals(str, enum.Enum):
    """How each flow's vehicles are spaced in time."""

    #: exponential headways (a Poisson process of the flow's rate): seeds matter
    POISSON = "poisson"
    #: equal headways of 3600 / density seconds
    UNIFORM = "uniform"


class DepartLane(str, enum.Enum):
    """SUMO's ``departLane`` for the inserted vehicles."""

    #: the lane with the most free room: insertion limited by the road, not by one lane
    FREE = "free"
    #: the lane that takes the vehicle furthest on its route without changing
    BEST = "best"


@dataclass(frozen=True)
class ThroughputSettings:
    """Settings of the throughput experiment (config section ``throughput``).

    Attributes
    ----------
    densities
        Vehicles per hour of every movement's flow (the paper's 450–1800).
    duration_s
        Simulated time of one run; flows run for all of it.
    step_length_s
        SUMO's step length.
    interval_s
        Length of the intervals of the entering/leaving time series.
    samples_per_class
        Interchanges simulated per class (seeded random choice); 0 = all.
    uturns
        Include movements back onto the entrance's own expressway.
    arrivals, depart_lane, depart_speed
        Insertion: headways, SUMO ``departLane`` and ``departSpeed``.
    time_to_teleport_s
        SUMO's ``--time-to-teleport`` (a vehicle stuck this long is teleported, counted).
    max_depart_delay_s
        SUMO's ``--max-depart-delay``: a vehicle that could not be inserted for this
        long is dropped (counted as not inserted); negative = never.
    min_stable_s
        Shortest stable window; a run whose window is shorter is not balanced.
    balance_tolerance
        Largest change of the vehicles in the network over the stable window,
        as a fraction of the vehicles that entered in it, for a balanced run.
    seed
        The configuration's master seed.
    """

    densities: tuple[float, ...] = (450.0, 900.0, 1350.0, 1800.0)
    duration_s: float = 2000.0
    step_length_s: float = 0.5
    interval_s: float = 20.0
    samples_per_class: int = 2
    uturns: bool = False
    arrivals: Arrivals = Arrivals.POISSON
    depart_lane: DepartLane = DepartLane.FREE
    depart_speed: str = "max"
    time_to_teleport_s: float = 300.0
    max_depart_delay_s: float = -1.0
    min_stable_s: float = 500.0
    balance_tolerance: float = 0.05
    seed: int = 20231024

    def __post_init__(self) -> None:
        if not self.densities or min(self.densities) <= 0:
            raise ConfigError("densities must be positive", element="throughput.densities")
        if self.interval_s < self.step_length_s or self.duration_s < 2 * self.interval_s:
            raise ConfigError("need step_length_s <= interval_s <= duration_s / 2",
                              element="throughput.interval_s")
        for whole, part in ((self.interval_s, self.step_length_s), (self.duration_s, self.interval_s)):
            if abs(whole / part - round(whole / part)) > 1e-9:
                raise ConfigError("duration_s must be a multiple of interval_s, and interval_s of "
                                  "step_length_s (a partial last interval would bias the series)",
                                  element="throughput.interval_s")

    @classmethod
    def from_config(cls, config: Mapping[str, Any]) -> "ThroughputSettings":
        """Settings from a whole (validated) configuration mapping."""
        sec = dict(config.get("throughput") or {})
        kw: dict[str, Any] = {"seed": int(config.get("seed", cls.seed))}
        if "densities" in sec:
            kw["densities"] = tuple(float(d) for d in sec.pop("densities"))
        for name, conv in (("duration_s", float), ("step_length_s", float), ("interval_s", float),
                           ("samples_per_class", int), ("uturns", bool),
                           ("arrivals", Arrivals), ("depart_lane", DepartLane),
                           ("depart_speed", str), ("time_to_teleport_s", float),
                           ("max_depart_delay_s", float),
                           ("min_stable_s", float), ("balance_tolerance", float)):
            if name in sec:
                try:
                    kw[name] = conv(sec.pop(name))
                except ValueError as exc:
                    raise ConfigError(str(exc), element=f"throughput.{name}") from None
        if sec:
            raise ConfigError(f"unknown keys {sorted(sec)}", element="throughput")
        return cls(**kw)


def _crc(text: str) -> int:
    return zlib.crc32(text.encode()) & 0x7FFFFFFF


def run_seed(seed: int, class_id: str, sample: int, density: float) -> int:
    """SUMO's seed for one run (interchange × density), derived from the master seed."""
    return _crc(f"{seed}/throughput/{class_id}/{int(sample)}/{float(density):g}")


def selection_seed(seed: int, class_id: str) -> int:
    """The seed of one class's choice of samples to simulate."""
    return _crc(f"{seed}/throughput-samples/{class_id}")
