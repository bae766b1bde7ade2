"""Cosine-weighted and uniform hemisphere sampling (EON paper Section 3.1, Eq. 21).

Cosine sampling is Malley's method written with the orientation of Listing 3
(``x = -R cos(phi)``) in the LTC frame of ``wo``: it is the CLTC sampler with M = I, so
the EON sampler at r = 0 (where M = I and P_u = 0) returns the same direction for the
same ``u``.  Uniform sampling is in the local (world) frame, as the uniform branch of
Listing 4.
"""

import math

import numpy as np

from .._jit import INV_PI, kernel

INV_2PI = 0.5 / math.pi
#: The largest float64 below 1: the top of the u range [0, 1).
U_MAX = 1.0 - 2.0**-53
_SQRT_HALF = math.sqrt(0.5)


@kernel
def cos_sin_2pi(u: float) -> tuple[float, float]:
    """Return (cos 2 pi u, sin 2 pi u) for u in [0, 1), to a few ulp (absolute).

    Why not ``math.cos``/``math.sin``: a libm call keeps LLVM from vectorising the batch
    loop (see ``openpbr_diffuse/_jit.py``), and in double precision the two calls alone cost about
    40 ns per sample on the 2-core test machine.  This is a few multiply-adds, branch-free,
    and accurate to 5e-16 (tested against long-double cos/sin).
    The angle is reduced exactly in u (quadrant q = floor(4u)) and centred on the
    quadrant's middle, x = (4u - q - 1/2) pi/2 in [-pi/4, pi/4); sin x and cos x come from
    their Taylor series to x^15 and x^16 (truncation < 5e-17 at |x| = pi/4); then
    cos/sin(pi/4 + x) = (cos x -/+ sin x)/sqrt(2), rotated by q quarter turns.
    """
    t = 4.0 * u
    q = np.floor(t)
    x = (t - q - 0.5) * (0.5 * math.pi)
    x2 = x * x
    s = x * (
        1.0
        - x2
        / 6.0
        * (
            1.0
            - x2
            / 20.0
            * (1.0 - x2 / 42.0 * (1.0 - x2 / 72.0 * (1.0 - x2 / 110.0 * (1.0 - x2 / 156.0 * (1.0 - x2 / 210.0)))))
        )
    )
    c = 1.0 - x2 / 2.0 * (
        1.0
        - x2
        / 12.0
        * (
            1.0
            - x2
            / 30.0
            * (1.0 - x2 / 56.0 * (1.0 - x2 / 90.0 * (1.0 - x2 / 132.0 * (1.0 - x2 / 182.0 * (1.0 - x2 / 240.0)))))
        )
    )
    C = (c - s) * _SQRT_HALF
    S = (c + s) * _SQRT_HALF
    # quarter turns q = 1, 2, 3: (-S, C), (-C, -S), (S, -C); selects keep the loop vectorisable
    odd = (q == 1.0) | (q == 3.0)
    cq = -S if odd else C
    sq = C if odd else S
    neg = q >= 2.0
    return (-cq if neg else cq), (-sq if neg else sq)


@kernel
def cosine_sample_local(u1: float, u2: float) -> tuple[float, float, float, float]:
    """Return (x, y, z, pdf) of a cosine-weighted direction in the LTC frame; pdf = z/pi.

    R = sqrt(u1), phi = 2 pi u2, (x, y) = (-R cos phi, R sin phi), z = sqrt(1 - u1).
    """
    R = math.sqrt(u1)
    cp, sp = cos_sin_2pi(u2)
    z = math.sqrt(max(0.0, 1.0 - u1))
    return -R * cp, R * sp, z, z * INV_PI


@kernel
def cosine_pdf(z: float) -> float:
    """Cosine-weighted hemisphere pdf mu_i/pi (Eq. 21)."""
    return max(z, 0.0) * INV_PI


@kernel
def uniform_sample(u1: float, u2: float) -> tuple[float, float, float, float]:
    """Return (x, y, z, pdf) of a uniform hemisphere direction: z = u1, phi = 2 pi u2, pdf = 1/(2 pi)."""
    z = u1
    st = math.sqrt(max(0.0, 1.0 - z * z))
    cp, sp = cos_sin_2pi(u2)
    return st * cp, st * sp, z, INV_2PI
