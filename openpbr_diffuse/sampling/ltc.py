"""Linearly transformed cosines for EON (Section 3.1, Eq. 22-28, Listings 2-3).

A direction ``wh`` drawn from the clamped cosine D_o(wh) = max(0, wh.z)/pi is mapped to
``w = M wh / |M wh|`` with

    M = [[a, 0, b], [0, c, 0], [d, 0, 1]],   det M = c (a - b d)           (Eq. 25)

whose coefficients a, b, c, d(mu_o, r) are the fit of Listing 2.  The density of ``w`` is
(Eq. 23-24, with M^-1 = adj(M)/det M and h = adj(M) w)

    D(w) = D_o(M^-1 w / |M^-1 w|) |det M^-1| / |M^-1 w|^3 = (det M / |h|^2)^2 max(h.z, 0) / pi.

The LTC frame (stated once here): X = normalize(wo.x, wo.y, 0), or (1, 0, 0) when wo is
the normal; Y = (-X.y, X.x, 0); Z = (0, 0, 1).  M acts in that frame.

Variants (all share ``ltc_sample_local`` / ``ltc_pdf_local``):

- general LTC: s = 1; the lobe extends below the horizon when d != 0;
- "non-negative" LTC: d = 0, the image of the upper hemisphere is the upper hemisphere;
- clipped LTC (CLTC, Eq. 27-28): ``wh`` is drawn only from the part of the cosine lobe
  that M maps above the horizon, the half-space d wh.x + wh.z > 0.  Its projection on the
  disk is a half disk and a half ellipse of semi-axis vz = 1/sqrt(1 + d^2); its cosine
  mass is s = (1 + vz)/2, so the density is D(w)/s.

Deviation from Listing 3 (documented, measure ~1e-6): the paper states d <= 0 for all
(mu_o, r), but the fit of Listing 2 gives 0 < d <= 3.5e-3 for mu_o > 0.99991 (r > 0).
Listing 3 always keeps the half ellipse on the +x side (x <- -(...)), correct for d <= 0
only; here the side follows the sign of d, so CLTC never samples below the horizon.  For
d <= 0 (every mu_o < 0.9999) the mapping is exactly Listing 3's.
"""

import math

from .._jit import PI, kernel
from .simple import cos_sin_2pi

#: The coefficients of Listing 2's fit, as ``_ltc_parts`` uses them (also read by ``export``):
#: a = 1 + r (A0 + (A1 + A2 mu) mu + (A3 + A4 mu) r); b = r (B0 + B1 mu + (B2 + B3 mu) r) / (mu^3 + B4);
#: c = 1 + (C0 + (C1 + C2 mu) mu) r; d = (D0 + (D1 + D2 mu) mu) r / (D3 + mu (D4 + mu)).
LTC_FIT_A = (0.303392, -0.518982, 0.111709, -0.276266, 0.335918)
LTC_FIT_B = (-1.16407, 1.15859, 0.150815, -0.150105, -1.43545)
LTC_FIT_C = (0.20013, -0.506373, 0.261777)
LTC_FIT_D = (0.540852, -1.01625, 0.475392, -1.0743, 0.0725628)


@kernel
def _ltc_parts(mu, r):
    """(a, b_num, b_den, c, d_num, d_den) of the Listing 2 fit: b = b_num / b_den, d = d_num / d_den."""
    A0, A1, A2, A3, A4 = LTC_FIT_A
    B0, B1, B2, B3, B4 = LTC_FIT_B
    C0, C1, C2 = LTC_FIT_C
    D0, D1, D2, D3, D4 = LTC_FIT_D
    a = 1.0 + r * (A0 + (A1 + A2 * mu) * mu + (A3 + A4 * mu) * r)
    bn = r * (B0 + B1 * mu + (B2 + B3 * mu) * r)
    bd = mu * mu * mu + B4
    c = 1.0 + (C0 + (C1 + C2 * mu) * mu) * r
    dn = (D0 + (D1 + D2 * mu) * mu) * r
    dd = D3 + mu * (D4 + mu)
    return a, bn, bd, c, dn, dd


@kernel
def ltc_coeffs(mu: float, r: float) -> tuple[float, float, float, float]:
    """Return (a, b, c, d) of the LTC matrix M (Eq. 25) for mu = mu_o, roughness r (Listing 2)."""
    a, bn, bd, c, dn, dd = _ltc_parts(mu, r)
    inv = 1.0 / (bd * dd)  # both denominators are < 0 on [0, 1]: one division for b and d
    return a, bn * dd * inv, c, dn * bd * inv


@kernel
def cltc_coeffs(mu: float, r: float) -> tuple[float, float, float, float, float]:
    """(a, b, c, d, s): ``ltc_coeffs`` and the CLTC's clip fraction s, taken from d's numerator
    and denominator (``clip_fraction_of``) so that s does not wait for d's division (the EON
    sampler's chain of square roots and divisions is a row's latency in the surface's scalar
    drivers)."""
    a, b, c, d = ltc_coeffs(mu, r)
    _, _, _, _, dn, dd = _ltc_parts(mu, r)  # the same values: inlined, computed once
    return a, b, c, d, clip_fraction_of(dn, dd)


