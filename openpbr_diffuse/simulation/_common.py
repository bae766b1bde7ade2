"""Pieces shared by both microgeometries: sampling, and per-path tallies.

Conventions of the whole sub-package: local macro frame with the normal +z; ``wi`` (towards
the light) and ``wo`` (towards the viewer) point away from the surface.  A path starts as
light arriving from ``wi``; ``k`` counts its scattering events (bounces) on Lambertian
microfacets of albedo rho, so after ``k`` bounces it carries rho**k per channel (the
geometry of a path does not depend on rho: every channel shares the same paths).

Random numbers come from numba's generator (Mersenne Twister, state per thread), seeded at
the start of each chunk with a 32-bit key derived from (seed, stream, chunk): a chunk's
result depends only on that key, never on which worker or thread ran it.
"""

import math

import numpy as np

from .._jit import walk, walk_step

PI = math.pi
INV_PI = 1.0 / math.pi
HALF_PI = 0.5 * math.pi

#: Bounce-order classes: orders 1, 2 and >= 3.
N_ORDERS = 3


@walk_step
def order_class(k):
    """Index of the order class of the k-th bounce (k >= 1): 0, 1 or 2 (k >= 3)."""
    return min(k, N_ORDERS) - 1


@walk_step
def onb(nx, ny, nz):
    """Orthonormal tangents (t, b) of the unit normal n (Duff et al. 2017, branchless)."""
    sign = 1.0 if nz >= 0.0 else -1.0
    a = -1.0 / (sign + nz)
    b = nx * ny * a
    return (1.0 + sign * nx * nx * a, sign * b, -sign * nx, b, sign + ny * ny * a, -ny)


@walk_step
def cosine_about(nx, ny, nz):
    """A direction drawn with density cos(theta)/pi about the unit normal n."""
    u1 = np.random.random()
    u2 = np.random.random()
    r = math.sqrt(u1)
    phi = 2.0 * PI * u2
    x = r * math.cos(phi)
    y = r * math.sin(phi)
    z = math.sqrt(max(0.0, 1.0 - u1))
    tx, ty, tz, bx, by, bz = onb(nx, ny, nz)
    return (x * tx + y * bx + z * nx, x * ty + y * by + z * ny, x * tz + y * bz + z * nz)


@walk_step
def cosine_hemisphere():
    """A direction above the macro surface with density mu/pi (cosine-weighted)."""
    return cosine_about(0.0, 0.0, 1.0)


@walk
def tally_path(k, escaped, rho, path_nee, alb_s1, alb_s2, nee_s1, nee_s2):
    """Add one finished path to the chunk sums.

    Albedo: the path's value in channel c is rho_c**k if it escaped after k bounces, in the
    class of k only.  A path cut at the bounce limit scores rho_c**k as well (k = limit + 1):
    it would leave later (nothing is absorbed at rho = 1 in an open cavity or in the Smith
    walk), so this is exact at rho = 1 and too high by less than rho**k otherwise; the classes are disjoint, so the
    total's second moment is the sum of the classes'.  BRDF: ``path_nee[j, q, c]`` holds the
    path's next-event sum towards wo_j from bounces of class q; it is reset here.
    """
    C = rho.shape[0]
    q = order_class(k)
    for c in range(C):
        v = rho[c] ** k
        alb_s1[q, c] += v
        alb_s2[q, c] += v * v
    m = path_nee.shape[0]
    for j in range(m):
        for c in range(C):
            tot = 0.0
            for q in range(N_ORDERS):
                v = path_nee[j, q, c]
                nee_s1[j, q, c] += v
                nee_s2[j, q, c] += v * v
                tot += v
                path_nee[j, q, c] = 0.0
            nee_s1[j, N_ORDERS, c] += tot
            nee_s2[j, N_ORDERS, c] += tot * tot
