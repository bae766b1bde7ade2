"""First-order BRDF of a Smith microsurface of Lambertian microfacets by quadrature over the
microfacet normals, independent of the random walk: Lambda by integrating the projected
area of D, and the height-correlated shadowing-masking 1 / (1 + Lambda_i + Lambda_o)
(Heitz 2014, "Understanding the masking-shadowing function", Eq. 99 for uniform heights)."""

import numpy as np


def _grid(n_theta=600, n_phi=720):
    x, w = np.polynomial.legendre.leggauss(n_theta)
    th = 0.25 * np.pi * (x + 1.0)
    wth = 0.25 * np.pi * w
    ph = (np.arange(n_phi) + 0.5) * 2.0 * np.pi / n_phi
    T, P = np.meshgrid(th, ph, indexing="ij")
    m = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], axis=-1)
    dA = (wth[:, None] * np.sin(T)) * (2.0 * np.pi / n_phi)
    return m, dA


def ndf(dist, alpha, cos_t):
    c2 = cos_t * cos_t
    t2 = (1.0 - c2) / c2
    if dist == "beckmann":
        return np.exp(-t2 / alpha**2) / (np.pi * alpha**2 * c2 * c2)
    return alpha**2 / (np.pi * c2 * c2 * (alpha**2 + t2) ** 2)


def first_order_brdf(dist, alpha, wi, wo):
    m, dA = _grid()
    D = ndf(dist, alpha, m[..., 2]) * dA
    norm = np.sum(D * m[..., 2])
    lam = lambda w: np.sum(D * np.maximum(m @ w, 0.0)) / w[2] - 1.0
    G2 = 1.0 / (1.0 + lam(wi) + lam(wo))
    f = np.sum(D * np.maximum(m @ wi, 0.0) * np.maximum(m @ wo, 0.0)) / np.pi
    return f * G2 / (wi[2] * wo[2]), norm
