"""The base specular lobe [dielectric_reflection]: GGX (height-correlated Smith G2, alpha =
r^2) with the exact Fresnel factor of the modulated index (F0 = specular_weight F0(eta_s)),
tint specular_color, under the coat; sampled by GGX (visible normals or the NDF).  Its GGX
reflection without Fresnel and its pdf are computed once a row and shared with the metal
lobe (``EvalInputs.ggx_f``, ``ggx_pdf``).

Example
-------
>>> from openpbr_diffuse.nodes import OpenPBRSurface
>>> p = OpenPBRSurface(specular_color=(0.5, 0.5, 0.5)).params
>>> round(weight_color(p, 0, 1), 6), bool(is_on(p, 0))
(0.5, True)
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..._jit import block
from ...microfacet import fresnel
from ...microfacet import kernels as mf
from .._surface_params import PARAM, S_GGX, UNDER_COAT
from ._common import base_ggx_pdf, fixed_sampler, sampler_width, separable_albedo

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

    from .._surface_params import Directions, EvalInputs

NAME = "specular"
LAYER = UNDER_COAT
constant_albedo, albedo, score = separable_albedo(state="specular")
pdf = base_ggx_pdf
sampler = fixed_sampler(S_GGX)
sample_setup = sampler_width(PARAM.ALPHA_S)


@block
def weight_color(p: NDArray[np.float64], offset: int, c: int) -> float:
    return p[offset + PARAM.BASE_MUL + c] * (1.0 - p[offset + PARAM.METAL]) * p[offset + PARAM.SPEC_COLOR + c]


@block
def is_on(p: NDArray[np.float64], offset: int) -> bool:
    tinted = (
        (p[offset + PARAM.SPEC_COLOR] > 0.0)
        or (p[offset + PARAM.SPEC_COLOR + 1] > 0.0)
        or (p[offset + PARAM.SPEC_COLOR + 2] > 0.0)
    )
    return (1.0 - p[offset + PARAM.METAL] > 0.0) and (p[offset + PARAM.X_S] > 0.0) and tinted


@block
def eval(p: NDArray[np.float64], offset: int, d: Directions, x: EvalInputs) -> tuple[float, float, float]:
    ior_x = p[offset + PARAM.X_S]
    v = (
        x.ggx_f
        * fresnel.dielectric(x.ggx_cos, p[offset + PARAM.ETA_S])
        * mf.multiscatter(ior_x * ior_x, x.e1_specular, x.multiscatter)
    )
    return v, v, v
