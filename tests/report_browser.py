"""Headless Chromium for the report tests: open pages from disk, check what a reader sees.

Drives Debian's ``chromium`` through ``chromedriver`` with Selenium (no download: the
driver and browser are given by path, Selenium Manager stays offline). Install with
``apt-get install -y chromium chromium-driver`` and ``pip install selenium``.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
import time
from pathlib import Path
from urllib.parse import unquote, urlparse

CHROMIUM = ("/usr/bin/chromium", "/usr/bin/chromium-browser", "/usr/bin/google-chrome")
CHROMEDRIVER = ("/usr/bin/chromedriver",)

#: the flags of a headless browser that makes no request of its own
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--disable-dev-shm-usage", "--window-size=1400,1000")


def browser_missing() -> str | None:
    """Why the browser tests cannot run here (``None`` when they can)."""
    try:
        import selenium  # noqa: F401, PLC0415
    except ImportError:
        return "selenium is not installed (pip install selenium)"
    if not any(os.access(p, os.X_OK) for p in CHROMIUM):
        return "no Chromium (apt-get install -y chromium chromium-driver)"
    if not any(os.access(p, os.X_OK) for p in CHROMEDRIVER):
        return "no chromedriver (apt-get install -y chromium-driver)"
    return None


@contextlib.contextmanager
def chromium():
    """A headless Chromium (Selenium WebDriver) with a fresh, empty profile."""
    from selenium import webdriver  # noqa: PLC0415
    from selenium.webdriver.chrome.service import Service  # noqa: PLC0415

    os.environ.setdefault("SE_OFFLINE", "true")
    profile = tempfile.mkdtemp(prefix="flyover-chromium-")
    opts = webdriver.ChromeOptions()
    opts.binary_location = next(p for p in CHROMIUM if os.access(p, os.X_OK))
    for flag in FLAGS:
        opts.add_argument(flag)
    opts.add_argument(f"--user-data-dir={profile}")
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    service = Service(next(p for p in CHROMEDRIVER if os.access(p, os.X_OK)))
    driver = webdriver.Chrome(options=opts, service=service)
    try:
        driver.set_page_load_timeout(60)
        yield driver
    finally:
        driver.quit()
        shutil.rmtree(profile, ignore_errors=True)


def open_page(driver, path: Path) -> None:
    driver.get(Path(path).resolve().as_uri())


def console_errors(driver) -> list[str]:
    """Console messages of level SEVERE since the last call (errors, failed loads)."""
    return [m["message"] for m in driver.get_log("browser") if m["level"] == "SEVERE"]


def broken_links(driver) -> list[str]:
    """Every ``a[href]`` of the page whose file does not exist (file:// links), and every
    non-file link (the report must need no network)."""
    hrefs = driver.execute_script(
        "return Array.from(document.querySelectorAll('a[href]')).map(a => a.href)")
    bad = []
    for href in hrefs:
        url = urlparse(href)
        if url.scheme != "file":
            bad.append(f"not a file link: {href}")
        elif not Path(unquote(url.path)).exists():
            bad.append(href)
    return bad


def broken_images(driver, timeout_s: float = 20.0) -> list[str]:
    """Every image that did not load, after making the lazy ones load (scrolled to)."""
    driver.execute_script(
        "document.querySelectorAll('img').forEach(i => { i.loading = 'eager'; });"
        "document.querySelectorAll('img').forEach(i => i.scrollIntoView());"
        "window.scrollTo(0, 0);")
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        pending = driver.execute_script(
            "return Array.from(document.images).filter(i => !i.complete).length")
        if not pending:
            break
        time.sleep(0.1)
    return driver.execute_script(
        "return Array.from(document.images)"
        ".filter(i => !i.complete || i.naturalWidth === 0).map(i => i.src)")


def external_requests(driver) -> list[str]:
    """Every resource the page fetched that is not a local file."""
    return driver.execute_script(
        "return performance.getEntriesByType('resource').map(e => e.name)"
        ".filter(n => !n.startsWith('file:') && !n.startsWith('data:'))")


def hover_ramp(driver) -> tuple[str, str]:
    """Move the mouse (a real input event) onto the middle of a ramp of the plan view;
    returns (the ramp pointed at, the text of the hover box)."""
    point = driver.execute_script("""
        const svg = document.getElementById('plan');
        for (const hit of svg.querySelectorAll('.hits polyline')) {
          const n = hit.getTotalLength();
          for (const f of [0.5, 0.4, 0.6, 0.3, 0.7]) {
            const p = hit.getPointAtLength(n * f);
            const q = svg.createSVGPoint(); q.x = p.x; q.y = p.y;
            const s = q.matrixTransform(svg.getScreenCTM());
            const top = document.elementFromPoint(s.x, s.y);
            if (top && top.closest('[data-el]') &&
                top.closest('[data-el]').getAttribute('data-el') === hit.dataset.el)
              return [hit.dataset.el, s.x, s.y];
          }
        }
        return null;""")
    if point is None:
        raise AssertionError("no ramp of the plan view can be pointed at")
    name, x, y = point
    for kind in ("mouseMoved",):
        driver.execute_cdp_cmd("Input.dispatchMouseEvent",
                               {"type": kind, "x": x - 5, "y": y - 5})
        driver.execute_cdp_cmd("Input.dispatchMouseEvent", {"type": kind, "x": x, "y": y})
    tip = driver.find_element("id", "tip")
    end = time.monotonic() + 5
    while time.monotonic() < end and not tip.is_displayed():
        time.sleep(0.05)
    return name, tip.text if tip.is_displayed() else ""


def screenshot(driver, path: Path, full_page: bool = True) -> Path:
    """A PNG of the page (the whole page's height, up to 6000 px, when ``full_page``)."""
    if full_page:
        h = driver.execute_script("return document.documentElement.scrollHeight")
        driver.set_window_size(1400, min(max(int(h), 600), 6000))
    driver.save_screenshot(str(path))
    driver.set_window_size(1400, 1000)
    return Path(path)
