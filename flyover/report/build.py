"""Build the dataset browser: static HTML pages over a results folder.

Pages (under the output folder, ``results/report/`` by default):

* ``index.html`` — overview: cities and their interchanges, classes, what each stage
  built, what was rejected or failed and why;
* ``classes/{class_id}.html`` — one class: coverage, geometry targets against what was
  achieved, validation, a gallery of plan views and every interchange's files;
* ``interchanges/{class_id}/{sample}.html`` — one interchange: the interactive plan view
  (pan, zoom, hover a ramp for its facts) and its rows of every table;
* ``evaluation.html`` — throughput (paper Fig. 4–6, Table III) and truck fuel (Table IV,
  Fig. 7), each figure beside the table it is drawn from.

The pages link to the results files where they lie (relative links, so the folder opens
from disk with no server and can be moved together with ``results/``); nothing of
``results/`` is copied except into the report's own figures. The output is the same
bytes for the same results. It is built in a temporary folder beside the output and
swapped in whole, so a reader never sees half a report and pages of classes that are
gone do not linger.
"""

from __future__ import annotations

import logging
import math
import os
import shutil
import tempfile
from importlib import resources
from pathlib import Path
from typing import Any, Mapping
from urllib.parse import quote

from flyover import __version__
from flyover.errors import FlyoverError
from flyover.report.data import Results, display

__all__ = ["build_report", "REPORT_PAGES"]

log = logging.getLogger(__name__)

#: the pages every report has (relative to the output folder)
REPORT_PAGES = ("index.html", "evaluation.html")

_GEOMETRY_SUMMARY = """
SELECT g.class_id, count(DISTINCT g.sample) AS interchanges, count(*) AS ramps,
       sum(g.ok::INT) AS ramps_ok, sum(g.first_try_ok::INT) AS first_try_ok,
       sum(g.resamples) AS resamples,
       count(*) FILTER (WHERE g.infeasible <> '' AND NOT starts_with(g.infeasible, 'not built'))
           AS infeasible,
       count(DISTINCT g.sample) FILTER (WHERE starts_with(g.infeasible, 'not built')) AS not_built,
       min(g.length_m) AS min_length_m, median(g.length_m) AS median_length_m,
       max(g.length_m) AS max_length_m, sum(g.length_m) / 1000 AS ramp_km,
       median(g.evaluations) AS median_evaluations
FROM geometry g
GROUP BY g.class_id ORDER BY g.class_id
"""

_BY_TARGET = """
SELECT class_id, {col} AS target, count(*) AS ramps, avg(ok::INT) AS ok_share,
       avg(first_try_ok::INT) AS first_try_share,
       min({got}) AS achieved_min, median({got}) AS achieved_median, max({got}) AS achieved_max
FROM geometry WHERE NOT starts_with(infeasible, 'not built')
GROUP BY ALL ORDER BY class_id, target
"""

_VALIDATION_BY_CHECK = """
SELECT class_id, "check", count(*) AS interchanges, sum(ok::INT) AS passed
FROM validation GROUP BY ALL ORDER BY class_id, "check"
"""

_FAILED_CHECKS = """
SELECT class_id, sample, "check", detail FROM validation WHERE NOT ok
ORDER BY class_id, sample, "check"
"""

_GEOMETRY_PROBLEMS = """
SELECT class_id, sample, ramp, infeasible AS reason FROM geometry WHERE infeasible <> ''
ORDER BY class_id, sample, ramp
"""

_THROUGHPUT_FAILED = """
SELECT class_id, sample, density_veh_h, reason FROM throughput WHERE NOT ok
ORDER BY class_id, sample, density_veh_h
"""

_FIG4_RUNS = f"""
WITH first AS (
  SELECT t.class_id, t.sample FROM throughput t
  LEFT JOIN (SELECT class_id, any_value(class_name) AS class_name FROM classes GROUP BY class_id) n
  USING (class_id) WHERE t.ok ORDER BY coalesce(n.class_name, t.class_id), t.class_id, t.sample
  LIMIT 1)
SELECT t.class_id, t.sample, t.density_veh_h, round(t.throughput_veh_h, 1) AS throughput_veh_h,
       t.stable_from_s, t.entered, t."left", t.not_inserted, t.teleports, t.collisions, t.balanced
FROM throughput t JOIN first USING (class_id, sample) WHERE t.ok ORDER BY t.density_veh_h
"""

