"""The documentation site: every public name is in the API reference, the generated pages are
current, and the site builds in strict mode (warnings are errors, internal links checked)."""

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

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


def test_site_builds_strictly(tmp_path):
    mkdocs = shutil.which("mkdocs")
    if mkdocs is None:
        pytest.skip("mkdocs not installed (pip install -e '.[docs]')")
    r = subprocess.run(
        [mkdocs, "build", "--strict", "-d", str(tmp_path / "site")], capture_output=True, text=True, cwd=ROOT
    )
    assert r.returncode == 0, r.stderr[-3000:]
    assert (tmp_path / "site" / "index.html").exists()
    assert 'id="openpbr_diffuse.evaluate"' in (tmp_path / "site" / "reference" / "api" / "index.html").read_text()
