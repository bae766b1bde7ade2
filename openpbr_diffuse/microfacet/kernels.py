"""Scalar compiled forms of the GGX lobe for the surface's batch drivers.

The same model as ``ggx`` (the NumPy form used by the table generation and the tests),
written per direction pair for numba (the Fresnel factors are ``fresnel``'s kernels): local frame, normal +z,
``wo``/``wi`` pointing away from the surface, alpha the GGX width.  ``tests/test_ggx.py``
checks these against the NumPy forms and both against quadrature.

- D(h) = alpha^2 / (pi (mu_h^2 (alpha^2 - 1) + 1)^2)                    (Walter 2007 Eq. 33)
- Lambda(mu) = (sqrt(1 + alpha^2 (1 - mu^2)/mu^2) - 1)/2, G2 = 1/(1 + Lambda_i + Lambda_o)
- f = F(wo.h) D G2 / (4 mu_i mu_o); visible-normal sampling (Heitz 2018, Listing 1) with
  pdf G1(wo) D / (4 mu_o), or NDF sampling with pdf D mu_h / (4 wo.h).
"""
import math

from .._jit import INV_PI, kernel
from ..sampling.simple import cos_sin_2pi
from .ggx import ALPHA_MIN


@kernel
def alpha_of(roughness):
    """GGX alpha = max(roughness^2, ALPHA_MIN) (OpenPBR's perceptual mapping; ``ggx.alpha_of``)."""
    return max(roughness * roughness, ALPHA_MIN)


@kernel
def ndf(mu_h, alpha):
    """GGX D(h) for mu_h = h.z (0 for mu_h <= 0)."""
    a2 = alpha * alpha
    d = mu_h * mu_h * (a2 - 1.0) + 1.0
    return a2 * INV_PI / (d * d) if mu_h > 0.0 else 0.0


@kernel
def smith_lambda(mu, alpha):
    """Smith Lambda of GGX for mu > 0."""
    mu2 = mu * mu
    return 0.5 * (math.sqrt(1.0 + alpha * alpha * (1.0 - mu2) / mu2) - 1.0)


@kernel
def reflection(ix, iy, iz, ox, oy, oz, alpha):
    """(D G2 / (4 mu_i mu_o), wo.h): the GGX BRDF without its Fresnel factor, and the cosine
    for the Fresnel factor; 0 unless both directions and the half vector are above the horizon."""
    hx, hy, hz = ix + ox, iy + oy, iz + oz
    n2 = hx * hx + hy * hy + hz * hz
    if not (iz > 0.0 and oz > 0.0 and n2 > 0.0):
        return 0.0, 0.0
    inv = 1.0 / math.sqrt(n2)
    mu_h = hz * inv
    c = min(max((ox * hx + oy * hy + oz * hz) * inv, 0.0), 1.0)
    g2 = 1.0 / (1.0 + smith_lambda(iz, alpha) + smith_lambda(oz, alpha))
    return ndf(mu_h, alpha) * g2 / (4.0 * iz * oz), c


@kernel
def reflection_pdf(ix, iy, iz, ox, oy, oz, alpha, vndf):
    """Solid-angle pdf of the reflected direction wi (whole sphere) given wo; 0 if mu_o <= 0
    or the half vector is below the horizon or faces away from wo."""
    hx, hy, hz = ix + ox, iy + oy, iz + oz
    n2 = hx * hx + hy * hy + hz * hz
    if not (oz > 0.0 and n2 > 0.0):
        return 0.0
    inv = 1.0 / math.sqrt(n2)
    mu_h = hz * inv
    c = (ox * hx + oy * hy + oz * hz) * inv
    if not (mu_h > 0.0 and c > 0.0):
        return 0.0
    D = ndf(mu_h, alpha)
    if vndf:
        return D / ((1.0 + smith_lambda(oz, alpha)) * 4.0 * oz)
    return D * mu_h / (4.0 * c)


@kernel
def ggx_visible_normal(vx, vy, vz, alpha, u1, u2):
    """A GGX microfacet normal h drawn from the visible normals D_v(h) ~ <v, h>_+ D(h) of the
    unit direction v, from (u1, u2) in [0, 1)^2 (Heitz 2018, "Sampling the GGX distribution
    of visible normals", Listing 1): stretch v to alpha = 1, sample the projected
    hemisphere, unstretch.  Exact for v below the horizon too (the microsurface walks of
    ``simulation.smith`` use that)."""
    sx, sy, sz = alpha * vx, alpha * vy, vz
    inv = 1.0 / math.sqrt(sx * sx + sy * sy + sz * sz)
    sx, sy, sz = sx * inv, sy * inv, sz * inv
    lensq = sx * sx + sy * sy
    if lensq > 0.0:
        il = 1.0 / math.sqrt(lensq)
        t1x, t1y, t1z = -sy * il, sx * il, 0.0
    else:
        t1x, t1y, t1z = 1.0, 0.0, 0.0
    t2x, t2y, t2z = sy * t1z - sz * t1y, sz * t1x - sx * t1z, sx * t1y - sy * t1x
    r = math.sqrt(u1)
    cp, sp = cos_sin_2pi(u2)
    p1 = r * cp
    p2 = r * sp
    s = 0.5 * (1.0 + sz)
    p2 = (1.0 - s) * math.sqrt(max(0.0, 1.0 - p1 * p1)) + s * p2
    p3 = math.sqrt(max(0.0, 1.0 - p1 * p1 - p2 * p2))
    nx = p1 * t1x + p2 * t2x + p3 * sx
    ny = p1 * t1y + p2 * t2y + p3 * sy
    nz = p1 * t1z + p2 * t2z + p3 * sz
    hx, hy, hz = alpha * nx, alpha * ny, max(0.0, nz)
    inv = 1.0 / math.sqrt(hx * hx + hy * hy + hz * hz)
    return hx * inv, hy * inv, hz * inv


@kernel
def sample_reflection(ox, oy, oz, alpha, u1, u2, vndf):
    """(wi.x, wi.y, wi.z, ok): wi = reflect(wo, h), h from the visible normals (Heitz 2018,
    Listing 1) or the NDF (Walter 2007 Eq. 35-36).  ok is False when the sample fails
    (NDF: h facing away from wo); wi may lie below the horizon (f = 0 there)."""
    if vndf:
        hx, hy, hz = ggx_visible_normal(ox, oy, oz, alpha, u1, u2)
    else:
        a2 = alpha * alpha
        cos2 = (1.0 - u1) / (1.0 + (a2 - 1.0) * u1)
        ct = math.sqrt(cos2)
        st = math.sqrt(max(0.0, 1.0 - cos2))
        cp, sp = cos_sin_2pi(u2)
        hx, hy, hz = st * cp, st * sp, ct
    d = ox * hx + oy * hy + oz * hz
    x, y, z = 2.0 * d * hx - ox, 2.0 * d * hy - oy, 2.0 * d * hz - oz
    inv = 1.0 / math.sqrt(x * x + y * y + z * z)
    return x * inv, y * inv, z * inv, d > 0.0


@kernel
def multiscatter(F0, E1, on):
    """Turquin 2019 factor 1 + F0 (1 - E1)/E1 (1 when ``on`` is False)."""
    return 1.0 + F0 * (1.0 - E1) / E1 if on else 1.0