_PVALUES = """
SELECT density_veh_h, a, b, round(t_stat, 2) AS t_stat, p_value,
       round(mean_a_veh_h, 1) AS mean_a_veh_h, round(mean_b_veh_h, 1) AS mean_b_veh_h
FROM throughput_stats WHERE scope = 'class' ORDER BY density_veh_h, a, b
"""

_TABLE3 = """
SELECT density_veh_h,
       round(any_value(std_veh_h) FILTER (WHERE scope = 'inter_class_std'), 1) AS inter_class_std_veh_h,
       round(any_value(std_veh_h) FILTER (WHERE scope = 'intra_class_std' AND a = '*'), 1)
           AS intra_class_std_veh_h
FROM throughput_stats GROUP BY density_veh_h ORDER BY density_veh_h
"""

_SAMPLE_THROUGHPUT = """
SELECT class_id, sample, density_veh_h, throughput_veh_h, stable_from_s, entered, "left",
       teleports, collisions, ok, reason FROM throughput ORDER BY class_id, sample, density_veh_h
"""

_FUEL_ROWS = """
SELECT class_id, sample, ramp, direction, length_m, fuel_ml, fuel_ml_per_km, mean_speed_mps,
       completed, reason FROM fuel ORDER BY class_id, sample, ramp
"""

_FUEL_BY_INTERCHANGE = """
SELECT class_id, sample, count(*) AS ramps, sum(fuel_ml) FILTER (WHERE completed) AS fuel_ml,
       count(*) FILTER (WHERE NOT completed) AS incomplete
FROM fuel GROUP BY ALL
"""


def _missing_stages(stages) -> list[tuple[str, str]]:
    """The evaluation stages :func:`flyover.summary.stage_status` does not list (it lists
    them once they ran), with the target that runs them."""
    if not stages:
        return []
    names = {s.stage for s in stages}
    core = {"sampling", "geometry", "export", "validation", "throughput"}
    out = [] if "throughput" in names else [("throughput", "throughput")]
    if not names - core:
        out.append(("plugins (e.g. truck_fuel)", "plugins"))
    return out


def _finite(value: Any) -> Any:
    """``value`` with non-finite floats as JSON can hold them (``"inf"``, ``null``)."""
    if isinstance(value, float) and not math.isfinite(value):
        return None if math.isnan(value) else ("inf" if value > 0 else "-inf")
    if isinstance(value, Mapping):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v) for v in value]
    return value


def _environment():
    import jinja2  # noqa: PLC0415

    env = jinja2.Environment(
        loader=jinja2.PackageLoader("flyover.report", "templates"),
        autoescape=jinja2.select_autoescape(("html",), default=True),
        undefined=jinja2.StrictUndefined, trim_blocks=True, lstrip_blocks=True,
        keep_trailing_newline=True)
    env.filters["cell"] = display
    env.filters["pct"] = lambda v: "—" if v is None or (isinstance(v, float) and math.isnan(v)) \
        else f"{100 * v:.1f} %"
    return env


class _Writer:
    """Renders templates into the (temporary) output folder, with relative paths."""

    def __init__(self, results: Results, tmp: Path, final: Path):
        self.env = _environment()
        self.results = results
        self.tmp = tmp
        # results as seen from the final output folder (the report moves there)
        self.res_from_out = Path(os.path.relpath(results.root.resolve(), final.resolve()))
        #: "{class_id}/{sample}" of every interchange page written so far (tables link them)
        self.interchange_pages: set[str] = set()
        self.env.globals["interchange_pages"] = self.interchange_pages

    def page(self, relpath: str, template: str, **context) -> None:
        depth = relpath.count("/")
        base = "../" * depth
        res = quote((Path(base or ".") / self.res_from_out).as_posix())
        html = self.env.get_template(template).render(
            base=base, res=res, version=__version__, page=relpath, **context)
        path = self.tmp / relpath
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(html, encoding="utf-8")


