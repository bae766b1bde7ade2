"""Full Oren-Nayar (Oren & Nayar 1994, Eq. 27-30), with the interreflection term.

alpha = max(theta_i, theta_o), beta = min(theta_i, theta_o),
cos(dphi) = s / (sin theta_i sin theta_o) (0 when either sine is 0):

- C1 = 1 - 0.5 s2/(s2 + 0.33)
- C2 = 0.45 s2/(s2 + 0.09) sin(alpha)                       if cos(dphi) >= 0
       0.45 s2/(s2 + 0.09) (sin(alpha) - (2 beta/pi)^3)       otherwise
- C3 = 0.125 s2/(s2 + 0.09) (4 alpha beta / pi^2)^2
- f1 = rho/pi [C1 + cos(dphi) C2 tan(beta) + (1 - |cos(dphi)|) C3 tan((alpha + beta)/2)]
- f2 = 0.17 rho^2/pi s2/(s2 + 0.13) [1 - cos(dphi) (2 beta/pi)^2]

No closed-form albedo: its albedo comes from the reference tables.  It gains energy near
grazing angles (albedo 1.0047 at rho = 1, sigma = 0.5, mu = 0.05).
"""

import math

from .._jit import INV_PI, acos, kernel, max_mu

#: Ceiling of tan((alpha + beta)/2): tan of pi/2 rounded to float64, what libm's tan gave at
#: alpha + beta = pi (both directions on the horizon).
TAN_MAX = 1.633123935319537e16


@kernel
def half_sum_tan(c_a: float, s_a: float, c_b: float, s_b: float) -> float:
    """tan((alpha + beta)/2) from the cosines and sines of alpha and beta, without libm.

    With x = alpha + beta, tan(x/2) = sin x / (1 + cos x) = (1 - cos x) / sin x; the first
    form is used where cos x >= 0 and the second where cos x < 0, so that neither divides a
    difference of nearly equal numbers (sin x = s_a c_b + c_a s_b is a sum of non-negative
    terms, accurate everywhere).  Both are computed and one selected: branch-free."""
    sx = s_a * c_b + c_a * s_b
    cx = c_a * c_b - s_a * s_b
    near = sx / (1.0 + cx)
    far = (1.0 - cx) / max(sx, 1.0 / TAN_MAX)
    return min(near if cx >= 0.0 else far, TAN_MAX)


@kernel
def full_on_terms(mu_i: float, mu_o: float, s: float, sigma: float) -> tuple[float, float]:
    """Return (g, h) with f = rho g + rho^2 h.

    alpha and beta come from the polynomial ``_jit.acos`` and tan((alpha + beta)/2) from
    ``half_sum_tan``, and the cases are selects: no libm call and no branch, so the batch
    loop vectorises as the other models' do."""
    s2 = sigma * sigma
    mi = min(max(mu_i, 0.0), 1.0)
    mo = min(max(mu_o, 0.0), 1.0)
    si = math.sqrt(max(0.0, 1.0 - mi * mi))
    so = math.sqrt(max(0.0, 1.0 - mo * mo))
    ti = acos(mi)
    to = acos(mo)
    alpha = max(ti, to)
    beta = min(ti, to)
    sin_alpha = max(si, so)
    sin_beta = min(si, so)
    # beta = min(theta) <-> cos(beta) = max(mu); exact ratio rather than tan(acos(.)).
    tan_beta = sin_beta / max_mu(mi, mo)  # floored: see _jit.MU_FLOOR
    denom = si * so
    cos_dphi = min(max(s / max(denom, 1e-300), -1.0), 1.0)
    cos_dphi = cos_dphi if denom > 0.0 else 0.0
    k = s2 / (s2 + 0.09)
    C1 = 1.0 - 0.5 * s2 / (s2 + 0.33)
    two_beta_pi = 2.0 * beta * INV_PI
    cube = two_beta_pi * two_beta_pi * two_beta_pi
    C2 = 0.45 * k * (sin_alpha - (cube if cos_dphi < 0.0 else 0.0))
    ab = 4.0 * alpha * beta * INV_PI * INV_PI
    C3 = 0.125 * k * ab * ab
    t_half = half_sum_tan(min(mi, mo), sin_alpha, max(mi, mo), sin_beta)
    g = (C1 + cos_dphi * C2 * tan_beta + (1.0 - abs(cos_dphi)) * C3 * t_half) * INV_PI
    h = 0.17 * s2 / (s2 + 0.13) * (1.0 - cos_dphi * two_beta_pi * two_beta_pi) * INV_PI
    return g, h
