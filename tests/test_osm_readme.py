"""Every extract of ``../shared/osm/`` reads as its README row says.

The rows (``../shared/osm/README.md``) name per file the real interchanges, their
legs, their loop ramps and, where it is one, the catalog design. Files the reader
does not yet read right are marked ``xfail(strict=True)`` with the reason: the
day one reads right, its test fails until the mark is removed. Skipped where the
folder does not exist.
"""

from __future__ import annotations

import bz2
import gzip
import logging
import os
from pathlib import Path

import osmium
import pytest

from flyover.osm import OsmOptions, read_osm_topologies
from flyover.osm.geom import turn_deg
from flyover.topology import class_id
from flyover.topology.catalog import catalog_class_names

OSM_DIR = Path(os.environ.get("FLYOVER_OSM_DIR")
               or Path(__file__).resolve().parents[2] / "shared" / "osm")
pytestmark = pytest.mark.skipif(not OSM_DIR.is_dir(), reason=f"no real OSM extracts at {OSM_DIR}")

#: a ramp whose path turns at least this much (degrees) is a loop (cloverleaf loops turn ~270°,
#: file 26's U-shaped ramp 213° and file 25's hairpin ~180° are not loops)
LOOP_TURN_DEG = 225.0

#: file stem → per real interchange (legs, loop ramps, catalog design or None), from the README rows
README_ROWS = {
    "02_de_bayreuth_dreieck_a9_a70": [(3, 0, None)],
    "06_us_me_bangor_i95_i395": [(4, 4, "cloverleaf")],
    "09_us_oh_columbus_i70_i270_west": [(4, 2, None)],
    "13_pt_porto_a41_a43": [(3, 1, "trumpet")],
    "20_au_sydney_a4_bradfield_cahill": [(3, 1, None)],
    "21_us_or_portland_i5_i84": [(3, 0, None)],
    "22_us_or_portland_i405_us26": [(3, 0, None)],
    "23_us_or_portland_i5_i405_marquam": [(3, 0, None)],
    "24_us_ma_boston_i93_us1": [(3, 2, None)],
    "25_us_ma_boston_i90_ma1a": [(3, 0, None)],
    "26_us_dc_i66_us50_e_st_expwy": [(5, 0, None)],
    "27_us_dc_i66_us29_whitehurst": [(3, 0, None)],
    "28_us_or_portland_region_fremont_i405_us30_i5": [(3, 0, None), (3, 0, None)],
}

#: files not yet read right, and why (the issue's reading patterns)
NOT_YET: dict[str, str] = {}


def reading(topologies) -> list[tuple[int, int, str | None]]:
    names = catalog_class_names()
    out = []
    for t in topologies:
        lines = t.attrs["osm"]["lines"]
        loops = sum(turn_deg(lines[r]) >= LOOP_TURN_DEG for r in t.ramps)
        out.append((t.legs, loops, names.get(class_id(t))))
    return sorted(out, key=lambda r: (r[0], r[1], r[2] or ""))


def _cases():
    for stem in sorted(README_ROWS):
        marks = [pytest.mark.xfail(strict=True, reason=NOT_YET[stem])] if stem in NOT_YET else []
        yield pytest.param(stem, marks=marks, id=stem[:2])


@pytest.mark.parametrize("stem", list(_cases()))
def test_extract_reads_as_its_readme_row(stem):
    logging.disable(logging.WARNING)
    try:
        ts = read_osm_topologies(OSM_DIR / f"{stem}.osm", OsmOptions())
    finally:
        logging.disable(logging.NOTSET)
    expected = sorted(README_ROWS[stem], key=lambda r: (r[0], r[1], r[2] or ""))
    got = reading(ts)
    # a catalog design named by the README must be met; elsewhere any class may come out
    got = [(legs, loops, design if any(e[2] for e in expected) else None) for legs, loops, design in got]
    assert got == expected, [t.summary() for t in ts]
    for t in ts:
        assert t.shape == {3: "T", 4: "cross"}.get(t.legs, "other")
        assert t.n_roads >= 3, t.summary()  # no motorway-to-motorway interchange has 2 roads