def _geometry_summary(results: Results):
    """Per class: ramps within targets, first try, lengths, DE effort (evaluations, not
    seconds: the report is the same bytes for the same results; times are in
    ``geometry_timing``)."""
    return results.sql(_GEOMETRY_SUMMARY)


def _class_context(results: Results) -> dict[str, Any]:
    """Every per-class table, grouped by class."""
    t = {
        "coverage": results.named("coverage"),
        "geometry": _geometry_summary(results),
        "radius": results.sql(_BY_TARGET.format(col="target_radius_m", got="min_radius_m")),
        "slope": results.sql(_BY_TARGET.format(col="target_slope_pct", got="max_slope_pct")),
        "validation": results.sql(_VALIDATION_BY_CHECK),
        "failed_checks": results.sql(_FAILED_CHECKS),
        "geometry_rows": results.sql("SELECT * FROM geometry ORDER BY class_id, sample, ramp"),
        "validation_rows": results.sql('SELECT * FROM validation ORDER BY class_id, sample, "check"'),
        "throughput_rows": results.sql(_SAMPLE_THROUGHPUT),
        "fuel_rows": results.sql(_FUEL_ROWS),
        "fuel_per_interchange": results.sql(_FUEL_BY_INTERCHANGE),
        "throughput_by_class": results.named("throughput-by-class"),
        "fuel_by_class": results.named("fuel-by-class"),
    }
    grouped = {k: results.by_class(v) for k, v in t.items()}
    return {"tables": t, "grouped": grouped}


def _interchange_rows(results: Results, class_id: str, ctx: Mapping[str, Any]) -> list[dict]:
    """Per interchange of a class: status of every stage and its files."""
    g = ctx["grouped"]
    samples = {r["sample"] for r in g["geometry_rows"].get(class_id, [])}
    samples |= set(results.samples(class_id))
    out = []
    for s in sorted(samples):
        ramps = [r for r in g["geometry_rows"].get(class_id, []) if r["sample"] == s]
        folder = f"interchanges/{class_id}/{s}"
        not_built = next((r["infeasible"] for r in ramps
                          if (r["infeasible"] or "").startswith("not built")), "")
        checks = [r for r in g["failed_checks"].get(class_id, []) if r["sample"] == s]
        validated = any(r["sample"] == s for r in g["validation_rows"].get(class_id, []))
        fuel = next((r for r in g["fuel_per_interchange"].get(class_id, []) if r["sample"] == s),
                    None)
        runs = [r for r in g["throughput_rows"].get(class_id, []) if r["sample"] == s]
        files = [(label, f"{folder}/{name}") for label, name in (
            ("geometry.json", "geometry.json"), ("OpenDRIVE", "interchange.xodr"),
            ("SUMO net", "interchange.net.xml"), ("plan.png", "plan.png"))
            if results.exists(f"{folder}/{name}")]
        out.append({
            "sample": s, "ramps": len(ramps), "ramps_ok": sum(bool(r["ok"]) for r in ramps),
            "not_built": not_built, "failed_checks": [r["check"] for r in checks],
            "validated": validated,
            "fuel": fuel, "throughput_runs": len(runs),
            "plan": f"{folder}/plan.png" if results.exists(f"{folder}/plan.png") else None,
            "view": results.exists(f"{folder}/geometry.json"),
            "files": files})
    return out


