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
from ...microfacet import kernels as mf
from .._surface_params import PARAM, S_GGX, UNDER_SPECULAR

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

    from .._surface_params import Directions, EvalInputs, LayerState

NAME = "transmission"
LAYER = UNDER_SPECULAR
READS_DIFFUSE_MODEL = False


@block
def weight_color(p: NDArray[np.float64], offset: int, c: int) -> float:
    return p[offset + PARAM.BASE_MUL + c] * (1.0 - p[offset + PARAM.METAL]) * p[offset + PARAM.TRANS_W]


@block
def constant_albedo(p: NDArray[np.float64], offset: int, c: int) -> float:
    return p[offset + PARAM.TRANS_TINT + c]


@block
def is_on(p: NDArray[np.float64], offset: int) -> bool:
    return (1.0 - p[offset + PARAM.METAL]) * p[offset + PARAM.TRANS_W] > 0.0


@block
def eval(p: NDArray[np.float64], offset: int, d: Directions, x: EvalInputs) -> tuple[float, float, float]:
    mt, _ = mf.reflection(d.wi_x, d.wi_y, -d.wi_z, d.wo_x, d.wo_y, d.wo_z, p[offset + PARAM.ALPHA_S])
    mt = mt / x.e1_specular
    tint = offset + PARAM.TRANS_TINT
    return mt * p[tint], mt * p[tint + 1], mt * p[tint + 2]


@block
def pdf(p: NDArray[np.float64], offset: int, d: Directions, dmodel: int, vndf: bool, ggx_pdf: float) -> float:
    return mf.reflection_pdf(d.wi_x, d.wi_y, -d.wi_z, d.wo_x, d.wo_y, d.wo_z, p[offset + PARAM.ALPHA_S], vndf)


@block
def sampler(dmodel: int) -> int:
    return S_GGX


@block
def sample_setup(p: NDArray[np.float64], offset: int) -> tuple[float, float]:
    return p[offset + PARAM.ALPHA_S], -1.0


@block
def albedo(c: int, p: NDArray[np.float64], offset: int, ms: bool, st: LayerState) -> float:
    return p[offset + PARAM.TRANS_TINT + c]


@block
def score(
    mx: bool, p: NDArray[np.float64], offset: int, weight_at: int, constant: float, ms: bool, st: LayerState
) -> float:
    return constant
