"""The dataset browser in a real browser: headless Chromium opens every page from disk
(file://, no server), with no console error, every link and image resolving, no request
leaving the machine, and the interactive plan view answering a hover, a zoom and a drag.

Needs Debian's ``chromium`` and ``chromium-driver`` and ``selenium``; skipped otherwise.
Screenshots of the overview and of a class page are saved under ``results/report/``.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from flyover.report import build_report
from tests import report_browser as rb
from tests.report_support import CLASS, make_results

pytestmark = [
    pytest.mark.integration,
    pytest.mark.skipif(rb.browser_missing() is not None,
                       reason=f"no headless browser: {rb.browser_missing()}"),
]


@pytest.fixture(scope="module")
def report(tmp_path_factory) -> Path:
    res = make_results(tmp_path_factory.mktemp("browser"))
    return build_report(res).parent


@pytest.fixture(scope="module")
def browser():
    with rb.chromium() as driver:
        yield driver


def check_pages(driver, report: Path) -> dict[str, list[str]]:
    """Every page of ``report`` opened: its console errors, broken links and images and
    requests to anything but local files (empty lists when all is well)."""
    problems: dict[str, list[str]] = {}
    for page in sorted(report.rglob("*.html")):
        rb.open_page(driver, page)
        found = [f"console: {m}" for m in rb.console_errors(driver)]
        found += [f"link: {h}" for h in rb.broken_links(driver)]
        found += [f"image: {s}" for s in rb.broken_images(driver)]
        found += [f"network: {u}" for u in rb.external_requests(driver)]
        found += [f"console: {m}" for m in rb.console_errors(driver)]  # from lazy images
        if found:
            problems[str(page.relative_to(report))] = found
    return problems


def test_every_page_opens_from_disk_without_errors(browser, report):
    assert check_pages(browser, report) == {}


def test_hovering_a_ramp_shows_its_targets_achieved_values_and_fuel(browser, report):
    rb.open_page(browser, report / "interchanges" / CLASS / "0.html")
    assert browser.find_element("id", "viewer").get_attribute("data-ready") == "1"
    ramp, tip = rb.hover_ramp(browser)
    assert tip.startswith(f"ramp {ramp}")
    assert "radius target" in tip and "achieved" in tip and "slope target" in tip
    assert "length" in tip and "truck fuel" in tip and "ml/km" in tip
    # the ramp's row of the table is highlighted with it
    row = browser.find_element("css selector", f'#ramps tr[data-el="{ramp}"]')
    assert "hover" in row.get_attribute("class")
    assert rb.console_errors(browser) == []


def test_the_plan_view_zooms_and_pans(browser, report):
    rb.open_page(browser, report / "interchanges" / CLASS / "1.html")

    def view_box():
        return [float(v) for v in browser.execute_script(
            "return document.getElementById('plan').getAttribute('viewBox')").split()]

    home = view_box()
    r = browser.execute_script("return document.getElementById('plan').getBoundingClientRect()"
                               ".toJSON()")
    cx, cy = r["x"] + r["width"] / 2, r["y"] + r["height"] / 2
    browser.execute_cdp_cmd("Input.dispatchMouseEvent", {
        "type": "mouseWheel", "x": cx, "y": cy, "deltaX": 0, "deltaY": -400})
    zoomed = view_box()
    assert zoomed[2] < 0.8 * home[2]  # zoomed in
    for kind, x in (("mousePressed", cx), ("mouseMoved", cx + 120), ("mouseReleased", cx + 120)):
        browser.execute_cdp_cmd("Input.dispatchMouseEvent", {
            "type": kind, "x": x, "y": cy, "button": "left", "buttons": 1 if kind != "mouseReleased"
            else 0, "clickCount": 1})
    panned = view_box()
    assert panned[0] < zoomed[0] and panned[2] == pytest.approx(zoomed[2])  # dragged right
    browser.find_element("css selector", 'button[data-zoom="reset"]').click()
    assert view_box() == pytest.approx(home)
    assert rb.console_errors(browser) == []


def test_screenshots_of_the_overview_and_a_class_page(browser, report):
    rb.open_page(browser, report / "index.html")
    rb.broken_images(browser)
    overview = rb.screenshot(browser, report / "screenshot-overview.png")
    rb.open_page(browser, report / "classes" / f"{CLASS}.html")
    rb.broken_images(browser)
    page = rb.screenshot(browser, report / "screenshot-class.png")
    for shot in (overview, page):
        assert shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and shot.stat().st_size > 10_000


def test_a_column_head_sorts_its_table(browser, report):
    rb.open_page(browser, report / "classes" / f"{CLASS}.html")
    head = browser.find_element("css selector", "#files table.data thead th:first-child")

    def samples():
        return [c.text for c in browser.find_elements(
            "css selector", "#files table.data tbody td:first-child")]

    assert samples() == ["0", "1", "2"]
    head.click()
    head.click()  # again: descending
    assert samples() == ["2", "1", "0"]
    assert head.get_attribute("aria-sort") == "descending"
    assert rb.console_errors(browser) == []
