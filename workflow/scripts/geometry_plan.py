"""Checkpoint geometry_plan: class id → sample numbers of its feature sets."""
import json
from pathlib import Path

from flyover.geometry.tables import read_feature_sets
from flyover.topology.io import atomic_write
from flyover.workflow_log import setup_logging

setup_logging(snakemake.log[0])
plan = {Path(p).stem: sorted(read_feature_sets(p)) for p in snakemake.input}
atomic_write(snakemake.output.plan, (json.dumps(plan, sort_keys=True) + "\n").encode())
