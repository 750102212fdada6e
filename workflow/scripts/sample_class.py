"""Rule sample_class: a class's topology → features/{class_id}.parquet + its coverage row."""
import logging

from flyover.geometry.feasibility import fixed_features, forbidden_features
from flyover.geometry.layout import LayoutSettings
from flyover.sampling.sample import COVERAGE_SCHEMA, FEATURES_SCHEMA, sample_topology
from flyover.sampling.settings import settings_from_config
from flyover.topology.io import read_graphml
from flyover.topology.tables import write_parquet
from flyover.workflow_log import setup_logging

setup_logging(snakemake.log[0])
class_id = snakemake.wildcards.class_id
p = snakemake.params
profiles = {p.profile: p.profile_spec} if p.profile_spec else {}
settings = settings_from_config(
    {"sampling": {"t": p.t, "work": p.work, "profile": p.profile, "profiles": profiles}})
topology = read_graphml(snakemake.input.topology)
sampling = sample_topology(topology, settings.profile, t=settings.t, seed=snakemake.params.seed,
                           class_id=class_id, fixed=fixed_features(topology),
                           extra=forbidden_features(topology, settings.profile,
                                                    LayoutSettings.from_config(p.geometry)),
                           budget=settings.budget)
write_parquet(sampling.feature_rows(), FEATURES_SCHEMA, snakemake.output.features)
write_parquet([sampling.coverage_row()], COVERAGE_SCHEMA, snakemake.output.coverage)
c = sampling.coverage
logging.getLogger("sampling").info(
    "%s: t=%d, %d parameters (%d fixed), %d rows (lower bound %d), %d/%d tuples covered; %s",
    class_id, c.t, c.n_params, len(sampling.model.fixed), c.rows, c.lower_bound,
    c.tuples_covered, c.tuples_total, sampling.array.construction)
