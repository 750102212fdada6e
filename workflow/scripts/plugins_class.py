"""Rule plugin_class: one class's interchanges through one plugin → hive partitions + rows."""
import logging
from pathlib import Path

import pyarrow.parquet as pq

from flyover.plugins import run_plugins_on_class
from flyover.workflow_log import setup_logging

setup_logging(snakemake.log[0])
class_id, plugin = snakemake.wildcards.class_id, snakemake.wildcards.plugin
results = Path(snakemake.input.geometry).parent.parent  # results/geometry/{class_id}.parquet
samples = sorted(set(pq.read_table(snakemake.input.geometry, columns=["sample"])
                     .column("sample").to_pylist()))
paths = [results / "interchanges" / class_id / str(s) / "geometry.json" for s in samples]
run = run_plugins_on_class(paths, results, config={plugin: snakemake.params.settings},
                           plugins=[plugin], class_tables={plugin: snakemake.output.table},
                           config_source="config/config.yaml", workers=snakemake.threads)
log = logging.getLogger("plugins")
for r in run.runs:
    log.info("%s %s on %s: %d interchanges, %d rows, %d failed, %.1f s CPU", r.plugin,
             r.version, class_id, r.interchanges, r.rows, len(r.failures), r.cpu_s)
    for path, reason in r.failures:
        log.warning("%s: %s: %s", r.plugin, path, reason)
