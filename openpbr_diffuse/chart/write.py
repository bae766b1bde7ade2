"""Writing the chart: a folder of scenes, each with its chart.json and the scene file(s).

    DIR/README.md                 render settings for every renderer
    DIR/scene_NN/chart.json       the scene's description (schema openpbr-diffuse-chart/1)
    DIR/scene_NN/chart.usda       --format usd
    DIR/scene_NN/chart.gltf, .bin --format gltf
    DIR/scene_NN/chart.mtlx       --format mtlx (materials only)
    DIR/scene_NN/render_blender.py --format blender

``DIR`` is created (its parent must exist) or must be an empty folder; no existing file is
replaced.

Example
-------
>>> import pathlib, tempfile
>>> d = pathlib.Path(tempfile.mkdtemp()) / "chart"
>>> files = write_chart(d, formats=("usd",), light="distant", resolution=256)
>>> sorted(p.name for p in (d / "scene_01").iterdir())
['chart.json', 'chart.usda']
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from .._outfile import write_output_file
from .layout import LIGHTS, build_scenes

FORMATS = ("usd", "gltf", "mtlx", "blender")

README = """# openpbr-diffuse conformance chart ({light} light)

Scenes of flat tiles whose rendered values are known analytically.  Render every
`scene_NN` at its chart.json `width` x `height` and grade each image:

    openpbr-diffuse check --image scene_NN.exr --chart scene_NN/chart.json [--model eon]

## Render settings (every renderer)

- Linear output: OpenEXR (float) preferred; a PNG/JPEG is accepted as sRGB-encoded 8-bit
  (its quantisation widens the tolerance; a linear 16-bit TIFF/PNG is better).
- No tone mapping, no view transform (Blender: "Standard", look None, exposure 0, gamma 1;
  not Filmic/AgX), no bloom, no auto-exposure, no denoiser, no firefly clamping.
- Black background, no ground plane, no environment light except in the furnace scenes.
- The camera is orthographic; keep the image size of chart.json (pixel rectangles of the
  tiles are exact at that size).  A box pixel filter one pixel wide is best; the grader
  leaves out 15 % of each tile's side on every edge, so a wider filter is fine.
- Samples: the light is a delta (sun, point) and the tiles are far apart, so direct light
  converges in a handful of samples per pixel; 16 are plenty.  The furnace needs
  environment sampling: with N samples per pixel and P interior pixels per tile the
  standard error of a tile is about 0.5/sqrt(N P) of its value; 256 spp at 1024^2 gives
  ~3e-4, well inside the tolerance.  The grader measures the noise itself (4 standard
  errors are allowed) -- more samples give a tighter grade, never a wrong one.
- Diffuse only: specular weight 0 (USD/MaterialX `specular_weight = 0`; glTF
  `KHR_materials_specular.specularFactor = 0`; Blender "Specular IOR Level" 0).
- The exposure is calibrated on the grey ramp (roughness 0 tiles, rho 0.05..1): any
  constant scale (light units of the renderer) is found and reported.

## Per format

- `chart.usda` (USD + MaterialX OpenPBR, `ND_open_pbr_surface_surfaceshader`): open it in
  a Hydra renderer (usdrecord, Karma, RenderMan, Arnold, Omniverse) with the camera
  `/Chart/Camera`.  UsdLux DistantLight intensity = the irradiance E (angle 0), SphereLight
  (point: radius 0) intensity I, DomeLight (furnace) intensity = L.
- `chart.gltf` + `chart.bin` (glTF 2.0, KHR_materials_diffuse_roughness,
  KHR_materials_specular, KHR_lights_punctual): one mesh per tile; the camera is the
  scene's orthographic camera.  glTF has no environment light: in the furnace give the
  viewer a uniform white environment of radiance L and no IBL prefiltering.
- `chart.mtlx` (MaterialX): one `open_pbr_surface` material `M_<tile id>` per tile.
  MaterialX's tools take the geometry separately: assign each material to its tile's quad
  (corners in chart.json) or render `chart.usda`, which binds the same materials.
- `render_blender.py` (Blender >= 4.2, Cycles): `blender -b -P render_blender.py -- OUT.exr
  [SAMPLES]` or `python render_blender.py OUT.exr` with the `bpy` module; it reads
  chart.json beside it and writes a float EXR with the settings above.

The schema of chart.json is documented in the openpbr-diffuse documentation, page
"chart.json schema" (docs/reference/chart-schema.md in its source).
"""


def _prepare(out: Path, create: bool) -> None:
    if out.is_symlink():
        raise ValueError(f"--out {out}: a symbolic link: not written through")
    if out.exists():
        if not out.is_dir():
            raise ValueError(f"--out {out}: exists and is not a folder")
        if any(out.iterdir()):
            raise ValueError(f"--out {out}: the folder is not empty: nothing written (give a new or empty folder)")
    else:
        if not out.parent.is_dir():
            raise ValueError(f"--out {out}: the parent folder {out.parent} does not exist")
        if create:
            out.mkdir()


def write_chart(
    out_dir: str | os.PathLike[str],
    *,
    formats: tuple[str, ...] = FORMATS,
    light: str = "distant",
    resolution: int = 1024,
) -> list[Path]:
    """Write the chart's scenes into ``out_dir`` (created, or empty); the paths written.

    >>> write_chart("/nonexistent/chart", formats=("usd",))
    Traceback (most recent call last):
    ...
    ValueError: --out /nonexistent/chart: the parent folder /nonexistent does not exist
    """
    bad = [f for f in formats if f not in FORMATS]
    if bad or not formats:
        raise ValueError(f"formats: expected names among {', '.join(FORMATS)}, got {list(formats)!r}")
    if light not in LIGHTS:
        raise ValueError(f"light: expected one of {', '.join(LIGHTS)}, got {light!r}")
    out = Path(out_dir)
    _prepare(out, create=False)  # refusals before the work
    scenes = build_scenes(light, resolution)  # checks the resolution before anything is written
    _prepare(out, create=True)
    written = [write_output_file(out / "README.md", README.format(light=light))]
    for scene in scenes:
        d = out / scene["id"]
        d.mkdir()
        written.append(write_output_file(d / "chart.json", json.dumps(scene, indent=1) + "\n"))
        if "usd" in formats:
            from .usd import usda

            written.append(write_output_file(d / "chart.usda", usda(scene)))
        if "gltf" in formats:
            from .gltf import gltf

            doc, blob = gltf(scene, "chart.bin")
            written.append(write_output_file(d / "chart.bin", blob))
            written.append(write_output_file(d / "chart.gltf", json.dumps(doc, indent=1) + "\n"))
        if "mtlx" in formats:
            from .mtlx import mtlx

            written.append(write_output_file(d / "chart.mtlx", mtlx(scene)))
        if "blender" in formats:
            from .blender import blender_script

            written.append(write_output_file(d / "render_blender.py", blender_script()))
    return written


__all__ = ["write_chart", "FORMATS", "README"]
