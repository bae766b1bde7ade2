"""Blender renders of the chart: the chart's own ``render_blender.py`` run by a Python with bpy.

The script (``openpbr-diffuse chart --format blender``) is what a Blender user takes: it builds
the scene (Principled BSDF with Diffuse Roughness, Specular IOR Level 0, a Sun of strength E,
view transform Standard) and renders a float EXR with the engine named on its command line.
It runs in ``$OPENPBR_DIFFUSE_BPY_PYTHON`` (see :func:`openpbr_diffuse.graders.cycles.bpy_python`)
under :func:`openpbr_diffuse.graders.limits.run_limited`; EEVEE and Storm need OpenGL, which
bpy gets from EGL (Mesa llvmpipe) when there is no display.

The engines (:data:`ENGINES`, the registry's Blender renderers):

- ``CYCLES``: CPU, 16 samples per pixel: the sun is a delta light; 16 average the box pixel filter.
- ``EEVEE`` (OpenGL through EGL): one render sample: the sun is a delta light of angle 0,
  and EEVEE's image of the chart is deterministic (64 samples give the same tile means to
  1e-6; they take 2 minutes on llvmpipe, one takes 5 s); ``scene.eevee.taa_render_samples``.
- ``HYDRA_STORM``: the ``hydra_storm`` add-on ships with Blender (4.0 and later) and is
  enabled by the script; Blender hands the scene to Hydra (USD) and Storm rasterises it with
  OpenGL (EGL here).  Storm takes no sample count: 1 is passed for the script's argument order.

Example
-------
>>> [(e.engine, e.samples) for e in ENGINES.values()]
[('CYCLES', 16), ('EEVEE', 1), ('HYDRA_STORM', 1)]
"""

from __future__ import annotations

import os
from dataclasses import dataclass
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


@dataclass(frozen=True)
class Engine:
    """A Blender render engine as a renderer (``render`` and ``version``): the chart's
    ``render_blender.py`` run with ``engine`` and ``samples``."""

    engine: str
    samples: int

    def version(self) -> str:
        """Blender's version string of the bpy the renders use (GraderUnavailable without bpy)."""
        return version()

    def render(self, scene_dir: Path, out: Path) -> list[str]:
        """Render ``scene_dir`` (a chart scene with ``render_blender.py``) into the EXR ``out``."""
        return render(scene_dir, out, self.engine, self.samples)


#: The Blender engines the chart is rendered with, by the name render_blender.py takes.
ENGINES = {e.engine: e for e in (Engine("CYCLES", 16), Engine("EEVEE", 1), Engine("HYDRA_STORM", 1))}
