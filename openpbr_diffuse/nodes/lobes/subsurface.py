"""The subsurface lobe [subsurface_bsdf], *approximated* as a Lambertian reflection of albedo
subsurface_color; when thin-walled [subsurface_thin_walled], the reflection half of the
reference graph's 0.5/0.5 mix: a QON reflection (sigma = base_diffuse_roughness) weighted
subsurface_color (1 - g) / 2 (its translucent half is ``subsurface_transmission``).  Cosine
sampled.

Example
-------
>>> from openpbr_diffuse.nodes import OpenPBRSurface
>>> p = OpenPBRSurface(subsurface_weight=1.0, subsurface_color=(0.5, 0.5, 0.5)).params
>>> round(weight_color(p, 0, 0), 6), round(constant_albedo(p, 0, 0), 6)  # Lambertian, not thin
(1.0, 0.5)
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..._jit import INV_PI, block
from ...models.qon import qon_terms
from ...sampling.simple import cosine_pdf
from .._surface_params import PARAM, S_COSINE, UNDER_SPECULAR
from ._common import fixed_sampler, sampler_width, separable_albedo

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

    from .._surface_params import Directions, EvalInputs

NAME = "subsurface"
LAYER = UNDER_SPECULAR
#: Lambertian albedo subsurface_color, times the QON albedo when thin-walled
constant_albedo, albedo, score = separable_albedo(color=PARAM.SSS_COLOR, state="thin_reflection")
sampler = fixed_sampler(S_COSINE)
sample_setup = sampler_width(-1)


@block
def weight_color(p: NDArray[np.float64], offset: int, c: int) -> float:
    solid = p[offset + PARAM.BASE_MUL + c] * (1.0 - p[offset + PARAM.METAL]) * (1.0 - p[offset + PARAM.TRANS_W])
    S, g = p[offset + PARAM.SSS_W], p[offset + PARAM.SSS_ANISO]
    thin = p[offset + PARAM.THIN] > 0.0
    return solid * S * 0.5 * p[offset + PARAM.SSS_COLOR + c] * (1.0 - g) if thin else solid * S


@block
def is_on(p: NDArray[np.float64], offset: int) -> bool:
    return (1.0 - p[offset + PARAM.METAL]) * (1.0 - p[offset + PARAM.TRANS_W]) * p[offset + PARAM.SSS_W] > 0.0


@block
def eval(p: NDArray[np.float64], offset: int, d: Directions, x: EvalInputs) -> tuple[float, float, float]:
    up = (d.wi_z > 0.0) & (d.wo_z > 0.0)
    s = d.wi_x * d.wo_x + d.wi_y * d.wo_y + d.wi_z * d.wo_z - d.wi_z * d.wo_z
    qon = qon_terms(d.wi_z, d.wo_z, s, p[offset + PARAM.QON_AB], p[offset + PARAM.QON_AB + 1])
    thin = p[offset + PARAM.THIN] > 0.0
    g = qon if thin else INV_PI
    g = g if up else 0.0
    color = offset + PARAM.SSS_COLOR
    return p[color] * g, p[color + 1] * g, p[color + 2] * g


@block
def pdf(p: NDArray[np.float64], offset: int, d: Directions, dmodel: int, vndf: bool, ggx_pdf: float) -> float:
    density = cosine_pdf(d.wi_z)
    return density if d.wi_z > 0.0 else 0.0
