"""Rule report run for real by Snakemake on a small city of two classes (every stage, SUMO
throughput and truck fuel included): the report is built, is rebuilt only when an input
changes, and opens in headless Chromium without an error (when Chromium is installed)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pyarrow.parquet as pq
import pytest
import yaml

from tests import report_browser as rb
from tests.small_city import small_city

pytestmark = [pytest.mark.integration, pytest.mark.slow]

REPO = Path(__file__).resolve().parents[1]
TARGET = "results/report/index.html"

def _snakefile(wd: Path) -> Path:
    return REPO / "Snakefile"


def snakemake(wd: Path, *args: str) -> subprocess.CompletedProcess:
    proc = subprocess.run([sys.executable, "-m", "snakemake", "-s", str(_snakefile(wd)),
                           "-d", str(wd), *args], cwd=wd, capture_output=True, text=True,
                          check=False)
    if proc.returncode != 0:
        raise AssertionError(proc.stderr[-4000:])
    return proc


def _jobs(log: str) -> set[str]:
    return {s.split()[1].rstrip(":") for s in map(str.strip, log.splitlines())
            if s.startswith(("rule ", "localrule ", "checkpoint "))}


@pytest.fixture(scope="module")
def workdir(tmp_path_factory) -> Path:
    wd = small_city(tmp_path_factory.mktemp("report_workflow"))
    snakemake(wd, "-j2", TARGET)
    return wd


def test_the_workflow_builds_the_report_of_every_class(workdir):
    report = workdir / "results" / "report"
    manifest = yaml.safe_load((workdir / "results" / "classes" / "manifest.json").read_text())
    for class_id in manifest["classes"]:
        assert (report / "classes" / f"{class_id}.html").is_file()
        samples = [p.name for p in (workdir / "results" / "interchanges" / class_id).iterdir()]
        assert {p.stem for p in (report / "interchanges" / class_id).glob("*.html")} == set(samples)
    assert (report / "figures" / "fuel_table4.png").is_file()
    assert "./dev run" not in (report / "evaluation.html").read_text(encoding="utf-8")


def test_the_report_is_rebuilt_only_when_an_input_changes(workdir):
    dry = snakemake(workdir, "-n", TARGET)
    assert "Nothing to be done" in dry.stdout + dry.stderr
    # new bytes, same rows (Snakemake compares a small file's content: a touch is no change)
    stats = workdir / "results" / "throughput_stats.parquet"
    pq.write_table(pq.read_table(stats), stats, compression="gzip")
    dry = snakemake(workdir, "-n", TARGET)
    assert _jobs(dry.stdout + dry.stderr) == {"report"}


@pytest.mark.skipif(rb.browser_missing() is not None,
                    reason=f"no headless browser: {rb.browser_missing()}")
def test_the_workflow_report_opens_in_chromium_without_errors(workdir):
    from tests.test_report_browser import check_pages  # noqa: PLC0415

    report = workdir / "results" / "report"
    with rb.chromium() as driver:
        assert check_pages(driver, report) == {}
        page = sorted((report / "interchanges").glob("*/0.html"))[0]
        rb.open_page(driver, page)
        ramp, tip = rb.hover_ramp(driver)
        assert tip.startswith(f"ramp {ramp}") and "truck fuel" in tip
        rb.open_page(driver, report / "index.html")
        rb.broken_images(driver)
        rb.screenshot(driver, report / "screenshot-overview.png")
        rb.open_page(driver, sorted((report / "classes").glob("*.html"))[0])
        rb.broken_images(driver)
        rb.screenshot(driver, report / "screenshot-class.png")
