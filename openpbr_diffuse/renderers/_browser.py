"""Web renderers: a page run by headless Chromium in a child process under the time limit.

The page (:mod:`.threejs`, :mod:`.babylonjs`) loads the chart's glTF with the renderer's own
loader from the npm cache (``~/.cache/openpbr-diffuse/npm``), renders into a float render
target (no tone mapping, linear output) and hands the pixels back; the child
(``_browser_child.py``) writes them as a float EXR.  WebGL runs on SwiftShader (ANGLE), so no
GPU is needed.
"""

from __future__ import annotations

import json
import shutil
import tempfile
from pathlib import Path

from ..graders.errors import GraderUnavailable

CHILD = Path(__file__).with_name("_browser_child.py")
#: address-space limit of the browser run, bytes: Chromium reserves tens of GiB of address
#: space (V8's pointer cage, the GPU process) that it never touches
MEMORY = 2**40
CHROMIUM_INSTALL = "apt-get install chromium; pip install playwright"


def chromium() -> str:
    """The Chromium executable (Debian's /usr/bin/chromium), GraderUnavailable when absent."""
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None and Path("/usr/bin/chromium").exists():
        exe = "/usr/bin/chromium"
    if exe is None:
        raise GraderUnavailable(f"Chromium is not installed: {CHROMIUM_INSTALL}")
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        raise GraderUnavailable(f"playwright is not installed: {CHROMIUM_INSTALL}") from None
    return exe


def render_page(page_html: str, scene_dir: Path, node_modules: Path, out: Path, label: str) -> dict:
    """Serve ``page_html`` with the scene and the npm packages, render, write ``out`` (EXR)."""
    from ..graders import limits

    exe = chromium()
    with tempfile.TemporaryDirectory(prefix="openpbr-diffuse-page-") as tmp:
        page = Path(tmp) / "index.html"
        page.write_text(page_html)
        cmd = limits.script_command(
            CHILD, str(page), str(scene_dir), str(node_modules), str(out), str(limits.TIMEOUT), exe
        )
        run = limits.run_limited(cmd, label=f"the {label} render in Chromium", memory=MEMORY)
    if run.returncode != 0 or not Path(out).is_file():
        err = run.stderr.decode(errors="replace").strip().splitlines() or ["no output"]
        raise GraderUnavailable(f"the {label} render failed (exit {run.returncode}): {err[-1][:400]}")
    lines = run.stdout.decode(errors="replace").strip().splitlines()
    return json.loads(lines[-1]) if lines else {}
