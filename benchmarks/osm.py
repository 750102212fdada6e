"""Benchmark: import a metro-sized OpenStreetMap extract (.osm.pbf and .osm).

Builds one ``.osm.pbf`` of about ``--mb`` MB by tiling the shared extracts
(``../shared/osm/*.osm``): each copy of each file gets its own id range and a
coordinate offset, so every copy is a separate place. Imports it (and smaller
tilings, and the same data as ``.osm`` XML) in a fresh process each, and prints
wall time, MB/s, peak memory (max RSS of the importing process) and the
interchanges found. Targets: ≤ 60 s and ≤ 2 GiB for ~100 MB ``.osm.pbf`` on 2 cores.

Checks printed beside the figures (outside the importer's own count): the
interchanges found must be ``copies × (interchanges of one set of the files,
each read on its own)``, and the class ids of the tiled import must be those of
the files read on their own, repeated ``copies`` times.

    .venv/bin/python benchmarks/osm.py [--mb 100] [--sizes 10,30,100] [--xml-mb 30] [--workdir DIR]
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

import osmium

SHARED = Path(os.environ.get("FLYOVER_OSM_DIR") or Path(__file__).resolve().parents[1].parent / "shared" / "osm")
ID_SPREAD = 1000  # tiled ids are (rank among all tiles) * spread: ~10^10 for a metro, as OSM ids today
GRID_DEG = 0.08      # copies sit on a grid of this step (about 9 km), each a separate place


def _load(files: list[str]):
    """Nodes (rank, lon, lat, tags) and ways (rank, node ranks, tags) of each file, as plain
    data; ids are replaced by their rank in the file (0, 1, ...) so that tiles can be numbered
    one after the other."""
    out = []
    for f in files:
        nodes, ways = [], []
        for o in osmium.FileProcessor(f, osmium.osm.NODE | osmium.osm.WAY):
            tags = {t.k: t.v for t in o.tags}
            if o.is_node():
                nodes.append((o.id, o.location.lon, o.location.lat, tags))
            else:
                ways.append((o.id, [n.ref for n in o.nodes], tags))
        rank = {nid: k for k, nid in enumerate(sorted(n[0] for n in nodes))}
        wrank = {wid: k for k, wid in enumerate(sorted(w[0] for w in ways))}
        nodes = sorted((rank[i], lon, lat, t) for i, lon, lat, t in nodes)
        ways = sorted((wrank[i], [rank[r] for r in refs], t) for i, refs, t in ways)
        out.append((nodes, ways))
    return out


def build_tiled(path: Path, copies: int, data) -> None:
    """Write ``copies`` copies of every file's data as one sorted .osm.pbf (nodes, then ways)."""
    mut = osmium.osm.mutable
    w = osmium.SimpleWriter(str(path), overwrite=True)
    try:
        tiles = [(c, f) for c in range(copies) for f in range(len(data))]
        node_off, way_off, k_n, k_w = {}, {}, 1, 1
        for t in tiles:
            node_off[t], way_off[t] = k_n, k_w
            k_n += len(data[t[1]][0])
            k_w += len(data[t[1]][1])
        for c, f in tiles:
            off = node_off[(c, f)]
            dx, dy = (c % 25) * GRID_DEG, (c // 25) * GRID_DEG
            for nid, lon, lat, tags in data[f][0]:
                w.add_node(mut.Node(id=(nid + off) * ID_SPREAD, location=(lon + dx, lat + dy), tags=tags))
        for c, f in tiles:
            off, woff = node_off[(c, f)], way_off[(c, f)]
            for wid, refs, tags in data[f][1]:
                w.add_way(mut.Way(id=(wid + woff) * ID_SPREAD, nodes=[(r + off) * ID_SPREAD for r in refs],
                                  tags=tags))
    finally:
        w.close()


_CHILD = """
import json, resource, sys, time
from flyover.osm import OsmOptions, read_osm_topologies
from flyover.topology.canonical import class_id
import logging
logging.disable(logging.WARNING)  # the extracts' quirks (snapped links), once per copy
t0, c0 = time.perf_counter(), time.process_time()
ts = read_osm_topologies(sys.argv[1], OsmOptions(), workers=int(sys.argv[2]))
wall = time.perf_counter() - t0
kids = resource.getrusage(resource.RUSAGE_CHILDREN)
cpu = time.process_time() - c0 + kids.ru_utime + kids.ru_stime
peak = max(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, kids.ru_maxrss) / 1024
print(json.dumps({"wall_s": wall, "cpu_s": cpu, "peak_mib": peak, "classes": [class_id(t) for t in ts]}))
"""


def import_once(path: Path, workers: int = 1) -> dict:
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[1]))
    res = subprocess.run([sys.executable, "-c", _CHILD, str(path), str(workers)], capture_output=True, text=True,
                         env=env, check=True)
    return json.loads(res.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mb", type=float, default=100.0, help="size of the largest .osm.pbf (MB)")
    ap.add_argument("--sizes", default="10,30", help="smaller .osm.pbf sizes (MB) for the growth")
    ap.add_argument("--xml-mb", type=float, default=10.0, help="size (as .osm.pbf) of the tiling also imported "
                    "as .osm XML")
    ap.add_argument("--workers", type=int, default=2, help="processes reading the places of the extract")
    ap.add_argument("--workdir", help="where the tiled files go (default: a temporary folder)")
    args = ap.parse_args()
    files = sorted(glob.glob(str(SHARED / "*.osm")))
    if not files:
        sys.exit(f"no extracts in {SHARED}")
    data = _load(files)
    one = import_once_per_file(files)
    tmp = Path(args.workdir or tempfile.mkdtemp(prefix="flyover-osm-bench-"))
    tmp.mkdir(parents=True, exist_ok=True)
    probe = tmp / "probe.osm.pbf"
    build_tiled(probe, 4, data)
    mb_per_copy = probe.stat().st_size / 4 / 1e6
    print(f"{len(files)} shared extracts; one tiled set = {mb_per_copy:.3f} MB of .osm.pbf; "
          f"{len(one)} interchanges in one set; {args.workers} worker(s); load average before: "
          f"{os.getloadavg()[0]:.1f}", flush=True)
    sizes = sorted({float(s) for s in args.sizes.split(",") if s} | {args.mb})
    rows = []
    for mb in sizes:
        copies = max(1, round(mb / mb_per_copy))
        pbf = tmp / f"tiled_{copies}.osm.pbf"
        t0 = time.perf_counter()
        build_tiled(pbf, copies, data)
        built = time.perf_counter() - t0
        size = pbf.stat().st_size / 1e6
        r = import_once(pbf, args.workers)
        expect = Counter({c: n * copies for c, n in Counter(one).items()})
        same = Counter(r["classes"]) == expect
        rows.append((mb, size, r["wall_s"]))
        print(f".osm.pbf {size:7.1f} MB ({copies} copies, written in {built:.0f} s): import {r['wall_s']:6.1f} s "
              f"(cpu {r['cpu_s']:.1f} s), {size / r['wall_s']:5.2f} MB/s, peak {r['peak_mib']:6.0f} MiB, "
              f"{len(r['classes'])} interchanges (expected {sum(expect.values())}; class ids as the files "
              f"alone: {'yes' if same else 'NO'})", flush=True)
        if mb == args.xml_mb or (mb == sizes[0] and args.xml_mb not in sizes):
            xml = tmp / f"tiled_{copies}.osm"
            w = osmium.SimpleWriter(str(xml), overwrite=True)
            for o in osmium.FileProcessor(str(pbf)):
                w.add(o)
            w.close()
            xs = xml.stat().st_size / 1e6
            rx = import_once(xml, args.workers)
            print(f".osm     {xs:7.1f} MB ({copies} copies): import {rx['wall_s']:6.1f} s (cpu {rx['cpu_s']:.1f} s), "
                  f"{xs / rx['wall_s']:5.2f} MB/s, peak {rx['peak_mib']:6.0f} MiB, same class ids as the .osm.pbf: "
                  f"{'yes' if rx['classes'] == r['classes'] else 'NO'}", flush=True)
            xml.unlink()
        pbf.unlink()
    if len(rows) > 1:
        (m0, s0, t0), (m1, s1, t1) = rows[0], rows[-1]
        print(f"growth {s0:.0f} -> {s1:.0f} MB: time x{t1 / t0:.1f} for size x{s1 / s0:.1f}")
    probe.unlink()


def import_once_per_file(files: list[str]) -> list[str]:
    """Class ids of every interchange of each shared file read on its own (the reference)."""
    out = []
    for f in files:
        try:
            out += import_once(Path(f))["classes"]
        except subprocess.CalledProcessError:  # a file without any interchange: nothing to compare
            pass
    return out


if __name__ == "__main__":
    main()