def _interchange_page(writer: _Writer, results: Results, class_id: str, info: Mapping,
                      row: Mapping, ctx: Mapping[str, Any], neighbours) -> None:
    from flyover.geometry.model import read_geometry  # noqa: PLC0415
    from flyover.report.view import plan_view  # noqa: PLC0415

    s = row["sample"]
    g = ctx["grouped"]
    fuel = [r for r in g["fuel_rows"].get(class_id, []) if r["sample"] == s]
    extra = {r["ramp"]: {"fuel_direction": r["direction"], "fuel_ml": r["fuel_ml"],
                         "fuel_ml_per_km": r["fuel_ml_per_km"], "fuel_completed": r["completed"]}
             for r in fuel}
    view, view_error = None, ""
    path = results.root / "interchanges" / class_id / str(s) / "geometry.json"
    try:
        view = plan_view(read_geometry(path), extra)
    except FlyoverError as exc:  # one unreadable file is a note on its page, not no report
        log.warning("report: %s", exc.one_line())
        view_error = exc.one_line()
    writer.interchange_pages.add(f"{class_id}/{s}")
    writer.page(
        f"interchanges/{class_id}/{s}.html", "interchange.html",
        class_id=class_id, cls=info, row=row, view=view, view_error=view_error,
        view_info=_finite(view.info) if view else {},
        ramps=[r for r in g["geometry_rows"].get(class_id, []) if r["sample"] == s],
        checks=None if ctx["tables"]["validation_rows"].absent else
        [r for r in g["validation_rows"].get(class_id, []) if r["sample"] == s],
        runs=[r for r in g["throughput_rows"].get(class_id, []) if r["sample"] == s],
        fuel=fuel, neighbours=neighbours)


def build_report(results: str | os.PathLike = "results", out: str | os.PathLike | None = None,
                 ) -> Path:
    """Build the report of ``results`` into ``out`` (default ``results/report``).

    Returns the path of ``index.html``.

    Raises
    ------
    ReportError
        When ``results`` is not a folder or a table or file in it cannot be read.

    Example
    -------
    >>> import tempfile, pathlib
    >>> with tempfile.TemporaryDirectory() as d:
    ...     index = build_report(d)
    ...     sorted(p.name for p in index.parent.iterdir())
    ['assets', 'evaluation.html', 'index.html']
    """
    from flyover.report import figures  # noqa: PLC0415
    from flyover.summary import stage_status  # noqa: PLC0415

    res = Results(Path(results))
    final = Path(out) if out is not None else res.root / "report"
    final.parent.mkdir(parents=True, exist_ok=True)
    _remove_leftovers(final)
    tmp = Path(tempfile.mkdtemp(prefix=f".{final.name}.", suffix=".tmp", dir=final.parent))
    try:
        writer = _Writer(res, tmp, final)
        _assets(tmp)
        manifest = res.manifest()
        ctx = _class_context(res)
        classes_tbl = res.sql("SELECT * FROM classes ORDER BY class_name, city, interchange")
        member_class = {(r["city"], r["interchange"]): r for r in classes_tbl.records}
        names = {c: m.get("class_name", c) for c, m in manifest.items()}
        classes = []
        for class_id, info in manifest.items():
            rows = _interchange_rows(res, class_id, ctx)
            fig = None
            geo_rows = [r for r in ctx["grouped"]["geometry_rows"].get(class_id, [])
                        if not (r["infeasible"] or "").startswith("not built")]
            if geo_rows:
                fig = f"figures/classes/{class_id}_geometry.png"
                figures.plot_class_geometry(geo_rows, tmp / fig,
                                            title=f"{names[class_id]} ({class_id})")
            topo = f"classes/{class_id}/topology.png"
            entry = {"class_id": class_id, "info": info, "rows": rows, "figure": fig,
                     "topology": topo if res.exists(topo) else None,
                     "graphml": f"classes/{class_id}/topology.graphml"
                     if res.exists(f"classes/{class_id}/topology.graphml") else None}
            classes.append(entry)
            writer.page(f"classes/{class_id}.html", "class.html", c=entry, t=ctx["tables"],
                        g=ctx["grouped"], names=names)
            viewable = [r for r in rows if r["view"]]
            for i, row in enumerate(viewable):
                prev_s = viewable[i - 1]["sample"] if i > 0 else None
                next_s = viewable[i + 1]["sample"] if i + 1 < len(viewable) else None
                _interchange_page(writer, res, class_id, info, row, ctx, (prev_s, next_s))
        stages = stage_status(res.root) if manifest else []
        overview = {
            "cities": res.cities(), "member_class": member_class, "classes": classes,
            "names": names, "stages": stages, "stages_missing": _missing_stages(stages),
            "classes_tbl": classes_tbl, "rejected": res.sql("SELECT * FROM rejected "
                                                            "ORDER BY city, source_file"),
            "geometry_problems": res.sql(_GEOMETRY_PROBLEMS),
            "failed_checks": ctx["tables"]["failed_checks"],
            "throughput_failed": res.sql(_THROUGHPUT_FAILED),
            "fuel_incomplete": res.named("fuel-incomplete"),
        }
        writer.page("index.html", "index.html", **overview)
        writer.page("evaluation.html", "evaluation.html", names=names,
                    **_evaluation(res, tmp, names))
        _swap(tmp, final)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    log.info("report: %d classes, %s", len(manifest), final / "index.html")
    return final / "index.html"


