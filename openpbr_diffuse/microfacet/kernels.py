"""Scalar compiled forms of the GGX lobe for the surface's batch drivers.

The same model as ``ggx`` (the NumPy form used by the table generation and the tests),
written per direction pair for numba (the Fresnel factors are ``fresnel``'s kernels): local frame, normal +z,
``wo``/``wi`` pointing away from the surface, alpha the GGX width.  ``tests/test_ggx.py``
checks these against the NumPy forms and both against quadrature.

- D(h) = alpha^2 / (pi (mu_h^2 (alpha^2 - 1) + 1)^2)                    (Walter 2007 Eq. 33)
- Lambda(mu) = (sqrt(1 + alpha^2 (1 - mu^2)/mu^2) - 1)/2, G2 = 1/(1 + Lambda_i + Lambda_o)
- f = F(wo.h) D G2 / (4 mu_i mu_o); visible-normal sampling (Heitz 2018, Listing 1) with
  pdf G1(wo) D / (4 mu_o), or NDF sampling with pdf D mu_h / (4 wo.h).

The kernels write these with the fewest divisions and square roots (they bound the
per-row cost of the surface's drivers, which are not vectorised): D of an unnormalised half
vector (``ndf_fraction``), Lambda as mu (1 + 2 Lambda) = sqrt(mu^2 + alpha^2 (1 - mu^2))
(``lambda_root``), and each verb's factors folded into one division.  ``ggx`` (NumPy, the
textbook forms) is the independent check.
"""

from __future__ import annotations

import math

from .._jit import INV_PI, kernel
from ..sampling.simple import cos_sin_2pi
from .ggx import ALPHA_MIN


@kernel
def alpha_of(roughness: float) -> float:
    """GGX alpha = max(roughness^2, ALPHA_MIN) (OpenPBR's perceptual mapping; ``ggx.alpha_of``)."""
    return max(roughness * roughness, ALPHA_MIN)


@kernel
def ndf_fraction(hx: float, hy: float, hz: float, a2: float) -> tuple[float, float]:
    """(num, den) with the GGX D(h) = num / den for the half vector h = (hx, hy, hz) of any
    length, hz > 0, alpha^2 = a2; callers fold den into their one division.

    D = a2 / (pi (mu_h^2 (a2 - 1) + 1)^2) with mu_h = hz/|h| is, multiplied out by |h|^4,
    a2 |h|^4 / (pi (hx^2 + hy^2 + a2 hz^2)^2): h needs no normalising, and the denominator
    has no cancellation when h is near the normal and alpha is small."""
    n2 = hx * hx + hy * hy + hz * hz
    dd = hx * hx + hy * hy + a2 * hz * hz
    return a2 * INV_PI * (n2 * n2), dd * dd


@kernel
def lambda_root(mu: float, a2: float) -> float:
    """sqrt(mu^2 + a2 (1 - mu^2)) = mu (1 + 2 Lambda(mu)) for mu > 0: Smith's Lambda without
    its division by mu."""
    return math.sqrt(mu * mu + a2 * (1.0 - mu * mu))


@kernel
def reflection(ix: float, iy: float, iz: float, ox: float, oy: float, oz: float, alpha: float) -> tuple[float, float]:
    """(D G2 / (4 mu_i mu_o), wo.h): the GGX BRDF without its Fresnel factor, and the cosine
    for the Fresnel factor; 0 unless both directions and the half vector are above the horizon.

    With the height-correlated G2 = 1/(1 + Lambda_i + Lambda_o) and mu (1 + 2 Lambda(mu))
    = ``lambda_root``, G2 / (4 mu_i mu_o) = 1 / (2 (mu_o root_i + mu_i root_o))."""
    hx, hy, hz = ix + ox, iy + oy, iz + oz
    n2 = hx * hx + hy * hy + hz * hz
    a2 = alpha * alpha
    c = min(max((ox * hx + oy * hy + oz * hz) / math.sqrt(n2), 0.0), 1.0)
    num, den = ndf_fraction(hx, hy, hz, a2)
    f = num / (den * 2.0 * (oz * lambda_root(iz, a2) + iz * lambda_root(oz, a2)))
    ok = (iz > 0.0) & (oz > 0.0) & (n2 > 0.0)  # selects: the rows' loop stays vectorisable
    return (f if ok else 0.0), (c if ok else 0.0)


