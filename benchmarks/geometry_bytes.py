"""geometry.json fingerprints of fixed samples: the check that a refactor changes no bytes.

Builds ``N`` feature sets per catalog design (drawn as ``benchmarks/geometry.py`` draws
them, seeded from the config) with the library and prints ``design sample sha256[:16]`` of
each interchange's ``geometry.json``. Run it before and after a change and diff the output:

    .venv/bin/python benchmarks/geometry_bytes.py 2 > before.txt   # on the old commit
    .venv/bin/python benchmarks/geometry_bytes.py 2 > after.txt
    diff before.txt after.txt
"""

import hashlib
import os
import sys
import tempfile
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).parent))

from geometry import drawn_feature_sets  # noqa: E402

from flyover.config import load_config  # noqa: E402
from flyover.geometry.layout import LayoutSettings  # noqa: E402
from flyover.geometry.tables import build_sample, domain_resampler, sample_seed, write_sample  # noqa: E402
from flyover.topology.canonical import class_id  # noqa: E402
from flyover.topology.catalog import catalog_topologies  # noqa: E402


def main() -> None:
    cfg = load_config("config/config.yaml")
    settings = LayoutSettings.from_config(cfg["geometry"])
    profile = cfg["sampling"]["profiles"][cfg["sampling"]["profile"]]
    seed = int(cfg["seed"])
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 2
    designs = sys.argv[2:] or None
    with tempfile.TemporaryDirectory() as d:
        for name, topo in catalog_topologies().items():
            if designs and name not in designs:
                continue
            cid = class_id(topo)
            sets = drawn_feature_sets(topo, profile, n, seed)
            for s in sorted(sets):
                ic = build_sample(topo, sets[s], class_id=cid, sample=s, seed=seed,
                                  settings=settings,
                                  resampler=domain_resampler(sets, sample_seed(seed, cid, s),
                                                             topo, settings, s))
                write_sample(ic, f"{d}/g.json", f"{d}/g.parquet")
                digest = hashlib.sha256(Path(f"{d}/g.json").read_bytes()).hexdigest()[:16]
                print(name, s, digest, flush=True)


if __name__ == "__main__":
    main()
