"""The dataset browser built from a small results folder made in-test (no browser here:
tests/test_report_browser.py opens the same pages in Chromium)."""

from __future__ import annotations

import json
import re
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlparse

import pytest

from flyover.cli import main
from flyover.geometry.model import read_geometry
from flyover.report import ReportError, build_report
from flyover.report.view import plan_view

from tests.report_support import CLASS, CLASS2, EVIL, make_results


class _Refs(HTMLParser):
    def __init__(self):
        super().__init__()
        self.refs: list[tuple[str, str]] = []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        for key in ("href", "src"):
            if a.get(key):
                self.refs.append((tag, a[key]))


def unresolved(report: Path) -> list[str]:
    """Every href/src of every page that is not a local file that exists (or an anchor)."""
    bad = []
    for page in sorted(report.rglob("*.html")):
        parser = _Refs()
        parser.feed(page.read_text(encoding="utf-8"))
        for tag, ref in parser.refs:
            url = urlparse(ref)
            if url.scheme or url.netloc:
                bad.append(f"{page.relative_to(report)}: external {ref}")
                continue
            if not url.path:
                continue  # #anchor
            if not (page.parent / unquote(url.path)).resolve().exists():
                bad.append(f"{page.relative_to(report)}: {tag} {ref}")
    return bad


def text(path: Path) -> str:
    return path.read_text(encoding="utf-8")


@pytest.fixture(scope="module")
def complete(tmp_path_factory) -> Path:
    res = make_results(tmp_path_factory.mktemp("complete"))
    build_report(res)
    return res


def test_a_complete_results_folder_gets_every_page(complete):
    report = complete / "report"
    pages = {str(p.relative_to(report)) for p in report.rglob("*.html")}
    assert pages == {"index.html", "evaluation.html", f"classes/{CLASS}.html",
                     f"classes/{CLASS2}.html", f"interchanges/{CLASS}/0.html",
                     f"interchanges/{CLASS}/1.html", f"interchanges/{CLASS}/2.html",
                     f"interchanges/{CLASS2}/0.html"}
    index = text(report / "index.html")
    assert "cloverleaf" in index and "T-4roads-2ramps" in index
    assert "town" in index and "a1_junction" in index
    assert "../topology/town/a1_junction.png" in index  # the OSM picture of an OSM input
    assert "./dev run" not in index  # nothing is missing
    evaluation = text(report / "evaluation.html")
    for fig in ("fig4_entering_leaving", "fig5_class_throughput", "fig6_pvalues"):
        assert f"../figures/{fig}.png" in evaluation
    assert (report / "figures" / "fuel_table4.png").is_file()
    assert (report / "figures" / "fuel_by_class.png").is_file()
    assert "flyover query --named fuel-grid" in evaluation
    assert "flyover query --named throughput-by-class" in evaluation


def test_every_link_and_image_resolves_to_a_local_file(complete):
    assert unresolved(complete / "report") == []


def test_images_are_lazy_loaded(complete):
    html = text(complete / "report" / "classes" / f"{CLASS}.html")
    imgs = re.findall(r"<img [^>]*>", html)
    assert len(imgs) >= 4  # topology, geometry figure, three plan views
    assert all('loading="lazy"' in i for i in imgs)


def test_class_page_shows_coverage_targets_validation_and_files(complete):
    html = text(complete / "report" / "classes" / f"{CLASS}.html")
    assert "40 / 40" in html  # t-tuples covered
    assert "∞" in html  # the straight ramp's target radius
    assert "asam_qc" in html and "1 issue: &lt;lane&gt; gap" in html  # the failed check, escaped
    for f in ("geometry.json", "interchange.xodr", "interchange.net.xml", "plan.png"):
        assert f"../../interchanges/{CLASS}/2/{f}" in html


def test_interchange_page_draws_the_plan_with_facts_for_hover(complete):
    html = text(complete / "report" / "interchanges" / CLASS / "0.html")
    assert html.count('class="ramp"') > 4  # ramps in pieces coloured by height
    assert 'data-el="r1"' in html and 'data-el="A1"' in html
    info = json.loads(re.search(r'<script type="application/json" id="view-info">(.*?)</script>',
                                html, re.S).group(1))
    assert info["r2"]["target_radius_m"] == "inf"  # JSON has no infinity
    assert info["r1"]["fuel_ml"] == pytest.approx(150.0)
    assert info["r1"]["kind"] == "ramp" and info["A1"]["kind"] == "road"
    assert '<script src="../../assets/viewer.js"></script>' in html


def test_text_from_the_data_is_escaped(complete):
    index = text(complete / "report" / "index.html")
    assert EVIL not in index
    assert "&lt;script&gt;alert(&#39;x&#39;)&lt;/script&gt;" in index


def test_the_same_results_give_the_same_bytes(complete, tmp_path):
    first = {p.relative_to(complete / "report"): p.read_bytes()
             for p in (complete / "report").rglob("*") if p.is_file()}
    out = build_report(complete, tmp_path / "again").parent
    again = {p.relative_to(out): p.read_bytes() for p in out.rglob("*") if p.is_file()}
    assert first.keys() == again.keys()
    # pages link to the results from where they lie: only those links may differ
    differ = [k for k in first if first[k] != again[k]]
    assert all(k.suffix == ".html" for k in differ)
    build_report(complete, complete / "report")
    assert {p.relative_to(complete / "report"): p.read_bytes()
            for p in (complete / "report").rglob("*") if p.is_file()} == first


