"""Gotanda 2012, "Beyond a simple physically based Blinn-Phong model in real-time" (SIGGRAPH
course notes), Section 3: the real-time Oren-Nayar approximations, implemented as printed.

- Eq. 20: QON rewritten with dot products (``simplified_qon``): algebraically identical to
  QON (EON paper Eq. 1-4), since min(1, N.L/N.E) = mu_i / max(mu_i, mu_o).
- Eq. 21: sigma = sqrt(2 / shininess) (``sigma_from_shininess``); Eq. 22-23: Eq. 20 with it
  substituted, 1/(2 + 0.33 shi) and 1/(2.22222 + 0.1 shi) (``shininess_qon``).
- Eq. 24: the "slightly improved" model (``improved_unsigned``): 0.65 in A and no max(0, .).
- Eq. 25: the "improved" model with the sign-dependent branch: the library's ``gotanda`` lobe
  (``improved``, which calls ``od.evaluate("gotanda")``).
- Eq. 27, 28: the scale of the SH DC coefficient (``dc_scale_eq27``, ``dc_scale_eq28``);
  the exact quantity is the directional albedo of the Eq. 25 lobe, E(mu_o) (``exact_dc_scale``).
- Eq. 29: the scale of the linear SH coefficients (``linear_scale_eq29``); the exact quantity
  is the response of the lobe to linear lighting along the normal relative to Lambert's,
  T_10 / ((2/3) Y_10(n)) (``exact_linear_scale``).

All BRDF functions return f (no cosine): Gotanda's L_r divided by E0 (N.L).
f(shi) = 1 - 1/(2 + 0.65 shi) and g(shi) = 1/(2.22222 + 0.1 shi) of Eq. 27 are the A and B
of Eq. 24-25 (shi = 2/sigma^2).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _arrays as ar

HALF_PI = 0.5 * math.pi
SIGMA_MAX = HALF_PI


def _dirs_sigma_rho(
    wi: ArrayLike, wo: ArrayLike, sigma: ArrayLike, rho: ArrayLike
) -> tuple[tuple[int, ...], NDArray[Any], NDArray[Any], NDArray[Any], NDArray[Any], NDArray[Any]]:
    wi = ar.directions("wi", wi, np.float64)
    wo = ar.directions("wo", wo, np.float64)
    sigma = ar.in_range("sigma", sigma, np.float64, 0.0, SIGMA_MAX, " (radians)")
    rho = ar.rho_array("rho", rho, np.float64)
    lead = ar.broadcast_leading(wi=wi.shape[:-1], wo=wo.shape[:-1], sigma=sigma.shape, rho=rho.shape[:-1])
    mu_i, mu_o = wi[..., 2], wo[..., 2]
    el = np.sum(wi * wo, axis=-1)
    return lead, mu_i, mu_o, el, sigma, rho


def _finish(lead, value, mu_i, mu_o, rho):
    """f = rho/pi * value above the horizon, 0 below; shape lead + (C,)."""
    up = (mu_i > 0.0) & (mu_o > 0.0)
    v = np.where(up, value, 0.0)
    return np.broadcast_to(v, lead)[..., None] * rho / math.pi


def sigma_from_shininess(shininess: ArrayLike) -> NDArray[np.float64]:
    """Eq. 21: sigma = sqrt(2 / shininess).

    Parameters
    ----------
    shininess : array_like
        Blinn-Phong exponent, > 0 (shininess >= 8/pi^2 = 0.81 gives sigma <= pi/2).

    Examples
    --------
    >>> float(sigma_from_shininess(2.0))
    1.0
    """
    shi = ar.in_range(
        "shininess", shininess, np.float64, 0.0, math.inf, " (Blinn-Phong exponent)", lo_open=True, hi_open=True
    )
    return np.sqrt(2.0 / shi)


def simplified_qon(wi: ArrayLike, wo: ArrayLike, sigma: ArrayLike, rho: ArrayLike = 1.0) -> NDArray[np.float64]:
    """Eq. 20: QON in dot products, f = rho/pi [A + B max(0, E.L - (N.E)(N.L)) min(1, N.L/N.E) / N.L].

    A = 1 - 0.5 sigma^2/(sigma^2 + 0.33), B = 0.45 sigma^2/(sigma^2 + 0.09).  Identical to
    QON (the grading measures the rounding difference and the distance to fullON).

    Parameters
    ----------
    wi, wo : array_like, shape (..., 3)
        Unit directions to the light (L) and the viewer (E), local frame (N = +z).
    sigma : array_like, shape (...)
        Roughness in radians, [0, pi/2].
    rho : array_like, shape (..., C)

    Returns
    -------
    ndarray, shape broadcast(...) + (C,): the BRDF (Gotanda's L_r / (E0 N.L)).

    Examples
    --------
    >>> import numpy as np, openpbr_diffuse as od
    >>> wi, wo = np.array([0.6, 0.0, 0.8]), np.array([0.0, 0.6, 0.8])
    >>> bool(np.isclose(simplified_qon(wi, wo, 0.5)[0], od.evaluate("qon", wi, wo, 0.5)[0]))
    True
    """
    lead, mu_i, mu_o, el, sigma, rho = _dirs_sigma_rho(wi, wo, sigma, rho)
    s2 = sigma * sigma
    A = 1.0 - 0.5 * s2 / (s2 + 0.33)
    B = 0.45 * s2 / (s2 + 0.09)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.minimum(1.0, mu_i / mu_o) / mu_i  # min(1, N.L/N.E) / N.L
    value = A + B * np.maximum(0.0, el - mu_o * mu_i) * ratio
    return _finish(lead, value, mu_i, mu_o, rho)


def _shininess_of(sigma):
    with np.errstate(divide="ignore"):
        return 2.0 / (sigma * sigma)


def shininess_qon(wi: ArrayLike, wo: ArrayLike, shininess: ArrayLike, rho: ArrayLike = 1.0) -> NDArray[np.float64]:
    """Eq. 23: Eq. 20 with sigma = sqrt(2/shininess) substituted (Eq. 21-22).

    f = rho/pi [1 - 1/(2 + 0.33 shi) + max(0, s) min(1, N.L/N.E) / (N.L (2.22222 + 0.1 shi))].
    Equal to Eq. 20 except for 2.22222 in place of 1/0.45 = 2.2222...

    Parameters
    ----------
    shininess : array_like, shape (...)
        Blinn-Phong exponent, > 0 (sigma = sqrt(2/shi); sigma <= pi/2 for shi >= 8/pi^2).
    """
    shi = np.asarray(shininess, dtype=np.float64)
    sigma = sigma_from_shininess(shi)  # checks shininess > 0 (any value is valid here)
    lead, mu_i, mu_o, el, _, rho = _dirs_sigma_rho(wi, wo, np.zeros_like(sigma), rho)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.minimum(1.0, mu_i / mu_o) / mu_i
    value = 1.0 - 1.0 / (2.0 + 0.33 * shi) + np.maximum(0.0, el - mu_o * mu_i) * ratio / (2.22222 + 0.1 * shi)
    return _finish(lead, value, mu_i, mu_o, rho)


def improved_unsigned(wi: ArrayLike, wo: ArrayLike, sigma: ArrayLike, rho: ArrayLike = 1.0) -> NDArray[np.float64]:
    """Eq. 24: f = rho/pi [1 - 1/(2 + 0.65 shi) + (E.L - (N.E)(N.L)) min(1, N.L/N.E) / (N.L (2.22222 + 0.1 shi))].

    The "slightly improved" model: 0.65 in A (A = 1 - 0.5 sigma^2/(sigma^2 + 0.65)) and the
    max(0, .) of Eq. 23 removed, so backward lighting (s < 0) darkens.  It can go negative
    (s < 0 with large B), as the grading reports.

    Parameters
    ----------
    sigma : array_like, shape (...)
        Roughness in radians, [0, pi/2] (shi = 2/sigma^2).
    """
    lead, mu_i, mu_o, el, sigma, rho = _dirs_sigma_rho(wi, wo, sigma, rho)
    shi = _shininess_of(sigma)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.minimum(1.0, mu_i / mu_o) / mu_i
        A = np.where(sigma > 0.0, 1.0 - 1.0 / (2.0 + 0.65 * shi), 1.0)
        B = np.where(sigma > 0.0, 1.0 / (2.22222 + 0.1 * shi), 0.0)
    value = A + B * (el - mu_o * mu_i) * ratio
    return _finish(lead, value, mu_i, mu_o, rho)


def improved(wi: ArrayLike, wo: ArrayLike, sigma: ArrayLike, rho: ArrayLike = 1.0) -> NDArray[np.float64]:
    """Eq. 25: the improved, sign-dependent model; the library lobe ``od.evaluate("gotanda")``.

    f = rho/pi (A + B s/t), A = 1 - 0.5 sigma^2/(sigma^2 + 0.65), B = 0.45 sigma^2/(sigma^2 + 0.09),
    t = max(N.L, N.E) if s >= 0 else 1 (FON's t).  The lobe uses 1/0.45 where the notes print
    2.22222 (relative difference 1e-6 in B).
    """
    from ..models import evaluate

    return evaluate("gotanda", wi, wo, sigma, rho)


def _fg(sigma):
    """f(shi), g(shi) of Eq. 27 at shi = 2/sigma^2 (the A, B of Eq. 24-25)."""
    shi = _shininess_of(sigma)
    with np.errstate(divide="ignore", invalid="ignore"):
        f = np.where(sigma > 0.0, 1.0 - 1.0 / (2.0 + 0.65 * shi), 1.0)
        g = np.where(sigma > 0.0, 1.0 / (2.22222 + 0.1 * shi), 0.0)
    return f, g


def _mu_sigma(mu_o: ArrayLike, sigma: ArrayLike) -> tuple[NDArray[Any], NDArray[Any]]:
    mu_o = ar.in_range("mu_o", mu_o, np.float64, 0.0, 1.0, " (N.E, cosine of the view angle)")
    sigma = ar.in_range("sigma", sigma, np.float64, 0.0, SIGMA_MAX, " (radians)")
    ar.broadcast_leading(mu_o=mu_o.shape, sigma=sigma.shape)
    return mu_o, sigma


def dc_scale_eq27(mu_o: ArrayLike, sigma: ArrayLike) -> NDArray[np.float64]:
    """Eq. 27: SH'_DC / SH_DC = f(shi) + (1/2) g(shi) (1 + 2 arccos(N.E)/pi - N.E).

    Approximates the directional albedo E(mu_o) of the Eq. 25 lobe at rho = 1 (Eq. 26, the
    integral Gotanda fitted).  As printed it reaches f + g at grazing, where the exact value
    is f + (1/2 - 2/(3 pi)) g (see the README erratum).

    Parameters
    ----------
    mu_o : array_like
        N.E in [0, 1].
    sigma : array_like
        Roughness in radians, [0, pi/2] (shi = 2/sigma^2).

    Examples
    --------
    >>> float(dc_scale_eq27(1.0, 0.0))
    1.0
    """
    mu_o, sigma = _mu_sigma(mu_o, sigma)
    f, g = _fg(sigma)
    return f + 0.5 * g * (1.0 + 2.0 * np.arccos(mu_o) / math.pi - mu_o)


def dc_scale_eq28(mu_o: ArrayLike, sigma: ArrayLike) -> NDArray[np.float64]:
    """Eq. 28: SH'_DC / SH_DC = f(shi) + g(shi) (1 - N.E) (the cheaper form of Eq. 27)."""
    mu_o, sigma = _mu_sigma(mu_o, sigma)
    f, g = _fg(sigma)
    return f + g * (1.0 - mu_o)


def linear_scale_eq29(mu_o: ArrayLike, sigma: ArrayLike) -> NDArray[np.float64]:
    """Eq. 29: SH'_linear / SH_linear = S(shi, N.E) = f(shi) + (f(shi) - 1)(1 - N.E).

    1 at sigma = 0; at sigma = 1, f = 0.697: S = 0.697 at N.E = 1 and 0.394 at N.E = 0.
    """
    mu_o, sigma = _mu_sigma(mu_o, sigma)
    f, _ = _fg(sigma)
    return f + (f - 1.0) * (1.0 - mu_o)


def exact_dc_scale(mu_o: ArrayLike, sigma: ArrayLike, model: str = "gotanda", *, n: int = 24) -> NDArray[np.float64]:
    """The exact DC scale: T_00 / (Lambert's T_00) = E(mu_o) of the lobe at rho = 1, by quadrature.

    ``model`` is "gotanda" (Eq. 25, what Eq. 27 fits) or "full_on" (at rho = 1).
    """
    from .sh import C0, lobe_transfer

    mu_o, sigma = _mu_sigma(mu_o, sigma)
    return lobe_transfer(model, mu_o, sigma, 1.0, n=n)[..., 0, 0] / C0


def exact_linear_scale(
    mu_o: ArrayLike, sigma: ArrayLike, model: str = "gotanda", *, n: int = 24, tangential: bool = False
) -> NDArray[np.float64] | tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The exact linear scale: T_10 / ((2/3) Y_10) (the response to linear light along N relative to
    Lambert's), by quadrature; with ``tangential`` also T_11 / ((2/3) C1), the part along the
    view's tangent that a scale of SH_linear cannot represent (Gotanda's "bent normal").
    """
    from .sh import C1, lobe_transfer

    mu_o, sigma = _mu_sigma(mu_o, sigma)
    T = lobe_transfer(model, mu_o, sigma, 1.0, n=n)[..., 0]
    s = T[..., 2] / (2.0 / 3.0 * C1)
    return (s, T[..., 3] / (2.0 / 3.0 * C1)) if tangential else s