@kernel
def ltc_frame(ox: float, oy: float) -> tuple[float, float]:
    """Return X = (X.x, X.y) of the LTC frame of wo (Y = (-X.y, X.x), Z = +z)."""
    l2 = ox * ox + oy * oy
    il = 1.0 / math.sqrt(l2)  # inf at the normal, discarded below (selects, not branches)
    normal = not l2 > 0.0  # wo at the normal: any azimuth will do, the lobe is isotropic there
    return (1.0 if normal else ox * il), (0.0 if normal else oy * il)


@kernel
def to_frame(Xx: float, Xy: float, wx: float, wy: float) -> tuple[float, float]:
    """Local (x, y) -> LTC-frame (x, y) (z is shared)."""
    return Xx * wx + Xy * wy, Xx * wy - Xy * wx


@kernel
def from_frame(Xx: float, Xy: float, lx: float, ly: float) -> tuple[float, float]:
    """LTC-frame (x, y) -> local (x, y): X lx + Y ly."""
    return Xx * lx - Xy * ly, Xy * lx + Xx * ly


@kernel
def clip_fraction_of(dn: float, dd: float) -> float:
    """s = (1 + vz)/2, vz = 1/sqrt(1 + d^2): cosine mass kept by the CLTC clipping (Eq. 28), for
    d = dn / dd (vz = |dd| / sqrt(dn^2 + dd^2): no division by dd first)."""
    return 0.5 * (1.0 + abs(dd) / math.sqrt(dn * dn + dd * dd))


@kernel
def clip_fraction(d: float) -> float:
    """s = (1 + vz)/2, vz = 1/sqrt(1 + d^2): cosine mass kept by the CLTC clipping (Eq. 28)."""
    return clip_fraction_of(d, 1.0)


@kernel
def ltc_sample_local(
    a: float, b: float, c: float, d: float, s: float, u1: float, u2: float
) -> tuple[float, float, float, float]:
    """Return (x, y, z, pdf) of an (optionally clipped) LTC sample in the LTC frame.

    ``s`` = 1 gives the plain LTC, ``s = clip_fraction(d)`` the CLTC of Listing 3: Heitz's
    (2018) map of the unit disk onto the half disk plus half ellipse (Nusselt analog of the
    clipped lobe), then reprojection to the hemisphere and w = M wh (Eq. 22).  The pdf is
    wh.z / (pi s) times the Jacobian |M wh|^3 / det M (Eq. 24, 28).
    """
    R = math.sqrt(u1)
    cp, sp = cos_sin_2pi(u2)  # phi = 2 pi u2
    x = R * cp
    y = R * sp
    # The clipped map x' = side ((1 - s) q + s x), q = sqrt(1 - y^2), and the height of the
    # disk point, hz^2 = 1 - x'^2 - y^2 = s (q - x) (2 (1 - s) q + s (q + x)).  Written so,
    # with q^2 - x^2 = 1 - u1 (exact) carried by whichever of q -+ x does not cancel, hz
    # stays > 0 up to u1 = 1 - 2^-53, where sqrt(u1) rounds to 1 and 1 - (x'^2 + y^2)
    # computed directly gave hz = 0 or a direction below the horizon.
    q = math.sqrt(max(0.0, 1.0 - u1 * sp * sp))
    P = q + abs(x)
    D = min((1.0 - u1) / max(P, 1e-300), P)  # = q - |x| >= 0
    q_minus_x = D if x >= 0.0 else P
    q_plus_x = P if x >= 0.0 else D
    hz = math.sqrt(s * q_minus_x * (2.0 * (1.0 - s) * q + s * q_plus_x))
    side = 1.0 if d > 0.0 else -1.0  # keep the removed lune on the side where d x + z < 0
    x = side * ((1.0 - s) * q + s * x)
    wx = a * x + b * hz
    wy = c * y
    wz = d * x + hz
    l2 = wx * wx + wy * wy + wz * wz
    inv = 1.0 / math.sqrt(l2)
    # 1/(pi s det M) does not depend on u: its division runs while the sample is mapped
    pdf = hz * (l2 * l2 * inv) * (1.0 / (PI * s * (c * (a - b * d))))
    return wx * inv, wy * inv, wz * inv, pdf


@kernel
def ltc_pdf_local(a: float, b: float, c: float, d: float, s: float, wx: float, wy: float, wz: float) -> float:
    """Density of the (clipped) LTC at the unit LTC-frame direction w: (det/|h|^2)^2 max(h.z, 0)/(pi s).

    h = adj(M) w (the adjugate keeps M^-1 free of a division); h.z <= 0 means w is
    outside the image of the upper hemisphere, where the lobe is zero.  The caller
    applies the horizon (CLTC is zero for w.z <= 0 as well).
    """
    e = a - b * d
    hx = c * (wx - b * wz)
    hy = e * wy
    hz = c * (a * wz - d * wx)
    det = c * e
    l2 = hx * hx + hy * hy + hz * hz
    pdf = det * det * hz / (PI * s * l2 * l2)
    return pdf if hz > 0.0 else 0.0
