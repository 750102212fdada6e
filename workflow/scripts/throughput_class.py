"""Rule throughput_class: one class's chosen interchanges x densities in SUMO (libsumo, one process)."""
import logging
from pathlib import Path

import pyarrow.parquet as pq

from flyover.traffic.batch import run_class, select_samples
from flyover.traffic.settings import ThroughputSettings
from flyover.workflow_log import setup_logging

setup_logging(snakemake.log[0])
class_id = snakemake.wildcards.class_id
settings = ThroughputSettings.from_config(
    {"seed": snakemake.params.seed, "throughput": snakemake.params.throughput})
listed = sorted(set(pq.read_table(snakemake.input.interchanges, columns=["sample"])
                    .column("sample").to_pylist()))  # the export table: rows per check
chosen = select_samples(listed, settings.samples_per_class, settings.seed, class_id)
logging.info("%s: %d of %d interchanges: %s", class_id, len(chosen), len(listed), chosen)
nets = [(s, Path(f"results/interchanges/{class_id}/{s}/interchange.net.xml")) for s in chosen]
rows = run_class(nets, class_id, settings, snakemake.output.table, snakemake.output.series,
                 workers=snakemake.threads)
failed = [r for r in rows if not r["ok"]]
logging.info("%s: %d runs, %d failed, %d flagged", class_id, len(rows), len(failed),
             sum(r["flagged"] for r in rows))
