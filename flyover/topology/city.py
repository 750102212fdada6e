"""Import a city folder: every file → native GraphML per interchange, rejections recorded.

This is the library side of the workflow's per-city rule; one bad file never
stops the others.
"""

from __future__ import annotations

import json
import logging
import os
from pathlib import Path
from typing import Any, Iterable

from flyover.errors import FlyoverError, TopologyError
from flyover.topology.io import atomic_write, read_topologies, write_graphml
from flyover.topology.names import check_name, child_path

__all__ = ["import_city", "CITY_INDEX", "read_city_index", "city_names"]

log = logging.getLogger(__name__)

#: per-city index written beside the GraphML files
CITY_INDEX = "index.json"


def import_city(city: str, files: Iterable[str | os.PathLike], outdir: str | os.PathLike,
                *, osm_options: Any = None) -> dict:
    """Read every file of ``city`` and write ``{outdir}/{interchange}.graphml``.

    ``osm_options`` (a :class:`flyover.osm.OsmOptions`) controls how OSM
    extracts are read. Also writes ``{outdir}/index.json``: the interchanges written (name,
    source file, GraphML path; for a name made from data, ``name_from``: what it was
    made from, e.g. OSM refs → name parts), the rejections (source file, element,
    reason) and the notes (an OSM interchange whose self-check disagrees: source file,
    interchange, check, detail, preview picture). Interchange names must be unique within a city, ignoring case (file
    systems that ignore case would merge them); a later duplicate is rejected.
    ``city`` and every interchange name must be safe names
    (:mod:`flyover.topology.names`): nothing is written outside ``outdir``.

    Raises
    ------
    UnsafeNameError
        ``city`` is not a safe name (nothing is written).

    Returns
    -------
    dict
        The index that was written.
    """
    check_name(city, what="city name")
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    interchanges, rejected, notes, taken = [], [], [], set()
    for path in sorted(map(str, files)):
        try:
            topologies = read_topologies(path, osm_options=osm_options)
        except FlyoverError as exc:
            exc.located(path)
            log.warning("rejected %s", exc.one_line())
            rejected.append({"city": city, "source_file": path, "element": exc.element or "",
                             "reason": exc.reason})
            continue
        for t in topologies:
            try:
                target = child_path(outdir, t.name, ".graphml", source=path)
                if t.name.lower() in taken:
                    raise TopologyError("duplicate interchange name in this city (case ignored)",
                                        source=path, element=t.name)
            except FlyoverError as exc:
                log.warning("rejected %s", exc.one_line())
                rejected.append({"city": city, "source_file": path, "element": exc.element or "",
                                 "reason": exc.reason})
                continue
            taken.add(t.name.lower())
            write_graphml(t, target)
            if "osm" in t.attrs:  # OSM import: its geometry picture beside the GraphML
                from flyover.osm.plot import plot_osm_topology  # noqa: PLC0415 (optional stage)
                plot_osm_topology(t, child_path(outdir, t.name, ".png", source=path))
            item = {"city": city, "interchange": t.name, "source_file": path, "graphml": str(target)}
            if t.attrs.get("name_from"):
                item["name_from"] = t.attrs["name_from"]
            interchanges.append(item)
            # an OSM interchange's self-check disagreements are the city's notes
            for row in (t.attrs.get("osm") or {}).get("self_check", []):
                notes.append({"city": city, "source_file": path, "interchange": t.name, **row,
                              "preview": str(child_path(outdir, t.name, ".png", source=path))})
            log.info("%s: %s", path, t.summary())
    index = {"city": city, "interchanges": interchanges, "rejected": rejected, "notes": notes}
    atomic_write(outdir / CITY_INDEX, json.dumps(index, indent=2, sort_keys=True).encode())
    return index


def city_names(cities_dir: str | os.PathLike, configured: Iterable[str] = ()) -> list[str]:
    """The cities to build: ``configured`` if any, else every folder of ``cities_dir``
    (hidden ones skipped), sorted; each must be a safe name (it becomes a folder name).

    Raises
    ------
    UnsafeNameError
        Naming the city folder (or ``cities_dir`` for a configured name) and the name.
    """
    configured = list(configured)
    if configured:
        return sorted(check_name(c, source=str(cities_dir), what="city name") for c in configured)
    root = Path(cities_dir)
    found = sorted(p for p in root.iterdir() if p.is_dir() and not p.name.startswith("."))
    return [check_name(p.name, source=str(p), what="city name") for p in found]


def read_city_index(outdir: str | os.PathLike) -> dict:
    """The index a previous :func:`import_city` wrote into ``outdir``."""
    return json.loads((Path(outdir) / CITY_INDEX).read_text(encoding="utf-8"))
