"""Fresnel factors of the OpenPBR specular layers: exact dielectric, F82-tint conductor.

``c`` is the cosine between the direction and the microfacet normal (wo.h); functions are
NumPy ufunc-style (leading axes broadcast).

References
----------
Walter, Marschner, Li, Torrance, EGSR 2007, Eq. 22 (dielectric Fresnel).  Kutz, Hasan,
Edmondson, "Novel aspects of the Adobe Standard Material", 2021 (F82-tint).  OpenPBR 1.1,
"Specular" and "Metal" (specular_weight as a modulation of F0; the F82-tint metal).
"""
import numpy as np

#: cos(theta) of the F82-tint reference angle, mu_bar = 1/7 (theta ~ 81.8 degrees).
MU_BAR = 1.0 / 7.0


def fresnel_dielectric(c, eta):
    """Exact unpolarised Fresnel reflectance of a dielectric interface (W07 Eq. 22).

    Parameters
    ----------
    c : array_like
        Cosine between the incident direction and the microfacet normal, in [0, 1].
    eta : array_like
        Relative index n_transmitted / n_incident (> 0).  eta < 1 gives total internal
        reflection (F = 1) below the critical angle; eta = 1 gives F = 0 exactly.
    """
    c = np.asarray(c, dtype=np.float64)
    g2 = np.square(eta) - 1.0 + np.square(c)
    g = np.sqrt(np.maximum(g2, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        a = (g - c) / (g + c)
        b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0)
        F = 0.5 * a * a * (1.0 + b * b)
    # g2 <= 0: total internal reflection (eta < 1), F = 1 -- except the index-matched
    # interface, whose g2 = c^2 vanishes at grazing c = 0 but which reflects nothing
    return np.where(eta == 1.0, 0.0, np.where(g2 > 0.0, F, 1.0))


def f0_of_eta(eta):
    """Normal-incidence reflectance F0 = ((eta - 1)/(eta + 1))^2."""
    eta = np.asarray(eta, dtype=np.float64)
    return np.square((eta - 1.0) / (eta + 1.0))


#: Upper clamp of specular_weight * F0 in the OpenPBR reference graph
#: (open_pbr_surface.mtlx, node ``scaled_specular_F0_clamped``): keeps eta' finite.
XI_MAX = 0.99999


def modulated_ior_parameter(specular_weight, ior):
    """x = sign(eta - 1) sqrt(clamp(specular_weight F0(eta), 0, XI_MAX)); eta' = (1 + x)/(1 - x).

    OpenPBR's specular_weight scales the normal-incidence reflectance F0 of the dielectric
    and the Fresnel factor is then the exact one of the modulated index eta' that has
    that F0 (OpenPBR spec, specular_weight; the MaterialX reference graph's nodes
    ``scaled_specular_F0`` .. ``modulated_eta_s``).  x is the signed sqrt(F0'); |x| is the
    coordinate of the albedo table.  x = 0 (specular_weight = 0 or eta = 1) is an
    index-matched interface, F = 0.
    """
    eta = np.asarray(ior, dtype=np.float64)
    xi = np.clip(np.asarray(specular_weight, dtype=np.float64) * f0_of_eta(eta), 0.0, XI_MAX)
    return np.sign(eta - 1.0) * np.sqrt(xi)


def eta_of_parameter(x):
    """eta' = (1 + x)/(1 - x) (inverse of F0 = x^2 with the side of 1 given by sign(x))."""
    x = np.asarray(x, dtype=np.float64)
    with np.errstate(divide="ignore"):
        return (1.0 + x) / (1.0 - x)


def fresnel_schlick(c, F0):
    """Schlick's F0 + (1 - F0)(1 - c)^5 (c broadcast against F0's channel axis by the caller)."""
    return F0 + (1.0 - F0) * (1.0 - c) ** 5


def f82_coefficient(F0, tint):
    """a of the F82-tint model: F(mu_bar) = tint * F_Schlick(mu_bar) fixes
    a = F_Schlick(mu_bar)(1 - tint) / (mu_bar (1 - mu_bar)^6)  (Kutz et al. 2021; OpenPBR "Metal")."""
    fs_bar = fresnel_schlick(MU_BAR, F0)
    return fs_bar * (1.0 - tint) / (MU_BAR * (1.0 - MU_BAR) ** 6)


def fresnel_f82_tint(c, F0, tint):
    """F82-tint conductor Fresnel: F_Schlick(c) - a c (1 - c)^6 (Kutz et al. 2021).

    ``c`` has shape (...) and is broadcast over the channel axis of ``F0``/``tint``
    (shape (..., C)).  Not clamped: with both F0 and tint near 0 it dips slightly below 0
    near c = 0.5, as the published formula does; OpenPBR materials stay far from that corner.
    """
    c = np.asarray(c, dtype=np.float64)[..., None]
    return fresnel_schlick(c, F0) - f82_coefficient(F0, tint) * c * (1.0 - c) ** 6
