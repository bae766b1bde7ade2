"""LuxCoreRender (``pyluxcore``) renders the chart: the scene is built with pyluxcore's API
from ``chart.json``, material ``roughmatte`` (Oren-Nayar), PATHCPU, 16 samples per pixel.

LuxCore has no OpenPBR material and no chart file of its own, so the scene is built as a
LuxCore user builds one from the chart's description: one inline quad mesh per tile
(``Scene.DefineMesh``: the tile's world corners and normal), ``roughmatte`` with
``kd`` = rho and ``sigma`` = r pi/2 (the diffuse roughness r in [0, 1] mapped onto
Oren-Nayar's sigma in [0, pi/2]: LuxCore takes sigma in radians, unconverted, in
``A = 1 - sigma^2 / (2 (sigma^2 + 0.33))``, ``B = 0.45 sigma^2 / (sigma^2 + 0.09)``),
a ``sharpdistant`` light (LuxCore's delta directional light: gain E gives irradiance E;
``distant`` is its cone light, whose ``theta`` = 0 is not a delta light), an orthographic
camera over the chart's extent, no pixel filter, a linear image pipeline (``TONEMAP_LINEAR``
scale 1) and the film's linear ``RGB`` output.  The child
(``_luxcore_child.py``) runs under the time limit of user code; the EXR is written here.

Example
-------
>>> SAMPLES
16
"""

from __future__ import annotations

from pathlib import Path

from ..graders.errors import GraderUnavailable
from ._film import render_film

CHILD = Path(__file__).with_name("_luxcore_child.py")
#: samples per pixel: a delta light on flat tiles leaves only the tile edges to average
SAMPLES = 16
INSTALL = "pip install pyluxcore"


def version() -> str:
    """pyluxcore's package version (GraderUnavailable when it is not installed)."""
    from importlib.metadata import PackageNotFoundError
    from importlib.metadata import version as dist_version

    try:
        return dist_version("pyluxcore")
    except PackageNotFoundError:
        raise GraderUnavailable(f"pyluxcore is not installed: {INSTALL}") from None


def render(scene_dir: Path, out: Path) -> list[str]:
    """Render ``scene_dir/chart.json`` with LuxCore into the EXR ``out``."""
    version()
    info = render_film(
        CHILD, scene_dir, out, what="the LuxCore render", tag="luxcore", film="film.npy", arg=str(SAMPLES)
    )
    return [f"LuxCore {info.get('version', '?')} PATHCPU, {SAMPLES} samples per pixel, roughmatte with sigma = r pi/2"]
