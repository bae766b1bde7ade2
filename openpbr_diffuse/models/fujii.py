"""Fujii's "tiny improvement" of QON (Fujii 2013).

QON coefficients with the interreflection tint of the full model added to A, and FON's t
(negative s allowed):
A = 1 - 0.5 s2/(s2 + 0.33) + 0.17 rho s2/(s2 + 0.13), B = 0.45 s2/(s2 + 0.09),
f = rho/pi (A + B s/t).  A depends on rho, so f = rho g + rho^2 h with h = K/pi.
Fujii notes it exceeds unit albedo for rho > 0.97 (as full Oren-Nayar does).
"""

from .._jit import INV_PI, kernel
from .fon import fon_shape_albedo, fon_shape_average, s_over_t


@kernel
def fujii_coeffs(sigma: float) -> tuple[float, float, float]:
    """Return (A0, B, K): A = A0 + K rho."""
    s2 = sigma * sigma
    return 1.0 - 0.5 * s2 / (s2 + 0.33), 0.45 * s2 / (s2 + 0.09), 0.17 * s2 / (s2 + 0.13)


@kernel
def fujii_terms(mu_i: float, mu_o: float, s: float, sigma: float) -> tuple[float, float]:
    """Return (g, h) with f = rho g + rho^2 h."""
    A0, B, K = fujii_coeffs(sigma)
    return (A0 + B * s_over_t(mu_i, mu_o, s)) * INV_PI, K * INV_PI


@kernel
def fujii_albedo_terms(mu: float, sigma: float, average: bool) -> tuple[float, float]:
    """(e_g, e_h) of E = rho e_g + rho^2 e_h (or of <E>): FON's shape, E = A + B G_F/pi + K rho."""
    A0, B, K = fujii_coeffs(sigma)
    if average:
        return fon_shape_average(A0, B), K
    return fon_shape_albedo(mu, A0, B), K
