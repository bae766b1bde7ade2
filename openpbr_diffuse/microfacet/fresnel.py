"""Fresnel factors of the OpenPBR specular layers: exact dielectric, F82-tint conductor.

``c`` is the cosine between the direction and the microfacet normal (wo.h).  Each formula
is written once, as a scalar compiled function (``dielectric``, ``f0``, ``modulated_x``,
``eta_of_x``, ``schlick``, ``f82_a``, ``f82``: what the surface's batch drivers call); the
NumPy names (``fresnel_dielectric``, ``f0_of_eta``, ...) are the same functions as
ufuncs (numba ``vectorize``: broadcasting, any shape).

References
----------
Walter, Marschner, Li, Torrance, EGSR 2007, Eq. 22 (dielectric Fresnel).  Kutz, Hasan,
Edmondson, "Novel aspects of the Adobe Standard Material", 2021 (F82-tint).  OpenPBR 1.1,
"Specular" and "Metal" (specular_weight as a modulation of F0; the F82-tint metal).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._jit import kernel, ufunc

#: cos(theta) of the F82-tint reference angle, mu_bar = 1/7 (theta ~ 81.8 degrees).
MU_BAR = 1.0 / 7.0
#: Upper clamp of specular_weight * F0 in the OpenPBR reference graph
#: (open_pbr_surface.mtlx, node ``scaled_specular_F0_clamped``): keeps eta' finite.
XI_MAX = 0.99999


@kernel
def dielectric(c: float, eta: float) -> float:
    """Exact unpolarised Fresnel reflectance of a dielectric interface (W07 Eq. 22).

    c: cosine between the incident direction and the microfacet normal, in [0, 1]; eta:
    relative index n_transmitted / n_incident (> 0).  eta < 1 gives total internal
    reflection (F = 1) below the critical angle; eta = 1 gives F = 0 exactly (the
    index-matched interface, whose g^2 = c^2 vanishes at grazing c = 0 but which reflects
    nothing).
    """
    g2 = eta * eta - 1.0 + c * c
    g = math.sqrt(max(g2, 0.0))
    # g + c = 0 only where a select below discards the value (eta = 1 at c = 0, or total
    # internal reflection); the floor keeps it finite there (no 0/0, no FP warning)
    a = (g - c) / max(g + c, 1e-300)
    b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0)
    F = 0.5 * a * a * (1.0 + b * b)
    # selects, not branches: a batch loop over rows that inlines this stays vectorisable
    F = F if g2 > 0.0 else 1.0
    return F if eta != 1.0 else 0.0


@kernel
def f0(eta: float) -> float:
    """Normal-incidence reflectance F0 = ((eta - 1)/(eta + 1))^2."""
    q = (eta - 1.0) / (eta + 1.0)
    return q * q


@kernel
def modulated_x(weight: float, eta: float) -> float:
    """x = sign(eta - 1) sqrt(clamp(weight F0(eta), 0, XI_MAX)); the modulated index is
    eta' = (1 + x)/(1 - x).

    OpenPBR's specular_weight scales the normal-incidence reflectance F0 of the dielectric
    and the Fresnel factor is then the exact one of the modulated index eta' that has
    that F0 (OpenPBR spec, specular_weight; the MaterialX reference graph's nodes
    ``scaled_specular_F0`` .. ``modulated_eta_s``).  x is the signed sqrt(F0'); |x| is the
    coordinate of the albedo table.  x = 0 (weight = 0 or eta = 1) is an index-matched
    interface, F = 0.
    """
    xi = min(max(weight * f0(eta), 0.0), XI_MAX)
    s = 1.0 if eta > 1.0 else (-1.0 if eta < 1.0 else 0.0)
    return s * math.sqrt(xi)


@kernel
def eta_of_x(x: float) -> float:
    """eta' = (1 + x)/(1 - x) (inverse of F0 = x^2 with the side of 1 given by sign(x))."""
    return (1.0 + x) / (1.0 - x)


@kernel
def schlick(c: float, F0: float) -> float:
    """Schlick's F0 + (1 - F0)(1 - c)^5."""
    m = 1.0 - c
    m2 = m * m
    return F0 + (1.0 - F0) * m2 * m2 * m


@kernel
def f82_a(F0: float, tint: float) -> float:
    """a of the F82-tint model: F(mu_bar) = tint * F_Schlick(mu_bar) fixes
    a = F_Schlick(mu_bar)(1 - tint) / (mu_bar (1 - mu_bar)^6)  (Kutz et al. 2021; OpenPBR "Metal")."""
    m = 1.0 - MU_BAR
    m3 = m * m * m
    return schlick(MU_BAR, F0) * (1.0 - tint) / (MU_BAR * m3 * m3)


@kernel
def f82(c: float, F0: float, a: float) -> float:
    """F82-tint conductor Fresnel F_Schlick(c) - a c (1 - c)^6 (Kutz et al. 2021), with a from
    ``f82_a``.  Not clamped: with both F0 and tint near 0 it dips slightly below 0 near
    c = 0.5, as the published formula does."""
    m = 1.0 - c
    m3 = m * m * m
    return schlick(c, F0) - a * c * m3 * m3


# --------------------------------------------------------------------------- NumPy forms


@ufunc
def fresnel_dielectric(c, eta):
    """``dielectric`` as a ufunc."""
    return dielectric(c, eta)


@ufunc
def f0_of_eta(eta):
    """``f0`` as a ufunc."""
    return f0(eta)


@ufunc
def modulated_ior_parameter(specular_weight, ior):
    """``modulated_x`` as a ufunc."""
    return modulated_x(specular_weight, ior)


@ufunc
def eta_of_parameter(x):
    """``eta_of_x`` as a ufunc."""
    return eta_of_x(x)


@ufunc
def f82_coefficient(F0, tint):
    """``f82_a`` as a ufunc."""
    return f82_a(F0, tint)


@ufunc
def _f82(c, F0, a):
    return f82(c, F0, a)


def fresnel_f82_tint(c: ArrayLike, F0: ArrayLike, tint: ArrayLike) -> NDArray[np.float64]:
    """F82-tint Fresnel (``f82``) with ``c`` (...) broadcast over the channel axis of
    ``F0``/``tint`` (..., C)."""
    c = np.asarray(c, dtype=np.float64)[..., None]
    F0 = np.asarray(F0, dtype=np.float64)
    return _f82(c, F0, f82_coefficient(F0, np.asarray(tint, dtype=np.float64)))
