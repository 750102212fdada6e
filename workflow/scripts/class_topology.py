"""Rule class_topology: a class's topology GraphML and its drawing."""
from flyover.topology.draw import draw_topology
from flyover.topology.io import read_graphml, write_graphml
from flyover.workflow_log import setup_logging

setup_logging(snakemake.log[0])
topology = read_graphml(snakemake.input[0])
topology.name = snakemake.wildcards.class_id
write_graphml(topology, snakemake.output.graphml)
title = f"{snakemake.params.name} ({snakemake.wildcards.class_id})"
draw_topology(topology, snakemake.output.png, title=title)
