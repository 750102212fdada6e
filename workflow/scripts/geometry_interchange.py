"""Rule geometry: one feature set of one class → geometry.json + its geometry rows."""
import logging

from flyover.geometry.layout import LayoutSettings
from flyover.geometry.tables import (
    build_sample, domain_resampler, read_feature_sets, sample_seed, write_sample,
)
from flyover.topology.io import read_graphml
from flyover.workflow_log import setup_logging

setup_logging(snakemake.log[0])
class_id, sample = snakemake.wildcards.class_id, int(snakemake.wildcards.sample)
seed = int(snakemake.params.seed)
topology = read_graphml(snakemake.input.topology)
feature_sets = read_feature_sets(snakemake.input.features)
settings = LayoutSettings.from_config(snakemake.params.settings)
ic = build_sample(topology, feature_sets[sample], class_id=class_id, sample=sample, seed=seed,
                  settings=settings,
                  resampler=domain_resampler(feature_sets, sample_seed(seed, class_id, sample)))
for o in ic.outcomes:
    if o.infeasible:
        logging.warning("%s sample %d ramp %s: %s", class_id, sample, o.ramp, o.infeasible)
write_sample(ic, snakemake.output.geometry, snakemake.output.table)
