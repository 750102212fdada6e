"""A small results folder made in-test for the report tests: every table and file of every
stage (or only the first ones), with the columns the stages write, in a second.

The geometry is real (``InterchangeGeometry`` written as ``geometry.json``); the other
files are what the report only links to (``.xodr``, ``.net.xml``) and small PNGs.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from flyover.geometry.model import (
    Attachment, BezierPiece, ElevationPoly, InterchangeGeometry, RampGeometry, RoadGeometry,
    write_geometry,
)
from flyover.geometry.tables import GEOMETRY_SCHEMA
from flyover.topology.tables import CLASSES_SCHEMA, REJECTED_SCHEMA

STAGES = ("topology", "sampling", "geometry", "export", "validation", "throughput", "fuel")
CLASS = "c0123456789"
CLASS2 = "c9876543210"
#: a reason with markup in it: the report must show it as text
EVIL = "<script>alert('x')</script> & \"quotes\""


def _png(path: Path, shade: float = 0.5) -> None:
    import matplotlib  # noqa: PLC0415

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    path.parent.mkdir(parents=True, exist_ok=True)
    plt.imsave(path, [[shade, 1 - shade], [1 - shade, shade]], cmap="viridis")


def _table(path: Path, rows: list[dict], schema: pa.Schema | None = None) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    pq.write_table(pa.Table.from_pylist(rows, schema=schema), path)


def geometry(class_id: str, sample: int) -> InterchangeGeometry:
    """A cross of two expressways on two levels and two ramps, one of them straight
    (target radius ∞), the other climbing from A1 to B1."""
    def road(id_, xw, level, start, heading):
        return RoadGeometry(id_, xw, 2, level, 6.5 * level, start, heading, 600.0)

    roads = (road("A1", "A", 0, (0.0, -300.0), math.pi / 2),
             road("A2", "A", 0, (-1.0, 300.0), -math.pi / 2),
             road("B1", "B", 1, (-300.0, 1.0), 0.0), road("B2", "B", 1, (300.0, -1.0), math.pi))
    bend = 10.0 * sample
    r1 = RampGeometry(
        "r1", 1, (BezierPiece(((7.5, -150.0), (7.5, -60.0 + bend), (60.0, -9.0), (150.0, -8.5)),
                              180.0),),
        (ElevationPoly(0.0, 0.0, 0.036, 0.0, 0.0),),
        Attachment("A1", "Out-R", 150.0, -7.5, math.pi / 2, 0.0),
        Attachment("B1", "In-R", 450.0, -7.5, 0.0, 6.5),
        60.0, 4.0, 58.2, 3.6, 180.0, ok=False, infeasible="")
    r2 = RampGeometry(
        "r2", 1, (BezierPiece(((-150.0, 8.5), (-60.0, 9.0), (-9.0, 60.0), (-8.5, 150.0)), 180.0),),
        (ElevationPoly(0.0, 6.5, -0.036, 0.0, 0.0),),
        Attachment("B2", "Out-R", 450.0, -7.5, math.pi, 6.5),
        Attachment("A2", "In-R", 150.0, -7.5, -math.pi / 2, 0.0),
        math.inf, 4.0, 120.0, 3.9, 190.0)
    return InterchangeGeometry(class_id, sample, 7 + sample, levels_m=(0.0, 6.5),
                               roads=roads, ramps=(r1, r2))


def make_results(root: Path, stages: tuple[str, ...] = STAGES) -> Path:
    """Write ``root/results`` with the tables and files of ``stages``; returns it."""
    res = root / "results"
    res.mkdir(parents=True)
    samples = {CLASS: [0, 1, 2], CLASS2: [0]}
    names = {CLASS: "cloverleaf", CLASS2: "T-4roads-2ramps"}
    if "topology" in stages:
        _table(res / "classes.parquet", [
            {"city": "town", "interchange": "a1_junction", "source_file": "config/cities/town/x.osm",
             "class_id": CLASS, "class_name": names[CLASS], "n_roads": 4, "n_ramps": 2,
             "shape": "cross"},
            {"city": "town", "interchange": "y", "source_file": "config/cities/town/y.yaml",
             "class_id": CLASS2, "class_name": names[CLASS2], "n_roads": 4, "n_ramps": 2,
             "shape": "T"}], CLASSES_SCHEMA)
        _table(res / "rejected.parquet", [{"city": "town", "source_file": "config/cities/town/bad.yaml",
                                           "element": "r9", "reason": EVIL}], REJECTED_SCHEMA)
        city = res / "topology" / "town"
        city.mkdir(parents=True)
        (city / "index.json").write_text(json.dumps({"city": "town", "interchanges": [
            {"city": "town", "interchange": "a1_junction", "source_file": "config/cities/town/x.osm",
             "graphml": "results/topology/town/a1_junction.graphml",
             "name_from": {"refs": {"A 1": "A1"}, "osm_node": 1}},
            {"city": "town", "interchange": "y", "source_file": "config/cities/town/y.yaml",
             "graphml": "results/topology/town/y.graphml"}], "rejected": []}), encoding="utf-8")
        for name in ("a1_junction", "y"):
            (city / f"{name}.graphml").write_text("<graphml/>\n", encoding="utf-8")
        _png(city / "a1_junction.png", 0.2)  # an OSM input's picture
        manifest = {"classes": {c: {"class_name": names[c], "members": [f"town/{m}"],
                                    "n_ramps": 2, "n_roads": 4, "shape": s,
                                    "label_counts": {"In-R": 2, "Out-R": 2},
                                    "representative": f"results/topology/town/{m}.graphml"}
                                for c, m, s in ((CLASS, "a1_junction", "cross"), (CLASS2, "y", "T"))}}
        (res / "classes").mkdir()
        (res / "classes" / "manifest.json").write_text(json.dumps(manifest), encoding="utf-8")
        for c in samples:
            _png(res / "classes" / c / "topology.png", 0.7)
            (res / "classes" / c / "topology.graphml").write_text("<graphml/>\n", encoding="utf-8")
    if "sampling" in stages:
        for c, ss in samples.items():
            _table(res / "features" / f"{c}.parquet", [
                {"class_id": c, "sample": s, "element": "r1", "kind": "ramp", "lanes": 1,
                 "radius_m": 60.0, "slope_pct": 4.0} for s in ss])
        _table(res / "coverage.parquet", [
            {"class_id": c, "t": 2, "n_params": 4, "rows": len(ss), "tuples_total": 40,
             "tuples_covered": 40, "lower_bound": len(ss)} for c, ss in samples.items()])
    if "geometry" in stages:
        rows, timing = [], []
        for c, ss in samples.items():
            crow = []
            for s in ss:
                g = geometry(c, s)
                write_geometry(g, res / "interchanges" / c / str(s) / "geometry.json")
                for r in g.ramps:
                    crow.append({"class_id": c, "sample": s, "ramp": r.id,
                                 "target_radius_m": r.target_radius_m,
                                 "target_slope_pct": r.target_slope_pct,
                                 "min_radius_m": r.min_radius_m, "max_slope_pct": r.max_slope_pct,
                                 "length_m": r.length_m, "ok": r.ok, "evaluations": 100,
                                 "first_try_ok": r.ok, "resamples": 0,
                                 "infeasible": "radius 60 m not met" if not r.ok else "",
                                 "conflicts": 0, "first_target_radius_m": r.target_radius_m,
                                 "first_target_slope_pct": r.target_slope_pct})
                    timing.append({"class_id": c, "sample": s, "ramp": r.id, "evaluations": 100,
                                   "seconds": 0.1})
            _table(res / "geometry" / f"{c}.parquet", crow, GEOMETRY_SCHEMA)
            rows += crow
        _table(res / "geometry.parquet", rows, GEOMETRY_SCHEMA)
        _table(res / "geometry_timing.parquet", timing)
    if "export" in stages:
        for c, ss in samples.items():
            erows = []
            for s in ss:
                folder = res / "interchanges" / c / str(s)
                (folder / "interchange.xodr").write_text("<OpenDRIVE/>\n", encoding="utf-8")
                (folder / "interchange.net.xml").write_text("<net/>\n", encoding="utf-8")
                _png(folder / "plan.png", 0.1 * s)
                erows += [{"class_id": c, "sample": s, "check": k, "ok": True, "detail": ""}
                          for k in ("export", "netconvert")]
            _table(res / "export" / f"{c}.parquet", erows)
    if "validation" in stages:
        vrows = [{"class_id": c, "sample": s, "check": k,
                  "ok": not (c == CLASS and s == 1 and k == "asam_qc"),
                  "detail": "1 issue: <lane> gap" if (c == CLASS and s == 1 and k == "asam_qc")
                  else "fine"}
                 for c, ss in samples.items() for s in ss
                 for k in ("asam_qc", "clearance", "continuity", "export", "netconvert", "routes",
                           "xsd")]
        for c in samples:
            _table(res / "validation" / f"{c}.parquet", [r for r in vrows if r["class_id"] == c])
        _table(res / "validation.parquet", vrows)
    if "throughput" in stages:
        trows = [{"class_id": c, "sample": s, "density_veh_h": d, "throughput_veh_h": 3 * d + s,
                  "entered": 100, "left": 90, "not_inserted": 0, "teleports": 0, "collisions": 0,
                  "stable_from_s": 250.0, "movements": 4, "demand_veh_h": 4 * d,
                  "entering_veh_h": 4 * d, "balanced": True, "running_end": 10,
                  "teleports_wrong_lane": 0, "teleports_jam": 0, "teleports_other": 0,
                  "flagged": False, "seed": 1, "ok": True, "reason": ""}
                 for c, ss in samples.items() for s in ss[:2] for d in (450.0, 1800.0)]
        _table(res / "throughput.parquet", trows)
        for c in samples:
            _table(res / "throughput" / f"{c}.parquet", [r for r in trows if r["class_id"] == c])
        stats = []
        for d in (450.0, 1800.0):
            stats.append({"density_veh_h": d, "scope": "class", "a": CLASS, "b": CLASS2,
                          "t_stat": 2.5, "p_value": 0.03, "n_a": 2, "n_b": 1,
                          "mean_a_veh_h": 3 * d, "mean_b_veh_h": 3 * d, "std_veh_h": math.nan,
                          "n_flagged_a": 0, "n_flagged_b": 0})
            for scope, a in (("inter_class_std", "*"), ("intra_class_std", "*")):
                stats.append({"density_veh_h": d, "scope": scope, "a": a, "b": "",
                              "t_stat": math.nan, "p_value": math.nan, "n_a": 2, "n_b": 0,
                              "mean_a_veh_h": math.nan, "mean_b_veh_h": math.nan,
                              "std_veh_h": 12.5, "n_flagged_a": 0, "n_flagged_b": 0})
        _table(res / "throughput_stats.parquet", stats)
        for f in ("fig4_entering_leaving", "fig5_class_throughput", "fig6_pvalues"):
            _png(res / "figures" / f"{f}.png", 0.4)
    if "fuel" in stages:
        for c, ss in samples.items():
            frows = []
            for s in ss:
                parts = []
                for ramp, direction in (("r1", "up"), ("r2", "down")):
                    row = {"class_id": c, "sample": s, "ramp": ramp, "direction": direction,
                           "length_m": 180.0, "min_radius_m": 58.0, "max_slope_pct": 3.6,
                           "climb_m": 6.5 if direction == "up" else -6.5, "target_speed_mps": 10.0,
                           "mean_speed_mps": 9.9, "duration_s": 18.0,
                           "fuel_ml": 150.0 + s if direction == "up" else 40.0,
                           "fuel_ml_per_km": (150.0 + s) / 0.18 if direction == "up" else 222.0,
                           "max_lateral_error_m": 0.01, "max_lateral_accel_mps2": 1.2,
                           "completed": not (s == 2 and ramp == "r2"),
                           "reason": "lateral error over 1 m" if (s == 2 and ramp == "r2") else ""}
                    frows.append(row)
                    parts.append({k: v for k, v in row.items() if k not in ("class_id", "sample")})
                _table(res / "fuel" / f"class_id={c}" / f"sample={s}" / "part-0.parquet", parts)
            _table(res / "plugins" / "truck_fuel" / f"{c}.parquet", frows)
    return res
