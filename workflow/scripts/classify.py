"""Checkpoint classify: all city indexes → classes.parquet, rejected.parquet, manifest."""
import logging
from pathlib import Path

from flyover.topology.city import read_city_index
from flyover.topology.tables import (
    CLASSES_SCHEMA,
    REJECTED_SCHEMA,
    classify_cities,
    write_class_sources,
    write_manifest,
    write_parquet,
)
from flyover.workflow_log import setup_logging

setup_logging(snakemake.log[0])
indexes = [read_city_index(d) for d in snakemake.input]
rows, rejected, manifest = classify_cities(
    indexes, catalog_names=snakemake.params.catalog_names
)
write_parquet(rows, CLASSES_SCHEMA, snakemake.output.table)
write_parquet(rejected, REJECTED_SCHEMA, snakemake.output.rejected)
write_manifest(manifest, snakemake.output.manifest)
changed = write_class_sources(manifest, Path(snakemake.output.manifest).parent)
log = logging.getLogger("classify")
for r in rejected:
    where = ": ".join(x for x in (r["source_file"], r["element"]) if x)
    log.warning("rejected %s: %s", where, r["reason"])
log.info("%d interchanges in %d classes, %d rejected; representative changed: %s",
         len(rows), len(manifest["classes"]), len(rejected), ", ".join(changed) or "none")
