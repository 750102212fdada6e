"""Bad OpenStreetMap input: one clear line naming the file (and way or node); the city's
other files are still imported; nothing half-written is left behind."""

from __future__ import annotations

import logging
import os
from pathlib import Path

import osmium
import pytest

from flyover.errors import InputFormatError
from flyover.osm import OsmOptions, read_osm_topologies
from flyover.topology.city import import_city

OSM_DIR = Path(os.environ.get("FLYOVER_OSM_DIR")
               or Path(__file__).resolve().parents[2] / "shared" / "osm")
pytestmark = pytest.mark.skipif(not OSM_DIR.is_dir(), reason=f"no real OSM extracts at {OSM_DIR}")
PORTO = OSM_DIR / "13_pt_porto_a41_a43.osm"


def _pbf(dst: Path) -> Path:
    w = osmium.SimpleWriter(str(dst), overwrite=True)
    try:
        for o in osmium.FileProcessor(str(PORTO)):
            w.add(o)
    finally:
        w.close()
    return dst


def _one_line(exc: InputFormatError, path: Path) -> str:
    line = exc.one_line()
    assert "\n" not in line and str(path) in line, line
    return line


def test_truncated_pbf_is_named_as_cut_short(tmp_path):
    full = _pbf(tmp_path / "full.osm.pbf").read_bytes()
    bad = tmp_path / "cut.osm.pbf"
    bad.write_bytes(full[: len(full) // 2])
    with pytest.raises(InputFormatError) as err:
        read_osm_topologies(bad, OsmOptions())
    assert "malformed OSM PBF (file cut short?)" in _one_line(err.value, bad)


@pytest.mark.parametrize("name, text, says", [
    ("notes.osm", "hello, not OSM\n", "malformed OSM XML"),
    ("notes.osm.pbf", "hello, not OSM\n", "malformed OSM PBF"),
    ("empty.osm", "", "malformed OSM XML"),
    ("half.osm", None, "malformed OSM XML"),
])
def test_a_file_that_is_not_osm_is_one_line(tmp_path, name, text, says):
    path = tmp_path / name
    path.write_text(text if text is not None else PORTO.read_text()[:30000])
    with pytest.raises(InputFormatError) as err:
        read_osm_topologies(path, OsmOptions())
    assert says in _one_line(err.value, path)


def test_no_motorway_at_all_is_one_line(tmp_path):
    path = tmp_path / "streets.osm"
    path.write_text('<?xml version="1.0"?>\n<osm version="0.6">\n'
                    '<node id="1" lat="41.0" lon="-8.5"/><node id="2" lat="41.001" lon="-8.5"/>\n'
                    '<way id="7"><nd ref="1"/><nd ref="2"/><tag k="highway" v="residential"/></way>\n</osm>\n')
    with pytest.raises(InputFormatError) as err:
        read_osm_topologies(path, OsmOptions())
    assert "no motorway or motorway_link way" in _one_line(err.value, path)


def test_ways_referring_to_missing_nodes_name_the_way_and_node(tmp_path, caplog):
    text = PORTO.read_text()
    # drop one node of a motorway way: the first <nd> of the first motorway_link way
    way_at = text.index('v="motorway_link"')
    way_start = text.rindex("<way ", 0, way_at)
    nd = text.index('<nd ref="', way_start)
    node_id = text[nd + 9: text.index('"', nd + 9)]
    node_el = text.index(f'<node id="{node_id}"')
    node_end = text.index(">", node_el) + 1
    if text[node_end - 2] != "/":
        node_end = text.index("</node>", node_el) + len("</node>")
    way_id = text[way_start + 9: text.index('"', way_start + 9)]
    path = tmp_path / "missing.osm"
    path.write_text(text[:node_el] + text[node_end:])
    with caplog.at_level(logging.WARNING, logger="flyover.osm"):
        try:
            read_osm_topologies(path, OsmOptions())
        except InputFormatError as exc:  # rejecting the file is also a clear outcome
            _one_line(exc, path)
    lines = [r.getMessage() for r in caplog.records if "missing from the file" in r.getMessage()]
    assert lines and str(path) in lines[0] and f"refers to node {node_id}" in lines[0]
    named_way = int(lines[0].split(": way ")[1].split()[0])  # one of the ways using that node
    assert f'<way id="{named_way}"' in text and way_id


def test_bad_files_are_rejected_and_the_others_imported(tmp_path):
    city = tmp_path / "city"
    city.mkdir()
    good = _pbf(city / "porto.osm.pbf")
    cut = city / "cut.osm.pbf"
    cut.write_bytes(good.read_bytes()[:2000])
    (city / "junk.osm.gz").write_bytes(b"not gzip at all")
    out = tmp_path / "results" / "topology" / "city"
    index = import_city("city", sorted(city.iterdir()), out, osm_options=OsmOptions())
    assert [i["source_file"] for i in index["interchanges"]] == [str(good)]
    assert sorted(Path(r["source_file"]).name for r in index["rejected"]) == ["cut.osm.pbf", "junk.osm.gz"]
    assert all("\n" not in r["reason"] for r in index["rejected"])
    written = sorted(p.name for p in out.iterdir())
    names = {i["interchange"] for i in index["interchanges"]}
    assert written == sorted([*(f"{n}.graphml" for n in names), *(f"{n}.png" for n in names), "index.json"])