def _evaluation(res: Results, tmp: Path, names: Mapping[str, str]) -> dict[str, Any]:
    from flyover.report import figures  # noqa: PLC0415

    ev: dict[str, Any] = {
        "by_class": res.named("throughput-by-class"),
        "fig4_runs": res.sql(_FIG4_RUNS),
        "pvalues": res.sql(_PVALUES),
        "table3": res.sql(_TABLE3),
        "fuel_grid": res.named("fuel-grid"),
        "fuel_by_class": res.named("fuel-by-class"),
        "fuel_totals": res.named("fuel-totals"),
        "fuel_direction": res.named("fuel-by-direction"),
        "tracking": res.named("tracking"),
        "figs": {f: f"figures/{f}.png" if res.exists(f"figures/{f}.png") else None
                 for f in ("fig4_entering_leaving", "fig5_class_throughput", "fig6_pvalues")},
        "fuel_grid_png": None, "fuel_fig7_png": None,
    }
    if not ev["fuel_grid"].absent and ev["fuel_grid"].rows:
        figures.plot_fuel_grid(ev["fuel_grid"].records, tmp / "figures" / "fuel_table4.png")
        ev["fuel_grid_png"] = "figures/fuel_table4.png"
    fuel = res.sql(_FUEL_ROWS)
    if not fuel.absent and fuel.rows:
        figures.plot_fuel_by_class([r for r in fuel.records if r["completed"]], names,
                                   tmp / "figures" / "fuel_by_class.png")
        ev["fuel_fig7_png"] = "figures/fuel_by_class.png"
    return ev


def _assets(tmp: Path) -> None:
    (tmp / "assets").mkdir(parents=True, exist_ok=True)
    for name in ("report.css", "viewer.js", "tables.js"):
        data = resources.files("flyover.report").joinpath("static", name).read_bytes()
        (tmp / "assets" / name).write_bytes(data)


def _remove_leftovers(final: Path, age_s: float = 3600.0) -> None:
    """Remove the temporary folders of builds that were killed (older than ``age_s``: a
    build running now beside this one keeps its own)."""
    import time  # noqa: PLC0415

    for p in final.parent.glob(f".{final.name}.*"):
        if p.is_dir() and (p.name.endswith(".tmp") or ".old." in p.name) and \
                time.time() - p.stat().st_mtime > age_s:
            shutil.rmtree(p, ignore_errors=True)


def _swap(tmp: Path, final: Path) -> None:
    """Replace ``final`` with ``tmp`` (the old report removed only once the new one is in)."""
    from flyover.topology.io import file_mode  # noqa: PLC0415

    fmode = file_mode()
    dmode = fmode | ((fmode & 0o444) >> 2)  # a folder is searchable by whoever may read
    os.chmod(tmp, dmode)
    for p in tmp.rglob("*"):
        os.chmod(p, dmode if p.is_dir() else fmode)
    old = None
    if final.exists():
        old = final.with_name(f".{final.name}.old.{os.getpid()}")
        os.replace(final, old)
    os.replace(tmp, final)
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)

