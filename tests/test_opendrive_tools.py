"""The external tools for real: ASAM checker, netconvert, routing, the CLI, plan.png."""

from __future__ import annotations

import subprocess

import pytest
from lxml import etree

from flyover.cli import main
from flyover.geometry.model import write_geometry
from flyover.opendrive import qc
from flyover.opendrive.samples import SAMPLES, sample_geometry
from flyover.opendrive.validate import CHECKS, validate_xodr, xsd_errors
from flyover.opendrive.writer import write_xodr

pytestmark = pytest.mark.integration


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    root = tmp_path_factory.mktemp("built")
    out = {}
    for kind in SAMPLES:
        d = root / kind
        write_geometry(sample_geometry(kind), d / "geometry.json")
        write_xodr(sample_geometry(kind), d / "interchange.xodr")
        out[kind] = d
    return out


@pytest.mark.parametrize("kind", SAMPLES)
def test_asam_checker_reports_zero_issues_and_skips_only_by_version(built, kind):
    outcomes = qc.run_asam_checker(built[kind] / "interchange.xodr")
    assert len(outcomes) >= 20
    assert [i for o in outcomes for i in o.issues] == []
    assert all(o.status in ("completed", "skipped") for o in outcomes)
    skipped = [o for o in outcomes if o.status == "skipped"]
    assert all(o.summary.startswith("Version") for o in skipped)
    assert len(skipped) <= 1


@pytest.mark.parametrize("kind", SAMPLES)
def test_every_check_passes_and_every_movement_routes(built, kind):
    results, times, _ = validate_xodr(built[kind] / "interchange.xodr",
                                      geometry=sample_geometry(kind),
                                      net_out=built[kind] / "interchange.net.xml")
    assert [r.check for r in results] == list(CHECKS)
    assert all(r.ok for r in results), [r for r in results if not r.ok]
    assert (built[kind] / "interchange.net.xml").stat().st_size > 0
    assert "movements routable" in results[-1].detail
    assert times["netconvert"] > 0 and times["asam_qc"] > 0


def test_asam_qc_completes_every_checker_over_the_file_and_its_1_7_rendition(built):
    asam = validate_xodr(built["t"] / "interchange.xodr", geometry=sample_geometry("t"))[0][1]
    n = len(qc.run_asam_checker(built["t"] / "interchange.xodr"))
    assert asam.ok, asam.detail
    assert asam.detail.startswith(f"{n}/{n} checkers completed, 0 issues; on 1.8 (the file): {n - 1} completed")
    assert "on 1.7 (written from geometry.json, for the checkers 1.8 excludes)" in asam.detail
    assert "not applicable to version 1.8: check_asam_xodr_junctions_connection_one_connection_element" \
        in asam.detail
    # the rendition runs only what 1.8 excludes (and its preconditions): nothing it skips
    assert "not applicable to version 1.7" not in asam.detail


def test_asam_qc_fails_on_a_file_that_can_only_be_checked_in_its_own_version(built):
    asam = validate_xodr(built["t"] / "interchange.xodr")[0][1]  # no geometry: no 1.7 rendition
    assert not asam.ok
    assert "0 issues" in asam.detail
    assert "not completed on any rendition: check_asam_xodr_junctions_connection_one_connection_element" \
        in asam.detail
    assert "no 1.7 rendition" in asam.detail


def _without_one_lane_link(data: bytes) -> bytes:
    """The file with the lane link of one lane across two lane sections of a road removed."""
    root = etree.fromstring(data)
    for road in root.iter("road"):
        sections = road.findall("lanes/laneSection")
        for sec in sections[:-1]:
            for lane in sec.iter("lane"):
                link = lane.find("link")
                if link is not None and link.find("successor") is not None:
                    lane.remove(link)
                    return etree.tostring(root, xml_declaration=True, encoding="UTF-8")
    raise AssertionError("no lane link across lane sections")


