"""A small city for the tests that run the workflow: two classes, a few interchanges each."""

from __future__ import annotations

import shutil
from pathlib import Path

import yaml

REPO = Path(__file__).resolve().parents[1]

#: a directional Y: expressway A ends where it joins B (a class the catalog does not have)
Y = """\
name: y
expressways: {A: [A1, A2], B: [B1, B2]}
ramps:
  rIn:  {from: A1 straight, to: B1 right @0.60}
  rOut: {from: B2 right @0.40, to: A2 straight}
"""
#: files whose bytes may differ between two runs of the same config (fitting times)
NOT_REPRODUCIBLE = ("results/geometry_timing.parquet", "results/geometry_timing/")


def small_city(root: Path) -> Path:
    """A workflow folder at ``root``: the repository's config, a city ``small`` of the Y and
    the catalog's trumpet, t = 1 (8 feature sets a class), a short throughput experiment."""
    shutil.copytree(REPO / "config", root / "config", symlinks=True)
    city = root / "config" / "cities" / "small"
    city.mkdir()
    (city / "y.yaml").write_text(Y, encoding="utf-8")
    shutil.copy(REPO / "flyover" / "catalog" / "trumpet.yaml", city / "trumpet.yaml")
    cfg = yaml.safe_load((root / "config" / "config.yaml").read_text(encoding="utf-8"))
    cfg["cities"] = ["small"]
    cfg["sampling"]["t"] = 1
    cfg["throughput"].update(samples_per_class=1, densities=[450, 1800], duration_s=900)
    (root / "config" / "config.yaml").write_text(yaml.safe_dump(cfg), encoding="utf-8")
    return root
