"""Light on a Smith microsurface of Lambertian microfacets: Heitz et al.'s random walk.

Heitz, Hanika, d'Eon, Dachsbacher, "Multiple-scattering microfacet BSDFs with the Smith
model", ACM TOG 35(4), 2016.  The microsurface is a random medium of microfacets whose
normals follow the distribution D (Beckmann or GGX, isotropic roughness alpha) and whose
heights are independent of their normals (the Smith assumption); with the uniform height
distribution of the paper (C1(h) = (h + 1)/2 on [-1, 1]):

- masking of direction w from height h: G1(w, h) = C1(h)^Lambda(w)          (Sec. 4.1)
- the next intersection height along w from h (Alg. 2, ``sampleHeight``):
  upwards, the ray escapes with probability G1(w, h), else
  C1(h') = C1(h) / (1 - U)^(1/Lambda(w)); downwards it always hits, by the same formula
  (Lambda(w) in (-1, 0) there);
- at an intersection the microfacet normal is drawn from the distribution of visible
  normals D_{-w}(m) proportional to <-w, m>_+ D(m), and the diffuse microfacet reflects into
  a cosine lobe about m: the phase function p(w_i -> w_o) = (1/pi) int <w_o, m>_+ D_wi(m) dm
  (Sec. 5.2, diffuse microsurface).

BRDF by next-event estimation (the paper's ``eval``, Alg. 3): each intersection at height h
with normal m adds rho^k <m, wo>_+ / pi * G1(wo, h) to f(wi, wo) mu_o.  Every path ends by
escaping, so the albedo at rho = 1 is 1 by construction (what the tests check).

Lambda: Beckmann (erf(a) - 1)/2 + exp(-a^2)/(2 a sqrt(pi)), GGX (-1 + sgn(a) sqrt(1 + 1/a^2))/2,
a = cot(theta)/alpha, for directions below the horizon too (Lambda(-w) = -1 - Lambda(w)).
Visible normals: GGX by Heitz 2018 ("Sampling the GGX distribution of visible normals", JCGT
7(4)), which stays exact for view directions below the horizon; Beckmann by inverting the
visible-slope CDF in the stretched (alpha = 1) configuration (Newton with bisection
safeguard, to 1e-10 in the slope), with an exact rejection sampler for the far tail.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from .._jit import walk_step
from ..microfacet.kernels import ggx_visible_normal
from ._common import INV_PI, cosine_about, order_class

BECKMANN = 0
GGX = 1
_SQRT_PI = math.sqrt(math.pi)


@walk_step
def C1(h: float) -> float:
    """Cumulative uniform height distribution on [-1, 1] (h = inf above the surface)."""
    return min(max(0.5 * (h + 1.0), 0.0), 1.0)


@walk_step
def lam(wz: float, alpha: float, dist: int) -> float:
    """Smith Lambda(w) of a direction with cosine ``wz`` (any sign), isotropic alpha."""
    s = math.sqrt(max(0.0, 1.0 - wz * wz))
    if s == 0.0 or alpha == 0.0:
        return 0.0 if wz > 0.0 else -1.0
    if wz == 0.0:
        return math.inf
    a = wz / (s * alpha)
    if dist == BECKMANN:
        return 0.5 * (math.erf(a) - 1.0) + math.exp(-a * a) / (2.0 * a * _SQRT_PI)
    sgn = 1.0 if a > 0.0 else -1.0
    # sqrt(1 + 1/a^2) as hypot(1, 1/|a|): 1/a^2 underflows to a division by zero at |wz| ~ 1e-160
    return 0.5 * (-1.0 + sgn * math.hypot(1.0, s * alpha / abs(wz)))


@walk_step
def G1(wz: float, h: float, alpha: float, dist: int) -> float:
    """Probability that a ray leaving height h along w escapes (0 downwards)."""
    if wz <= 0.0:
        return 0.0
    L = lam(wz, alpha, dist)
    if L == 0.0:
        return 1.0
    c = C1(h)
    if c <= 0.0:
        return 0.0
    return c**L


@walk_step
def sample_height(wz: float, h: float, alpha: float, dist: int) -> float:
    """Height of the next intersection along w from h, or inf when the ray escapes."""
    U = np.random.random()
    if wz > 0.0:
        L = lam(wz, alpha, dist)
        if L == 0.0:
            return math.inf
        if U > 1.0 - C1(h) ** L:
            return math.inf
    else:
        L = lam(wz, alpha, dist)
        if L == -1.0:  # straight down (or a flat surface): C1(h') = U C1(h)
            return 2.0 * U * C1(h) - 1.0
    if L == math.inf:  # horizontal ray: hits where it is (Heitz's code does the same)
        return min(h, 1.0)
    c = C1(h) / (1.0 - U) ** (1.0 / L)
    return 2.0 * min(c, 1.0) - 1.0


@walk_step
def _beckmann_visible_slope_x(cos_t, sin_t):
    """x-slope of a visible normal, alpha = 1, view in the xz-plane at angle theta.

    Density proportional to (cos t - x sin t)_+ exp(-x^2) on x < cot t (Heitz & d'Eon 2014);
    its CDF is F(x) / F(cot t) with F(x) = cos t sqrt(pi)/2 (1 + erf x) + sin t/2 exp(-x^2).
    """
    if sin_t < 1e-12:
        return np.random.normal() * math.sqrt(0.5)
    hi = cos_t / sin_t
    if hi < -2.5:
        # far tail (view from well below): x = hi - t, t density ~ t exp(-2|hi| t) exp(-t^2):
        # Gamma(2, 2|hi|) proposal accepted with probability exp(-t^2) (>= 0.8 here)
        while True:
            t = -(math.log(1.0 - np.random.random()) + math.log(1.0 - np.random.random())) / (-2.0 * hi)
            if np.random.random() < math.exp(-t * t):
                return hi - t
    target = np.random.random()
    Fhi = cos_t * 0.5 * _SQRT_PI * (1.0 + math.erf(hi)) + 0.5 * sin_t * math.exp(-hi * hi)
    target *= Fhi
    lo = min(hi, 0.0) - 7.0
    up = hi
    x = max(lo, min(up, 0.0 if hi > 0.0 else hi - 0.5))
    for _ in range(100):
        F = cos_t * 0.5 * _SQRT_PI * (1.0 + math.erf(x)) + 0.5 * sin_t * math.exp(-x * x) - target
        if F > 0.0:
            up = x
        else:
            lo = x
        dF = (cos_t - x * sin_t) * math.exp(-x * x)
        xn = x - F / dF if dF > 0.0 else 0.5 * (lo + up)
        if not (lo < xn < up):
            xn = 0.5 * (lo + up)
        # 1e-10: far below any Monte Carlo error; tighter tolerances hit the rounding noise of
        # F in the tails and fall back to ~40 bisection steps
        if abs(xn - x) < 1e-10 * (1.0 + abs(x)) or up - lo < 1e-10:
            return xn
        x = xn
    return x


@walk_step
def sample_visible_normal(vx: float, vy: float, vz: float, alpha: float, dist: int) -> tuple[float, float, float]:
    """A microfacet normal drawn from D_v(m) ~ <v, m>_+ D(m) (v may point downwards)."""
    if dist == GGX:
        return ggx_visible_normal(vx, vy, vz, alpha, np.random.random(), np.random.random())
    # stretch to alpha = 1
    sx = alpha * vx
    sy = alpha * vy
    n = math.sqrt(sx * sx + sy * sy + vz * vz)
    sx /= n
    sy /= n
    sz = vz / n
    # Beckmann: visible slope in the frame of the stretched view, then rotate and unstretch
    sin_t = math.sqrt(sx * sx + sy * sy)
    x = _beckmann_visible_slope_x(sz, sin_t)
    y = np.random.normal() * math.sqrt(0.5)
    if sin_t > 0.0:
        cp = sx / sin_t
        sp = sy / sin_t
    else:
        cp = 1.0
        sp = 0.0
    px = alpha * (cp * x - sp * y)
    py = alpha * (sp * x + cp * y)
    il = 1.0 / math.sqrt(px * px + py * py + 1.0)
    return -px * il, -py * il, il


@walk_step
def walk(
    wi_x: float,
    wi_y: float,
    wi_z: float,
    wo: NDArray[np.float64],
    alpha: float,
    dist: int,
    rho: NDArray[np.float64],
    rk: NDArray[np.float64],
    path_nee: NDArray[np.float64],
    max_bounces: int,
) -> tuple[int, bool]:
    """Trace one path (Heitz et al. 2016, Alg. 3 with diffuse microfacets); returns (k, escaped)."""
    C = rho.shape[0]
    m = wo.shape[0]
    for c in range(C):
        rk[c] = rho[c]
    wx = -wi_x
    wy = -wi_y
    wz = -wi_z
    h = math.inf
    k = 0
    while True:
        h = sample_height(wz, h, alpha, dist)
        if h == math.inf:
            return k, True
        k += 1
        if k > max_bounces:
            return k, False
        if k > 1:
            for c in range(C):
                rk[c] *= rho[c]
        mx, my, mz = sample_visible_normal(-wx, -wy, -wz, alpha, dist)
        if m > 0:
            q = order_class(k)
            for j in range(m):
                oz = wo[j, 2]
                if oz <= 0.0:
                    continue
                cm = mx * wo[j, 0] + my * wo[j, 1] + mz * oz
                if cm <= 0.0:
                    continue
                g = cm * INV_PI * G1(oz, h, alpha, dist) / oz
                for c in range(C):
                    path_nee[j, q, c] += rk[c] * g
        wx, wy, wz = cosine_about(mx, my, mz)
