"""The metal lobe [metal_bsdf]: GGX with the F82-tint Fresnel factor, F0 = base_weight
base_color, tint specular_color, weight base_metalness specular_weight, under the coat;
it shares the base specular's GGX reflection and pdf (``EvalInputs.ggx_f``, ``ggx_pdf``).
Its albedo is a colour of mu_o, so its score sums over the channels.

Example
-------
>>> from openpbr_diffuse.nodes import OpenPBRSurface
>>> p = OpenPBRSurface(base_metalness=1.0).params
>>> round(weight_color(p, 0, 0), 6), bool(is_on(p, 0))
(1.0, True)
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..._jit import block, opaque
from ...microfacet import fresnel
from ...microfacet import kernels as mf
from .._surface_params import PARAM, S_GGX, UNDER_COAT
from ._common import base_ggx_pdf, fixed_sampler, metal_albedo, norm_or_max, sampler_width, unit_albedo

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

    from .._surface_params import Directions, EvalInputs, LayerState

NAME = "metal"
LAYER = UNDER_COAT
constant_albedo = unit_albedo
pdf = base_ggx_pdf
sampler = fixed_sampler(S_GGX)
sample_setup = sampler_width(PARAM.ALPHA_S)


@block
def weight_color(p: NDArray[np.float64], offset: int, c: int) -> float:
    return p[offset + PARAM.BASE_MUL + c] * p[offset + PARAM.METAL] * p[offset + PARAM.SPEC_WEIGHT]


@block
def is_on(p: NDArray[np.float64], offset: int) -> bool:
    return (p[offset + PARAM.METAL] > 0.0) and (p[offset + PARAM.SPEC_WEIGHT] > 0.0)


@block
def eval(p: NDArray[np.float64], offset: int, d: Directions, x: EvalInputs) -> tuple[float, float, float]:
    F0r, F0g, F0b = p[offset + PARAM.METAL_F0], p[offset + PARAM.METAL_F0 + 1], p[offset + PARAM.METAL_F0 + 2]
    m, c, E1, ms = x.ggx_f, x.ggx_cos, x.e1_specular, x.multiscatter
    return (
        m * fresnel.f82(c, F0r, p[offset + PARAM.METAL_A]) * mf.multiscatter(F0r, E1, ms),
        m * fresnel.f82(c, F0g, p[offset + PARAM.METAL_A + 1]) * mf.multiscatter(F0g, E1, ms),
        m * fresnel.f82(c, F0b, p[offset + PARAM.METAL_A + 2]) * mf.multiscatter(F0b, E1, ms),
    )


@block
def albedo(c: int, p: NDArray[np.float64], offset: int, ms: bool, st: LayerState) -> float:
    return metal_albedo(p, offset, c, st.e1_specular, st.e5_specular, st.e6_specular, ms)


@block
def score(
    mx: bool, p: NDArray[np.float64], offset: int, weight_at: int, constant: float, ms: bool, st: LayerState
) -> float:
    E1, E5, E6 = st.e1_specular, st.e5_specular, st.e6_specular
    m0 = p[weight_at] * metal_albedo(p, offset, opaque(0), E1, E5, E6, ms)
    m1 = p[weight_at + 1] * metal_albedo(p, offset, opaque(1), E1, E5, E6, ms)
    m2 = p[weight_at + 2] * metal_albedo(p, offset, opaque(2), E1, E5, E6, ms)
    return norm_or_max(True, m0, m1, m2) if mx else norm_or_max(False, m0, m1, m2)
