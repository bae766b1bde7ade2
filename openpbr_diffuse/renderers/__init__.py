"""Render the conformance chart in the renderers users use, and grade the images.

Each renderer is rendered from the chart file its users would take (``openpbr-diffuse chart
--format ...``), in a child process under the time limit of user code
(:func:`openpbr_diffuse.graders.limits.run_limited`), at a small size (256^2 by default:
the tile interiors are what is graded), and the image is graded by
:func:`openpbr_diffuse.chart.grading.grade_image` exactly as ``check --image`` grades it.

=================  ===============================================  ==============  ==========
name               renderer                                         chart file      needs
=================  ===============================================  ==============  ==========
cycles-render      Blender Cycles (Principled BSDF), CPU            render_blender  bpy
eevee              Blender EEVEE (Principled BSDF), OpenGL (EGL)    render_blender  bpy, EGL
storm              Blender Hydra Storm (hydra_storm add-on), GL     render_blender  bpy, EGL
threejs-render     three.js WebGLRenderer, GLTFLoader               chart.gltf      Chromium
babylonjs-render   Babylon.js Engine, glTF loader                   chart.gltf      Chromium
luxcore            LuxCoreRender roughmatte (Oren-Nayar), PATHCPU   chart.json      pyluxcore
materialx-render   MaterialX GlslRenderer, one render per tile      chart.mtlx      Xvfb (GLX)
=================  ===============================================  ==============  ==========

``openpbr-diffuse check --implementation NAME`` (one of the names above) renders and grades.

Example
-------
>>> sorted(RENDERERS)[:2]
['babylonjs-render', 'cycles-render']
>>> RENDERERS["eevee"].chart_format
'blender'
"""

from __future__ import annotations

import importlib
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ..chart.grading import ImageGrade

#: the chart scene rendered by default (light-view angle 35 degrees, L.V = 0.82)
DEFAULT_SCENE = "scene_01"
#: the image width = height rendered by default
DEFAULT_RESOLUTION = 256


@dataclass(frozen=True)
class Renderer:
    """A registered renderer: its module (``render``, ``version``), label and chart format; a
    Blender renderer names its engine (the module's ``ENGINES`` entry has ``render``, ``version``)."""

    name: str
    module: str
    label: str
    chart_format: str
    engine: str | None = None

    def load(self) -> Any:
        """What renders: the module, or its Blender engine.

        >>> RENDERERS["storm"].load().engine
        'HYDRA_STORM'
        """
        module = importlib.import_module(f"{__name__}.{self.module}")
        return module.ENGINES[self.engine] if self.engine else module


RENDERERS = {
    r.name: r
    for r in (
        Renderer("cycles-render", "_blender", "Blender Cycles (Principled BSDF, CPU)", "blender", "CYCLES"),
        Renderer("eevee", "_blender", "Blender EEVEE (Principled BSDF)", "blender", "EEVEE"),
        Renderer("storm", "_blender", "Blender Hydra Storm (Principled BSDF)", "blender", "HYDRA_STORM"),
        Renderer("threejs-render", "threejs", "three.js WebGLRenderer (GLTFLoader)", "gltf"),
        Renderer("babylonjs-render", "babylonjs", "Babylon.js (glTF loader)", "gltf"),
        # LuxCore reads chart.json (written with every format): the smallest format is asked for
        Renderer("luxcore", "luxcore", "LuxCoreRender (roughmatte, PATHCPU)", "mtlx"),
        Renderer("materialx-render", "materialx_render", "MaterialX GlslRenderer (open_pbr_surface)", "mtlx"),
    )
}


@dataclass
class RenderResult:
    """A renderer's image of a chart scene and its grade."""

    renderer: str
    label: str
    version: str
    scene: str
    light: str
    resolution: int
    seconds: float
    grade: ImageGrade
    notes: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        d = self.grade.to_dict()
        d.update(
            renderer=self.renderer,
            label=self.label,
            renderer_version=self.version,
            scene=self.scene,
            resolution=self.resolution,
            render_seconds=round(self.seconds, 2),
            notes=self.notes,
        )
        return d


def renderer(name: str) -> Renderer:
    """The registered renderer ``name``.

    >>> renderer("storm").label
    'Blender Hydra Storm (Principled BSDF)'
    >>> renderer("povray")
    Traceback (most recent call last):
    ...
    ValueError: renderer: 'povray' is not one of cycles-render, eevee, storm, threejs-render, babylonjs-render, luxcore, materialx-render
    """
    if name not in RENDERERS:
        raise ValueError(f"renderer: {name!r} is not one of {', '.join(RENDERERS)}")
    return RENDERERS[name]


def render_and_grade(
    name: str,
    *,
    scene: str = DEFAULT_SCENE,
    light: str = "distant",
    resolution: int = DEFAULT_RESOLUTION,
    keep: str | Path | None = None,
) -> RenderResult:
    """Write the chart, render ``scene`` with renderer ``name`` and grade the image.

    The chart and the image go to a temporary folder, or to ``keep`` (a new or empty folder:
    ``keep/chart/...`` and ``keep/<name>.exr``).  Raises ValueError for an unknown name or
    scene, GraderUnavailable (an OSError) when the renderer is missing, fails or runs past
    the time limit.
    """
    from ..chart.grading import grade_image
    from ..chart.image import read_image
    from ..chart.schema import read_chart
    from ..chart.write import write_chart

    r = renderer(name)
    mod = r.load()
    version = mod.version()  # GraderUnavailable before any work
    with tempfile.TemporaryDirectory(prefix="openpbr-diffuse-render-") as tmp:
        work = Path(keep) if keep is not None else Path(tmp)
        if keep is not None:
            work.mkdir(exist_ok=True)
            if any(work.iterdir()):
                raise ValueError(f"keep: {work} is not empty: nothing written (give a new or empty folder)")
        write_chart(work / "chart", formats=(r.chart_format,), light=light, resolution=resolution)
        scene_dir = work / "chart" / scene
        if not (scene_dir / "chart.json").is_file():
            names = sorted(p.name for p in (work / "chart").iterdir() if p.is_dir())
            raise ValueError(f"scene: {scene!r} is not one of {', '.join(names)}")
        image = work / f"{name}.exr"
        t0 = time.monotonic()
        notes = mod.render(scene_dir, image) or []
        seconds = time.monotonic() - t0
        chart = read_chart(scene_dir / "chart.json")
        grade = grade_image(read_image(image), chart)
    return RenderResult(name, r.label, version, scene, light, resolution, seconds, grade, list(notes))


def summary(result: RenderResult) -> dict[str, Any]:
    """One line of the results page: verdict, diagnosis, largest error.

    >>> summary.__name__
    'summary'
    """
    g = result.grade
    d = result.to_dict()
    return {
        "renderer": result.label,
        "name": result.renderer,
        "version": result.version,
        "chart": f"{result.scene}, {result.resolution}x{result.resolution}",
        "light": result.light,
        "verdict": "conforms" if g.passed else "does not conform",
        "diagnosis": g.grade.diagnosis,
        "closest": g.grade.closest,
        "non_linear": g.non_linear,
        "exposure": g.exposure,
        "max_rel_error": d.get("max_rel_error"),
        "max_abs_error": d.get("max_abs_error"),
        "seconds": round(result.seconds, 1),
    }


__all__ = ["RENDERERS", "Renderer", "RenderResult", "render_and_grade", "renderer", "summary"]
