"""The translucent half of the thin-walled subsurface mix [subsurface_thin_walled]: a
Lambertian transmission of albedo subsurface_color weighted subsurface_color (1 + g) / 2;
cosine sampled below the surface.

Example
-------
>>> from openpbr_diffuse.nodes import OpenPBRSurface
>>> p = OpenPBRSurface(subsurface_weight=1.0, geometry_thin_walled=True, subsurface_color=(0.5, 0.5, 0.5)).params
>>> round(weight_color(p, 0, 0), 6), bool(is_on(p, 0))  # 0.5 colour (1 + g), g = 0
(0.25, True)
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..._jit import INV_PI, block
from ...sampling.simple import cosine_pdf
from .._surface_params import PARAM, S_COSINE, UNDER_SPECULAR
from ._common import fixed_sampler, sampler_width, separable_albedo

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

    from .._surface_params import Directions, EvalInputs

NAME = "subsurface_transmission"
LAYER = UNDER_SPECULAR
constant_albedo, albedo, score = separable_albedo(color=PARAM.SSS_COLOR)
sampler = fixed_sampler(S_COSINE)
sample_setup = sampler_width(-1, side=-1.0)  # below the surface


@block
def weight_color(p: NDArray[np.float64], offset: int, c: int) -> float:
    solid = p[offset + PARAM.BASE_MUL + c] * (1.0 - p[offset + PARAM.METAL]) * (1.0 - p[offset + PARAM.TRANS_W])
    return solid * p[offset + PARAM.SSS_W] * 0.5 * p[offset + PARAM.SSS_COLOR + c] * (1.0 + p[offset + PARAM.SSS_ANISO])


@block
def is_on(p: NDArray[np.float64], offset: int) -> bool:
    dielectric = 1.0 - p[offset + PARAM.METAL]
    return (p[offset + PARAM.THIN] > 0.0) and (
        dielectric * (1.0 - p[offset + PARAM.TRANS_W]) * p[offset + PARAM.SSS_W] > 0.0
    )


@block
def eval(p: NDArray[np.float64], offset: int, d: Directions, x: EvalInputs) -> tuple[float, float, float]:
    g = INV_PI if (d.wi_z < 0.0) & (d.wo_z > 0.0) else 0.0
    color = offset + PARAM.SSS_COLOR
    return p[color] * g, p[color + 1] * g, p[color + 2] * g


@block
def pdf(p: NDArray[np.float64], offset: int, d: Directions, dmodel: int, vndf: bool, ggx_pdf: float) -> float:
    return cosine_pdf(-d.wi_z)
