# Step 3: per class, the feature sets to build = rows of a small t-way covering array
# over its roads' and ramps' features (flyover/sampling).

# Bump when the algorithm changes: params are rerun triggers.
# 2: slope fixed at 0 on level ramps (flyover.geometry.feasibility), not sampled.
# 3: per-ramp domains from the layout (no radius inf on a turning ramp, no (radius, slope) a
#    ramp cannot build within geometry.max_ramp_length_m): the geometry section feeds them.
# 4: an outer connector's radius exceeds its loop's (flyover.geometry.feasibility.round_loops)
# 5: so on cloverleaf_cd, whose connectors and loops join C-D roads (each counts as the
#    carriageway it runs beside, chains.Movements.through_stubs): 167 of its 304 pairs broke
#    the rule; 64 rows (the lower bound) instead of 77; other classes unchanged
# 6: a right turn by at most 90 degrees between two roads on one level without a planned
#    crest is a level ramp, slope fixed at 0 (feasibility.level_ramps: DC's r14, fitted
#    level, every slope drawn for it infeasible); catalog unchanged
# 7: a ramp running straight on between two ramps (feasibility.straight_connectors:
#    Columbus's r12) has its radius fixed at inf; catalog unchanged (no such ramp)
# 8: DC's E Street Expressway meets the I-66 line at a junction of its own (GEOMETRY 37):
#    r5 turns right by 90 degrees on one level, a level ramp (slope fixed at 0); r8 and r13
#    are no loops (they join on the left); the other classes unchanged
# 9: a level ramp between two windows the layout fixes (feasibility.shift_rooms: DC's
#    continuation ramps r3 / r4) is sampled only radii its sideways shift can be built
#    with at its road's lanes (no inf); the other classes unchanged (no such ramp)
# 10: a loop joining a collector road (a stub splitting off its road's chain, one of whose
#    branches leads back onto it: Columbus's r13) goes to that road for the outer-connector
#    rule (chains.Movements.collects): Columbus's r2 is sampled wider than the loop r5 (75
#    rows instead of 77); the layout is unchanged; the other classes unchanged (no such stub)
SAMPLING_VERSION = 10


rule sample_class:
    """One class's topology → its feature sets and their coverage."""
    input:
        topology="results/classes/{class_id}/topology.graphml",
    output:
        features="results/features/{class_id}.parquet",
        coverage="results/coverage/{class_id}.parquet",
    log:
        "logs/sampling/{class_id}.log",
    conda:
        "../envs/flyover.yaml"
    params:
        version=SAMPLING_VERSION,
        t=config["sampling"]["t"],
        work=config["sampling"]["work"],
        profile=config["sampling"]["profile"],
        profile_spec=config["sampling"]["profiles"].get(config["sampling"]["profile"]),
        seed=config["seed"],
        geometry=config["geometry"],  # the per-ramp domains (flyover.geometry.feasibility)
    threads: 1
    # measured per Slurm job: peak 0.63 GB, CPU 4 s at t <= 2 (t = 3 arrays take longer)
    resources:
        mem_mb=1000,
        runtime=30,
    benchmark:
        "logs/benchmarks/sampling/{class_id}.tsv"
    script:
        "../scripts/sample_class.py"


rule coverage_table:
    """Every class's coverage row → results/coverage.parquet."""
    input:
        class_coverage_rows,
    output:
        table="results/coverage.parquet",
    log:
        "logs/coverage.log",
    conda:
        "../envs/flyover.yaml"
    params:
        version=SAMPLING_VERSION,
    script:
        "../scripts/sample_coverage.py"


rule sampling:
    """Target: the sampling stage only (feature sets of every class, coverage table)."""
    input:
        "results/coverage.parquet",
        class_feature_tables,
