"""Fujii Oren-Nayar (FON), EON paper Eq. 10-15.

``r`` in [0, 1] is an interpolation weight, not an angle.  ``s = wi.wo - mu_i mu_o``.

References
----------
Portsmouth, Kutz, Hill, "EON: A practical energy-preserving rough diffuse BRDF",
JCGT 14(1), 2025, Section 2.2 (Eq. 10-15) and Listing 1.
"""

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._jit import INV_PI, PI, kernel, max_mu
from .qon import G_qon

#: Eq. 11/15 constants.
C1 = 0.5 - 2.0 / (3.0 * PI)
C2 = 2.0 / 3.0 - 28.0 / (15.0 * PI)
#: Eq. 14 polynomial fit of G_F / pi in m = 1 - mu.
G1, G2, G3, G4 = 0.0571085289, 0.491881867, -0.332181442, 0.0714429953

#: A scalar, or an array of them: the kernels that are also called on numpy arrays (outside
#: numba) take either; they return the same kind (float or ``NDArray[np.float64]``), written
#: ``Any`` since numba's dispatcher type does not carry a type variable through.
FloatOrArray = float | NDArray[np.float64]


@kernel
def s_over_t(mu_i: float, mu_o: float, s: float) -> float:
    """The FON ratio s/t (Eq. 10): s / max(mu_i, mu_o) for s > 0, else s (see ``max_mu``)."""
    if s > 0.0:
        return s / max_mu(mu_i, mu_o)
    return s


@kernel
def fon_A(r: FloatOrArray) -> Any:
    """A_F = 1 / (1 + c1 r) (Eq. 11); B_F = r A_F."""
    return 1.0 / (1.0 + C1 * r)


@kernel
def fon_terms(mu_i: float, mu_o: float, s: float, r: float) -> float:
    """f_FON / rho (Eq. 10): A_F (1 + r s/t) / pi."""
    return fon_A(r) * (1.0 + r * s_over_t(mu_i, mu_o, s)) * INV_PI


@kernel
def G_fon(mu: float) -> float:
    """G_F of Eq. 13: G_QON - (2/3) S (negative s contributes with FON's t = 1).

    Same stable form as ``G_qon``; G_F(0) = pi/2 - 2/3, so E_F(0) = 1 for every r.
    """
    mu = min(max(mu, 0.0), 1.0)
    S = math.sqrt(max(0.0, 1.0 - mu * mu))
    return G_qon(mu) - (2.0 / 3.0) * S


@kernel
def E_F_exact(mu: float, r: float) -> float:
    """Exact FON directional albedo E_F(mu) at rho = 1 (Eq. 12-13)."""
    A = fon_A(r)
    return A + r * A * INV_PI * G_fon(mu)


@kernel
def E_F_approx(mu: float, r: float) -> float:
    """Approximate FON albedo (Eq. 14): (1 + r G_F/pi) / (1 + c1 r), polynomial G_F/pi."""
    m = 1.0 - min(max(mu, 0.0), 1.0)
    g = m * (G1 + m * (G2 + m * (G3 + m * G4)))
    return (1.0 + r * g) / (1.0 + C1 * r)


#: 2 * int_0^1 (G_F/pi)_approx(mu) mu dmu: the cosine-weighted average of the Eq. 14 fit
#: (the exact average of G_F/pi is c2).  Used for the exact albedo of "eon_approx".
C2_APPROX = 2.0 * (G1 / 6.0 + G2 / 12.0 + G3 / 20.0 + G4 / 30.0)


@kernel
def E_F(mu: float, r: float, approx: bool) -> float:
    """E_F(mu): exact (Eq. 12) or the Eq. 14 fit."""
    if approx:
        return E_F_approx(mu, r)
    return E_F_exact(mu, r)


@kernel
def E_F_avg(r: FloatOrArray) -> Any:
    """Average albedo <E_F> = A_F (1 + c2 r) (Eq. 15)."""
    return fon_A(r) * (1.0 + C2 * r)


@kernel
def E_F_avg_of(r: float, approx: bool) -> float:
    """True cosine-weighted average of the E_F variant in use (c2 -> C2_APPROX for Eq. 14)."""
    if approx:
        return fon_A(r) * (1.0 + C2_APPROX * r)
    return E_F_avg(r)


@kernel
def fon_shape_albedo(mu: float, A: float, B: float) -> float:
    """E(mu) / rho = A + B G_F(mu)/pi of any lobe (A + B s/t)/pi with FON's t (Eq. 12-13).

    FON itself (A = A_F, B = r A_F), and Gotanda's and Fujii's lobes, which share its shape.
    """
    return A + B * G_fon(mu) * INV_PI


@kernel
def fon_shape_average(A: float, B: float) -> float:
    """<E> / rho = A + c2 B of a lobe (A + B s/t)/pi (Eq. 15)."""
    return A + C2 * B


@kernel
def fon_albedo(mu: float, r: float, average: bool) -> float:
    """FON albedo E_F(mu) (Eq. 12-13), or <E_F> (Eq. 15) when ``average``."""
    A = fon_A(r)
    if average:
        return fon_shape_average(A, r * A)
    return fon_shape_albedo(mu, A, r * A)
