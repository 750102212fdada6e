# Shared helpers: config validation, city discovery, input functions,
# wildcard constraints. No rule lives here.
import json
from pathlib import Path

from flyover.config import validate_config
from flyover.topology.io import TOPOLOGY_SUFFIXES


validate_config(config, "config/config.yaml")

# Bump a stage's version when its algorithm changes: params are rerun triggers.
TOPOLOGY_VERSION = 1
EXPORT_VERSION = 1
VALIDATION_VERSION = 3


wildcard_constraints:
    city=r"[A-Za-z0-9_.-]+",
    class_id=r"c[0-9a-f]{10}",


def city_names():
    """Cities to build: config `cities`, else every folder of cities_dir."""
    if config["cities"]:
        return sorted(config["cities"])
    root = Path(config["cities_dir"])
    return sorted(p.name for p in root.iterdir() if p.is_dir() and not p.name.startswith("."))


CITIES = city_names()


def city_files(wildcards):
    """The topology files of one city (GraphML, YAML specs, OSM extracts)."""
    root = Path(config["cities_dir"]) / wildcards.city
    return sorted(
        str(p)
        for p in root.iterdir()
        if p.is_file() and p.suffix.lower() in TOPOLOGY_SUFFIXES
    )


def class_manifest():
    """The classify checkpoint's manifest (class id → representative etc.)."""
    path = checkpoints.classify.get().output.manifest
    return json.loads(Path(path).read_text(encoding="utf-8"))


def class_ids():
    return sorted(class_manifest()["classes"])


def class_representative(wildcards):
    """The GraphML of the first member of a class (by city, file, name)."""
    return class_manifest()["classes"][wildcards.class_id]["representative"]


def class_name(wildcards):
    """The readable name of a class (catalog design or shape-roads-ramps)."""
    return class_manifest()["classes"][wildcards.class_id]["class_name"]


def class_topology_outputs(wildcards):
    return expand(
        "results/classes/{class_id}/topology.{ext}",
        class_id=class_ids(),
        ext=["graphml", "png"],
    )


# -- sampling (step 3) --

def class_feature_tables(wildcards):
    """Every class's feature sets (results/features/{class_id}.parquet)."""
    return expand("results/features/{class_id}.parquet", class_id=class_ids())


def class_coverage_rows(wildcards):
    """Every class's row of coverage.parquet, kept per class so one class reruns alone."""
    return expand("results/coverage/{class_id}.parquet", class_id=class_ids())


# -- export (step 5) --

def exported_interchanges():
    """(class_id, sample) of every interchange to export.

    Uses the geometry stage's `geometry_interchanges()` when its rules define
    it; otherwise the geometry.json files already on disk.
    """
    if "geometry_interchanges" in globals():
        return sorted(globals()["geometry_interchanges"]())
    found = glob_wildcards("results/interchanges/{class_id}/{sample}/geometry.json")
    return sorted(zip(found.class_id, found.sample))


def validation_tables(wildcards):
    """Every interchange's rows of validation.parquet (made from geometry.json alone)."""
    return [
        f"results/interchanges/{c}/{s}/validation.parquet"
        for c, s in exported_interchanges()
    ]


def export_outputs(wildcards):
    """Every interchange's .xodr, SUMO network and plan (targets of rule all, not inputs
    of the validation table: one failed export must not keep the table from being built)."""
    return [
        f"results/interchanges/{c}/{s}/{name}"
        for c, s in exported_interchanges()
        for name in ("interchange.xodr", "interchange.net.xml", "plan.png")
    ]


# -- geometry stage (workflow/rules/geometry.smk) --------------------------------
# 3: straight leads on climbing ramps (geometry.leads)
# 4: compiled DE generation step (other random trajectories), restarts 5
# 10: exact stretch tests in the conflict kernel, popsize 4, built C-D roads
# 11: an interchange with a ramp still in conflict is rebuilt with other seeds (rebuilds);
#     a child on the side of its parent facing a road attaches where it has room
GEOMETRY_VERSION = 11


def _features_buildable(class_id):
    """True when a rule makes (or has made) the class's feature sets."""
    made = any("results/features/" in str(o) for r in workflow.rules for o in r.output)
    return made or Path(f"results/features/{class_id}.parquet").exists()


def geometry_features(wildcards):
    """The feature sets of every class that has (or will have) them."""
    return [f"results/features/{c}.parquet" for c in class_ids() if _features_buildable(c)]


def geometry_interchanges():
    """(class_id, sample) of every interchange to build (used by the export rules)."""
    path = checkpoints.geometry_plan.get().output.plan
    plan = json.loads(Path(path).read_text(encoding="utf-8"))
    return [(c, int(s)) for c, samples in sorted(plan.items()) for s in samples]


def geometry_tables(wildcards):
    return [f"results/interchanges/{c}/{s}/geometry.parquet" for c, s in geometry_interchanges()]
