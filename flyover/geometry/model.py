"""The concrete 3D interchange: the ``geometry.json`` contract (format ``flyover-geometry/1``).

Everything the export stage (OpenDRIVE, SUMO) needs to build a network:
straight one-way carriageways (:class:`RoadGeometry`), ramps as G1/G2 chains of
cubic Bézier pieces in plan view (:class:`BezierPiece`) with an OpenDRIVE-style
cubic elevation profile (:class:`ElevationPoly`), their attachment points
(:class:`Attachment`) and the levels of the interchange.

Frame: right-handed local Cartesian frame in metres, x east, y north, z up,
origin at the interchange centre; headings in radians counter-clockwise from
+x; right-hand traffic.

Reference lines
---------------
* A road's reference line is its LEFT edge (median side); its ``lanes``
  driving lanes lie to its right (OpenDRIVE lanes -1..-n), then the right
  shoulder.
* A ramp's plan curve is its reference line = its LEFT edge, its lane(s) to
  the right. The radius targets (``target_radius_m``, ``min_radius_m``) apply
  to the ramp's **lane centre line** (the reference line offset by half the
  ramp's total lane width to the right), which is what a driver follows.
* ``Attachment.offset_m`` is the lateral position of the ramp's reference line
  relative to the parent's reference line (positive = left).

Compatibility: later versions may add keys, never rename; :func:`from_json`
ignores unknown keys.

Example
-------
>>> g = InterchangeGeometry(class_id="c0", sample=0, seed=1, levels_m=(0.0, 6.5))
>>> InterchangeGeometry.from_json(g.to_json()) == g
True
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import asdict, dataclass, field, fields
from typing import Any, Mapping

__all__ = [
    "FORMAT",
    "BezierPiece",
    "ElevationPoly",
    "Attachment",
    "RoadGeometry",
    "RampGeometry",
    "InterchangeGeometry",
    "write_geometry",
    "read_geometry",
]

FORMAT = "flyover-geometry/1"

Point2 = tuple[float, float]


def _known(cls, data: Mapping[str, Any]) -> dict[str, Any]:
    names = {f.name for f in fields(cls)}
    return {k: v for k, v in data.items() if k in names}


def _num(x: float) -> float | str:
    """JSON-safe float: ``inf`` is written as the string ``"inf"``."""
    x = float(x)
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return x


@dataclass(frozen=True)
class BezierPiece:
    """One cubic Bézier piece of a ramp's plan view.

    Attributes
    ----------
    p
        The four control points ``((x0, y0), (x1, y1), (x2, y2), (x3, y3))``
        in travel order.
    length_m
        Arc length of the piece.
    """

    p: tuple[Point2, Point2, Point2, Point2]
    length_m: float

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "BezierPiece":
        p = tuple((float(x), float(y)) for x, y in d["p"])
        return cls(p=p, length_m=float(d["length_m"]))  # type: ignore[arg-type]

    def to_dict(self) -> dict[str, Any]:
        return {"p": [[float(x), float(y)] for x, y in self.p], "length_m": float(self.length_m)}


@dataclass(frozen=True)
class ElevationPoly:
    """``z = a + b·ds + c·ds² + d·ds³`` with ``ds = s − s_m`` (OpenDRIVE ``<elevation>``)."""

    s_m: float
    a: float
    b: float
    c: float
    d: float

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "ElevationPoly":
        return cls(**{k: float(v) for k, v in _known(cls, d).items()})

    def to_dict(self) -> dict[str, Any]:
        return {k: float(v) for k, v in asdict(self).items()}


@dataclass(frozen=True)
class Attachment:
    """Where a ramp starts on (or ends into) its parent road or ramp.

    Attributes
    ----------
    parent
        Road or ramp id of the parent.
    label
        The topology edge label (``Out-R``, ``In-L``, ...).
    s_m
        Position along the parent's reference line.
    offset_m
        Lateral position of the ramp's reference line (left edge) relative to
        the parent's reference line, positive = left.
    heading_rad, z_m
        Heading and height at the attachment point.
    """

    parent: str
    label: str
    s_m: float
    offset_m: float
    heading_rad: float
    z_m: float

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "Attachment":
        k = _known(cls, d)
        return cls(parent=str(k["parent"]), label=str(k["label"]),
                   **{n: float(k[n]) for n in ("s_m", "offset_m", "heading_rad", "z_m")})

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        return {k: (v if isinstance(v, str) else float(v)) for k, v in d.items()}


@dataclass(frozen=True)
class RoadGeometry:
    """A straight one-way carriageway at constant height.

    The reference line (left edge) starts at ``start`` and runs along
    ``heading_rad`` for ``length_m`` at height ``z_m`` (= ``levels_m[level]``).
    """

    id: str
    expressway: str
    lanes: int
    level: int
    z_m: float
    start: Point2
    heading_rad: float
    length_m: float

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "RoadGeometry":
        k = _known(cls, d)
        return cls(id=str(k["id"]), expressway=str(k["expressway"]), lanes=int(k["lanes"]),
                   level=int(k["level"]), z_m=float(k["z_m"]),
                   start=(float(k["start"][0]), float(k["start"][1])),
                   heading_rad=float(k["heading_rad"]), length_m=float(k["length_m"]))

    def to_dict(self) -> dict[str, Any]:
        return {"id": self.id, "expressway": self.expressway, "lanes": int(self.lanes),
                "level": int(self.level), "z_m": float(self.z_m),
                "start": [float(self.start[0]), float(self.start[1])],
                "heading_rad": float(self.heading_rad), "length_m": float(self.length_m)}


@dataclass(frozen=True)
class RampGeometry:
    """A ramp: plan view, elevation profile, attachments, targets and achieved values.

    ``min_radius_m`` / ``max_slope_pct`` / ``length_m`` are measured on the
    final curve (densely sampled), not taken from the optimiser. Radii are of
    the lane centre line. ``target_radius_m`` may be ``inf`` (written as the
    JSON string ``"inf"``). ``ok`` is True when the ramp meets its targets
    within tolerance; ``resamples`` counts how many times its features were
    resampled (Algorithm 1), and ``infeasible`` names a systematic reason when
    no feature set could be met (empty otherwise).
    """

    id: str
    lanes: int
    plan: tuple[BezierPiece, ...]
    elevation: tuple[ElevationPoly, ...]
    start: Attachment
    end: Attachment
    target_radius_m: float
    target_slope_pct: float
    min_radius_m: float
    max_slope_pct: float
    length_m: float
    ok: bool = True
    resamples: int = 0
    infeasible: str = ""

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "RampGeometry":
        k = _known(cls, d)
        return cls(
            id=str(k["id"]), lanes=int(k["lanes"]),
            plan=tuple(BezierPiece.from_dict(x) for x in k["plan"]),
            elevation=tuple(ElevationPoly.from_dict(x) for x in k["elevation"]),
            start=Attachment.from_dict(k["start"]), end=Attachment.from_dict(k["end"]),
            target_radius_m=float(k["target_radius_m"]),
            target_slope_pct=float(k["target_slope_pct"]),
            min_radius_m=float(k["min_radius_m"]), max_slope_pct=float(k["max_slope_pct"]),
            length_m=float(k["length_m"]), ok=bool(k.get("ok", True)),
            resamples=int(k.get("resamples", 0)), infeasible=str(k.get("infeasible", "")))

    def to_dict(self) -> dict[str, Any]:
        return {
            "id": self.id, "lanes": int(self.lanes),
            "plan": [p.to_dict() for p in self.plan],
            "elevation": [e.to_dict() for e in self.elevation],
            "start": self.start.to_dict(), "end": self.end.to_dict(),
            "target_radius_m": _num(self.target_radius_m),
            "target_slope_pct": _num(self.target_slope_pct),
            "min_radius_m": _num(self.min_radius_m), "max_slope_pct": _num(self.max_slope_pct),
            "length_m": float(self.length_m), "ok": bool(self.ok),
            "resamples": int(self.resamples), "infeasible": self.infeasible,
        }


@dataclass(frozen=True)
class InterchangeGeometry:
    """A whole concrete interchange (one sample of one topology class)."""

    class_id: str
    sample: int
    seed: int
    lane_width_m: float = 3.75
    shoulder_width_m: float = 2.5
    ramp_lane_width_m: float = 4.0
    levels_m: tuple[float, ...] = (0.0,)
    roads: tuple[RoadGeometry, ...] = field(default_factory=tuple)
    ramps: tuple[RampGeometry, ...] = field(default_factory=tuple)

    def road(self, id_: str) -> RoadGeometry:
        """The road with id ``id_`` (``KeyError`` if absent)."""
        for r in self.roads:
            if r.id == id_:
                return r
        raise KeyError(id_)

    def ramp(self, id_: str) -> RampGeometry:
        """The ramp with id ``id_`` (``KeyError`` if absent)."""
        for r in self.ramps:
            if r.id == id_:
                return r
        raise KeyError(id_)

    def to_dict(self) -> dict[str, Any]:
        return {
            "format": FORMAT, "class_id": self.class_id, "sample": int(self.sample),
            "seed": int(self.seed), "lane_width_m": float(self.lane_width_m),
            "shoulder_width_m": float(self.shoulder_width_m),
            "ramp_lane_width_m": float(self.ramp_lane_width_m),
            "levels_m": [float(z) for z in self.levels_m],
            "roads": [r.to_dict() for r in self.roads],
            "ramps": [r.to_dict() for r in self.ramps],
        }

    def to_json(self) -> str:
        """Canonical JSON text (sorted keys, 2-space indent, trailing newline)."""
        return json.dumps(self.to_dict(), indent=2, sort_keys=True, allow_nan=False) + "\n"

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "InterchangeGeometry":
        fmt = d.get("format", FORMAT)
        if not str(fmt).startswith("flyover-geometry/"):
            raise ValueError(f"not a flyover geometry: format {fmt!r}")
        return cls(
            class_id=str(d["class_id"]), sample=int(d["sample"]), seed=int(d["seed"]),
            lane_width_m=float(d.get("lane_width_m", 3.75)),
            shoulder_width_m=float(d.get("shoulder_width_m", 2.5)),
            ramp_lane_width_m=float(d.get("ramp_lane_width_m", 4.0)),
            levels_m=tuple(float(z) for z in d.get("levels_m", (0.0,))),
            roads=tuple(RoadGeometry.from_dict(r) for r in d.get("roads", ())),
            ramps=tuple(RampGeometry.from_dict(r) for r in d.get("ramps", ())),
        )

    @classmethod
    def from_json(cls, text: str | bytes) -> "InterchangeGeometry":
        """Parse ``geometry.json`` text (unknown keys are ignored)."""
        return cls.from_dict(json.loads(text))


def write_geometry(geometry: InterchangeGeometry, path: str | os.PathLike) -> None:
    """Write ``geometry.json`` atomically (never half-written)."""
    from flyover.topology.io import atomic_write  # noqa: PLC0415

    atomic_write(path, geometry.to_json().encode())


def read_geometry(path: str | os.PathLike) -> InterchangeGeometry:
    """Read a ``geometry.json`` file.

    Raises
    ------
    InputFormatError
        Naming the file when it is not valid geometry JSON.
    """
    from flyover.errors import InputFormatError  # noqa: PLC0415

    try:
        with open(path, "rb") as fh:
            return InterchangeGeometry.from_json(fh.read())
    except (ValueError, KeyError, TypeError) as exc:
        raise InputFormatError(f"invalid geometry.json: {exc}", source=str(path)) from None
