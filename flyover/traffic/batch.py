"""Runs and tables: one interchange at every density, one class in one process, the aggregate.

Tables (``../shared/DESIGN.md``, "Traffic throughput"):

``results/throughput/{class_id}.parquet`` → ``results/throughput.parquet``
    One row per interchange × density (:data:`THROUGHPUT_SCHEMA`): the DESIGN
    columns, then ``movements``, ``demand_veh_h`` (movements × density),
    ``entering_veh_h`` (over the stable window), ``balanced``, ``running_end``,
    the teleports by reason, ``flagged`` (teleports or collisions: such a run
    is never averaged in silently), ``seed``, ``ok`` and ``reason`` (a network
    SUMO cannot load, a movement without a route, an aborted run).
``results/throughput/{class_id}/series.parquet``
    The time series (:data:`SERIES_SCHEMA`): vehicles entering and leaving per
    interval, and in the network at its end, per interchange and density.

Every table is written atomically (temporary file, then ``os.replace``).
"""

from __future__ import annotations

import logging
import os
import tempfile
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from flyover.errors import FlyoverError
from flyover.topology.tables import write_parquet
from flyover.traffic.demand import DemandError, Flow, interchange_or_network_flows, routes_xml
from flyover.traffic.measure import stable_window
from flyover.traffic.settings import ThroughputSettings, run_seed, selection_seed
from flyover.traffic.simulate import RunResult, simulate

__all__ = ["THROUGHPUT_SCHEMA", "SERIES_SCHEMA", "select_samples", "run_flows",
           "run_interchange", "run_class", "read_rows", "aggregate_tables"]

log = logging.getLogger(__name__)

THROUGHPUT_SCHEMA = pa.schema([
    ("class_id", pa.string()), ("sample", pa.int64()), ("density_veh_h", pa.float64()),
    ("throughput_veh_h", pa.float64()), ("entered", pa.int64()), ("left", pa.int64()),
    ("not_inserted", pa.int64()), ("teleports", pa.int64()), ("collisions", pa.int64()),
    ("stable_from_s", pa.float64()),
    ("movements", pa.int64()), ("demand_veh_h", pa.float64()), ("entering_veh_h", pa.float64()),
    ("balanced", pa.bool_()), ("running_end", pa.int64()), ("teleports_wrong_lane", pa.int64()),
    ("teleports_jam", pa.int64()), ("teleports_other", pa.int64()), ("flagged", pa.bool_()),
    ("seed", pa.int64()), ("ok", pa.bool_()), ("reason", pa.string()),
])

SERIES_SCHEMA = pa.schema([
    ("class_id", pa.string()), ("sample", pa.int64()), ("density_veh_h", pa.float64()),
    ("t_s", pa.float64()), ("entered", pa.int64()), ("left", pa.int64()),
    ("in_network", pa.int64()),
])


def select_samples(samples: Iterable[int], k: int, seed: int, class_id: str) -> list[int]:
    """``k`` of a class's ``samples``, chosen at random with the class's seed (all if k = 0).

    >>> select_samples(range(10), 3, 1, "c0") == select_samples(reversed(range(10)), 3, 1, "c0")
    True
    """
    pool = sorted({int(s) for s in samples})
    if k <= 0 or k >= len(pool):
        return pool
    rng = np.random.default_rng(selection_seed(seed, class_id))
    return sorted(int(s) for s in rng.choice(pool, size=k, replace=False))


def _row(class_id: str, sample: int, density: float, seed: int, n_moves: int, **kw) -> dict:
    row = {"class_id": class_id, "sample": int(sample), "density_veh_h": float(density),
           "throughput_veh_h": float("nan"), "entered": 0, "left": 0, "not_inserted": 0,
           "teleports": 0, "collisions": 0, "stable_from_s": float("nan"),
           "movements": int(n_moves), "demand_veh_h": float(n_moves * density),
           "entering_veh_h": float("nan"), "balanced": False, "running_end": 0,
           "teleports_wrong_lane": 0, "teleports_jam": 0, "teleports_other": 0,
           "flagged": False, "seed": int(seed), "ok": False, "reason": ""}
    row.update(kw)
    return row


def _measured(res: RunResult, settings: ThroughputSettings) -> dict:
    w = stable_window(res.entered, res.left, res.interval_s, min_stable_s=settings.min_stable_s,
                      balance_tolerance=settings.balance_tolerance)
    why = res.teleport_reasons
    wrong, jam = why.get("wrong lane", 0), why.get("jam", 0)
    return {"throughput_veh_h": w.throughput_veh_h, "entered": int(res.entered.sum()),
            "left": int(res.left.sum()), "not_inserted": res.not_inserted,
            "teleports": res.teleports, "collisions": res.collisions,
            "stable_from_s": w.stable_from_s, "entering_veh_h": w.entering_veh_h,
            "balanced": w.balanced, "running_end": res.running,
            "teleports_wrong_lane": wrong, "teleports_jam": jam,
            "teleports_other": res.teleports - wrong - jam,
            "flagged": bool(res.teleports or res.collisions), "ok": True}


def run_flows(net: str | os.PathLike, flows: Sequence[Flow], density: float, seed: int,
              settings: ThroughputSettings) -> RunResult:
    """One run of ``flows`` at ``density`` veh/h each on the network ``net``."""
    with tempfile.TemporaryDirectory(prefix="flyover-demand-") as tmp:
        routes = Path(tmp) / "demand.rou.xml"
        routes.write_text(routes_xml(list(flows), density, settings), encoding="utf-8")
        return simulate(net, routes, seed, settings)


