"""Cosine-weighted and uniform hemisphere sampling (EON paper Section 3.1, Eq. 21).

Cosine sampling is Malley's method written with the orientation of Listing 3
(``x = -R cos(phi)``) in the LTC frame of ``wo``: it is the CLTC sampler with M = I, so
the EON sampler at r = 0 (where M = I and P_u = 0) returns the same direction for the
same ``u``.  Uniform sampling is in the local (world) frame, as the uniform branch of
Listing 4.
"""
import math

from ..models._jit import INV_PI, PI, kernel

INV_2PI = 0.5 / math.pi


@kernel
def cosine_sample_local(u1, u2):
    """Return (x, y, z, pdf) of a cosine-weighted direction in the LTC frame; pdf = z/pi."""
    R = math.sqrt(u1)
    phi = 2.0 * PI * u2
    z = math.sqrt(max(0.0, 1.0 - u1))
    return -R * math.cos(phi), R * math.sin(phi), z, z * INV_PI


@kernel
def cosine_pdf(z):
    """Cosine-weighted hemisphere pdf mu_i/pi (Eq. 21)."""
    return max(z, 0.0) * INV_PI


@kernel
def uniform_sample(u1, u2):
    """Return (x, y, z, pdf) of a uniform hemisphere direction: z = u1, phi = 2 pi u2, pdf = 1/(2 pi)."""
    z = u1
    st = math.sqrt(max(0.0, 1.0 - z * z))
    phi = 2.0 * PI * u2
    return st * math.cos(phi), st * math.sin(phi), z, INV_2PI
