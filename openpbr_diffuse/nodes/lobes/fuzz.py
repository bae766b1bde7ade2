"""The fuzz lobe [fuzz_bsdf]: the Zeltner 2022 LTC sheen (``microfacet.sheen``), tint
fuzz_color, roughness fuzz_roughness, weight fuzz_weight, on top of every layer; sampled by
its LTC.

Example
-------
>>> from openpbr_diffuse.nodes import OpenPBRSurface
>>> p = OpenPBRSurface(fuzz_weight=0.5, fuzz_color=(1.0, 0.5, 0.0)).params
>>> round(weight_color(p, 0, 1), 6), bool(is_on(p, 0))
(0.25, True)
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..._jit import block
from ...microfacet.sheen import sheen_density
from ...sampling.ltc import ltc_frame, to_frame
from .._surface_params import ON_TOP, PARAM, S_SHEEN
from ._common import fixed_sampler, on_where_positive, sampler_width, separable_albedo

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

    from .._surface_params import Directions, EvalInputs

NAME = "fuzz"
LAYER = ON_TOP
constant_albedo, albedo, score = separable_albedo(state="fuzz")
sampler = fixed_sampler(S_SHEEN)
is_on = on_where_positive(PARAM.FUZZ_W)
sample_setup = sampler_width(PARAM.FUZZ_R)


@block
def weight_color(p: NDArray[np.float64], offset: int, c: int) -> float:
    return p[offset + PARAM.FUZZ_W] * p[offset + PARAM.FUZZ_COLOR + c]


@block
def eval(p: NDArray[np.float64], offset: int, d: Directions, x: EvalInputs) -> tuple[float, float, float]:
    up = (d.wi_z > 0.0) & (d.wo_z > 0.0)
    Xx, Xy = ltc_frame(d.wo_x, d.wo_y)
    lx, ly = to_frame(Xx, Xy, d.wi_x, d.wi_y)
    v = x.e_fuzz * sheen_density(lx, ly, d.wi_z, d.wo_z, p[offset + PARAM.FUZZ_R]) / d.wi_z
    v = v if up else 0.0
    return v, v, v


@block
def pdf(p: NDArray[np.float64], offset: int, d: Directions, dmodel: int, vndf: bool, ggx_pdf: float) -> float:
    Xx, Xy = ltc_frame(d.wo_x, d.wo_y)
    lx, ly = to_frame(Xx, Xy, d.wi_x, d.wi_y)
    return sheen_density(lx, ly, d.wi_z, d.wo_z, p[offset + PARAM.FUZZ_R])
