"""Export figures: pass rate of each check and seconds per interchange.

Usage::

    .venv/bin/python benchmarks/export.py results/interchanges/*/*/geometry.json
    .venv/bin/python benchmarks/export.py --samples          # the built-in loop/flyover/T/fork/y
    .venv/bin/python benchmarks/export.py --catalog 1        # every catalog design, built here

``--catalog SEED`` lays out every catalog design with the geometry stage
(``build_interchange``; fixed targets 120 m / 4 %, a short DE run: maxiter
120, no resampling; the export does not depend on how well targets are met).

For every ``geometry.json``: the seconds to write the ``.xodr`` (writer only),
the seconds of ``netconvert``, and every check of ``flyover validate`` (XSD,
ASAM checker, 3D continuity, netconvert, routes). Prints one line per
interchange, then the pass rate per check and the mean/max seconds.

The ASAM checker runs on each interchange's file (1.8) and its 1.7 rendition
(no one version completes every checker of the bundle). Its seconds per
interchange are printed three ways: one process of the checker's own command
(``python -m qc_opendrive -c config.xml``) per file, as flyover ran it
before; one process per interchange (``flyover.opendrive.qc.run_qc_batch``,
what ``flyover validate`` and the workflow do; with the XSD 1.1 check of the
1.8 file in the same process); and one process for every interchange.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from flyover.geometry.model import read_geometry
from flyover.opendrive import qc
from flyover.opendrive.validate import CHECKS, validate_xodr
from flyover.opendrive.writer import ExportOptions, xodr_bytes


def checker_per_file(paths: list[Path]) -> float:
    """Seconds of the checker's own command, one process per file."""
    py = qc.find_qc_python()
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        for p in paths:
            cfg, res = Path(tmp) / "config.xml", Path(tmp) / "result.xqar"
            cfg.write_text(qc.checker_config(p.resolve(), res), encoding="utf-8")
            subprocess.run([str(py), "-m", "qc_opendrive", "-c", str(cfg)], cwd=tmp,
                           capture_output=True, check=True)
    return time.perf_counter() - t0


def run(items, keep: Path | None, compare_checker: bool = True) -> int:
    passed = {c: 0 for c in CHECKS}
    t_xodr, t_nc, n = [], [], 0
    t_qc_before, t_qc_after, renditions = [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        for name, g in items:
            out = (keep or Path(tmp)) / f"{name.replace('/', '_')}.xodr"
            t0 = time.perf_counter()
            try:
                data = xodr_bytes(g)
            except Exception as exc:  # noqa: BLE001 - a benchmark reports every failure
                print(f"{name}: export failed: {exc}")
                n += 1
                continue
            t_xodr.append(time.perf_counter() - t0)
            out.write_bytes(data)
            results, times, _ = validate_xodr(out, geometry=g)
            t_nc.append(times.get("netconvert", float("nan")))
            r17 = Path(tmp) / f"{name.replace('/', '_')}.1.7.xodr"
            r17.write_bytes(xodr_bytes(g, ExportOptions(opendrive_minor=7)))
            renditions += [out, r17]
            t_qc_after.append(times.get("asam_qc", float("nan")))
            if compare_checker:
                t_qc_before.append(checker_per_file([out, r17]))
            n += 1
            for r in results:
                passed[r.check] += r.ok
            bad = [f"{r.check}: {r.detail[:200]}" for r in results if not r.ok]
            print(f"{name}: xodr {t_xodr[-1]:.3f} s, netconvert {t_nc[-1]:.3f} s, "
                  f"{len(g.ramps)} ramps, {'all checks ok' if not bad else ' | '.join(bad)}", flush=True)
    print(f"\n{n} interchanges")
    for c in CHECKS:
        print(f"  {c:<11} pass rate {passed[c]}/{n} = {100 * passed[c] / max(n, 1):.0f} %")
    if t_xodr:
        print(f"  seconds per interchange, writing .xodr: mean {statistics.mean(t_xodr):.3f}, "
              f"max {max(t_xodr):.3f}")
        print(f"  seconds per interchange, netconvert:    mean {statistics.mean(t_nc):.3f}, "
              f"max {max(t_nc):.3f}")
    if t_qc_after and compare_checker:
        batch = qc.run_qc_batch(renditions)
        print("  seconds per interchange, ASAM checker on the file (1.8) and its 1.7 rendition:")
        print(f"    one process per file (checker's own command): mean {statistics.mean(t_qc_before):.3f}, "
              f"max {max(t_qc_before):.3f}")
        print(f"    one process per interchange (+ XSD 1.1):      mean {statistics.mean(t_qc_after):.3f}, "
              f"max {max(t_qc_after):.3f}")
        print(f"    one process for all {len(t_qc_after)} interchanges:            "
              f"{batch.seconds / len(t_qc_after):.3f} (startup {batch.startup_seconds:.2f} s once)")
    return 0 if n and all(passed[c] == n for c in CHECKS) else 1


def catalog_items(seed: int) -> list:
    """(name, geometry) of every catalog design, laid out by the geometry stage."""
    from flyover.geometry.fit import FitSettings
    from flyover.geometry.layout import LayoutSettings, RampFeatures, build_interchange
    from flyover.topology.catalog import catalog_topologies

    st = LayoutSettings(max_resamples=0, fit=FitSettings(maxiter=120, min_generations=10))
    out = []
    for name, topo in catalog_topologies().items():
        feats = {r: RampFeatures(120.0, 4.0) for r in topo.ramps}
        out.append((name, build_interchange(topo, {}, feats, class_id=name, sample=0, seed=seed,
                                            settings=st).geometry))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("geometry", nargs="*", help="geometry.json files")
    ap.add_argument("--samples", action="store_true", help="the built-in small interchanges")
    ap.add_argument("--catalog", type=int, metavar="SEED", help="build the catalog designs first")
    ap.add_argument("--keep", type=Path, help="keep the .xodr files in this folder")
    ap.add_argument("--no-checker-timing", action="store_true",
                    help="skip the two comparison runs of the ASAM checker (one process per file, "
                         "one for all): checks only, about twice as fast on a large set")
    a = ap.parse_args(argv)
    items = []
    if a.samples:
        from flyover.opendrive.samples import SAMPLES, sample_geometry

        items += [(k, sample_geometry(k)) for k in SAMPLES]
    if a.catalog is not None:
        items += catalog_items(a.catalog)
    for p in a.geometry:
        g = read_geometry(p)
        items.append((str(Path(p).parent), g))
    if a.keep:
        a.keep.mkdir(parents=True, exist_ok=True)
    return run(items, a.keep, compare_checker=not a.no_checker_timing)


if __name__ == "__main__":
    sys.exit(main())
