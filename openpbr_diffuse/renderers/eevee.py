"""Blender EEVEE renders the chart (``render_blender.py ... EEVEE``) on OpenGL through EGL.

One render sample: the sun is a delta light of angle 0, and EEVEE's image of the chart is
deterministic (64 samples give the same tile means to 1e-6; they take 2 minutes on llvmpipe,
one takes 5 s).

Example
-------
>>> SAMPLES
1
"""

from __future__ import annotations

from pathlib import Path

from . import _blender

#: EEVEE render samples (``scene.eevee.taa_render_samples``)
SAMPLES = 1
version = _blender.version


def render(scene_dir: Path, out: Path) -> list[str]:
    """Render ``scene_dir`` (a chart scene with ``render_blender.py``) into the EXR ``out``."""
    return _blender.render(scene_dir, out, "EEVEE", SAMPLES)