def test_a_file_missing_a_lane_link_fails_asam_qc(built, tmp_path):
    bad = tmp_path / "interchange.xodr"
    bad.write_bytes(_without_one_lane_link((built["t"] / "interchange.xodr").read_bytes()))
    results = {r.check: r for r in validate_xodr(bad, geometry=sample_geometry("t"))[0]}
    assert results["xsd"].ok  # still valid against the schema: only the checker sees it
    assert not results["asam_qc"].ok
    assert "check_asam_xodr_road_lane_link_lanes_across_lane_sections on 1.8: Missing lane link." \
        in results["asam_qc"].detail
    assert "no 1.7 rendition: the file is not what flyover writes" in results["asam_qc"].detail


def test_one_checker_process_gives_what_the_checkers_own_command_gives(built, tmp_path):
    bad = tmp_path / "bad.xodr"
    bad.write_bytes(_without_one_lane_link((built["t"] / "interchange.xodr").read_bytes()))
    files = [built["t"] / "interchange.xodr", bad, built["loop"] / "interchange.xodr"]
    batch = qc.run_qc_batch(files)
    assert [r.error for r in batch.checker] == ["", "", ""]
    for f, run in zip(files, batch.checker):
        cfg, res = tmp_path / "config.xml", tmp_path / "result.xqar"
        cfg.write_text(qc.checker_config(f.resolve(), res))
        subprocess.run([str(qc.find_qc_python()), "-m", "qc_opendrive", "-c", str(cfg)], cwd=tmp_path,
                       capture_output=True, check=True)
        assert list(run.outcomes) == qc.parse_result(res), f
    assert any(o.issues for o in batch.checker[1].outcomes)


def test_xsd_11_validation_in_the_checker_process_reports_errors(built, tmp_path):
    bad = tmp_path / "bad.xodr"
    bad.write_bytes((built["t"] / "interchange.xodr").read_bytes().replace(b'<road ', b'<road foo="1" ', 1))
    assert xsd_errors(built["t"] / "interchange.xodr", (1, 8)) == []
    errors = xsd_errors(bad, (1, 8))
    assert errors and errors[0].startswith("line ") and "foo" in errors[0]


def test_across_versions_1_7_and_1_8_every_checker_completes_without_issue(tmp_path):
    from flyover.opendrive.writer import ExportOptions, xodr_bytes

    status = {}
    for minor in (7, 8):
        path = tmp_path / f"fork_1{minor}.xodr"
        path.write_bytes(xodr_bytes(sample_geometry("fork"), ExportOptions(opendrive_minor=minor)))
        for o in qc.run_asam_checker(path):
            assert not o.issues, (minor, o.checker_id, o.issues[:2])
            if o.status == "completed":
                status[o.checker_id] = "completed"
            else:
                status.setdefault(o.checker_id, o.status)
    assert status and set(status.values()) == {"completed"}, status


def test_asam_checker_flags_a_schema_violation(tmp_path):
    bad = tmp_path / "bad.xodr"
    bad.write_text('<OpenDRIVE><header revMajor="1" revMinor="7"/><road id="1" length="10">'
                   '<planView><geometry s="0" x="0" y="0" hdg="0" length="10"><line/></geometry>'
                   '</planView><lanes><laneSection s="0"><center><lane id="0" type="none"/></center>'
                   '</laneSection></lanes></road></OpenDRIVE>')
    outcomes = qc.run_asam_checker(bad)
    schema = next(o for o in outcomes if o.checker_id.endswith("valid_schema"))
    assert schema.issues


def test_cli_validate_reports_and_exits_nonzero_on_failure(built, tmp_path, capsys):
    assert main(["validate", str(built["t"] / "interchange.xodr")]) == 0
    out = capsys.readouterr().out
    assert "OK (5/5 checks)" in out and "movements routable" in out
    bad = tmp_path / "broken.xodr"
    bad.write_text("<OpenDRIVE><header/>")
    assert main(["validate", "--no-qc", str(bad)]) == 1
    assert "FAIL" in capsys.readouterr().out


