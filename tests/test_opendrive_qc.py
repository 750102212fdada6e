"""The ASAM checker's verdict over renditions, the renditions themselves, and export failures
as validation rows (no external tools: these run in the fast suite)."""

from __future__ import annotations

import pyarrow.parquet as pq
import pytest

from flyover.geometry.model import write_geometry
from flyover.opendrive.pipeline import (PIPELINE_CHECKS, VALIDATION_SCHEMA, collect_validation,
                                        export_interchange, validate_interchange)
from flyover.opendrive.qc import CheckerIssue, CheckerOutcome, Rendition, bundle_verdict
from flyover.opendrive.samples import detached_ramp, sample_geometry
from flyover.opendrive.validate import other_rendition
from flyover.opendrive.writer import ExportError, ExportOptions, xodr_bytes

ONLY_17 = "check_asam_xodr_junctions_connection_one_connection_element"
ONLY_18 = "check_asam_xodr_junctions_connection_one_link_to_incoming"


def _outcomes(version: str, *, issue_in: str | None = None, error_in: str | None = None):
    """A bundle's outcomes on one file: the checker of the other version skipped by version."""
    out = []
    for cid in ("check_asam_xodr_xml_valid_schema", ONLY_17, ONLY_18):
        excluded = (cid == ONLY_17 and version == "1.8") or (cid == ONLY_18 and version == "1.7")
        status = "skipped" if excluded else "error" if cid == error_in else "completed"
        summary = f"Version {version}.0 is not valid according to ..." if excluded else ""
        issues = (CheckerIssue(cid, "error", "Missing lane link.", "/OpenDRIVE/road[3]"),) \
            if cid == issue_in else ()
        out.append(CheckerOutcome(cid, status, summary, issues))
    return tuple(out)


def test_union_of_the_1_8_file_and_its_1_7_rendition_completes_the_bundle():
    ok, detail = bundle_verdict([Rendition("1.8", "the file", _outcomes("1.8")),
                                 Rendition("1.7", "written from geometry.json", _outcomes("1.7"))])
    assert ok, detail
    assert detail.startswith("3/3 checkers completed, 0 issues")
    assert f"on 1.8 (the file): 2 completed, not applicable to version 1.8: {ONLY_17}" in detail
    assert f"on 1.7 (written from geometry.json): 2 completed, not applicable to version 1.7: {ONLY_18}" \
        in detail


def test_a_checker_skipped_by_version_fails_when_only_one_rendition_is_available():
    ok, detail = bundle_verdict([Rendition("1.8", "the file", _outcomes("1.8"))],
                                ["no 1.7 rendition: no geometry.json to write one from"])
    assert not ok
    assert f"not completed on any rendition: {ONLY_17}" in detail
    assert "not applicable to version 1.8" in detail and "no 1.7 rendition" in detail


@pytest.mark.parametrize("where", ["1.8", "1.7"])
def test_an_issue_in_either_rendition_fails_the_check(where):
    rends = [Rendition(v, "x", _outcomes(v, issue_in="check_asam_xodr_xml_valid_schema" if v == where else None))
             for v in ("1.8", "1.7")]
    ok, detail = bundle_verdict(rends)
    assert not ok
    assert f"check_asam_xodr_xml_valid_schema on {where}: Missing lane link. at /OpenDRIVE/road[3]" in detail


def test_a_checker_in_error_fails_the_check_even_when_the_other_rendition_completes_it():
    rends = [Rendition("1.8", "x", _outcomes("1.8", error_in="check_asam_xodr_xml_valid_schema")),
             Rendition("1.7", "y", _outcomes("1.7"))]
    ok, detail = bundle_verdict(rends)
    assert not ok and "error in check_asam_xodr_xml_valid_schema on 1.8" in detail


def test_no_run_is_no_pass():
    assert bundle_verdict([])[0] is False


def test_rendition_of_our_file_is_the_writers_other_version():
    g = sample_geometry("fork")
    r17 = other_rendition(xodr_bytes(g), (1, 8), g)
    assert (r17.version, r17.reason) == ((1, 7), "")
    assert r17.data == xodr_bytes(g, ExportOptions(opendrive_minor=7))
    r18 = other_rendition(r17.data, (1, 7), g)
    assert r18.version == (1, 8) and r18.data == xodr_bytes(g)


def test_rendition_honours_the_export_options_the_file_was_written_with():
    g = sample_geometry("t")
    opts = ExportOptions(taper_length_m=60.0)
    assert other_rendition(xodr_bytes(g, opts), (1, 8), g).data is None  # default options: not this file
    r17 = other_rendition(xodr_bytes(g, opts), (1, 8), g, opts)
    assert r17.version == (1, 7)
    assert r17.data == xodr_bytes(g, ExportOptions(taper_length_m=60.0, opendrive_minor=7))


def test_no_rendition_of_an_edited_file_nor_without_geometry_nor_of_other_versions():
    g = sample_geometry("t")
    edited = xodr_bytes(g).replace(b'name="ct/0"', b'name="edited"')
    assert edited != xodr_bytes(g)
    assert "not what flyover writes" in other_rendition(edited, (1, 8), g).reason
    assert "no geometry.json" in other_rendition(xodr_bytes(g), (1, 8), None).reason
    r = other_rendition(xodr_bytes(g), (1, 6), g)
    assert (r.version, r.data) == (None, None) and "renders only" in r.reason


def _unwritable_geometry(path):
    """geometry.json of a loop whose ramp starts 30 m from its attachment (the writer refuses r1)."""
    write_geometry(detached_ramp(sample_geometry("loop")), path)
    return path


def test_broken_geometry_json_yields_failed_rows_not_a_missing_table(tmp_path):
    geometry = tmp_path / "c0123456789" / "3" / "geometry.json"
    geometry.parent.mkdir(parents=True)
    geometry.write_text('{"format": "flyover-geometry/1", "roads": [')
    table = tmp_path / "validation.parquet"
    rows = validate_interchange(geometry, table, class_id="c0123456789", sample=3)
    assert [r["check"] for r in rows] == list(PIPELINE_CHECKS)
    assert not any(r["ok"] for r in rows)
    assert rows[0]["detail"].startswith(f"{geometry}: ") and "\n" not in rows[0]["detail"]
    assert all(r["detail"].startswith("not run") for r in rows[1:])
    assert pq.read_table(table).to_pylist() == rows
    assert collect_validation([table], tmp_path / "all.parquet") == len(PIPELINE_CHECKS)
    assert pq.read_table(tmp_path / "all.parquet").schema.equals(VALIDATION_SCHEMA, check_metadata=False)


def test_geometry_the_writer_refuses_yields_a_failed_export_row_naming_file_and_element(tmp_path):
    geometry = _unwritable_geometry(tmp_path / "geometry.json")
    rows = validate_interchange(geometry, tmp_path / "v.parquet", class_id="c0123456789", sample=0)
    assert rows[0]["check"] == "export" and not rows[0]["ok"]
    assert rows[0]["detail"].startswith(f"{geometry}: r1")
    assert (tmp_path / "v.parquet").exists()


def test_failed_export_leaves_neither_xodr_nor_plan(tmp_path):
    geometry = _unwritable_geometry(tmp_path / "geometry.json")
    with pytest.raises(ExportError, match="r1") as err:
        export_interchange(geometry, tmp_path / "interchange.xodr", tmp_path / "plan.png")
    assert str(geometry) in str(err.value)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["geometry.json"]
