"""Test-side Gauss-Legendre quadrature: the one Gauss-Legendre helper of the test suite
(``gauss_legendre``) and a hemisphere rule for BRDFs built on it.

Written independently of the library's albedo code: it only calls ``evaluate``.  The
integrand is smooth in (theta_i, phi) except at theta_i = theta_o (the max(mu_i, mu_o)
switch) and at |phi| = pi/2 (the sign of s), so the panels are split there; with wo in the
xz-plane the integrand is even in phi and phi in [0, pi] suffices.
"""

import numpy as np

import openpbr_diffuse as od


def gauss_legendre(lo, hi, n):
    """Gauss-Legendre nodes and weights of order n on [lo, hi].

    ``lo``, ``hi`` may be arrays (they broadcast); the nodes are on a new last axis, so
    ``gauss_legendre(edges[:-1], edges[1:], n)`` gives one rule per panel, shape (P, n).
    """
    x, w = np.polynomial.legendre.leggauss(n)
    lo, hi = np.asarray(lo, dtype=np.float64)[..., None], np.asarray(hi, dtype=np.float64)[..., None]
    return 0.5 * (lo + hi) + 0.5 * (hi - lo) * x, 0.5 * (hi - lo) * w


def _panels(edges, n):
    """Nodes and weights of order n on each non-empty panel of ``edges``, concatenated."""
    edges = np.asarray(edges, dtype=np.float64)
    keep = edges[1:] > edges[:-1]
    x, w = gauss_legendre(edges[:-1][keep], edges[1:][keep], n)
    return x.ravel(), w.ravel()


def hemisphere_grid(mu_o, n=48):
    """Directions wi (n_t, n_p, 3) and weights for  int f(wi) mu_i dwi  (phi folded by 2)."""
    theta_o = np.arccos(np.clip(mu_o, 0.0, 1.0))
    t, wt = _panels([0.0, theta_o, 0.5 * np.pi], n)
    p, wp = _panels([0.0, 0.5 * np.pi, np.pi], n)
    T, P = np.meshgrid(t, p, indexing="ij")
    wi = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], axis=-1)
    weight = 2.0 * np.outer(wt, wp) * np.cos(T) * np.sin(T)
    return wi, weight


def wo_of(mu_o):
    return np.array([np.sqrt(max(0.0, 1.0 - mu_o * mu_o)), 0.0, mu_o])


def quad_albedo(model, mu_o, roughness, rho=1.0, n=48, **kw):
    """E(mu_o) of ``model`` by quadrature of its ``evaluate``; shape (C,)."""
    wi, weight = hemisphere_grid(mu_o, n)
    f = od.evaluate(model, wi, wo_of(mu_o), roughness, rho, **kw)
    return np.einsum("tpc,tp->c", f, weight)


def quad_average(model, roughness, rho=1.0, n=48, n_mu=48, **kw):
    """<E> = 2 int_0^1 E(mu) mu dmu, Gauss-Legendre in theta_o (E is smooth in theta)."""
    t, w = _panels([0.0, 0.5 * np.pi], n_mu)
    total = 0.0
    for ti, wti in zip(t, w):
        total = total + wti * 2.0 * np.cos(ti) * np.sin(ti) * quad_albedo(model, np.cos(ti), roughness, rho, n, **kw)
    return total


def sphere_rule(mu_o, n=64):
    """Directions (T, P, 3) and weights for  int g(wi) dwi  over the whole sphere, wo in the
    xz-plane at cos(theta_o) = mu_o (integrands even in phi: phi in [0, pi], doubled).

    Panel edges in theta at theta_o (the reflection peak), pi/2 (the horizon) and
    pi - theta_o (the mirrored peak below, and where the GGX half vector reaches the
    horizon); in phi at pi/2 and 0.9 pi (towards the peaks at phi = pi).
    """
    th_o = float(np.arccos(np.clip(mu_o, 0.0, 1.0)))
    t, wt = _panels(np.unique([0.0, th_o, 0.5 * np.pi, np.pi - th_o, np.pi]), n)
    p, wp = _panels([0.0, 0.5 * np.pi, 0.9 * np.pi, np.pi], n)
    T, P = np.meshgrid(t, p, indexing="ij")
    wi = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], axis=-1)
    return wi, 2.0 * np.outer(wt, wp) * np.sin(T)
