"""Formulas more than one lobe reads."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from ..._jit import block
from ...microfacet import kernels as mf
from .._surface_params import PARAM

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray


@block
def norm_or_max(mx: bool, a: float, b: float, c: float) -> float:
    """|(a, b, c)| (RGB length), or its largest component's magnitude when ``mx``."""
    return max(max(abs(a), abs(b)), abs(c)) if mx else math.sqrt(a * a + b * b + c * c)


@block
def metal_albedo(p: NDArray[np.float64], offset: int, c: int, E1: float, E5: float, E6: float, ms: bool) -> float:
    """F82-tint GGX albedo F0 (E1 - E5) + E5 - a E6 (times the multiple-scattering factor)."""
    F0 = p[offset + PARAM.METAL_F0 + c]
    return (F0 * (E1 - E5) + E5 - p[offset + PARAM.METAL_A + c] * E6) * mf.multiscatter(F0, E1, ms)


@block
def unit_albedo(p: NDArray[np.float64], offset: int, c: int) -> float:
    """The colour of a lobe's albedo when the albedo is a scalar (1): its score's constant."""
    return 1.0
