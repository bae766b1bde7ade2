"""Qualitative Oren-Nayar (QON), Oren & Nayar 1994; EON paper Eq. 1-9.

sigma is the slope angle in radians.  f = rho/pi (A + B max(0, s) / max(mu_i, mu_o)).
The "footnote" variant uses 0.57 instead of 0.33 in A (Oren & Nayar's footnote).
"""
from ._jit import INV_PI, PI, kernel, max_mu

#: <G/pi> weighted by 2 mu: the constant of the QON average albedo (Eq. 9).
QON_AVG_G = 2.0 / 3.0 - 64.0 / (45.0 * PI)


@kernel
def qon_AB(sigma, a_const):
    """A = 1 - 0.5 s2/(s2 + a_const), B = 0.45 s2/(s2 + 0.09), s2 = sigma^2 (Eq. 2-3)."""
    s2 = sigma * sigma
    return 1.0 - 0.5 * s2 / (s2 + a_const), 0.45 * s2 / (s2 + 0.09)


@kernel
def qon_terms(mu_i, mu_o, s, A, B):
    """f_QON / rho (Eq. 1): (A + B max(0, s) / max(mu_i, mu_o)) / pi."""
    return (A + B * max(0.0, s) / max_mu(mu_i, mu_o)) * INV_PI
