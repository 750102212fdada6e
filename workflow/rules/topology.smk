# Step 1–2: city files → topologies → isomorphism classes.


rule import_city:
    """Every file of one city → results/topology/{city}/{interchange}.graphml."""
    input:
        city_files,
    output:
        directory("results/topology/{city}"),
    log:
        "logs/topology/{city}.log",
    threads: 2
    conda:
        "../envs/flyover.yaml"
    params:
        version=TOPOLOGY_VERSION,
        city="{city}",
        osm=city_osm_options,
    script:
        "../scripts/import_city.py"


checkpoint classify:
    """All topologies → classes table, rejected inputs, class manifest."""
    input:
        expand("results/topology/{city}", city=CITIES),
    output:
        table="results/classes.parquet",
        rejected="results/rejected.parquet",
        manifest="results/classes/manifest.json",
    log:
        "logs/classify.log",
    conda:
        "../envs/flyover.yaml"
    params:
        version=TOPOLOGY_VERSION,
        catalog_names=config["topology"]["catalog_names"],
    benchmark:
        "logs/benchmarks/classify.tsv"
    script:
        "../scripts/classify.py"


rule class_topology:
    """One class: its topology as GraphML and a drawing in the paper's style."""
    input:
        class_representative,
    output:
        graphml="results/classes/{class_id}/topology.graphml",
        png="results/classes/{class_id}/topology.png",
    log:
        "logs/classes/{class_id}.log",
    conda:
        "../envs/flyover.yaml"
    params:
        version=TOPOLOGY_VERSION,
        name=class_name,
    script:
        "../scripts/class_topology.py"


rule topology:
    """Target: the topology stage only (classes, rejections, class drawings)."""
    input:
        "results/classes.parquet",
        "results/rejected.parquet",
        "results/classes/manifest.json",
        class_topology_outputs,
