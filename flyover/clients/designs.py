"""Catalog interchanges with fixed feature sets: the clients' test and benchmark inputs.

The library path of the workflow (catalog topology → ``build_interchange`` →
``xodr_bytes``) on one or two feature sets per design, without sampling.
"""

from __future__ import annotations

from flyover.geometry.layout import RampFeatures, build_interchange
from flyover.geometry.model import InterchangeGeometry

__all__ = ["FEATURE_SETS", "catalog_geometry", "catalog_names"]

#: (lanes per road, ramp radius m, ramp slope %) per variant
FEATURE_SETS = ((2, 150.0, 4.0), (3, 200.0, 3.0))


def catalog_names() -> list[str]:
    """The catalog's design names, in file-name order."""
    from flyover.topology.catalog import catalog_topologies  # noqa: PLC0415

    return list(catalog_topologies())


def catalog_geometry(name: str, variant: int = 0, seed: int = 3) -> InterchangeGeometry:
    """The geometry of catalog design ``name`` with feature set ``FEATURE_SETS[variant]``."""
    from flyover.topology.catalog import catalog_topologies  # noqa: PLC0415

    t = catalog_topologies()[name]
    lanes, radius, slope = FEATURE_SETS[variant]
    ic = build_interchange(t, {r: lanes for r in t.roads},
                           {r: RampFeatures(radius, slope) for r in t.ramps},
                           class_id=name, sample=variant, seed=seed)
    return ic.geometry
