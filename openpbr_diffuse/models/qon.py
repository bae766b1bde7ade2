"""Qualitative Oren-Nayar (QON), Oren & Nayar 1994; EON paper Eq. 1-9.

sigma is the slope angle in radians.  f = rho/pi (A + B max(0, s) / max(mu_i, mu_o)).
The "footnote" variant uses 0.57 instead of 0.33 in A (Oren & Nayar's footnote).
Albedo: E(mu) = A + B G(mu)/pi (Eq. 8), <E> = A + (2/3 - 64/(45 pi)) B (Eq. 9).
"""

import math

from .._jit import INV_PI, PI, acos, kernel, max_mu

#: <G/pi> weighted by 2 mu: the constant of the QON average albedo (Eq. 9).
QON_AVG_G = 2.0 / 3.0 - 64.0 / (45.0 * PI)


@kernel
def qon_AB(sigma: float, a_const: float) -> tuple[float, float]:
    """A = 1 - 0.5 s2/(s2 + a_const), B = 0.45 s2/(s2 + 0.09), s2 = sigma^2 (Eq. 2-3)."""
    s2 = sigma * sigma
    return 1.0 - 0.5 * s2 / (s2 + a_const), 0.45 * s2 / (s2 + 0.09)


@kernel
def qon_terms(mu_i: float, mu_o: float, s: float, A: float, B: float) -> float:
    """f_QON / rho (Eq. 1): (A + B max(0, s) / max(mu_i, mu_o)) / pi."""
    return (A + B * max(0.0, s) / max_mu(mu_i, mu_o)) * INV_PI


@kernel
def G_qon(mu: float) -> float:
    """G(theta) of the QON albedo (Eq. 5/8) as a function of mu = cos(theta).

    ``sin(th)(th - sin cos) + (2/3) tan(th)(1 - sin^3)`` with ``tan(1 - S^3)`` rewritten as
    ``S mu (1 + S + S^2) / (1 + S)`` (since ``1 - S = mu^2 / (1 + S)``): no division by mu,
    no cancellation, and the limit pi/2 at mu = 0 comes out exactly.
    """
    mu = min(max(mu, 0.0), 1.0)
    S = math.sqrt(max(0.0, 1.0 - mu * mu))
    return S * (acos(mu) - S * mu) + (2.0 / 3.0) * S * mu * (1.0 + S + S * S) / (1.0 + S)


@kernel
def qon_albedo(mu: float, A: float, B: float) -> float:
    """Directional albedo E(mu) / rho = A + B G(mu)/pi (Eq. 8)."""
    return A + B * G_qon(mu) * INV_PI


@kernel
def qon_average_albedo(A: float, B: float) -> float:
    """Average albedo <E> / rho = A + (2/3 - 64/(45 pi)) B (Eq. 9)."""
    return A + QON_AVG_G * B
