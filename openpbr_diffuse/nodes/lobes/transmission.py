"""The transmission lobe [dielectric_transmission], *approximated* as the base specular's GGX
lobe mirrored below the surface, normalised to albedo 1 and tinted by transmission_color (1
when transmission_depth > 0, as the reference graph): its weight and albedo are exact for the
mixture (the dielectric transmits 1 - E_spec), its shape ignores refraction.

Example
-------
>>> from openpbr_diffuse.nodes import OpenPBRSurface
>>> p = OpenPBRSurface(transmission_weight=1.0, transmission_color=(0.2, 0.4, 0.8)).params
>>> round(weight_color(p, 0, 0), 6), round(constant_albedo(p, 0, 2), 6)
(1.0, 0.8)
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..._jit import block
from .._surface_params import PARAM, S_GGX, UNDER_SPECULAR, ggx_reflection, ggx_reflection_pdf, mirrored
from ._common import fixed_sampler, sampler_width, separable_albedo

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

    from .._surface_params import Directions, EvalInputs

NAME = "transmission"
LAYER = UNDER_SPECULAR
constant_albedo, albedo, score = separable_albedo(color=PARAM.TRANS_TINT)
sampler = fixed_sampler(S_GGX)
sample_setup = sampler_width(PARAM.ALPHA_S, side=-1.0)  # mirrored below the surface


@block
def weight_color(p: NDArray[np.float64], offset: int, c: int) -> float:
    return p[offset + PARAM.BASE_MUL + c] * (1.0 - p[offset + PARAM.METAL]) * p[offset + PARAM.TRANS_W]


@block
def is_on(p: NDArray[np.float64], offset: int) -> bool:
    return (1.0 - p[offset + PARAM.METAL]) * p[offset + PARAM.TRANS_W] > 0.0


@block
def eval(p: NDArray[np.float64], offset: int, d: Directions, x: EvalInputs) -> tuple[float, float, float]:
    mt, _ = ggx_reflection(mirrored(d), p[offset + PARAM.ALPHA_S])
    mt = mt / x.e1_specular
    tint = offset + PARAM.TRANS_TINT
    return mt * p[tint], mt * p[tint + 1], mt * p[tint + 2]


@block
def pdf(p: NDArray[np.float64], offset: int, d: Directions, dmodel: int, vndf: bool, ggx_pdf: float) -> float:
    return ggx_reflection_pdf(mirrored(d), p[offset + PARAM.ALPHA_S], vndf)
