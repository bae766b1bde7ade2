"""The coat lobe [coat_bsdf]: GGX dielectric reflection with coat_ior and coat_roughness,
weight coat_weight, under the fuzz; GGX sampled.

Example
-------
>>> from openpbr_diffuse.nodes import OpenPBRSurface
>>> p = OpenPBRSurface(coat_weight=0.5).params
>>> round(weight_color(p, 0, 0), 6), bool(is_on(p, 0))
(0.5, True)
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..._jit import block
from ...microfacet import fresnel
from ...microfacet import kernels as mf
from .._surface_params import PARAM, S_GGX, UNDER_FUZZ, ggx_reflection, ggx_reflection_pdf
from ._common import fixed_sampler, on_where_positive, sampler_width, separable_albedo

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

    from .._surface_params import Directions, EvalInputs

NAME = "coat"
LAYER = UNDER_FUZZ
constant_albedo, albedo, score = separable_albedo(state="coat")
sampler = fixed_sampler(S_GGX)
is_on = on_where_positive(PARAM.COAT_W)
sample_setup = sampler_width(PARAM.ALPHA_C)


@block
def weight_color(p: NDArray[np.float64], offset: int, c: int) -> float:
    return p[offset + PARAM.COAT_W]


@block
def eval(p: NDArray[np.float64], offset: int, d: Directions, x: EvalInputs) -> tuple[float, float, float]:
    mc, cc = ggx_reflection(d, p[offset + PARAM.ALPHA_C])
    ior_x = p[offset + PARAM.X_C]
    v = mc * fresnel.dielectric(cc, p[offset + PARAM.ETA_C]) * mf.multiscatter(ior_x * ior_x, x.e1_coat, x.multiscatter)
    return v, v, v


@block
def pdf(p: NDArray[np.float64], offset: int, d: Directions, dmodel: int, vndf: bool, ggx_pdf: float) -> float:
    return ggx_reflection_pdf(d, p[offset + PARAM.ALPHA_C], vndf)
