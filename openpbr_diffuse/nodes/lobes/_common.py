"""Formulas more than one lobe reads."""

import math

from ..._jit import block
from ...microfacet import kernels as mf
from .._surface_params import PARAM


@block
def norm_or_max(mx, a, b, c):
    """|(a, b, c)| (RGB length), or its largest component's magnitude when ``mx``."""
    return max(max(abs(a), abs(b)), abs(c)) if mx else math.sqrt(a * a + b * b + c * c)


@block
def metal_albedo(p, offset, c, E1, E5, E6, ms):
    """F82-tint GGX albedo F0 (E1 - E5) + E5 - a E6 (times the multiple-scattering factor)."""
    F0 = p[offset + PARAM.METAL_F0 + c]
    return (F0 * (E1 - E5) + E5 - p[offset + PARAM.METAL_A + c] * E6) * mf.multiscatter(F0, E1, ms)


@block
def unit_albedo(p, offset, c):
    """The colour of a lobe's albedo when the albedo is a scalar (1): its score's constant."""
    return 1.0
