"""The main job's sample of CommonRoad's map verifier (rule clients_sample,
``flyover.clients.sample``): which interchange, its rows, and the run without the
clients' environment."""

from __future__ import annotations

import pyarrow.parquet as pq
import pytest

from flyover.clients.sample import pick_sample, verify_sample
from flyover.opendrive.pipeline import VALIDATION_SCHEMA
from flyover.topology.tables import write_parquet
from tests.clients_support import clients_python, write_design  # noqa: F401


def _export_table(path, class_id, samples, failed=()):
    rows = [{"class_id": class_id, "sample": s, "check": c, "ok": s not in failed or c != "export",
             "detail": ""} for s in samples for c in ("export", "netconvert")]
    write_parquet(rows, VALIDATION_SCHEMA, path)
    return path


def test_the_sample_is_seeded_order_free_and_only_among_exported_interchanges(tmp_path):
    a = _export_table(tmp_path / "a.parquet", "c000000000a", range(6), failed={0, 1, 2, 3, 4})
    b = _export_table(tmp_path / "b.parquet", "c000000000b", range(3), failed={0, 1, 2})
    assert pick_sample([a, b], seed=1) == ("c000000000a", 5)  # the only exported one
    c = _export_table(tmp_path / "c.parquet", "c000000000c", range(40))
    picks = {pick_sample([a, b, c], seed=s) for s in range(20)}
    assert len(picks) > 1 and all(p == ("c000000000a", 5) or p[0] == "c000000000c" for p in picks)
    assert pick_sample([c, b, a], seed=7) == pick_sample([a, b, c], seed=7)
    assert pick_sample([b], seed=7) is None


def test_with_a_size_the_sample_is_among_the_smallest_tenth(tmp_path):
    # the verifier's time grows with the square of the lanelets: the main job's sample is one
    # of the smallest interchanges, still seeded and order-free
    c = _export_table(tmp_path / "c.parquet", "c000000000c", range(40))
    d = _export_table(tmp_path / "d.parquet", "c000000000d", range(30))
    size = {("c000000000c", s): 1000.0 + s for s in range(40)}
    size.update({("c000000000d", s): 500.0 + 100 * s for s in range(30)})
    picks = {pick_sample([c, d], seed=s, size=lambda k, n: size[(k, n)]) for s in range(40)}
    smallest = set(sorted(size, key=size.get)[:7])  # 70 interchanges: the smallest 7
    assert len(picks) > 1 and picks <= smallest
    assert pick_sample([d, c], seed=3, size=lambda k, n: size[(k, n)]) == \
        pick_sample([c, d], seed=3, size=lambda k, n: size[(k, n)])


def test_without_the_clients_environment_the_rows_say_skipped_and_where_to_get_it(
        tmp_path, monkeypatch, caplog):
    monkeypatch.setenv("FLYOVER_CLIENTS_PYTHON", str(tmp_path / "nope" / "python"))
    t = _export_table(tmp_path / "e.parquet", "c000000000a", range(2))
    out = tmp_path / "clients_sample.parquet"
    rows = verify_sample([t], out, seed=3, folder=str(tmp_path / "{class_id}" / "{sample}"))
    back = pq.read_table(out).to_pylist()
    assert back == rows and [r["check"] for r in rows] == ["commonroad_conversion",
                                                          "commonroad_verifier"]
    assert all(r["ok"] is None and r["detail"].startswith("skipped:") and
               "FLYOVER_CLIENTS_PYTHON" in r["detail"] for r in rows)
    assert "skipped" in caplog.text


@pytest.mark.slow
def test_the_sample_converts_and_verifies_one_interchange_of_the_run(tmp_path, clients_python):
    """Real conversion and verifier (the main job's formulas) on a semi-directional T."""
    folder = tmp_path / "c000000000a" / "0"
    folder.mkdir(parents=True)
    _, path = write_design(tmp_path, "semidirectional_t")
    path.rename(folder / "interchange.xodr")
    t = _export_table(tmp_path / "e.parquet", "c000000000a", [0])
    exclude = ["potential_left_opposite_dir_parallel_adj", "potential_right_opposite_dir_parallel_adj"]
    rows = verify_sample([t], tmp_path / "s.parquet", seed=0, exclude=exclude,
                         folder=str(tmp_path / "{class_id}" / "{sample}"), python=clients_python)
    conv, ver = rows
    assert conv["check"] == "commonroad_conversion" and conv["ok"], conv
    assert ver["check"] == "commonroad_verifier" and ver["ok"], ver
    assert "only the conversion's types" in ver["detail"] and "connections_successor=" in ver["detail"]
    assert all(f in ver["detail"] for f in exclude)
