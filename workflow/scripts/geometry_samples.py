"""Checkpoint geometry_samples: the sample numbers of one class's feature sets."""
import json

from flyover.geometry.tables import read_feature_sets
from flyover.topology.io import atomic_write
from flyover.workflow_log import setup_logging

setup_logging(snakemake.log[0])
samples = sorted(read_feature_sets(snakemake.input.features))
atomic_write(snakemake.output.samples, (json.dumps(samples) + "\n").encode())
