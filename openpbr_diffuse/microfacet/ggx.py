"""GGX microfacet reflection: distribution, Smith masking-shadowing, sampling.

Frame and conventions (stated once): local shading frame with the normal +z; ``wo`` (to
the viewer) and ``wi`` (to the light) point away from the surface; ``h`` is the half vector
normalize(wi + wo); ``alpha`` is the GGX width (OpenPBR: alpha = specular_roughness^2).
All functions are NumPy ufunc-style: leading axes broadcast, directions have a trailing
axis of 3, scalars per direction have none.

Microfacet model (Walter et al. 2007; Heitz 2014):

- GGX normal distribution D(h) = alpha^2 / (pi (mu_h^2 (alpha^2 - 1) + 1)^2)   (W07 Eq. 33)
- Smith Lambda(w) = (-1 + sqrt(1 + alpha^2 tan^2 theta)) / 2   (H14, GGX's Lambda)
- masking G1(w) = 1 / (1 + Lambda(w)) (W07 Eq. 34); height-correlated masking-shadowing
  G2(wi, wo) = 1 / (1 + Lambda(wi) + Lambda(wo))                 (H14, height-correlated G2)
- f(wi, wo) = F(wo.h) D(h) G2 / (4 mu_i mu_o)                                   (W07 Eq. 20)

Sampling: visible normals (Heitz 2018, "Sampling the GGX distribution of visible normals",
JCGT 7(4), Listing 1) with pdf(wi) = G1(wo) D(h) / (4 mu_o), or the plain NDF
(W07 Eq. 35-36) with pdf(wi) = D(h) mu_h / (4 wo.h).  Both are densities of the reflected
direction over the whole sphere: a reflection below the horizon is a valid sample whose
BRDF value is 0, so the VNDF pdf integrates to 1 over the sphere, not the hemisphere.  An
NDF-sampled h with wo.h <= 0 reflects nothing (the sample fails, pdf 0): the NDF pdf
integrates to the probability of success.

References
----------
Walter, Marschner, Li, Torrance, "Microfacet models for refraction through rough
surfaces", EGSR 2007 (W07).  Heitz, "Understanding the masking-shadowing function in
microfacet-based BRDFs", JCGT 3(2), 2014 (H14).  Heitz, JCGT 7(4), 2018.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Smallest GGX alpha used.  alpha = 0 is a mirror (a delta lobe with no density); like
#: the OpenPBR viewer we clamp instead of adding a degenerate branch.
ALPHA_MIN = 1e-4

SAMPLING_METHODS = ("vndf", "ndf")


def alpha_of(roughness: ArrayLike) -> NDArray[np.float64]:
    """GGX alpha = max(roughness^2, ALPHA_MIN) (OpenPBR's perceptual mapping)."""
    return np.maximum(np.square(np.asarray(roughness, dtype=np.float64)), ALPHA_MIN)


def _dot(a, b):
    return np.einsum("...k,...k->...", a, b)


def _normalize(v):
    n = np.sqrt(_dot(v, v))
    with np.errstate(invalid="ignore", divide="ignore"):
        return v / n[..., None], n


# --------------------------------------------------------------------------- microfacets
def ndf(mu_h: float | NDArray[np.floating[Any]], alpha: float | NDArray[np.floating[Any]]) -> NDArray[np.float64]:
    """GGX D(h) for the cosine mu_h = h.z (0 for mu_h <= 0)."""
    a2 = np.square(alpha)
    c2 = np.square(mu_h)
    d = c2 * (a2 - 1.0) + 1.0
    return np.where(mu_h > 0.0, a2 / (math.pi * d * d), 0.0)


def smith_lambda(
    mu: float | NDArray[np.floating[Any]], alpha: float | NDArray[np.floating[Any]]
) -> NDArray[np.float64]:
    """Smith Lambda for GGX, written with alpha^2 tan^2 = alpha^2 (1 - mu^2)/mu^2 (mu > 0)."""
    mu2 = np.square(mu)
    with np.errstate(divide="ignore", invalid="ignore"):
        t2 = np.square(alpha) * (1.0 - mu2) / mu2
    return 0.5 * (np.sqrt(1.0 + t2) - 1.0)


def smith_g1(mu: float | NDArray[np.floating[Any]], alpha: float | NDArray[np.floating[Any]]) -> NDArray[np.float64]:
    """Masking G1 = 1/(1 + Lambda); 0 for mu <= 0."""
    with np.errstate(divide="ignore", invalid="ignore"):
        g = 1.0 / (1.0 + smith_lambda(mu, alpha))
    return np.where(mu > 0.0, g, 0.0)


def smith_g2(
    mu_i: float | NDArray[np.floating[Any]],
    mu_o: float | NDArray[np.floating[Any]],
    alpha: float | NDArray[np.floating[Any]],
) -> NDArray[np.float64]:
    """Height-correlated masking-shadowing G2 = 1/(1 + Lambda_i + Lambda_o); 0 below the horizon."""
    ok = (mu_i > 0.0) & (mu_o > 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        g = 1.0 / (1.0 + smith_lambda(mu_i, alpha) + smith_lambda(mu_o, alpha))
    return np.where(ok, g, 0.0)


def half_vector(wi: ArrayLike, wo: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(h, wo.h); h = normalize(wi + wo), undefined (NaN-free zeros) when wi = -wo."""
    h, n = _normalize(np.asarray(wi) + np.asarray(wo))
    h = np.where((n > 0.0)[..., None], h, 0.0)
    return h, _dot(wo, h)


def microfacet_terms(
    wi: ArrayLike, wo: ArrayLike, alpha: float | NDArray[np.floating[Any]]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Return (D G2 / (4 mu_i mu_o), wo.h): the BRDF without its Fresnel factor.

    The first term is 0 unless both directions are above the horizon and the half vector
    faces the normal.
    """
    wi = np.asarray(wi, dtype=np.float64)
    wo = np.asarray(wo, dtype=np.float64)
    mu_i, mu_o = wi[..., 2], wo[..., 2]
    h, c = half_vector(wi, wo)
    ok = (mu_i > 0.0) & (mu_o > 0.0) & (h[..., 2] > 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        val = ndf(h[..., 2], alpha) * smith_g2(mu_i, mu_o, alpha) / (4.0 * mu_i * mu_o)
    return np.where(ok, val, 0.0), np.clip(c, 0.0, 1.0)


# --------------------------------------------------------------------------- sampling
def _reflect(wo, h):
    return 2.0 * _dot(wo, h)[..., None] * h - wo


def sample_vndf_normal(
    wo: NDArray[np.floating[Any]],
    alpha: ArrayLike,
    u1: float | NDArray[np.floating[Any]],
    u2: float | NDArray[np.floating[Any]],
) -> NDArray[np.float64]:
    """Visible-normal sample h for wo (mu_o > 0), Heitz 2018 Listing 1."""
    a = np.asarray(alpha, dtype=np.float64)
    Vh, _ = _normalize(np.stack([a * wo[..., 0], a * wo[..., 1], wo[..., 2]], axis=-1))
    lensq = Vh[..., 0] ** 2 + Vh[..., 1] ** 2
    inv = np.where(lensq > 0.0, 1.0 / np.sqrt(np.where(lensq > 0.0, lensq, 1.0)), 0.0)
    T1 = np.where(
        (lensq > 0.0)[..., None],
        np.stack([-Vh[..., 1] * inv, Vh[..., 0] * inv, np.zeros_like(inv)], axis=-1),
        np.array([1.0, 0.0, 0.0]),
    )
    T2 = np.cross(Vh, T1)
    r = np.sqrt(u1)
    phi = 2.0 * math.pi * u2
    t1 = r * np.cos(phi)
    t2 = r * np.sin(phi)
    s = 0.5 * (1.0 + Vh[..., 2])
    t2 = (1.0 - s) * np.sqrt(np.maximum(0.0, 1.0 - t1 * t1)) + s * t2
    Nh = t1[..., None] * T1 + t2[..., None] * T2 + np.sqrt(np.maximum(0.0, 1.0 - t1 * t1 - t2 * t2))[..., None] * Vh
    Ne, _ = _normalize(np.stack([a * Nh[..., 0], a * Nh[..., 1], np.maximum(0.0, Nh[..., 2])], axis=-1))
    return Ne


def sample_ndf_normal(
    alpha: float | NDArray[np.floating[Any]],
    u1: float | NDArray[np.floating[Any]],
    u2: float | NDArray[np.floating[Any]],
) -> NDArray[np.float64]:
    """h distributed as D(h) mu_h: tan^2 theta_h = alpha^2 u1/(1 - u1), phi = 2 pi u2 (W07 Eq. 35-36)."""
    a2 = np.square(alpha)
    cos2 = (1.0 - u1) / (1.0 + (a2 - 1.0) * u1)
    ct = np.sqrt(cos2)
    st = np.sqrt(np.maximum(0.0, 1.0 - cos2))
    phi = 2.0 * math.pi * u2
    return np.stack([st * np.cos(phi), st * np.sin(phi), ct], axis=-1)


def reflection_pdf(
    wo: ArrayLike, wi: ArrayLike, alpha: float | NDArray[np.floating[Any]], method: str = "vndf"
) -> NDArray[np.float64]:
    """Solid-angle pdf of the reflected direction wi (whole sphere) given wo.

    vndf: G1(wo) D(h) / (4 mu_o);  ndf: D(h) mu_h / (4 wo.h).  0 if mu_o <= 0 or the half
    vector is below the horizon (no microfacet produces that reflection).
    """
    wo = np.asarray(wo, dtype=np.float64)
    h, c = half_vector(wi, wo)
    mu_o = wo[..., 2]
    D = ndf(h[..., 2], alpha)
    with np.errstate(divide="ignore", invalid="ignore"):
        if method == "vndf":
            p = smith_g1(mu_o, alpha) * D / (4.0 * mu_o)
        else:
            p = D * h[..., 2] / (4.0 * c)
    return np.where((mu_o > 0.0) & (c > 0.0) & (h[..., 2] > 0.0), p, 0.0)


def sample_reflection(
    wo: ArrayLike,
    alpha: float | NDArray[np.floating[Any]],
    u1: float | NDArray[np.floating[Any]],
    u2: float | NDArray[np.floating[Any]],
    method: str = "vndf",
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Return (wi, pdf): wi = reflect(wo, h) with h from the visible normals or the NDF.

    wi may lie below the horizon (the BRDF is then 0; the pdf is still reported).  pdf = 0
    marks a failed sample: mu_o <= 0 (wi is then the normal), or an NDF-sampled h with
    wo.h <= 0.
    """
    wo = np.asarray(wo, dtype=np.float64)
    if method == "vndf":
        h = sample_vndf_normal(wo, alpha, u1, u2)
    elif method == "ndf":
        h = sample_ndf_normal(np.broadcast_to(alpha, np.shape(u1)), u1, u2)
    else:
        raise ValueError(f"specular_sampling must be one of {', '.join(SAMPLING_METHODS)}; got {method!r}")
    wi = _reflect(wo, h)
    wi, _ = _normalize(wi)  # removes rounding drift; |reflect| = 1 analytically
    pdf = reflection_pdf(wo, wi, alpha, method)
    ok = wo[..., 2] > 0.0
    wi = np.where(ok[..., None], wi, np.array([0.0, 0.0, 1.0]))
    return wi, np.where(ok, pdf, 0.0)
