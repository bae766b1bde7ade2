"""The report page in headless Chromium: no console error, no failed request, every image
loaded; a screenshot is saved beside the page (Debian's /usr/bin/chromium via playwright)."""
import shutil
from pathlib import Path

import pytest

from openpbr_diffuse.report.runner import run_report
from openpbr_diffuse.report.sections import SECTIONS

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--no-first-run"]


def test_page_opens_in_chromium_without_errors(tmp_path):
    sync_api = pytest.importorskip("playwright.sync_api")
    if not Path(CHROMIUM).exists():
        pytest.skip("chromium not installed (apt-get install chromium)")
    out = tmp_path / "report"
    run_report(None, out, quick=True, progress=False)
    url = (out / "index.html").resolve().as_uri()
    console, failed = [], []
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=FLAGS)
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 900})
            page.on("console", lambda m: console.append((m.type, m.text)))
            page.on("pageerror", lambda e: console.append(("pageerror", str(e))))
            page.on("requestfailed", lambda r: failed.append(r.url))
            page.goto(url, wait_until="load")
            images = page.eval_on_selector_all(
                "img", "els => els.map(e => [e.getAttribute('src'), e.complete, e.naturalWidth])")
            keys = page.eval_on_selector_all("section[data-key]", "els => els.map(e => e.dataset.key)")
            page.screenshot(path=str(out / "screenshot.png"), full_page=True)
        finally:
            browser.close()
    assert [c for c in console if c[0] in ("error", "pageerror")] == []
    assert failed == []
    assert images and all(done and width > 0 for _, done, width in images), images
    assert keys == list(SECTIONS)
    assert (out / "screenshot.png").stat().st_size > 10_000
