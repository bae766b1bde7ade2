"""Blender Cycles renders the chart (``render_blender.py ... CYCLES``): CPU, 16 samples per pixel.

Example
-------
>>> SAMPLES
16
"""

from __future__ import annotations

from pathlib import Path

from . import _blender

#: samples per pixel: the sun is a delta light; 16 average the box pixel filter
SAMPLES = 16
version = _blender.version


def render(scene_dir: Path, out: Path) -> list[str]:
    """Render ``scene_dir`` (a chart scene with ``render_blender.py``) into the EXR ``out``."""
    return _blender.render(scene_dir, out, "CYCLES", SAMPLES)
