"""The report page as a person reads it, in headless Chromium at a 1400 px window: no sideways
scroll, the first screen without an implementation holds an example command, and the
third-party section counts its findings with a list per implementation."""

from __future__ import annotations

import pytest
from _system import need
from test_report_page import CHROMIUM, FLAGS

from openpbr_diffuse.report.render import render_html
from openpbr_diffuse.report.runner import run_report

WIDTH, HEIGHT = 1400, 900


def _measure(html):
    from playwright import sync_api

    need("chromium")
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=FLAGS)
        try:
            page = browser.new_page(viewport={"width": WIDTH, "height": HEIGHT})
            page.goto(html.resolve().as_uri(), wait_until="load")
            return page.evaluate(
                """() => {
                  const d = document.documentElement;
                  const start = document.getElementById('start');
                  const wide = [...document.querySelectorAll('table, pre, figure')]
                      .filter(e => e.getBoundingClientRect().right > d.clientWidth + 1)
                      .map(e => e.tagName + ': ' + (e.querySelector('caption') || e).textContent.slice(0, 60));
                  return {scroll: d.scrollWidth, client: d.clientWidth, wide: wide,
                          start: start ? start.innerText : '',
                          startBottom: start ? start.getBoundingClientRect().bottom : 1e9};
                }"""
            )
        finally:
            browser.close()


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    """A quick report of the sections with the widest tables (long material paths, the
    approximations' tables, the grader's deviations), without an implementation under test."""
    out = tmp_path_factory.mktemp("layout") / "r"
    run_report(None, out, quick=True, progress=False, sections=["materials", "implementations", "approximations"])
    return out / "index.html"


def test_no_sideways_scroll_at_1400px(page):
    m = _measure(page)
    assert m["scroll"] <= m["client"], m
    assert m["wide"] == [], m["wide"]


def test_first_screen_holds_an_example_command_and_the_guide(page):
    m = _measure(page)
    assert "openpbr-diffuse report --glsl mine.glsl --function f" in m["start"]
    assert "openpbr-diffuse template glsl --out mine.glsl" in m["start"] and "docs/guide/report.md" in m["start"]
    assert m["startBottom"] <= HEIGHT, m


def test_findings_are_counted_with_a_list_per_implementation(tmp_path):
    """A findings section (as the third-party section makes it): its count in the summary and
    above a list per implementation, never "0 / 0" beside a failing row."""
    doc = {
        "version": "x",
        "generated": "now",
        "quick": True,
        "elapsed_s": 1.0,
        "paths": [],
        "passed": True,
        "evidence": {"n_checks": 0, "n_failed": 0, "n_not_run": 0},
        "sections": [
            {
                "key": "graders",
                "title": "Third-party implementations",
                "status": "findings",
                "not_run": None,
                "elapsed_s": 0.0,
                "error": None,
                "notes": [],
                "warnings": [],
                "checks": [],
                "figures": [],
                "tables": [{"caption": "graded", "columns": ["implementation", "verdict"], "rows": [["a", "FAIL"]]}],
                "lists": [
                    {"title": "impl-a", "items": ["brdf: FINDING: does not conform (ldotv_clamped)", "version: 1"]},
                    {"title": "impl-b", "items": ["brdf: conforms"]},
                ],
                "findings": 1,
            }
        ],
    }
    html = render_html(doc)
    assert "1 finding (2 implementations graded)" in html and "0 / 0" not in html
    assert html.count('<ul class="items">') == 2 and "<h3>impl-a</h3>" in html
