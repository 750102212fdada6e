"""The built-in catalog of standard interchange designs (``flyover/catalog/*.yaml``).

The workflow's default city ``config/cities/catalog`` is this folder.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

from flyover.topology.model import Topology

__all__ = ["catalog_dir", "catalog_topologies", "catalog_class_names"]


def catalog_dir() -> Path:
    """The folder holding the catalog's YAML specs."""
    return Path(__file__).resolve().parent.parent / "catalog"


@lru_cache(maxsize=1)
def catalog_topologies() -> dict[str, Topology]:
    """Catalog design name → topology, in file-name order."""
    from flyover.topology.io import read_yaml_spec  # noqa: PLC0415 (avoid import cycle)

    return {t.name: t for t in map(read_yaml_spec, sorted(catalog_dir().glob("*.yaml")))}


@lru_cache(maxsize=1)
def catalog_class_names() -> dict[str, str]:
    """Class id → catalog design name, for naming classes readably."""
    from flyover.topology.canonical import class_id  # noqa: PLC0415

    return {class_id(t): name for name, t in catalog_topologies().items()}