def test_readme_table_names_every_shared_extract():
    """The expectations above cover every extract the folder holds (a new file needs a row)."""
    assert sorted(p.stem for p in OSM_DIR.glob("*.osm")) == sorted(README_ROWS)


# -- one reader for every format ----------------------------------------------------------

def _as_pbf(src: Path, dst: Path) -> Path:
    w = osmium.SimpleWriter(str(dst), overwrite=True)
    try:
        for o in osmium.FileProcessor(str(src)):
            w.add(o)
    finally:
        w.close()
    return dst


@pytest.mark.parametrize("stem", ["13_pt_porto_a41_a43", "06_us_me_bangor_i95_i395",
                                  "28_us_or_portland_region_fremont_i405_us30_i5"])
def test_same_topologies_and_class_ids_whatever_the_format(tmp_path, stem):
    src = OSM_DIR / f"{stem}.osm"
    files = [src, _as_pbf(src, tmp_path / f"{stem}.osm.pbf")]
    (tmp_path / f"{stem}.osm.gz").write_bytes(gzip.compress(src.read_bytes()))
    (tmp_path / f"{stem}.osm.bz2").write_bytes(bz2.compress(src.read_bytes()))
    files += [tmp_path / f"{stem}.osm.gz", tmp_path / f"{stem}.osm.bz2"]
    readings = []
    for f in files:
        ts = read_osm_topologies(f, OsmOptions())
        readings.append([(t.name, class_id(t), t.n_roads, t.n_ramps) for t in ts])
    assert readings[0]
    assert all(r == readings[0] for r in readings[1:]), readings


def test_bbox_reads_only_the_motorways_inside():
    """File 28 holds two interchanges ~1.2 km apart (Fremont Bridge); a bbox around its west
    end reads fewer interchanges, each of motorway ways with a node inside the box."""
    src = OSM_DIR / "28_us_or_portland_region_fremont_i405_us30_i5.osm"
    box = (-122.71, 45.52, -122.686, 45.57)
    whole = read_osm_topologies(src, OsmOptions())
    cut = read_osm_topologies(src, OsmOptions(bbox=box))
    assert 0 < len(cut) < len(whole)
    for t in cut:
        lat0, lon0 = t.attrs["osm"]["origin"]
        assert box[0] - 0.02 < lon0 < box[2] + 0.02 and box[1] - 0.02 < lat0 < box[3] + 0.02


# -- the self-check ------------------------------------------------------------------------

def test_self_check_flags_the_five_leg_interchange_read_with_six():
    """File 26 is 5 legs on the map (one of them the US 50 stub, whose two carriageways are
    one way turning back at 23rd Street); read as 6, the self-check says so."""
    from flyover.osm.check import ring_legs, self_check

    [t] = read_osm_topologies(OSM_DIR / "26_us_dc_i66_us50_e_st_expwy.osm", OsmOptions())
    assert ring_legs(t)[0] == 5
    rows = self_check(t)
    assert (t.legs == 5) == (not [r for r in rows if r["check"] == "legs"])
    wrong = _split_expressway(t, "way50428544")  # E Street Expressway read as two legs: 6
    assert wrong.legs == 6
    legs = [r for r in self_check(wrong) if r["check"] == "legs"]
    assert len(legs) == 1 and "crosses 5 legs" in legs[0]["detail"] and "has 6" in legs[0]["detail"]


def _split_expressway(t, expressway: str):
    """``t`` with every road of ``expressway`` an expressway of its own (a wrong reading:
    more legs than the map has), the OSM geometry unchanged."""
    from flyover.topology import Topology  # noqa: PLC0415

    g = t.graph.copy()
    for k, r in enumerate(sorted(r for r in t.roads if g.nodes[r].get("expressway") == expressway)):
        g.nodes[r]["expressway"] = f"{expressway}-{k}"
    return Topology(t.name, g, t.source, t.attrs)


@pytest.mark.parametrize("stem", sorted(README_ROWS))
def test_self_check_agrees_where_the_reading_is_right(stem):
    """Every shared extract reads as its README row (above), so its self-check has nothing to say:
    the stubs of 06 and 26 (a motorway ending at ordinary roads inside the ring), the forks of
    25 and 27 (two legs side by side at the ring) are legs of the map."""
    for t in read_osm_topologies(OSM_DIR / f"{stem}.osm", OsmOptions()):
        assert t.attrs["osm"]["self_check"] == [], t.summary()


