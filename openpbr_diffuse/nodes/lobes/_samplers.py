"""The samplers the lobes share (a lobe names its own by ``sampler``), one function per
sampler with one signature, indexed by the sampler ids of ``_surface_params`` (S_EON,
S_COSINE, S_GGX, S_SHEEN).  The sample pass of a block gathers the rows whose chosen lobes
share a sampler and runs that sampler over them, so that its loop vectorises; the lobe only
sets the sampler's width (``sample_setup``: its GGX alpha, its roughness) and the side of
the surface.

The hemisphere samplers never return z = 0: as in ``sampling`` (``sample``), |z| is floored
at ``Z_MIN``, which only rounding reaches (a CLTC direction on the clipped boundary), so
that the sample lies in its lobe and its pdf is the lobe's pdf there.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..._jit import block
from ...microfacet import kernels as mf
from ...microfacet.sheen import sheen_sample
from ...sampling.ltc import from_frame, ltc_frame
from ...sampling.mis import eon_sample
from ...sampling.simple import cosine_sample_local
from .._surface_params import PARAM, Z_MIN

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray


@block
def _in_frame(ox: float, oy: float, lx: float, ly: float, z: float) -> tuple[float, float, float, bool]:
    """A direction (lx, ly, z) of wo's azimuthal frame (``sampling.ltc``) as a sample (x, y,
    z, ok) of the local frame, z floored at ``Z_MIN``."""
    Xx, Xy = ltc_frame(ox, oy)
    x, y = from_frame(Xx, Xy, lx, ly)
    return x, y, max(z, Z_MIN), True


@block
def eon(
    p: NDArray[np.float64], offset: int, ox: float, oy: float, oz: float, u1: float, u2: float, vndf: bool, width: float
) -> tuple[float, float, float, bool]:
    """The EON sampler (EON paper Listing 4) at r = width."""
    mu = min(max(oz, 0.0), 1.0)
    Xx, Xy = ltc_frame(ox, oy)
    x, y, z, _ = eon_sample(Xx, Xy, mu, width, p[offset + PARAM.R_TENTH], u1, u2)
    return x, y, max(z, Z_MIN), True


@block
def cosine(
    p: NDArray[np.float64], offset: int, ox: float, oy: float, oz: float, u1: float, u2: float, vndf: bool, width: float
) -> tuple[float, float, float, bool]:
    lx, ly, z, _ = cosine_sample_local(u1, u2)
    return _in_frame(ox, oy, lx, ly, z)


@block
def ggx(
    p: NDArray[np.float64], offset: int, ox: float, oy: float, oz: float, u1: float, u2: float, vndf: bool, width: float
) -> tuple[float, float, float, bool]:
    """GGX at alpha = width: visible normals (Heitz 2018) or the NDF; fails (ok False) when
    an NDF normal faces away from wo."""
    return mf.sample_reflection(ox, oy, oz, width, u1, u2, vndf)


@block
def sheen(
    p: NDArray[np.float64], offset: int, ox: float, oy: float, oz: float, u1: float, u2: float, vndf: bool, width: float
) -> tuple[float, float, float, bool]:
    """The LTC sheen's sampler at fuzz roughness = width."""
    lx, ly, z = sheen_sample(min(max(oz, 0.0), 1.0), width, u1, u2)
    return _in_frame(ox, oy, lx, ly, z)


#: the samplers, by sampler id
SAMPLERS = (eon, cosine, ggx, sheen)
#: the samplers that branch on ``specular_sampling`` (their pass is compiled once for each)
BRANCHES_ON_VNDF = (False, False, True, False)
