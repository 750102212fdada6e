"""The geometry stage's files: feature sets in, ``geometry.json`` and ``geometry.parquet`` out.

Example
-------
>>> rows = []  # geometry_rows(build_sample(...)) for every sample
>>> GEOMETRY_SCHEMA.names[:4]
['class_id', 'sample', 'ramp', 'target_radius_m']
"""

from __future__ import annotations

import logging
import math
import os
import zlib
from dataclasses import dataclass
from typing import Iterable, Mapping, Sequence

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from flyover.errors import InputFormatError
from flyover.geometry.feasibility import (
    LEVEL_SLOPE_PCT, RoundLoop, round_loops, straight_connectors,
)
from flyover.geometry.layout import Interchange, LayoutSettings, RampFeatures, build_interchange
from flyover.geometry.model import write_geometry
from flyover.topology.model import Topology
from flyover.topology.tables import write_parquet

__all__ = ["GEOMETRY_SCHEMA", "GEOMETRY_TIMING_SCHEMA", "FeatureSet", "read_feature_sets", "sample_seed", "DomainResampler",
           "domain_resampler",
           "build_sample", "geometry_rows", "write_sample", "merge_tables", "summary"]

log = logging.getLogger(__name__)

GEOMETRY_SCHEMA = pa.schema([
    ("class_id", pa.string()), ("sample", pa.int64()), ("ramp", pa.string()),
    ("target_radius_m", pa.float64()), ("target_slope_pct", pa.float64()),
    ("min_radius_m", pa.float64()), ("max_slope_pct", pa.float64()),
    ("length_m", pa.float64()), ("ok", pa.bool_()), ("evaluations", pa.int64()),
    # additions beyond DESIGN.md (backwards compatible)
    ("first_try_ok", pa.bool_()), ("resamples", pa.int32()), ("infeasible", pa.string()),
    ("conflicts", pa.int32()),
    # the feature set's targets (target_* are the resampled ones when resamples > 0)
    ("first_target_radius_m", pa.float64()), ("first_target_slope_pct", pa.float64()),
])

#: how long each ramp's fit took (wall seconds of all its DE runs): the one figure that
#: differs between runs, so it is a table of its own and geometry.parquet is byte-reproducible
GEOMETRY_TIMING_SCHEMA = pa.schema([
    ("class_id", pa.string()), ("sample", pa.int64()), ("ramp", pa.string()),
    ("evaluations", pa.int64()), ("seconds", pa.float64()),
])

FeatureSet = tuple[dict[str, int], dict[str, RampFeatures]]


def read_feature_sets(path: str | os.PathLike) -> dict[int, FeatureSet]:
    """``features/{class_id}.parquet`` → sample → (road lanes, ramp targets).

    Raises
    ------
    InputFormatError
        Naming the file and the row at fault.
    """
    table = pq.read_table(path).to_pylist()
    out: dict[int, FeatureSet] = {}
    for i, row in enumerate(table):
        try:
            sample = int(row["sample"])
            lanes, ramps = out.setdefault(sample, ({}, {}))
            if row["kind"] == "road":
                lanes[str(row["element"])] = int(row["lanes"])
            elif row["kind"] == "ramp":
                ramps[str(row["element"])] = RampFeatures(float(row["radius_m"]),
                                                          float(row["slope_pct"]))
            else:
                raise ValueError(f"unknown kind {row['kind']!r}")
        except (KeyError, TypeError, ValueError) as exc:
            raise InputFormatError(f"bad feature row: {exc}", source=str(path),
                                   element=f"row {i}") from None
    return out


def sample_seed(seed: int, class_id: str, sample: int) -> int:
    """The seed of one interchange, derived from the config seed."""
    return zlib.crc32(f"{seed}/{class_id}/{sample}".encode())


