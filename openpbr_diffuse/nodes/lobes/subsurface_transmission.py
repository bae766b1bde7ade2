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

from ..._jit import INV_PI, block
from ...sampling.simple import cosine_pdf
from .._surface_params import PARAM, S_COSINE, UNDER_SPECULAR

NAME = "subsurface_transmission"
LAYER = UNDER_SPECULAR
READS_DIFFUSE_MODEL = False


@block
def weight_color(p, offset, c):
    solid = p[offset + PARAM.BASE_MUL + c] * (1.0 - p[offset + PARAM.METAL]) * (1.0 - p[offset + PARAM.TRANS_W])
    return solid * p[offset + PARAM.SSS_W] * 0.5 * p[offset + PARAM.SSS_COLOR + c] * (1.0 + p[offset + PARAM.SSS_ANISO])


@block
def constant_albedo(p, offset, c):
    return p[offset + PARAM.SSS_COLOR + c]


@block
def is_on(p, offset):
    dielectric = 1.0 - p[offset + PARAM.METAL]
    return (p[offset + PARAM.THIN] > 0.0) and (
        dielectric * (1.0 - p[offset + PARAM.TRANS_W]) * p[offset + PARAM.SSS_W] > 0.0
    )


@block
def eval(p, offset, d, x):
    g = INV_PI if (d.wi_z < 0.0) & (d.wo_z > 0.0) else 0.0
    color = offset + PARAM.SSS_COLOR
    return p[color] * g, p[color + 1] * g, p[color + 2] * g


@block
def pdf(p, offset, d, dmodel, vndf, ggx_pdf):
    return cosine_pdf(-d.wi_z)


@block
def sampler(dmodel):
    return S_COSINE


@block
def sample_setup(p, offset):
    return 0.0, -1.0


@block
def albedo(c, p, offset, ms, st):
    return p[offset + PARAM.SSS_COLOR + c]


@block
def score(mx, p, offset, weight_at, constant, ms, st):
    return constant
