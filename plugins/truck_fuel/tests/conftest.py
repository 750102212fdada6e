"""Shared fixtures of the truck_fuel tests: settings and one real catalog interchange."""

from __future__ import annotations

import pytest

from flyover_truck_fuel.params import settings


@pytest.fixture(scope="session")
def st():
    return settings({})


@pytest.fixture(scope="session")
def j1_geometry():
    """The paper's J1 from flyover's catalog, built in-process (radius 60 m, slope 4 %)."""
    from flyover.geometry.layout import RampFeatures, build_interchange
    from flyover.topology.catalog import catalog_topologies

    t = catalog_topologies()["j1"]
    ic = build_interchange(t, {r: 2 for r in t.roads},
                           {r: RampFeatures(60.0, 4.0) for r in t.ramps},
                           class_id="c0000000j1x", sample=0, seed=3)
    return ic.geometry
