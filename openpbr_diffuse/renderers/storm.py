"""Blender's Hydra Storm renders the chart (``render_blender.py ... HYDRA_STORM``).

The ``hydra_storm`` add-on ships with Blender (4.0 and later) and is enabled by the script;
Blender hands the scene to Hydra (USD) and Storm rasterises it with OpenGL (EGL here).

Example
-------
>>> SAMPLES
1
"""

from __future__ import annotations

from pathlib import Path

from . import _blender

#: Storm takes no sample count; passed for the script's argument order
SAMPLES = 1
version = _blender.version


def render(scene_dir: Path, out: Path) -> list[str]:
    """Render ``scene_dir`` (a chart scene with ``render_blender.py``) into the EXR ``out``."""
    return _blender.render(scene_dir, out, "HYDRA_STORM", SAMPLES)
