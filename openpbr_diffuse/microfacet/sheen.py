"""The fuzz lobe of OpenPBR: Zeltner, Burley, Chiang 2022, "Practical Multiple-Scattering
Sheen Using Linearly Transformed Cosines" (the sheen model OpenPBR names; MaterialX
``sheen_bsdf`` mode "zeltner").

The lobe is an LTC: a clamped cosine D_o transformed by M^-1 = [[a, 0, b], [0, a, 0],
[0, 0, 1]] in the frame of wo (X in the plane of wo and the normal), so

    D(w) = D_o(M^-1 w / |M^-1 w|) a^2 / |M^-1 w|^4,  f(wi, wo) = R(mu_o, r) D(wi) / mu_i,

whose directional albedo is exactly R (M^-1 keeps z, so D integrates to 1 over the upper
hemisphere).  a = aInv(mu_o, r), b = bInv(mu_o, r) and the albedo R(mu_o, r) are the
paper's fitted functions in the rational/Gaussian form that MaterialX ships
(``mx_microfacet_sheen.glsl``); r = fuzz_roughness is clamped to [0.01, 1], the range of
the fit.  Sampling draws a cosine direction and maps it by M (pdf = D).
"""

from __future__ import annotations

import math

from .._jit import INV_PI, kernel
from ..sampling.simple import cosine_sample_local

#: fuzz_roughness range of the fit.
R_MIN = 0.01


@kernel
def clamp_roughness(r: float) -> float:
    return min(max(r, R_MIN), 1.0)


@kernel
def sheen_albedo_fit(r: float) -> tuple[float, float, float]:
    """(s, m, o) of the albedo fit R(mu_o, r) = N(mu_o; m, s) + o at roughness r: the part
    that depends on r alone (once per material in the surface)."""
    y = clamp_roughness(r)
    s = y * (0.0206607 + 1.58491 * y) / (0.0379424 + y * (1.32227 + y))
    m = y * (-0.193854 + y * (-1.14885 + y * (1.7932 - 0.95943 * y * y))) / (0.046391 + y)
    o = y * (0.000654023 + (-0.0207818 + 0.119681 * y) * y) / (1.26264 + y * (-1.92021 + y))
    return s, m, o


@kernel
def sheen_albedo_at(mu: float, s: float, m: float, o: float) -> float:
    """R(mu_o) from the fit's (s, m, o) (``sheen_albedo_fit``), floored at 0: the fit dips
    to -1.9e-5 near mu_o = 0.9, r = 0.1, and a negative albedo would make the fuzz lobe and
    its selection weight negative."""
    t = (min(max(mu, 0.0), 1.0) - m) / s
    return max(math.exp(-0.5 * t * t) / (s * math.sqrt(2.0 * math.pi)) + o, 0.0)


@kernel
def sheen_albedo(mu: float, r: float) -> float:
    """Directional albedo R(mu_o, r) of the sheen lobe (Zeltner 2022 fit), floored at 0."""
    s, m, o = sheen_albedo_fit(r)
    return sheen_albedo_at(mu, s, m, o)


@kernel
def ltc_inverse(mu: float, r: float) -> tuple[float, float]:
    """(a, b) of M^-1 (Zeltner 2022 rational fits)."""
    x = min(max(mu, 0.0), 1.0)
    y = clamp_roughness(r)
    a = (2.58126 * x + 0.813703 * y) * y / (1.0 + 0.310327 * x * x + 2.60994 * x * y)
    b = math.sqrt(1.0 - x) * (y - 1.0) * y * y * y / (0.0000254053 + 1.71228 * x - 1.71506 * x * y + 1.34174 * y * y)
    return a, b


@kernel
def sheen_density(lx: float, ly: float, lz: float, mu: float, r: float) -> float:
    """D(w) at the direction (lx, ly, lz) of the wo frame (X towards wo); 0 for lz <= 0."""
    a, b = ltc_inverse(mu, r)
    x, y, z = a * lx + b * lz, a * ly, lz
    len2 = x * x + y * y + z * z
    q = a / len2
    return z * INV_PI * q * q if lz > 0.0 else 0.0  # a select: the rows' loop stays vectorisable


@kernel
def sheen_sample(mu: float, r: float, u1: float, u2: float) -> tuple[float, float, float]:
    """(lx, ly, lz) in the wo frame, distributed as ``sheen_density``."""
    a, b = ltc_inverse(mu, r)
    cx, cy, cz, _ = cosine_sample_local(u1, u2)
    x, y, z = cx / a - cz * b / a, cy / a, cz
    inv = 1.0 / math.sqrt(x * x + y * y + z * z)
    return x * inv, y * inv, z * inv
