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