@pytest.mark.parametrize("stages, missing", [
    (("topology",), ["./dev run sampling", "./dev run geometry", "./dev run throughput",
                     "./dev run plugins"]),
    (("topology", "sampling", "geometry"), ["./dev run validation", "./dev run throughput",
                                            "./dev run plugins", "./dev run export"]),
    (("topology", "sampling", "geometry", "export", "validation"),
     ["./dev run throughput", "./dev run plugins"]),
])
def test_a_stage_not_built_is_named_with_the_target_that_builds_it(tmp_path, stages, missing):
    res = make_results(tmp_path, stages)
    build_report(res)
    report = res / "report"
    html = "".join(text(p) for p in report.rglob("*.html"))
    for target in missing:
        assert target in html, target
    if "sampling" in stages:  # the overview's stage table names the stages not run yet
        assert "not run yet: <code>./dev run throughput</code>" in text(report / "index.html")
    assert unresolved(report) == []


def test_nothing_built_yet_says_what_to_run(tmp_path):
    index = build_report(tmp_path)
    assert "./dev run topology" in text(index)
    assert "./dev run throughput" in text(index.parent / "evaluation.html")


def test_a_class_that_is_gone_leaves_no_page(tmp_path):
    res = make_results(tmp_path)
    build_report(res)
    manifest = json.loads(text(res / "classes" / "manifest.json"))
    del manifest["classes"][CLASS2]
    (res / "classes" / "manifest.json").write_text(json.dumps(manifest), encoding="utf-8")
    build_report(res)
    assert not (res / "report" / "classes" / f"{CLASS2}.html").exists()
    assert not (res / "report" / "interchanges" / CLASS2).exists()
    assert not list(res.glob(".report*"))  # no temporary folder left


def test_a_corrupt_table_is_an_error_naming_the_folder(tmp_path):
    res = make_results(tmp_path, ("topology",))
    (res / "classes.parquet").write_bytes(b"not parquet")
    with pytest.raises(ReportError, match=str(res)):
        build_report(res)
    assert not (res / "report").exists()


def test_the_command_writes_where_it_is_told(complete, tmp_path, capsys):
    out = tmp_path / "site"
    assert main(["report", "--results", str(complete), "-o", str(out)]) == 0
    assert capsys.readouterr().out.strip() == str(out / "index.html")
    assert unresolved(out) == []
    assert main(["report", "--results", str(tmp_path / "nowhere")]) == 1


def test_plan_view_orders_pieces_by_height_and_colours_them():
    g = read_geometry_from(make_geometry())
    v = plan_view(g)
    heights = [s.z_m for s in v.shapes]
    assert heights == sorted(heights)  # higher pieces drawn last (on top)
    ramp = [s for s in v.shapes if s.element == "r1"]
    assert len(ramp) > 3 and ramp[0].colour != ramp[-1].colour  # climbs: colours change
    assert {e for e, _ in v.hits} == {"r1", "r2"}
    x, y, w, h = v.view_box
    assert w < 600  # framed on the ramps, not on the 600 m carriageways
    inside = [(float(a), float(b)) for _, pts in v.hits for a, b in
              (p.split(",") for p in pts.split())]
    assert all(x <= a <= x + w and y <= b <= y + h for a, b in inside)  # every ramp in view
    labels = {e: (a, b) for e, a, b in v.labels}
    assert all(x <= labels[r][0] <= x + w and y <= labels[r][1] <= y + h
               for r in ("A1", "A2", "B1", "B2"))  # road names where the roads enter the view


def make_geometry():
    from tests.report_support import geometry  # noqa: PLC0415

    return geometry(CLASS, 0)


def read_geometry_from(g):
    import tempfile  # noqa: PLC0415

    from flyover.geometry.model import write_geometry  # noqa: PLC0415

    with tempfile.TemporaryDirectory() as d:
        write_geometry(g, Path(d) / "geometry.json")
        return read_geometry(Path(d) / "geometry.json")


def test_an_unreadable_geometry_json_is_a_note_on_its_page(tmp_path, caplog):
    res = make_results(tmp_path)
    bad = res / "interchanges" / CLASS / "1" / "geometry.json"
    bad.write_text("{not json", encoding="utf-8")
    build_report(res)
    html = text(res / "report" / "interchanges" / CLASS / "1.html")
    assert "The plan view cannot be drawn" in html and "geometry.json" in html
    assert "<svg" not in html
    assert "<svg" in text(res / "report" / "interchanges" / CLASS / "0.html")
    assert any("geometry.json" in r.getMessage() for r in caplog.records)


def test_geometry_without_its_timing_table_is_still_shown(tmp_path):
    res = make_results(tmp_path, ("topology", "sampling", "geometry"))
    (res / "geometry_timing.parquet").unlink()
    build_report(res)
    html = text(res / "report" / "classes" / f"{CLASS}.html")
    assert "ramps within their targets" in html and "geometry_timing" not in html


def test_problem_tables_link_each_interchange_to_its_page(complete):
    index = text(complete / "report" / "index.html")
    assert f'<a href="interchanges/{CLASS}/1.html">1</a>' in index  # the failed asam_qc


def test_a_killed_build_leaves_nothing_behind_the_next_one(tmp_path):
    import os  # noqa: PLC0415

    res = make_results(tmp_path, ("topology",))
    stale = res / ".report.abc.tmp"
    (stale / "classes").mkdir(parents=True)
    os.utime(stale, (0, 0))
    fresh = res / ".report.def.tmp"  # another build, running now
    fresh.mkdir()
    build_report(res)
    assert not stale.exists() and fresh.exists()


def test_class_page_shows_its_throughput_and_fuel(complete):
    html = text(complete / "report" / "classes" / f"{CLASS}.html")
    assert "flyover query --named throughput-by-class" in html
    assert "flyover query --named fuel-by-class" in html
    assert "1350" in html or "1800" in html  # a density of its runs
