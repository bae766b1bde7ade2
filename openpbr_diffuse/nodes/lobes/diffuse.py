"""The diffuse lobe [diffuse_bsdf]: EON with rho = base_color, r = base_diffuse_roughness (or
QON, Lambert: ``diffuse_model``), under the dielectric specular layer, weighted
base_weight (1 - subsurface_weight) of the solid dielectric base; sampled by the EON sampler
(EON paper Listing 4) or, for QON and Lambert, by cosine sampling.

Its albedo is rho e_g + rho_ms e_h (EON Eq. 20; e_h = 0 for QON and Lambert), the same form
for every model, so its selection score is a quadratic in (e_g, e_h) whose coefficients are
constants of the material (PARAM.DIFFUSE_SCORE).

Example
-------
>>> from openpbr_diffuse.nodes import OpenPBRSurface
>>> p = OpenPBRSurface(base_color=(0.5, 0.5, 0.5), specular_weight=0.0).params
>>> round(weight_color(p, 0, 0), 6), bool(is_on(p, 0))  # the whole base: weight 1
(1.0, True)
>>> from openpbr_diffuse.nodes._surface_params import D_LAMBERT, Directions, EvalInputs
>>> f = eval(p, 0, Directions(0.0, 0.0, 1.0, 0.0, 0.0, 1.0), EvalInputs(D_LAMBERT, True, 0.0, 0.0, 1.0, 1.0, 0.0))
>>> round(f[0] * 3.141592653589793, 12)  # Lambert: rho / pi
0.5
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from ..._jit import INV_PI, block
from ...models.eon import eon_terms
from ...models.qon import qon_terms
from ...sampling.ltc import ltc_frame, to_frame
from ...sampling.mis import eon_pdf
from ...sampling.simple import cosine_pdf
from .._surface_params import D_EON, D_QON, PARAM, S_COSINE, S_EON, UNDER_SPECULAR
from ._common import norm_or_max, sampler_width

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

    from .._surface_params import Directions, EvalInputs, LayerState

NAME = "diffuse"
LAYER = UNDER_SPECULAR
READS_DIFFUSE_MODEL = True  # its pass is compiled once per diffuse model
#: the EON sampler reads r = base_diffuse_roughness
sample_setup = sampler_width(PARAM.R_DIFF)


@block
def weight_color(p: NDArray[np.float64], offset: int, c: int) -> float:
    """K[c], the material part of the weight: the coat's factor, times dielectric, opaque,
    not subsurface, base_weight."""
    base = p[offset + PARAM.BASE_MUL + c] * (1.0 - p[offset + PARAM.METAL])
    solid = base * (1.0 - p[offset + PARAM.TRANS_W])
    return solid * (1.0 - p[offset + PARAM.SSS_W]) * p[offset + PARAM.BASE_WEIGHT]


@block
def constant_albedo(p: NDArray[np.float64], offset: int, c: int) -> float:
    return 1.0  # unused: the score is the quadratic of PARAM.DIFFUSE_SCORE


@block
def is_on(p: NDArray[np.float64], offset: int) -> bool:
    dielectric = 1.0 - p[offset + PARAM.METAL]
    return (
        dielectric * (1.0 - p[offset + PARAM.TRANS_W]) * (1.0 - p[offset + PARAM.SSS_W]) * p[offset + PARAM.BASE_WEIGHT]
        > 0.0
    )


@block
def diffuse_gh(dmodel: int, p: NDArray[np.float64], offset: int, iz: float, oz: float, s: float) -> tuple[float, float]:
    """(g, h) of the BSDF f = rho g + rho_ms h, channel-free: EON Eq. 16-19, QON Eq. 1 (the
    material's A, B: PARAM.QON_AB) or Lambert (h = 0 for both)."""
    if dmodel == D_EON:
        g, h, _ = eon_terms(iz, oz, s, p[offset + PARAM.R_DIFF], False)
        return g, h
    if dmodel == D_QON:
        return qon_terms(iz, oz, s, p[offset + PARAM.QON_AB], p[offset + PARAM.QON_AB + 1]), 0.0
    return INV_PI, 0.0


@block
def eval(p: NDArray[np.float64], offset: int, d: Directions, x: EvalInputs) -> tuple[float, float, float]:
    up = (d.wi_z > 0.0) & (d.wo_z > 0.0)
    s = d.wi_x * d.wo_x + d.wi_y * d.wo_y + d.wi_z * d.wo_z - d.wi_z * d.wo_z
    g, h = diffuse_gh(x.dmodel, p, offset, d.wi_z, d.wo_z, s)
    g = g if up else 0.0
    h = h if up else 0.0
    return (
        p[offset + PARAM.BASE_COLOR] * g + p[offset + PARAM.RHO_MS] * h,
        p[offset + PARAM.BASE_COLOR + 1] * g + p[offset + PARAM.RHO_MS + 1] * h,
        p[offset + PARAM.BASE_COLOR + 2] * g + p[offset + PARAM.RHO_MS + 2] * h,
    )


@block
def pdf(p: NDArray[np.float64], offset: int, d: Directions, dmodel: int, vndf: bool, ggx_pdf: float) -> float:
    if dmodel == D_EON:
        Xx, Xy = ltc_frame(d.wo_x, d.wo_y)
        lx, ly = to_frame(Xx, Xy, d.wi_x, d.wi_y)
        density = eon_pdf(lx, ly, d.wi_z, min(d.wo_z, 1.0), p[offset + PARAM.R_DIFF], p[offset + PARAM.R_TENTH])
    else:
        density = cosine_pdf(d.wi_z)
    return density if d.wi_z > 0.0 else 0.0  # a select: no branch on the direction


@block
def sampler(dmodel: int) -> int:
    return S_EON if dmodel == D_EON else S_COSINE


@block
def diffuse_albedo(rho: float, rho_ms: float, eg: float, eh: float) -> float:
    """One channel of the albedo rho e_g + rho_ms e_h (e_h = 0 for QON and Lambert)."""
    return rho * eg + rho_ms * eh


@block
def albedo(c: int, p: NDArray[np.float64], offset: int, ms: bool, st: LayerState) -> float:
    return diffuse_albedo(p[offset + PARAM.BASE_COLOR + c], p[offset + PARAM.RHO_MS + c], st.diffuse_g, st.diffuse_h)


@block
def score(
    mx: bool, p: NDArray[np.float64], offset: int, weight_at: int, constant: float, ms: bool, st: LayerState
) -> float:
    """|K E|: by length sqrt(|K rho|^2 e_g^2 + 2 (K rho).(K rho_ms) e_g e_h + |K rho_ms|^2
    e_h^2) from the material's constants; by max over the three channels."""
    eg, eh = st.diffuse_g, st.diffuse_h
    d0 = p[weight_at] * diffuse_albedo(p[offset + PARAM.BASE_COLOR], p[offset + PARAM.RHO_MS], eg, eh)
    d1 = p[weight_at + 1] * diffuse_albedo(p[offset + PARAM.BASE_COLOR + 1], p[offset + PARAM.RHO_MS + 1], eg, eh)
    d2 = p[weight_at + 2] * diffuse_albedo(p[offset + PARAM.BASE_COLOR + 2], p[offset + PARAM.RHO_MS + 2], eg, eh)
    q2 = (
        p[offset + PARAM.DIFFUSE_SCORE] * eg * eg
        + 2.0 * p[offset + PARAM.DIFFUSE_SCORE + 1] * eg * eh
        + p[offset + PARAM.DIFFUSE_SCORE + 2] * eh * eh
    )
    return norm_or_max(True, d0, d1, d2) if mx else math.sqrt(max(q2, 0.0))
