"""Rule clients_sample: CommonRoad's map verifier on one seeded interchange of the run."""
from flyover.clients.sample import verify_sample
from flyover.workflow_log import setup_logging

setup_logging(snakemake.log[0])
verify_sample(snakemake.input.exports, snakemake.output.table,
              seed=int(snakemake.params.sample["seed"]),
              exclude=list(snakemake.params.sample["exclude_formulas"]))
