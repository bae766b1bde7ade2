"""The documentation site: every public name is in the API reference, the generated pages are
current, and the site builds in strict mode (warnings are errors, internal links checked)."""

import subprocess
import sys
from pathlib import Path

import pytest
from _system import need

import openpbr_diffuse

ROOT = Path(__file__).resolve().parents[1]
API = ROOT / "docs" / "reference" / "api"


def test_every_public_name_is_in_the_api_reference():
    text = "\n".join(p.read_text(encoding="utf-8") for p in API.glob("*.md"))
    missing = [n for n in openpbr_diffuse.__all__ if n not in text]
    assert not missing, missing


def test_generated_pages_are_current():
    r = subprocess.run(
        [sys.executable, str(ROOT / "tools" / "gen_docs.py"), "--check"], capture_output=True, text=True, cwd=ROOT
    )
    assert r.returncode == 0, r.stdout + r.stderr


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """The site built once, strictly (warnings are errors, internal links checked)."""
    out = tmp_path_factory.mktemp("site")
    r = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "-d", str(out)], capture_output=True, text=True, cwd=ROOT
    )
    assert r.returncode == 0, r.stderr[-3000:]
    return out


def test_site_builds_strictly(site):
    assert (site / "index.html").exists()
    assert 'id="openpbr_diffuse.evaluate"' in (site / "reference" / "api" / "index.html").read_text()
    assert "0.1.0" in (site / "changelog" / "index.html").read_text()


@pytest.mark.parametrize("page", ["index.html", "reference/api/index.html"])
def test_pages_render_in_chromium_with_search_and_no_console_error(site, page):
    """The home page and the API page, served over HTTP (the search index loads in a web worker)
    and opened in headless Chromium: they render, a search box is there, nothing errs."""
    import functools
    import http.server
    import threading

    from playwright import sync_api
    from test_report_page import CHROMIUM, FLAGS

    need("chromium")
    handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=str(site))
    handler.log_message = lambda *a, **k: None  # type: ignore[attr-defined]
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    errors: list[str] = []
    try:
        with sync_api.sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, args=FLAGS)
            try:
                tab = browser.new_page(viewport={"width": 1280, "height": 800})
                tab.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
                tab.on("pageerror", lambda e: errors.append(str(e)))
                tab.goto(f"http://127.0.0.1:{server.server_address[1]}/{page}", wait_until="networkidle")
                title = tab.inner_text("h1")
                search = tab.query_selector('input[data-md-component="search-query"]')
                assert search is not None
                search.click()
                tab.keyboard.type("evaluate", delay=20)
                tab.wait_for_selector(".md-search-result__item", timeout=20_000)
                hits = tab.inner_text(".md-search-result")
            finally:
                browser.close()
    finally:
        server.shutdown()
    assert title.strip()
    assert "evaluate" in hits.lower()
    assert not errors, errors


SUBPACKAGES = (
    "models",
    "sampling",
    "albedo",
    "nodes",
    "readers",
    "spectral",
    "graders",
    "simulation",
    "approximations",
    "microfacet",
)


def test_every_public_name_of_the_subpackages_is_in_their_api_page(site):
    """Each sub-package's ``__all__`` (its functions, classes and constants; sub-modules are
    their own pages' business) has an anchor in the built API page of the sub-packages."""
    import importlib
    import importlib.util
    import types

    html = (site / "reference" / "api" / "subpackages" / "index.html").read_text(encoding="utf-8")
    missing = []
    for name in SUBPACKAGES:
        mod = importlib.import_module(f"openpbr_diffuse.{name}")
        for attr in mod.__all__:
            is_module = isinstance(getattr(mod, attr), types.ModuleType) or importlib.util.find_spec(
                f"{mod.__name__}.{attr}"
            )  # a name that is also a sub-module (spectral.colorimetry) is documented as the module
            if not is_module and f'id="{mod.__name__}.{attr}"' not in html:
                missing.append(f"{mod.__name__}.{attr}")
    assert not missing, missing