def test_cli_export_writes_xodr_and_plan(built, tmp_path):
    png = tmp_path / "plan.png"
    assert main(["export", str(built["loop"] / "geometry.json"), "-o", str(tmp_path / "x.xodr"),
                 "--plan", str(png)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (tmp_path / "x.xodr").read_bytes() == (built["loop"] / "interchange.xodr").read_bytes()


def _identity_violations(data: bytes) -> dict[str, bytes]:
    """The file and copies that break the 1.8 schema's keys in different ways."""
    root = etree.fromstring(data)
    roads, junctions = root.findall("road"), root.findall("junction")
    out = {"valid": data}

    def variant(name, edit):
        copy = etree.fromstring(data)
        edit(copy)
        out[name] = etree.tostring(copy)

    variant("duplicate road id", lambda r: r.findall("road")[1].set("id", roads[0].get("id")))
    variant("road without id", lambda r: r.findall("road")[2].attrib.pop("id"))
    variant("road id in a key twice, once first", lambda r: r.insert(1, etree.Element(
        "road", id=roads[-1].get("id"), length="1")))
    variant("length not a number", lambda r: r.findall("road")[0].set("length", "abc"))
    variant("unknown element inside a road", lambda r: etree.SubElement(r.findall("road")[1], "bogus"))
    if len(junctions) > 1:
        variant("duplicate junction id", lambda r: r.findall("junction")[1].set("id", junctions[0].get("id")))
    return out


def test_shared_document_annotations_give_the_same_xsd_11_errors(built, tmp_path):
    """The checker process skips repeated whole-document type annotations (``_qc_driver``):
    every error, identity constraints included, is what plain ``xmlschema`` reports."""
    import re

    xsd = qc.schema_dir() / "1.8.0" / "OpenDRIVE_Core.xsd"
    jobs = []
    for kind in ("t", "loop"):
        for name, data in _identity_violations((built[kind] / "interchange.xodr").read_bytes()).items():
            path = tmp_path / f"{kind}_{len(jobs)}.xodr"
            path.write_bytes(data)
            jobs.append((xsd, path))
    runs = [qc.run_qc_batch(xsd11=jobs, share_annotations=share).xsd11 for share in (True, False)]
    address = re.compile(r" at 0x[0-9a-f]+")
    shared, plain = ([[address.sub("", e) for e in r.errors] for r in run] for run in runs)
    assert [r.error for run in runs for r in run] == [""] * 2 * len(jobs)
    assert shared == plain
    assert shared[0] == [] and all(errors for errors in shared[1:len(shared) // 2])
    assert any("duplicat" in e.lower() for errors in shared for e in errors), shared


_TYPED_KEY_XSD = """<xs:schema xmlns:xs="http://www.w3.org/2001/XMLSchema">
  <xs:element name="r">
    <xs:complexType><xs:sequence>
      <xs:element name="k" maxOccurs="unbounded"><xs:complexType>
        <xs:attribute name="id" type="xs:int" use="required"/>
      </xs:complexType></xs:element>
    </xs:sequence></xs:complexType>
    <xs:key name="k_id"><xs:selector xpath="k"/><xs:field xpath="@id"/></xs:key>
  </xs:element>
</xs:schema>"""


def test_shared_document_annotations_keep_typed_keys_typed_in_every_document(tmp_path):
    """``1`` and ``01`` are one ``xs:int`` key value only when the document carries its schema
    types: a skipped annotation that should have run (another document, say) misses them."""
    xsd = tmp_path / "typed_key.xsd"
    xsd.write_text(_TYPED_KEY_XSD)
    docs = {"distinct": '"1" "2" "3"', "1 and 01": '"1" "2" "01"', "+2 and 2": '"2" "+2" "3"'}
    jobs = []
    for i, ids in enumerate(docs.values()):
        path = tmp_path / f"doc{i}.xml"
        path.write_text("<r>" + "".join(f"<k id={v}/>" for v in ids.split()) + "</r>")
        jobs.append((xsd, path))
    shared, plain = ([r.errors for r in qc.run_qc_batch(xsd11=jobs, share_annotations=s).xsd11]
                     for s in (True, False))
    assert shared == plain
    assert shared[0] == () and all(len(e) == 1 and "duplicate" in e[0].lower() for e in shared[1:]), shared