def run_interchange(net: str | os.PathLike, settings: ThroughputSettings, *, class_id: str,
                    sample: int, densities: Sequence[float] | None = None
                    ) -> tuple[list[dict], list[dict]]:
    """Every density on one interchange: rows of the throughput and the series tables.

    The movements come from ``geometry.json`` and ``interchange.xodr`` beside
    ``net`` (else every entry → exit of the bare network). A missing network,
    a movement without a route or a failed run becomes a row with ``ok`` False
    and the reason; nothing is raised.
    """
    densities = tuple(settings.densities if densities is None else densities)
    seeds = {d: run_seed(settings.seed, class_id, sample, d) for d in densities}
    try:
        if not Path(net).exists():
            raise DemandError("no SUMO network (the export failed?)", source=str(net))
        flows, _ = interchange_or_network_flows(net, uturns=settings.uturns)
    except FlyoverError as exc:
        log.error("%s", exc.one_line())
        return [_row(class_id, sample, d, seeds[d], 0, reason=exc.one_line()) for d in densities], []
    rows, series = [], []
    for d in densities:
        try:
            res = run_flows(net, flows, d, seeds[d], settings)
        except FlyoverError as exc:
            log.error("%s", exc.one_line())
            rows.append(_row(class_id, sample, d, seeds[d], len(flows), reason=exc.one_line()))
            continue
        row = _row(class_id, sample, d, seeds[d], len(flows), **_measured(res, settings))
        if row["flagged"]:
            row["reason"] = (f"{res.teleports} teleports ({res.teleport_reasons}), "
                             f"{res.collisions} collisions")
            log.warning("%s sample %d at %g veh/h: %s", class_id, sample, d, row["reason"])
        rows.append(row)
        in_net = np.cumsum(res.entered - res.left)
        series += [{"class_id": class_id, "sample": int(sample), "density_veh_h": float(d),
                    "t_s": float(i * res.interval_s), "entered": int(res.entered[i]),
                    "left": int(res.left[i]), "in_network": int(in_net[i])}
                   for i in range(len(res.entered))]
        log.info("%s sample %d at %g veh/h: %.0f veh/h from %.0f s (%d entered, %d left, "
                 "%d not inserted, %d teleports, %d collisions) in %.1f s", class_id, sample, d,
                 row["throughput_veh_h"], row["stable_from_s"], row["entered"], row["left"],
                 row["not_inserted"], row["teleports"], row["collisions"], res.wall_s)
    return rows, series


def _run_one(settings: ThroughputSettings, class_id: str, job: tuple[int, str, float]
             ) -> tuple[list[dict], list[dict]]:
    sample, net, density = job
    return run_interchange(net, settings, class_id=class_id, sample=int(sample), densities=[density])


def run_class(interchanges: Sequence[tuple[int, str | os.PathLike]], class_id: str,
              settings: ThroughputSettings, table: str | os.PathLike,
              series: str | os.PathLike, workers: int = 1) -> list[dict]:
    """Run ``(sample, net)`` interchanges of one class at every density.

    Each run is its own libsumo simulation, seeded by class, sample and density; ``workers``
    forked processes share them (the same rows for any number). Writes the class's
    throughput rows to ``table`` and its time series to ``series`` (both atomically);
    returns the rows.
    """
    from functools import partial  # noqa: PLC0415

    from flyover.parallel import map_ordered  # noqa: PLC0415

    jobs = [(int(sample), str(net), float(d))
            for sample, net in sorted(interchanges, key=lambda t: int(t[0]))
            for d in settings.densities]
    # the densest runs take longest (up to ~10x the lightest): started first, they leave
    # the short ones to fill the workers' ends instead of one long run ending alone;
    # the rows keep the order of ``jobs``
    order = sorted(range(len(jobs)), key=lambda i: (-jobs[i][2], i))
    done = dict(zip(order, map_ordered(partial(_run_one, settings, class_id),
                                       [jobs[i] for i in order], workers)))
    rows, srows = [], []
    for i in range(len(jobs)):
        rows += done[i][0]
        srows += done[i][1]
    write_parquet(rows, THROUGHPUT_SCHEMA, table)
    write_parquet(srows, SERIES_SCHEMA, series)
    return rows


def read_rows(paths: Iterable[str | os.PathLike], schema: pa.Schema) -> list[dict]:
    """The rows of per-class tables, concatenated in the order given."""
    rows: list[dict] = []
    for p in paths:
        rows += pq.read_table(p, schema=schema).to_pylist()
    return rows


def aggregate_tables(class_tables: Sequence[str | os.PathLike],
                     series_tables: Sequence[str | os.PathLike], throughput: str | os.PathLike,
                     stats: str | os.PathLike) -> tuple[list[dict], list[dict], list[dict]]:
    """Per-class tables → ``throughput.parquet`` and ``throughput_stats.parquet``.

    ``series_tables`` are the classes' time series (the sample t-tests use the
    per-interval throughputs of the stable windows). Returns the rows of both
    tables and the series rows.
    """
    from flyover.traffic.stats import STATS_SCHEMA, throughput_stats  # noqa: PLC0415

    rows = read_rows(sorted(class_tables, key=lambda p: Path(p).name), THROUGHPUT_SCHEMA)
    series = read_rows(sorted(series_tables, key=lambda p: Path(p).parent.name), SERIES_SCHEMA)
    write_parquet(rows, THROUGHPUT_SCHEMA, throughput)
    srows = throughput_stats(rows, series)
    write_parquet(srows, STATS_SCHEMA, stats)
    flagged = sum(r["flagged"] for r in rows)
    if flagged:
        log.warning("%d of %d runs flagged (teleports or collisions): kept in the statistics and "
                    "counted in their n_flagged columns", flagged, len(rows))
    return rows, srows, series
