"""MaterialX's own GLSL renderer (``PyMaterialXRenderGlsl.GlslRenderer``) renders the chart's
MaterialX document (``chart.mtlx``), one tile per render.

``GlslRenderer`` renders one geometry with one material, so each tile is rendered alone (its
quad as an OBJ, the chart's orthographic camera, a ``directional_light`` of intensity E) and
the tiles' rectangles are assembled into the image; see ``_materialx_child.py``.  Its GL
context comes from GLX: the child runs ``Xvfb`` (Mesa llvmpipe), under the time limit of
user code with the child.  The EXR is written here.

Example
-------
>>> XVFB_INSTALL
'apt-get install xvfb'
"""

from __future__ import annotations

import shutil
from pathlib import Path

from ..graders.errors import GraderUnavailable
from ._film import render_film

CHILD = Path(__file__).with_name("_materialx_child.py")
XVFB_INSTALL = "apt-get install xvfb"


def version() -> str:
    """MaterialX's version (GraderUnavailable without its GLSL renderer or without Xvfb)."""
    try:
        import MaterialX as mx
        import MaterialX.PyMaterialXRenderGlsl  # type: ignore[import-untyped]  # noqa: F401
    except ImportError:
        raise GraderUnavailable("MaterialX's GLSL renderer is not installed: pip install materialx") from None
    if shutil.which("Xvfb") is None:
        raise GraderUnavailable(f"Xvfb is not installed (MaterialX's GlslRenderer needs GLX): {XVFB_INSTALL}")
    return str(mx.__version__)


def render(scene_dir: Path, out: Path) -> list[str]:
    """Render ``scene_dir/chart.mtlx`` on the tiles of ``chart.json`` into the EXR ``out``."""
    version()
    info = render_film(CHILD, scene_dir, out, what="the MaterialX GLSL render", tag="materialx", film="frame.npy")
    return [f"MaterialX {info.get('version', '?')} GlslRenderer on Xvfb (GLX, llvmpipe), one render per tile"]