@dataclass(frozen=True)
class DomainResampler:
    """Algorithm 1's resampling: new targets drawn from the class's feature domain.

    Called as ``resampler(ramp, attempt)``. ``radii``/``slopes`` are the values
    to draw from; ``level`` the ramps whose slope is fixed at 0 (they keep it);
    ``finite`` the ramps that never get an ``inf`` radius (sampling forbids it on a
    ramp that must turn, :func:`flyover.geometry.feasibility.forbidden_features`):
    they draw from the finite radii. ``rounds`` the outer connectors and the loops they
    go round (:func:`flyover.geometry.feasibility.round_loops`): given the radius targets
    in force (``radii``: ramp → radius, the feature set's with what was resampled so
    far), a connector draws only radii wider than its loop's by the pair's margin and a
    loop only radii its connector is wider than, as sampling asks (a pair no value of
    the domain satisfies draws from the whole domain).
    Deterministic: each draw is seeded by ``seed``, the ramp and the attempt.
    """

    radii: tuple[float, ...]
    slopes: tuple[float, ...]
    level: frozenset[str]
    seed: int
    finite: frozenset[str] = frozenset()
    rounds: tuple[RoundLoop, ...] = ()
    #: ramps whose radius sampling fixes at ``inf`` (:func:`flyover.geometry.feasibility.
    #: straight_connectors`): they keep it
    straight: frozenset[str] = frozenset()

    def _radii(self, ramp: str, radii: Mapping[str, float] | None = None) -> tuple[float, ...]:
        if ramp in self.straight:
            return (math.inf,)
        out = self.radii
        if ramp in self.finite:
            out = tuple(r for r in out if math.isfinite(r))
        for pair in self.rounds if radii else ():
            if ramp == pair.connector and pair.loop in radii:
                kept = tuple(r for r in out if pair.allows(r, radii[pair.loop]))
            elif ramp == pair.loop and pair.connector in radii:
                kept = tuple(r for r in out if pair.allows(radii[pair.connector], r))
            else:
                continue
            out = kept or out
        return out

    def _rng(self, ramp: str, attempt: int, *salt: int) -> np.random.Generator:
        return np.random.default_rng([self.seed, zlib.crc32(ramp.encode()), attempt, *salt])

    def __call__(self, ramp: str, attempt: int,
                 radii: Mapping[str, float] | None = None) -> RampFeatures | None:
        if not self.radii or not (self.slopes or ramp in self.level):
            return None
        rng = self._rng(ramp, attempt)
        radius = float(rng.choice(self._radii(ramp, radii)))
        if ramp in self.level:
            return RampFeatures(radius, LEVEL_SLOPE_PCT)
        return RampFeatures(radius, float(rng.choice(self.slopes)))

    def clearing(self, ramp: str, attempt: int,
                 radii: Mapping[str, float] | None = None) -> RampFeatures | None:
        """Targets for a ramp that still meets something at its own level after
        resampling: the steepest slope of the domain (it climbs over, or dives
        under, what it meets in the shortest distance) with a radius drawn as usual;
        ``None`` for a level ramp (no slope can help it)."""
        if not self.radii or not self.slopes or ramp in self.level:
            return None
        radius = float(self._rng(ramp, attempt, 1).choice(self._radii(ramp, radii)))
        return RampFeatures(radius, max(self.slopes))


def domain_resampler(feature_sets: Mapping[int, FeatureSet], seed: int,
                     topology: Topology | None = None,
                     settings: LayoutSettings | None = None) -> DomainResampler:
    """The :class:`DomainResampler` of a class's feature sets.

    The domain is the set of radius and slope values that occur for ramps in
    the class's feature sets (i.e. the configured domain as sampled). A ramp
    whose slope is 0 in every feature set is a level ramp (slope fixed by
    sampling, :mod:`flyover.geometry.feasibility`): it keeps slope 0, and its
    0 is no slope to draw for other ramps. A ramp whose radius is finite in every
    feature set while others have ``inf`` (``inf`` forbidden on it) keeps a finite one.
    Given the ``topology`` (and its ``settings``), its outer connectors are kept wider
    than their loops (:func:`flyover.geometry.feasibility.round_loops`).
    """
    sets = [ramps for _, ramps in feature_sets.values()]
    names = {r for ramps in sets for r in ramps}
    level = {r for r in names if all(ramps[r].slope_pct == LEVEL_SLOPE_PCT
                                     for ramps in sets if r in ramps)}
    radii = sorted({f.radius_m for ramps in sets for f in ramps.values()})
    slopes = sorted({f.slope_pct for ramps in sets for r, f in ramps.items() if r not in level})
    finite = set()
    if any(math.isinf(r) for r in radii):
        finite = {r for r in names if all(math.isfinite(ramps[r].radius_m)
                                          for ramps in sets if r in ramps)}
    straight = straight_connectors(topology) if topology is not None else frozenset()
    return DomainResampler(tuple(radii), tuple(slopes), frozenset(level), int(seed),
                           frozenset(finite),
                           round_loops(topology, settings) if topology is not None else (),
                           straight)