@kernel
def reflection_pdf(ix: float, iy: float, iz: float, ox: float, oy: float, oz: float, alpha: float, vndf: bool) -> float:
    """Solid-angle pdf of the reflected direction wi (whole sphere) given wo; 0 if mu_o <= 0
    or the half vector is below the horizon or faces away from wo.

    VNDF: G1(wo) D / (4 mu_o) = D / (2 (mu_o + root_o)) (``lambda_root``); NDF: D mu_h /
    (4 wo.h) = D h.z / (4 wo.(h |h|)), h unnormalised: one division, no square root but
    Lambda's."""
    hx, hy, hz = ix + ox, iy + oy, iz + oz
    oh = ox * hx + oy * hy + oz * hz
    a2 = alpha * alpha
    num, den = ndf_fraction(hx, hy, hz, a2)
    q = num / (den * 2.0 * (oz + lambda_root(oz, a2))) if vndf else num * hz / (den * 4.0 * oh)
    ok = (oz > 0.0) & (hz > 0.0) & (oh > 0.0)  # selects: the rows' loop stays vectorisable
    return q if ok else 0.0


@kernel
def ggx_visible_normal_h(
    vx: float, vy: float, vz: float, alpha: float, u1: float, u2: float
) -> tuple[float, float, float, float]:
    """(hx, hy, hz, |h|^2): the microfacet normal of ``ggx_visible_normal`` before its final
    normalisation (a caller that reflects about it divides by |h|^2 instead)."""
    sx, sy, sz = alpha * vx, alpha * vy, vz
    inv = 1.0 / math.sqrt(sx * sx + sy * sy + sz * sz)
    sx, sy, sz = sx * inv, sy * inv, sz * inv
    # T1 = (-s.y, s.x, 0)/|s.xy| = (-v.y, v.x, 0)/|v.xy|: from v, so that its square root
    # and division run beside the stretch's, not after them
    lensq = vx * vx + vy * vy
    il = 1.0 / math.sqrt(lensq)  # inf at the normal, not selected there
    side = lensq > 0.0
    t1x, t1y, t1z = (-vy * il if side else 1.0), (vx * il if side else 0.0), 0.0
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
    return hx, hy, hz, hx * hx + hy * hy + hz * hz


@kernel
def ggx_visible_normal(
    vx: float, vy: float, vz: float, alpha: float, u1: float, u2: float
) -> tuple[float, float, float]:
    """A GGX microfacet normal h drawn from the visible normals D_v(h) ~ <v, h>_+ D(h) of the
    unit direction v, from (u1, u2) in [0, 1)^2 (Heitz 2018, "Sampling the GGX distribution
    of visible normals", Listing 1): stretch v to alpha = 1, sample the projected
    hemisphere, unstretch.  Exact for v below the horizon too (the microsurface walks of
    ``simulation.smith`` use that)."""
    hx, hy, hz, n2 = ggx_visible_normal_h(vx, vy, vz, alpha, u1, u2)
    inv = 1.0 / math.sqrt(n2)
    return hx * inv, hy * inv, hz * inv


@kernel
def ggx_normal(alpha: float, u1: float, u2: float) -> tuple[float, float, float, float]:
    """(hx, hy, hz, 1): a microfacet normal drawn from D(h) mu_h (Walter 2007 Eq. 35-36)."""
    a2 = alpha * alpha
    cos2 = (1.0 - u1) / (1.0 + (a2 - 1.0) * u1)
    ct = math.sqrt(cos2)
    st = math.sqrt(max(0.0, 1.0 - cos2))
    cp, sp = cos_sin_2pi(u2)
    return st * cp, st * sp, ct, 1.0


@kernel
def sample_reflection(
    ox: float, oy: float, oz: float, alpha: float, u1: float, u2: float, vndf: bool
) -> tuple[float, float, float, bool]:
    """(wi.x, wi.y, wi.z, ok): wi = reflect(wo, h), h from the visible normals (Heitz 2018,
    Listing 1) or the NDF (Walter 2007 Eq. 35-36).  ok is False when the sample fails
    (NDF: h facing away from wo); wi may lie below the horizon (f = 0 there).

    wi = 2 (wo.h) h / |h|^2 - wo for the unnormalised h: one division, and wi is a unit
    vector to rounding (|wo| = 1), so it is not normalised again."""
    if vndf:
        hx, hy, hz, n2 = ggx_visible_normal_h(ox, oy, oz, alpha, u1, u2)
    else:
        hx, hy, hz, n2 = ggx_normal(alpha, u1, u2)
    d = ox * hx + oy * hy + oz * hz
    f = 2.0 * d / n2
    return f * hx - ox, f * hy - oy, f * hz - oz, d > 0.0


@kernel
def multiscatter(F0: float, E1: float, on: bool) -> float:
    """Turquin 2019 factor 1 + F0 (1 - E1)/E1 (1 when ``on`` is False)."""
    return 1.0 + F0 * ((1.0 - E1) / E1) if on else 1.0
