"""Blender renders of the chart: the chart's own ``render_blender.py`` run by a Python with bpy.

The script (``openpbr-diffuse chart --format blender``) is what a Blender user takes: it builds
the scene (Principled BSDF with Diffuse Roughness, Specular IOR Level 0, a Sun of strength E,
view transform Standard) and renders a float EXR with the engine named on its command line.
It runs in ``$OPENPBR_DIFFUSE_BPY_PYTHON`` (see :func:`openpbr_diffuse.graders.cycles.bpy_python`)
under :func:`openpbr_diffuse.graders.limits.run_limited`; EEVEE and Storm need OpenGL, which
bpy gets from EGL (Mesa llvmpipe) when there is no display.
"""

from __future__ import annotations

import os
from pathlib import Path

from ..graders.errors import GraderUnavailable

#: address-space limit of a Blender render, bytes: bpy with llvmpipe maps more than the 4 GiB
#: default of user code (its resident memory stays below 1 GiB at 256^2)
MEMORY = 16 * 2**30


def version() -> str:
    """Blender's version string of the bpy the renders use (GraderUnavailable without bpy)."""
    from ..graders.cycles import bpy_version

    return bpy_version()


def render(scene_dir: Path, out: Path, engine: str, samples: int) -> list[str]:
    """Run ``scene_dir/render_blender.py OUT SAMPLES ENGINE``; the notes of the run.

    Raises GraderUnavailable (one line) when the render fails or writes no image.
    """
    from ..graders import limits
    from ..graders.cycles import bpy_python

    script = Path(scene_dir) / "render_blender.py"
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}  # bpy pins its own numpy
    run = limits.run_limited(
        [bpy_python(), str(script), str(out), str(samples), engine],
        label=f"Blender {engine} render",
        memory=MEMORY,
        env=env,
    )
    if run.returncode != 0 or not Path(out).is_file():
        err = run.stderr.decode(errors="replace").strip().splitlines()
        useful = [e for e in err if "Error" in e or "error" in e] or err or ["no output"]
        raise GraderUnavailable(f"the Blender {engine} render failed (exit {run.returncode}): {useful[-1][:300]}")
    return [f"Blender {engine}, {samples} samples per pixel"]