def build_sample(topology: Topology, features: FeatureSet, *, class_id: str, sample: int,
                 seed: int, settings: LayoutSettings, resampler=None) -> Interchange:
    """One interchange from one feature set (see :func:`build_interchange`)."""
    lanes, ramps = features
    return build_interchange(topology, lanes, ramps, class_id=class_id, sample=sample,
                             seed=sample_seed(seed, class_id, sample), settings=settings,
                             resampler=resampler)


def geometry_rows(ic: Interchange) -> list[dict]:
    """Rows of ``geometry.parquet`` for one interchange (achieved values measured densely),
    with each ramp's ``seconds`` too (:data:`GEOMETRY_TIMING_SCHEMA`; a writer with
    :data:`GEOMETRY_SCHEMA` leaves it out)."""
    g = ic.geometry
    rows = []
    for o in sorted(ic.outcomes, key=lambda o: o.ramp):
        f = o.fit
        rows.append({
            "class_id": g.class_id, "sample": g.sample, "ramp": o.ramp,
            "target_radius_m": f.spec.target_radius_m, "target_slope_pct": f.spec.target_slope_pct,
            "min_radius_m": f.min_radius_m, "max_slope_pct": f.max_slope_pct,
            "length_m": f.length_m, "ok": bool(f.ok), "evaluations": int(o.evaluations),
            "seconds": round(float(o.seconds), 3), "first_try_ok": bool(o.first_try_ok),
            "resamples": int(o.resamples), "infeasible": o.infeasible,
            "conflicts": int(f.conflicts),
            "first_target_radius_m": o.first_targets.radius_m,
            "first_target_slope_pct": o.first_targets.slope_pct,
        })
    return rows


def write_sample(ic: Interchange, geometry_path, table_path) -> None:
    """Write ``geometry.json`` and the interchange's rows (both atomically; no timings)."""
    write_geometry(ic.geometry, geometry_path)
    write_parquet(geometry_rows(ic), GEOMETRY_SCHEMA, table_path)


def merge_tables(paths: Iterable[str | os.PathLike], out: str | os.PathLike,
                 schema: pa.Schema = GEOMETRY_SCHEMA) -> int:
    """Concatenate per-class tables into ``geometry.parquet`` (or, with
    :data:`GEOMETRY_TIMING_SCHEMA`, the timing table); returns the row count."""
    rows: list[dict] = []
    for p in paths:
        rows += pq.read_table(p, schema=schema).to_pylist()
    rows.sort(key=lambda r: (r["class_id"], r["sample"], r["ramp"]))
    write_parquet(rows, schema, out)
    return len(rows)


def summary(rows: Sequence[dict]) -> list[dict]:
    """Per class: ramps, within tolerance on first try, resampled, infeasible."""
    by: dict[str, list[dict]] = {}
    for r in rows:
        by.setdefault(r["class_id"], []).append(r)
    out = []
    for c, rs in sorted(by.items()):
        out.append({"class_id": c, "ramps": len(rs),
                    "first_try_ok": sum(r["first_try_ok"] for r in rs),
                    "resampled": sum(r["resamples"] > 0 for r in rs),
                    "ok": sum(r["ok"] for r in rs),
                    "infeasible": sum(bool(r["infeasible"]) for r in rs),
                    "conflicts": sum(r["conflicts"] > 0 for r in rs)})
    return out