@pytest.mark.parametrize("stem, expressway", [("06_us_me_bangor_i95_i395", "I395"),
                                              ("25_us_ma_boston_i90_ma1a", "I90"),
                                              ("27_us_dc_i66_us29_whitehurst", "US29")])
def test_self_check_flags_a_wrong_leg_count_where_it_used_to_false_alarm(stem, expressway):
    """The check is right on these files, not quiet: read with one more leg than the map has
    (an expressway's two carriageways taken as two expressways), it says so."""
    from flyover.osm.check import ring_legs, self_check

    [t] = read_osm_topologies(OSM_DIR / f"{stem}.osm", OsmOptions())
    wrong = _split_expressway(t, expressway)
    assert wrong.legs > t.legs == ring_legs(t)[0]
    assert [r["check"] for r in self_check(wrong)][:1] == ["legs"]


def test_a_city_of_extracts_read_right_has_no_notes(tmp_path):
    """File 26 reads right (5 legs): its city's index.json has no notes. (That a disagreement
    becomes a notes row is tested on a synthetic extract in tests/test_osm.py.)"""
    from flyover.topology.city import import_city

    src = OSM_DIR / "26_us_dc_i66_us50_e_st_expwy.osm"
    index = import_city("dc", [src], tmp_path / "dc", osm_options=OsmOptions())
    [t] = read_osm_topologies(src, OsmOptions())
    assert t.legs == 5 and t.attrs["osm"]["self_check"] == []
    assert index["notes"] == [] and [r["interchange"] for r in index["interchanges"]] == [t.name]


def test_a_ramp_back_onto_its_own_carriageway_is_a_self_check_row():
    from flyover.osm.check import self_check
    from flyover.topology import Connection, Label, Ramp, Road, Topology

    roads = [Road("A1", "A"), Road("A2", "A"), Road("B1", "B"), Road("B2", "B")]
    conns = [Connection("A1", "r1", Label.OUT_R), Connection("r1", "B1", Label.IN_R),
             Connection("B2", "r2", Label.OUT_R), Connection("r2", "B2", Label.IN_R)]
    t = Topology.build("x", roads, [Ramp("r1"), Ramp("r2")], conns,
                       attrs={"osm": {"junctions": [([0.0, 0.0], "A1", "r1", "Out-R")], "lines": {}}})
    rows = [r for r in self_check(t) if r["check"] == "ramp"]
    assert len(rows) == 1 and "r2" in rows[0]["detail"] and "same carriageway B2" in rows[0]["detail"]


def _load_benchmark():
    import importlib.util  # noqa: PLC0415

    spec = importlib.util.spec_from_file_location("osm_bench", Path(__file__).resolve().parents[1] / "benchmarks"
                                                  / "osm.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_workers_give_the_same_bytes_and_leave_the_collector_as_found(tmp_path, caplog):
    """Two copies of every shared extract tiled into one .osm.pbf (many places): built in 2
    forked workers (``OsmOptions.workers``, as the workflow's import rule passes its threads),
    every topology is byte for byte the one built in one process; the garbage collector is on
    and nothing stays frozen afterwards."""
    import gc  # noqa: PLC0415
    import json  # noqa: PLC0415

    from flyover.topology.io import graphml_bytes  # noqa: PLC0415

    bench = _load_benchmark()
    files = sorted(str(p) for p in OSM_DIR.glob("*.osm"))
    tiled = tmp_path / "tiled.osm.pbf"
    bench.build_tiled(tiled, 2, bench._load(files))
    caplog.set_level(logging.ERROR)

    def dump(ts):
        return [(graphml_bytes(t), json.dumps(t.attrs, sort_keys=True, default=str)) for t in ts]

    one = dump(read_osm_topologies(tiled, OsmOptions(workers=1)))
    two = dump(read_osm_topologies(tiled, OsmOptions(workers=2)))
    assert len(one) == 2 * sum(len(v) for v in README_ROWS.values())  # one per README row (20, 26 too)
    assert two == one
    assert gc.isenabled() and gc.get_freeze_count() == 0
