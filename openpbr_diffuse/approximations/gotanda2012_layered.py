"""Gotanda 2012, "Beyond a simple physically based Blinn-Phong model in real-time" (SIGGRAPH
course notes), Sections 1-2: the physically based Blinn-Phong model and the layered model.

- Eq. 1: the physically based Blinn-Phong BRDF of Gotanda 2010 (``blinn_phong``), diffuse
  weighted by the constant (1 - F0), specular normalised by 0.0397436 s + 0.0856832
  (``normalisation``; the exact constant that makes the specular lobe's albedo 1 at normal
  incidence with F = 1 is ``exact_normalisation``).
- Eq. 2: Beer-Lambert absorption of the top layer along the refracted paths
  (``beer_lambert``), I/I0 = exp(-alpha d (1/cos theta_i + 1/cos theta_r)).
- Eq. 3: its linear approximation with non-refracted angles (``linear_absorption``),
  max(0, 1 - alpha' (1/N.L + 1/N.E)).
- Eq. 4: the Fresnel factor of the bottom layer seen through the top (``bottom_fresnel``),
  (1 - F(n1)) F(n2/n1) (1 - F(1/n1)), each F at its own angle.
- Eq. 5: its constants (``transmittance`` = 1 - F(n1) at the view angle, and
  ``bottom_fresnel_constant`` = F0(n2/n1) (1 - F0(1/n1))).
- Eq. 6-7: the bottom-layer specular under image-based lighting, mirror reflection
  N.L = N.E (``ibl_specular_factor``): F_bottom max(0, 1 - alpha' 2/N.E).
- Eq. 8: the cosine-weighted hemispherical integral of (1/cos theta_r + 1/cos theta_i)
  over the light directions, 2 + 1/cos theta_r (``hemispherical_path_factor``).
- Eq. 9: the bottom-layer diffuse under image-based lighting (``ibl_diffuse_factor``):
  (1 - F_bottom) max(0, 1 - alpha' (2 + 1/N.E)).

F(n) is the exact unpolarised Fresnel reflectance (the library's ``fresnel_dielectric``);
Eq. 1's F_spec is Schlick's approximation, as printed.  All functions are NumPy-vectorised
(broadcasting); cosines are in (0, 1].
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..microfacet.fresnel import fresnel_dielectric

#: Eq. 1's normalisation constants as printed
NORM_SLOPE = 0.0397436
NORM_OFFSET = 0.0856832


def _cos(name: str, v: ArrayLike) -> np.ndarray:
    a = np.asarray(v, dtype=float)
    if not np.all((a > 0.0) & (a <= 1.0)):
        raise ValueError(f"{name} must be cosines in (0, 1]")
    return a


def _ior(name: str, v: ArrayLike) -> np.ndarray:
    a = np.asarray(v, dtype=float)
    if not np.all(np.isfinite(a) & (a > 0.0)):
        raise ValueError(f"{name} must be a positive finite index of refraction")
    return a


def fresnel(mu: ArrayLike, n: ArrayLike) -> np.ndarray:
    """F(n) of Eq. 4: exact Fresnel reflectance at cosine mu for the relative index n.

    Example
    -------
    >>> round(float(fresnel(1.0, 1.5)), 6)
    0.04
    """
    return np.asarray(fresnel_dielectric(np.asarray(mu, dtype=float), np.asarray(n, dtype=float)), dtype=float)


def f0(n: ArrayLike) -> np.ndarray:
    """F0(n) = ((n - 1)/(n + 1))^2, the Fresnel reflectance at normal incidence (Eq. 5).

    Example
    -------
    >>> round(float(f0(1.5)), 6)
    0.04
    """
    n = _ior("n", n)
    return ((n - 1.0) / (n + 1.0)) ** 2


def schlick(c: ArrayLike, F0: float | NDArray[np.floating[Any]]) -> np.ndarray:
    """F_spec(F0) of Eq. 1: Schlick's F0 + (1 - F0)(1 - c)^5, c = the cosine to the half vector.

    Example
    -------
    >>> float(schlick(1.0, 0.04)), float(schlick(0.0, 0.04))
    (0.04, 1.0)
    """
    c = np.asarray(c, dtype=float)
    return F0 + (1.0 - F0) * (1.0 - c) ** 5


def normalisation(shininess: ArrayLike) -> np.ndarray:
    """Eq. 1's specular normalisation as printed: 0.0397436 s + 0.0856832.

    Example
    -------
    >>> round(float(normalisation(100.0)), 7)
    4.0600432
    """
    return NORM_SLOPE * np.asarray(shininess, dtype=float) + NORM_OFFSET


def exact_normalisation(shininess: ArrayLike, n: int = 2048) -> np.ndarray:
    """The constant K(s) with K int (n.h)^s / max(n.l, n.v) (n.l) dl = 1 at v = n (the lobe's
    albedo at normal incidence with F = 1): there max(n.l, 1) = 1 and n.h = cos(theta_l/2),
    so 1/K = 2 pi int_0^{pi/2} cos^s(t/2) cos t sin t dt (Gauss-Legendre).  For large s,
    K -> s/(8 pi) = 0.0397887 s: Eq. 1's slope.

    Example
    -------
    >>> round(float(exact_normalisation(1e6) / 1e6 * 8 * math.pi), 4)
    1.0
    """
    s = np.asarray(shininess, dtype=float)
    x, w = np.polynomial.legendre.leggauss(n)
    t = 0.25 * math.pi * (x + 1.0)
    w = 0.25 * math.pi * w
    integrand = np.cos(t / 2.0)[None] ** s.reshape(-1, 1) * (np.cos(t) * np.sin(t))[None]
    return (1.0 / (2.0 * math.pi * (integrand * w).sum(axis=1))).reshape(s.shape)


def blinn_phong(
    wi: ArrayLike, wo: ArrayLike, shininess: ArrayLike, F0: float | NDArray[np.floating[Any]], rho: ArrayLike
) -> np.ndarray:
    """Eq. 1: f = rho/pi (1 - F0) + (0.0397436 s + 0.0856832) F_spec(F0) (n.h)^s / max(n.l, n.v).

    wi, wo: unit vectors (..., 3), normal +z; rho (..., C).  Returns f (no cosine), (..., C).

    Example
    -------
    >>> f = blinn_phong([0, 0, 1.0], [0, 0, 1.0], 10.0, 0.04, [0.5])
    >>> round(float(f[0]), 6)
    0.172114
    """
    wi, wo = np.asarray(wi, dtype=float), np.asarray(wo, dtype=float)
    h = wi + wo
    h = h / np.linalg.norm(h, axis=-1, keepdims=True)
    nh = np.clip(h[..., 2], 0.0, 1.0)
    lh = np.clip(np.sum(wi * h, axis=-1), 0.0, 1.0)
    spec = (
        normalisation(shininess)
        * schlick(lh, F0)
        * nh**shininess
        / np.maximum(np.maximum(wi[..., 2], wo[..., 2]), 1e-12)
    )
    rho = np.asarray(rho, dtype=float)
    return rho / math.pi * (1.0 - np.asarray(F0, dtype=float))[..., None] + np.asarray(spec)[..., None]


def refracted_cos(mu: ArrayLike, n: ArrayLike) -> np.ndarray:
    """Cosine inside a layer of relative index n of a direction at cosine mu outside (Snell).

    Example
    -------
    >>> round(float(refracted_cos(0.0 + 1e-300, 1.5)), 6)
    0.745356
    """
    mu = np.asarray(mu, dtype=float)
    return np.sqrt(np.maximum(0.0, 1.0 - (1.0 - mu * mu) / np.asarray(n, dtype=float) ** 2))


def beer_lambert(alpha: ArrayLike, d: ArrayLike, mu_i: ArrayLike, mu_o: ArrayLike, n: ArrayLike) -> np.ndarray:
    """Eq. 2: I/I0 = exp(-alpha l), l = d (1/cos theta_i + 1/cos theta_r) with the refracted
    angles of the light and the view inside the layer of index n.

    Example
    -------
    >>> round(float(beer_lambert(1.0, 0.1, 1.0, 1.0, 1.5)), 6)
    0.818731
    """
    l = np.asarray(d, dtype=float) * (
        1.0 / refracted_cos(_cos("mu_i", mu_i), n) + 1.0 / refracted_cos(_cos("mu_o", mu_o), n)
    )
    return np.exp(-np.asarray(alpha, dtype=float) * l)


def linear_absorption(alpha_p: ArrayLike, mu_l: ArrayLike, mu_e: ArrayLike) -> np.ndarray:
    """Eq. 3: I/I0 = max(0, 1 - alpha' (1/N.L + 1/N.E)) (non-refracted cosines).

    Example
    -------
    >>> float(linear_absorption(0.1, 1.0, 0.5))
    0.7
    """
    return np.maximum(
        0.0, 1.0 - np.asarray(alpha_p, dtype=float) * (1.0 / _cos("mu_l", mu_l) + 1.0 / _cos("mu_e", mu_e))
    )


def bottom_fresnel(mu: ArrayLike, n1: ArrayLike, n2: ArrayLike) -> np.ndarray:
    """Eq. 4: F_bottom(n1, n2) = (1 - F(n1)) F(n2/n1) (1 - F(1/n1)) at the view cosine mu:
    in through the top (cosine mu), reflected by the bottom interface (refracted cosine),
    out through the top from inside (refracted cosine).

    Example
    -------
    >>> round(float(bottom_fresnel(1.0, 1.33333, 1.5)), 5)
    0.00332
    """
    mu = _cos("mu", mu)
    n1, n2 = _ior("n1", n1), _ior("n2", n2)
    mt = refracted_cos(mu, n1)
    return (1.0 - fresnel(mu, n1)) * fresnel(mt, n2 / n1) * (1.0 - fresnel(mt, 1.0 / n1))


def transmittance(mu: ArrayLike, n1: ArrayLike) -> np.ndarray:
    """Eq. 5, first line: F_transmittance(n1) = 1 - F(n1) at cosine mu.

    Example
    -------
    >>> round(float(transmittance(1.0, 1.5)), 6)
    0.96
    """
    return 1.0 - fresnel(_cos("mu", mu), _ior("n1", n1))


def bottom_fresnel_constant(n1: ArrayLike, n2: ArrayLike) -> np.ndarray:
    """Eq. 5, second line: F_bottom(n1, n2) = F0(n2/n1) (1 - F0(1/n1)).

    Example
    -------
    >>> round(float(bottom_fresnel_constant(1.33333, 1.5)), 6)
    0.00339
    """
    n1, n2 = _ior("n1", n1), _ior("n2", n2)
    return f0(n2 / n1) * (1.0 - f0(1.0 / n1))


def mirror_path_factor(mu_e: ArrayLike) -> np.ndarray:
    """Eq. 6: with N.L = N.E (mirror), 1/N.L + 1/N.E = 2/N.E.

    Example
    -------
    >>> float(mirror_path_factor(0.5))
    4.0
    """
    return 2.0 / _cos("mu_e", mu_e)


def ibl_specular_factor(alpha_p: ArrayLike, mu_e: ArrayLike, n1: ArrayLike, n2: ArrayLike) -> np.ndarray:
    """Eq. 7 without IBL_specular: F_bottom(n1, n2) max(0, 1 - alpha' 2/N.E) (Eq. 5's constant).

    Example
    -------
    >>> round(float(ibl_specular_factor(0.1, 1.0, 1.33333, 1.5)), 6)
    0.002712
    """
    return bottom_fresnel_constant(n1, n2) * np.maximum(
        0.0, 1.0 - np.asarray(alpha_p, dtype=float) * mirror_path_factor(mu_e)
    )


def hemispherical_path_factor(mu_r: ArrayLike) -> np.ndarray:
    """Eq. 8: int (1/cos theta_r + 1/cos theta_i) cos theta_i / pi dw_i = 2 + 1/cos theta_r.

    Example
    -------
    >>> float(hemispherical_path_factor(0.5))
    4.0
    """
    return 2.0 + 1.0 / _cos("mu_r", mu_r)


def ibl_diffuse_factor(alpha_p: ArrayLike, mu_e: ArrayLike, n1: ArrayLike, n2: ArrayLike) -> np.ndarray:
    """Eq. 9 without IBL_diffuse: (1 - F_bottom(n1, n2)) max(0, 1 - alpha' (2 + 1/N.E)).

    Example
    -------
    >>> round(float(ibl_diffuse_factor(0.1, 1.0, 1.33333, 1.5)), 6)
    0.697627
    """
    return (1.0 - bottom_fresnel_constant(n1, n2)) * np.maximum(
        0.0, 1.0 - np.asarray(alpha_p, dtype=float) * hemispherical_path_factor(mu_e)
    )


def layered_diffuse_albedo(mu: ArrayLike, n: ArrayLike, rho: ArrayLike, alpha_p: ArrayLike = 0.0) -> np.ndarray:
    """The diffuse albedo of Gotanda's layered model for a diffuse base under a dielectric
    top layer of index n (no bottom interface: F_bottom(n, n) = 0): Eq. 5's transmittance
    at the view times Eq. 9's absorption, rho (1 - F(mu; n)) max(0, 1 - alpha' (2 + 1/mu)).

    Example
    -------
    >>> round(float(layered_diffuse_albedo(1.0, 1.5, 0.8)), 6)
    0.768
    """
    return (
        np.asarray(rho, dtype=float)
        * transmittance(mu, n)
        * np.maximum(0.0, 1.0 - np.asarray(alpha_p, dtype=float) * hemispherical_path_factor(mu))
    )


def blinn_phong_diffuse_albedo(n: ArrayLike, rho: ArrayLike) -> np.ndarray:
    """The diffuse albedo of Eq. 1: rho (1 - F0(n)), the same at every angle.

    Example
    -------
    >>> round(float(blinn_phong_diffuse_albedo(1.5, 0.8)), 6)
    0.768
    """
    return np.asarray(rho, dtype=float) * (1.0 - f0(n))
