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
from .._surface_params import PARAM, S_GGX, UNDER_FUZZ
from ._common import unit_albedo

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

    from .._surface_params import Directions, EvalInputs, LayerState

NAME = "coat"
LAYER = UNDER_FUZZ
READS_DIFFUSE_MODEL = False
constant_albedo = unit_albedo


@block
def weight_color(p: NDArray[np.float64], offset: int, c: int) -> float:
    return p[offset + PARAM.COAT_W]


@block
def is_on(p: NDArray[np.float64], offset: int) -> bool:
    return p[offset + PARAM.COAT_W] > 0.0


@block
def eval(p: NDArray[np.float64], offset: int, d: Directions, x: EvalInputs) -> tuple[float, float, float]:
    mc, cc = mf.reflection(d.wi_x, d.wi_y, d.wi_z, d.wo_x, d.wo_y, d.wo_z, p[offset + PARAM.ALPHA_C])
    ior_x = p[offset + PARAM.X_C]
    v = mc * fresnel.dielectric(cc, p[offset + PARAM.ETA_C]) * mf.multiscatter(ior_x * ior_x, x.e1_coat, x.multiscatter)
    return v, v, v


@block
def pdf(p: NDArray[np.float64], offset: int, d: Directions, dmodel: int, vndf: bool, ggx_pdf: float) -> float:
    return mf.reflection_pdf(d.wi_x, d.wi_y, d.wi_z, d.wo_x, d.wo_y, d.wo_z, p[offset + PARAM.ALPHA_C], vndf)


@block
def sampler(dmodel: int) -> int:
    return S_GGX


@block
def sample_setup(p: NDArray[np.float64], offset: int) -> tuple[float, float]:
    return p[offset + PARAM.ALPHA_C], 1.0


@block
def albedo(c: int, p: NDArray[np.float64], offset: int, ms: bool, st: LayerState) -> float:
    return st.coat


@block
def score(
    mx: bool, p: NDArray[np.float64], offset: int, weight_at: int, constant: float, ms: bool, st: LayerState
) -> float:
    return st.coat * constant
