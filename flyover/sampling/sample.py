"""The feature sets of one class: a covering array over its feature model, as table rows.

Examples
--------
>>> from flyover.topology.catalog import catalog_topologies
>>> from flyover.sampling.model import default_profile
>>> s = sample_topology(catalog_topologies()["j1"], default_profile(), t=2, seed=1)
>>> s.coverage.rows, s.coverage.lower_bound, s.coverage.complete
(64, 64, True)
>>> sorted(s.feature_rows()[0])
['class_id', 'element', 'kind', 'lanes', 'radius_m', 'sample', 'slope_pct']
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from typing import Iterable, Mapping

import pyarrow as pa

from flyover.sampling.covering import CoveringArray, SearchBudget, covering_array
from flyover.sampling.model import Feature, FeatureModel, ForbidRule, Profile, feature_model
from flyover.sampling.tuples import Coverage
from flyover.topology.canonical import class_id as topology_class_id
from flyover.topology.model import Topology

__all__ = ["Sampling", "sample_topology", "sampling_seed", "FEATURES_SCHEMA", "COVERAGE_SCHEMA"]

FEATURES_SCHEMA = pa.schema([
    ("class_id", pa.string()), ("sample", pa.int64()), ("element", pa.string()),
    ("kind", pa.string()), ("lanes", pa.int32()), ("radius_m", pa.float64()),
    ("slope_pct", pa.float64()),
])

COVERAGE_SCHEMA = pa.schema([
    ("class_id", pa.string()), ("t", pa.int32()), ("n_params", pa.int32()), ("rows", pa.int32()),
    ("tuples_total", pa.int64()), ("tuples_covered", pa.int64()), ("lower_bound", pa.int64()),
])


def sampling_seed(seed: int, class_id: str) -> int:
    """The seed of one class's sampling, derived from the config's master seed."""
    digest = hashlib.sha256(f"{seed}/sampling/{class_id}".encode()).digest()
    return int.from_bytes(digest[:8], "little")


@dataclass(frozen=True, eq=False)
class Sampling:
    """The feature sets of one class: the model and its covering array."""

    class_id: str
    model: FeatureModel
    array: CoveringArray

    @property
    def coverage(self) -> Coverage:
        return self.array.coverage

    def feature_rows(self) -> list[dict]:
        """Rows of ``features/{class_id}.parquet``: one per sample × road/ramp (fixed
        features hold their value in every row)."""
        columns: dict[tuple[str, Feature], int] = {
            (p.element, p.feature): i for i, p in enumerate(self.model.parameters)}
        rows = []
        for sample, values in enumerate(self.array.rows):
            for element, kind in self.model.elements():
                row = {"class_id": self.class_id, "sample": sample, "element": element,
                       "kind": kind.value, "lanes": None, "radius_m": None, "slope_pct": None}
                for feature in Feature:
                    i = columns.get((element, feature))
                    value = (self.model.parameters[i].values[values[i]] if i is not None
                             else self.model.value(element, feature))
                    if value is not None:
                        row[feature.value] = int(value) if feature is Feature.LANES else float(value)
                rows.append(row)
        return rows

    def coverage_row(self) -> dict:
        """The row of ``coverage.parquet``."""
        c = self.coverage
        return {"class_id": self.class_id, "t": c.t, "n_params": c.n_params, "rows": c.rows,
                "tuples_total": c.tuples_total, "tuples_covered": c.tuples_covered,
                "lower_bound": c.lower_bound}


def sample_topology(topology: Topology, profile: Profile, *, t: int = 2, seed: int = 0,
                    class_id: str | None = None, extra: Iterable[ForbidRule] = (),
                    fixed: Mapping[tuple[str, Feature], float] | None = None,
                    budget: SearchBudget = SearchBudget()) -> Sampling:
    """The smallest covering array this module finds for ``topology``'s features.

    Parameters
    ----------
    topology
        The class's topology.
    profile
        Value domains and forbidden combinations.
    t
        Coverage strength.
    seed
        The master seed; the class's own seed is derived from it and the class id.
    class_id
        Defaults to the topology's canonical class id.
    extra
        Further forbidden combinations (e.g. from the geometry stage).
    fixed
        ``(element, feature) → value`` held constant, not covered (e.g.
        :func:`flyover.geometry.feasibility.fixed_features`: slope 0 on level ramps).
    budget
        Search effort.
    """
    cid = class_id or topology_class_id(topology)
    model = feature_model(topology, profile, extra, fixed)
    array = covering_array(model.levels, t, forbidden=model.forbidden,
                           seed=sampling_seed(seed, cid), budget=budget)
    return Sampling(cid, model, array)

