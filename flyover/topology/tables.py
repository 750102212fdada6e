"""Tables of the topology stage: ``classes.parquet``, ``rejected.parquet``, the manifest."""

from __future__ import annotations

import io
import json
import os
from pathlib import Path
from typing import Iterable, Sequence

import pyarrow as pa
import pyarrow.parquet as pq

from flyover.topology.classify import TopologyClass, classify
from flyover.topology.io import atomic_write, read_graphml

__all__ = ["CLASSES_SCHEMA", "REJECTED_SCHEMA", "write_parquet", "classify_cities",
           "write_class_sources", "write_manifest"]

CLASSES_SCHEMA = pa.schema([
    ("city", pa.string()), ("interchange", pa.string()), ("source_file", pa.string()),
    ("class_id", pa.string()), ("class_name", pa.string()), ("n_roads", pa.int32()),
    ("n_ramps", pa.int32()), ("shape", pa.string()),
])

REJECTED_SCHEMA = pa.schema([
    ("city", pa.string()), ("source_file", pa.string()), ("element", pa.string()),
    ("reason", pa.string()),
])


def write_parquet(rows: Sequence[dict], schema: pa.Schema, path: str | os.PathLike) -> None:
    """Write ``rows`` as Parquet with ``schema``, atomically and byte-reproducibly."""
    table = pa.Table.from_pylist(list(rows), schema=schema)
    buf = io.BytesIO()
    pq.write_table(table, buf, compression="zstd", write_statistics=False,
                   store_schema=False)
    atomic_write(path, buf.getvalue())


def classify_cities(indexes: Iterable[dict], *, catalog_names: bool = True
                    ) -> tuple[list[dict], list[dict], dict]:
    """Classify every interchange of the given city indexes.

    Returns the rows of ``classes.parquet``, of ``rejected.parquet``, and the
    class manifest (class id → name, representative GraphML, members).
    """
    topologies, where, rejected = [], {}, []
    for index in indexes:
        rejected += index["rejected"]
        for item in index["interchanges"]:
            t = read_graphml(item["graphml"], name=item["interchange"])
            # classify by (city, source) for a representative independent of input order
            t.source = f"{item['city']}/{item['source_file']}"
            where[id(t)] = item
            topologies.append(t)
    classes: list[TopologyClass] = classify(topologies)
    rows, manifest = [], {}
    for c in classes:
        name = c.class_name if catalog_names else c.class_id
        # the catalog's member when the class has one (the built-in city: its element names
        # are the designs' own), else the first by (city/source, name)
        rep = where[id(min(c.members, key=lambda m: (where[id(m)]["city"] != "catalog",
                                                      m.source or "", m.name)))]
        manifest[c.class_id] = {
            "class_name": name, "representative": rep["graphml"], "n_roads": c.n_roads,
            "n_ramps": c.n_ramps, "shape": c.shape, "label_counts": c.label_counts(),
            "members": sorted(f"{where[id(m)]['city']}/{m.name}" for m in c.members),
        }
        for m in c.members:
            item = where[id(m)]
            rows.append({"city": item["city"], "interchange": m.name, "source_file": item["source_file"],
                         "class_id": c.class_id, "class_name": name, "n_roads": m.n_roads,
                         "n_ramps": m.n_ramps, "shape": m.shape})
    rows.sort(key=lambda r: (r["city"], r["interchange"]))
    rejected.sort(key=lambda r: (r["city"], r["source_file"], r["element"]))
    return rows, rejected, {"classes": manifest}


def write_class_sources(manifest: dict, folder: str | os.PathLike) -> list[str]:
    """Each class's representative topology as ``{folder}/{class_id}/representative.graphml``
    (named after the class), rewritten only when its bytes change.

    The class's later stages read this file, at a path that does not depend on which member
    represents the class: a new city whose interchanges join existing classes leaves their
    files (and so their jobs) untouched unless the representative itself changes. Returns
    the classes whose file was (re)written.
    """
    from flyover.topology.io import graphml_bytes, write_if_changed  # noqa: PLC0415

    changed = []
    for class_id, entry in sorted(manifest["classes"].items()):
        topology = read_graphml(entry["representative"])
        topology.name = class_id
        if write_if_changed(Path(folder) / class_id / "representative.graphml", graphml_bytes(topology)):
            changed.append(class_id)
    return changed


def write_manifest(manifest: dict, path: str | os.PathLike) -> None:
    """Write the class manifest JSON (sorted keys, atomically)."""
    atomic_write(path, json.dumps(manifest, indent=2, sort_keys=True).encode())
