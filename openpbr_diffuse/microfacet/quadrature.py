"""Directional albedo of a GGX lobe by half-vector quadrature (generates the shipped tables).

Independent of the samplers and of ``ggx.microfacet_terms`` (only ``ggx.smith_g2`` is
shared); ``tools/make_specular_table.py`` drives it and ``tests/test_ggx.py`` grades it
against a spherical-coordinate quadrature of the BRDF.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .ggx import smith_g2


def _gauss(a, b, n):
    x, w = np.polynomial.legendre.leggauss(n)
    a = np.asarray(a, dtype=np.float64)[..., None]
    b = np.asarray(b, dtype=np.float64)[..., None]
    return 0.5 * (a + b) + 0.5 * (b - a) * x, 0.5 * (b - a) * w


def _phi_panels(mu_o, so):
    """Panel edges in phi on [0, pi], graded towards pi/2.

    The horizon cut theta_max(phi) = (delta + pi/2)/2 with delta = atan2(so cos phi, mu_o)
    swings from ~pi/2 to ~0 within |phi - pi/2| ~ mu_o/so: at grazing mu_o that is a
    near-step, resolved by panels of width (mu_o/so) 4^k on both sides of pi/2.
    """
    half = 0.5 * math.pi
    widths = []
    w = mu_o / max(so, 1e-300)
    while w < 0.25 * math.pi:
        widths.append(w)
        w *= 4.0
    inner = [half - w for w in reversed(widths)] + [half] + [half + w for w in widths]
    return np.array([0.0] + inner + [math.pi])


def _v_of_theta(theta, alpha):
    """v = 1 - sqrt(1 - t(theta)) = 1 - alpha cos / sqrt(alpha^2 cos^2 + sin^2) (t: GGX CDF)."""
    c, s = np.cos(theta), np.sin(theta)
    return 1.0 - alpha * c / np.sqrt(alpha * alpha * c * c + s * s)


def albedo_quadrature(
    mu_o: float, alpha: float, fresnels: Callable[[NDArray[np.float64]], ArrayLike], n_t: int = 64, n_phi: int = 64
) -> NDArray[np.float64]:
    """Directional albedos int F D G2/(4 mu_i mu_o) mu_i dwi of one GGX lobe for several F.

    Half-vector quadrature, independent of the samplers and of ``microfacet_terms``: with dwi = 4 (wo.h) dh and
    t = CDF of D(h) mu_h in theta_h (tan^2 theta_h = alpha^2 t/(1 - t)),

        E(mu_o) = (1/2pi) int_0^2pi int_0^1 F(wo.h) G2 (wo.h) / (mu_o mu_h) dt dphi .

    Every source of non-smoothness is put on a panel edge, so Gauss-Legendre converges fast:

    - the horizon: for each phi_h the reflected direction is above the horizon exactly for
      theta_h < (delta + pi/2)/2, delta = atan2(sin theta_o cos phi_h, mu_o) (mu_i =
      R cos(2 theta_h - delta)): the t-range is cut there;
    - 1/mu_h ~ 1/sqrt(1 - t) as theta_h -> pi/2 (grazing mu_o): t = 1 - (1 - v)^2;
    - the near-step of that cut in phi at grazing mu_o: graded phi panels (``_phi_panels``).

    F must be smooth in wo.h (true for eta >= 1; total internal reflection, eta < 1, puts a
    kink inside the panels and slows convergence).

    The integrand is even in phi: phi in [0, pi], doubled.

    Parameters
    ----------
    mu_o, alpha : float
    fresnels : callable
        ``fresnels(c)`` -> array (K, ...) of K Fresnel-like factors at cosines c = wo.h.
    n_t, n_phi : int
        Gauss-Legendre orders per panel.

    Returns
    -------
    ndarray (K,)
    """
    mu_o = float(mu_o)
    alpha = float(alpha)
    so = math.sqrt(max(0.0, 1.0 - mu_o * mu_o))
    pe = _phi_panels(mu_o, so)
    phi, wphi = _gauss(pe[:-1], pe[1:], n_phi)
    phi, wphi = phi.ravel(), wphi.ravel()
    cphi = np.cos(phi)
    delta = np.arctan2(so * cphi, mu_o)
    theta_max = 0.5 * (delta + 0.5 * math.pi)
    edges = np.stack([np.zeros_like(phi), theta_max], axis=-1)  # (P, 2)
    ve = _v_of_theta(edges, alpha)
    v, wv = _gauss(ve[:, :-1], ve[:, 1:], n_t)  # (P, E-1, n_t)
    v = v.reshape(len(phi), -1)
    w = wv.reshape(len(phi), -1) * wphi[:, None] * 2.0 * (1.0 - v)  # dt = 2 (1 - v) dv
    one_v = 1.0 - v
    u = alpha * alpha * v * (2.0 - v) / np.square(one_v)  # tan^2 theta_h
    mu_h = 1.0 / np.sqrt(1.0 + u)
    sin_h = np.sqrt(u) * mu_h
    h = np.stack([sin_h * cphi[:, None], sin_h * np.sin(phi)[:, None], mu_h], axis=-1)
    c = h @ np.array([so, 0.0, mu_o])
    mu_i = 2.0 * c * mu_h - mu_o
    g = smith_g2(mu_i, mu_o, alpha) * c / (mu_o * mu_h)
    F = np.asarray(fresnels(np.clip(c, 0.0, 1.0)))
    # 1/(2 pi) of the phi average, times 2 for phi in [pi, 2 pi]
    return np.einsum("kpt,pt->k", F * g, w) / math.pi
