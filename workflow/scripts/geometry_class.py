"""Rule geometry_class: one class's feature sets → every sample's geometry.json + the class's rows."""
from flyover.geometry.batch import build_class
from flyover.geometry.layout import LayoutSettings
from flyover.workflow_log import setup_logging

setup_logging(snakemake.log[0])
build_class(snakemake.input.topology, snakemake.input.features, snakemake.output.table,
            snakemake.params.folder, class_id=snakemake.wildcards.class_id,
            seed=int(snakemake.params.seed),
            settings=LayoutSettings.from_config(snakemake.params.settings),
            timing=snakemake.output.timing, workers=snakemake.threads)
