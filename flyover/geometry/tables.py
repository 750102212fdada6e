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
from dataclasses import dataclass, field
from typing import Iterable, Mapping, Sequence

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from flyover.errors import InputFormatError
from flyover.geometry.feasibility import (
    LEVEL_SLOPE_PCT, RoundLoop, sampling_model,
)
from flyover.geometry.layout import Interchange, LayoutSettings, RampFeatures, build_interchange
from flyover.geometry.model import write_geometry
from flyover.sampling.model import Feature, Profile
from flyover.topology.model import Kind, Topology
from flyover.topology.tables import write_parquet

__all__ = ["GEOMETRY_SCHEMA", "GEOMETRY_TIMING_SCHEMA", "FeatureSet", "read_feature_sets", "sample_seed", "DomainResampler",
           "SamplingRules", "domain_resampler",
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


class SamplingRules:
    """What sampling allows a class: the feature model rule ``sample_class`` covers
    (:func:`flyover.geometry.feasibility.sampling_model`: the profile's domains and rules,
    the features geometry cannot build and those it fixes), built on first use. Answers
    whether one ramp's (radius, slope) breaks none of its forbidden combinations, given the
    rest of a feature set (``(element, feature) → value``); a combination naming a feature
    not given (or a value outside its domain) does not apply."""

    def __init__(self, topology: Topology, profile: Profile,
                 settings: LayoutSettings | None = None):
        self.topology, self.profile, self.settings = topology, profile, settings
        self._built = None

    def _model(self):
        if self._built is None:
            model = sampling_model(self.topology, self.profile, self.settings)
            index = {(p.element, p.feature): i for i, p in enumerate(model.parameters)}
            values = [{v: k for k, v in enumerate(p.values)} for p in model.parameters]
            by_ramp: dict[str, list] = {}
            for forb in model.forbidden:
                for ramp in dict.fromkeys(model.parameters[p].element for p in forb.params
                                          if model.parameters[p].kind is Kind.RAMP):
                    by_ramp.setdefault(ramp, []).append(forb)
            self._built = (model, index, values, by_ramp)
        return self._built

    def fixed(self, ramp: str, feature: Feature) -> float | None:
        """The value sampling fixes for ``ramp``'s ``feature`` (``None``: sampled)."""
        return self._model()[0].value(ramp, feature)

    def allows(self, ramp: str, radius_m: float, slope_pct: float,
               given: Mapping[tuple[str, Feature], float], own: bool = False) -> bool:
        """Whether ``ramp`` may take ``(radius_m, slope_pct)`` with the other features
        ``given``; ``own``: only the combinations naming no other ramp (its own and its
        roads' lanes)."""
        model, index, values, by_ramp = self._model()
        params = model.parameters
        row = {}
        for key, v in (*given.items(), ((ramp, Feature.RADIUS_M), radius_m),
                       ((ramp, Feature.SLOPE_PCT), slope_pct)):
            p = index.get(key)
            if p is not None and v in values[p]:
                row[p] = values[p][v]
        for forb in by_ramp.get(ramp, ()):
            if own and any(params[p].kind is Kind.RAMP and params[p].element != ramp
                           for p in forb.params):
                continue
            if forb.matches(row):
                return False
        return True


@dataclass(frozen=True)
class DomainResampler:
    """Algorithm 1's resampling: new targets drawn from the class's feature domain.

    Called as ``resampler(ramp, attempt, radii)``. ``radii``/``slopes`` are the values
    to draw from; ``level`` the ramps whose slope is fixed at 0 (they keep it).
    With ``rules`` (:class:`SamplingRules`, the class's feature model as sampling covers
    it), a draw is one sampling allows: a (radius, slope) that breaks none of its
    forbidden combinations given ``given`` (the sample's lanes and targets) and the
    radius targets in force (``radii``: ramp → radius, the feature set's with what was
    resampled so far); where none does, one that breaks none naming another ramp, else
    any. A feature sampling fixes keeps its value.
    Without ``rules``, the same rules as read from the feature sets: ``finite`` the ramps
    that never get an ``inf`` radius (sampling forbids it on a ramp that must turn,
    :func:`flyover.geometry.feasibility.forbidden_features`): they draw from the finite
    radii. ``rounds`` the outer connectors and the loops they go round
    (:func:`flyover.geometry.feasibility.round_loops`): given the radius targets in
    force, a connector draws only radii wider than its loop's by the pair's margin and a
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
    #: what sampling allows (see the class doc); ``None``: the fields above
    rules: SamplingRules | None = field(default=None, compare=False)
    #: the sample's features, ``(element, feature) → value`` (lanes of its roads, its
    #: ramps' targets), that a draw is checked against with ``rules``
    given: Mapping[tuple[str, Feature], float] = field(default_factory=dict, compare=False)

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

    def _slope(self, ramp: str) -> float | None:
        """The slope sampling fixes for ``ramp`` (``None``: drawn)."""
        fixed = self.rules.fixed(ramp, Feature.SLOPE_PCT) if self.rules is not None else None
        if fixed is None and ramp in self.level:
            fixed = LEVEL_SLOPE_PCT
        return fixed

    def allowed(self, ramp: str, radii: Mapping[str, float] | None = None,
                slopes: Sequence[float] | None = None) -> dict[float, tuple[float, ...]]:
        """Radius → the slopes (of ``slopes``, else the domain's; the fixed one of a level
        ramp) ``ramp`` may be drawn with, given the radius targets in force ``radii``: what
        :attr:`rules` allow (see the class doc), else the radii of :meth:`_radii` with
        every slope."""
        fixed = self._slope(ramp)
        ss = (fixed,) if fixed is not None else tuple(self.slopes if slopes is None else slopes)
        if self.rules is None:
            return {r: ss for r in self._radii(ramp, radii)}
        pinned = self.rules.fixed(ramp, Feature.RADIUS_M)
        rs = (pinned,) if pinned is not None else self.radii
        given = dict(self.given)
        given.update({(r, Feature.RADIUS_M): v for r, v in (radii or {}).items()})
        for own in (False, True):
            out = {r: kept for r in rs
                   if (kept := tuple(s for s in ss if self.rules.allows(ramp, r, s, given, own)))}
            if out:
                return out
        return {r: ss for r in rs}

    def _rng(self, ramp: str, attempt: int, *salt: int) -> np.random.Generator:
        return np.random.default_rng([self.seed, zlib.crc32(ramp.encode()), attempt, *salt])

    def __call__(self, ramp: str, attempt: int,
                 radii: Mapping[str, float] | None = None) -> RampFeatures | None:
        if not self.radii or not (self.slopes or self._slope(ramp) is not None):
            return None
        rng = self._rng(ramp, attempt)
        allowed = self.allowed(ramp, radii)
        radius = float(rng.choice(tuple(allowed)))
        fixed = self._slope(ramp)
        if fixed is not None:
            return RampFeatures(radius, fixed)
        return RampFeatures(radius, float(rng.choice(allowed[radius])))

    def clearing(self, ramp: str, attempt: int,
                 radii: Mapping[str, float] | None = None) -> RampFeatures | None:
        """Targets for a ramp that still meets something at its own level after
        resampling: the steepest slope of the domain (it climbs over, or dives
        under, what it meets in the shortest distance) with a radius drawn as usual
        (one allowed with that slope); ``None`` for a level ramp (no slope can help it)."""
        if not self.radii or not self.slopes or self._slope(ramp) is not None:
            return None
        steep = max(self.slopes)
        radius = float(self._rng(ramp, attempt, 1).choice(
            tuple(self.allowed(ramp, radii, (steep,)))))
        return RampFeatures(radius, steep)


def domain_resampler(feature_sets: Mapping[int, FeatureSet], seed: int,
                     topology: Topology | None = None,
                     settings: LayoutSettings | None = None,
                     sample: int | None = None) -> DomainResampler:
    """The :class:`DomainResampler` of a class's feature sets.

    The domain is the set of radius and slope values that occur for ramps in
    the class's feature sets (i.e. the configured domain as sampled). A ramp
    whose slope is 0 in every feature set is a level ramp (slope fixed by
    sampling, :mod:`flyover.geometry.feasibility`): it keeps slope 0, and its
    0 is no slope to draw for other ramps. Given the ``topology`` (and its
    ``settings``), a draw is one sampling allows (:class:`SamplingRules` on the domain
    as sampled: lanes, radii and slopes that occur; the profile's own forbidden
    combinations are not known here), checked against the features of ``sample`` (its
    lanes and targets; without it, combinations naming lanes or another ramp's slope do
    not apply). Without a topology: a ramp whose radius is finite in every feature set
    while others have ``inf`` (``inf`` forbidden on it) keeps a finite one.
    """
    sets = [ramps for _, ramps in feature_sets.values()]
    names = {r for ramps in sets for r in ramps}
    level = {r for r in names if all(ramps[r].slope_pct == LEVEL_SLOPE_PCT
                                     for ramps in sets if r in ramps)}
    radii = sorted({f.radius_m for ramps in sets for f in ramps.values()})
    slopes = sorted({f.slope_pct for ramps in sets for r, f in ramps.items() if r not in level})
    if topology is None:
        finite = set()
        if any(math.isinf(r) for r in radii):
            finite = {r for r in names if all(math.isfinite(ramps[r].radius_m)
                                              for ramps in sets if r in ramps)}
        return DomainResampler(tuple(radii), tuple(slopes), frozenset(level), int(seed),
                               frozenset(finite))
    lanes = sorted({float(n) for lanes_, _ in feature_sets.values() for n in lanes_.values()})
    domains = []
    if lanes:
        domains.append((Kind.ROAD, ((Feature.LANES, tuple(lanes)),)))
    ramp_domain = tuple((f, tuple(float(v) for v in vs)) for f, vs in
                        ((Feature.RADIUS_M, radii), (Feature.SLOPE_PCT, slopes)) if vs)
    if ramp_domain:
        domains.append((Kind.RAMP, ramp_domain))
    given: dict[tuple[str, Feature], float] = {}
    if sample is not None:
        lanes_, ramps_ = feature_sets[sample]
        given.update({(r, Feature.LANES): float(n) for r, n in lanes_.items()})
        for r, f in ramps_.items():
            given[r, Feature.RADIUS_M] = float(f.radius_m)
            given[r, Feature.SLOPE_PCT] = float(f.slope_pct)
    rules = SamplingRules(topology, Profile("as sampled", tuple(domains)), settings)
    return DomainResampler(tuple(radii), tuple(slopes), frozenset(level), int(seed),
                           rules=rules, given=given)


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

