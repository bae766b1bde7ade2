"""Open a report page in headless Chromium (Debian's /usr/bin/chromium through playwright, the
way tests/test_report_page.py drives it) and read what the first screen shows."""

from pathlib import Path

from _system import need
from test_report_page import CHROMIUM, FLAGS


def first_screen(html: Path, selector: str = "#headline", width: int = 1280, height: int = 800) -> dict:
    """{"text": the element's text, "bottom": its bottom edge (px), "height": the viewport's,
    "body": the page's text, "errors": page errors and console errors, "failed": failed
    requests, "images": [(src, complete, naturalWidth)]}.  Skips when playwright or Chromium
    is absent."""
    from playwright import sync_api

    need("chromium")
    errors, failed = [], []
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=FLAGS)
        try:
            page = browser.new_page(viewport={"width": width, "height": height})
            page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.on("requestfailed", lambda r: failed.append(r.url))
            page.goto(Path(html).resolve().as_uri(), wait_until="load")
            text = page.inner_text(selector)
            bottom = page.eval_on_selector(selector, "e => e.getBoundingClientRect().bottom")
            body = page.inner_text("body")
            images = page.eval_on_selector_all(
                "img", "els => els.map(e => [e.getAttribute('src'), e.complete, e.naturalWidth])"
            )
        finally:
            browser.close()
    return {
        "text": text,
        "bottom": bottom,
        "height": height,
        "body": body,
        "errors": errors,
        "failed": failed,
        "images": images,
    }
