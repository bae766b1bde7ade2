"""Open a report page in headless Chromium (Debian's /usr/bin/chromium through playwright, the
way tests/test_report_page.py drives it) and read what the first screen shows."""

import contextlib
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from _system import need
from test_report_page import CHROMIUM, FLAGS


@contextlib.contextmanager
def opened_page(
    html: Path, viewport: dict | None = None, on: dict[str, Callable] | None = None, flags: list[str] = FLAGS
) -> Iterator[tuple[Any, list[str]]]:
    """``(page, errors)``: the file ``html`` loaded in headless Chromium started with ``flags``,
    and the page's errors and console errors as they come (``on``: more page events to listen
    to from before the load); the browser is closed on leaving.  Skips when playwright or
    Chromium is absent."""
    from playwright import sync_api

    need("chromium")
    errors: list[str] = []
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=flags)
        try:
            page = browser.new_page(**({"viewport": viewport} if viewport else {}))
            page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
            page.on("pageerror", lambda e: errors.append(str(e)))
            for event, listener in (on or {}).items():
                page.on(event, listener)
            page.goto(Path(html).resolve().as_uri(), wait_until="load")
            yield page, errors
        finally:
            browser.close()


def first_screen(html: Path, selector: str = "#headline", width: int = 1280, height: int = 800) -> dict:
    """{"text": the element's text, "bottom": its bottom edge (px), "height": the viewport's,
    "body": the page's text, "errors": page errors and console errors, "failed": failed
    requests, "images": [(src, complete, naturalWidth)]}.  Skips when playwright or Chromium
    is absent."""
    failed: list[str] = []
    listen = {"requestfailed": lambda r: failed.append(r.url)}
    with opened_page(html, {"width": width, "height": height}, listen) as (page, errors):
        text = page.inner_text(selector)
        bottom = page.eval_on_selector(selector, "e => e.getBoundingClientRect().bottom")
        body = page.inner_text("body")
        images = page.eval_on_selector_all(
            "img", "els => els.map(e => [e.getAttribute('src'), e.complete, e.naturalWidth])"
        )
    return {
        "text": text,
        "bottom": bottom,
        "height": height,
        "body": body,
        "errors": errors,
        "failed": failed,
        "images": images,
    }
