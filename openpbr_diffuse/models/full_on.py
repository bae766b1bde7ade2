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

from .._jit import INV_PI, PI, kernel, max_mu



@kernel
def full_on_terms(mu_i, mu_o, s, sigma):
    """Return (g, h) with f = rho g + rho^2 h."""
    s2 = sigma * sigma
    mi = min(max(mu_i, 0.0), 1.0)
    mo = min(max(mu_o, 0.0), 1.0)
    si = math.sqrt(max(0.0, 1.0 - mi * mi))
    so = math.sqrt(max(0.0, 1.0 - mo * mo))
    ti = math.acos(mi)
    to = math.acos(mo)
    alpha = max(ti, to)
    beta = min(ti, to)
    sin_alpha = max(si, so)
    # beta = min(theta) <-> cos(beta) = max(mu); exact ratio rather than tan(acos(.)).
    tan_beta = min(si, so) / max_mu(mi, mo)  # floored: see _jit.MU_FLOOR
    denom = si * so
    cos_dphi = 0.0
    if denom > 0.0:
        cos_dphi = min(max(s / denom, -1.0), 1.0)
    k = s2 / (s2 + 0.09)
    C1 = 1.0 - 0.5 * s2 / (s2 + 0.33)
    two_beta_pi = 2.0 * beta * INV_PI
    if cos_dphi >= 0.0:
        C2 = 0.45 * k * sin_alpha
    else:
        C2 = 0.45 * k * (sin_alpha - two_beta_pi * two_beta_pi * two_beta_pi)
    ab = 4.0 * alpha * beta * INV_PI * INV_PI
    C3 = 0.125 * k * ab * ab
    g = (C1 + cos_dphi * C2 * tan_beta
         + (1.0 - abs(cos_dphi)) * C3 * math.tan(0.5 * (alpha + beta))) * INV_PI
    h = 0.17 * s2 / (s2 + 0.13) * (1.0 - cos_dphi * two_beta_pi * two_beta_pi) * INV_PI
    return g, h
