"""Order-2 spherical-harmonics (SH) lighting of any lobe: basis, zonal rotation, exact transfer.

Real SH up to l = 2 (9 coefficients) in the ordering and normalisation of Ramamoorthi and
Hanrahan 2001 / Sloan 2008 (the ``Ylm`` listing of the energy-compensation post):

    index  0    1       2       3       4        5        6               7        8
    Y      c0   c1 y    c1 z    c1 x    c2 xy    c2 yz    c3 (3z^2 - 1)   c2 xz    c2/2 (x^2 - y^2)

c0 = 1/(2 sqrt(pi)), c1 = sqrt(3/(4 pi)), c2 = sqrt(15/(4 pi)), c3 = sqrt(5/(16 pi)).

An environment L(w) = sum_k L_k Y_k(w) lights a lobe f with the outgoing radiance

    L_o(wo) = int_{H+} L(wi) f(wi, wo) mu_i dwi = sum_k L_k T_k(wo),
    T_k(wo) = int_{H+} Y_k(wi) f(wi, wo) mu_i dwi                         (the transfer vector)

``lobe_transfer`` computes T_k exactly (Gauss-Legendre quadrature of ``od.evaluate``, panels
split at the lobe's kinks) in the local frame with wo in the xz-plane; ``rotate`` turns it into
any frame; ``zh_project`` gives the zonal-harmonic (ZH) coefficients of a function of mu_i
alone (Lambert's cosine, the multiple-scattering lobe of Kulla-Conty), and ``zh_rotate`` the
full SH vector of a ZH lobe about a direction n (Sloan 2008: E_lm = sqrt(4 pi/(2l+1)) E_l Y_lm(n)).
These are the exact quantities that Gotanda's DC / linear scales (Eq. 27-29) and the post's
E0, E1, E2 fits approximate.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _arrays as ar

C0 = 0.5 / math.sqrt(math.pi)
C1 = math.sqrt(3.0 / (4.0 * math.pi))
C2 = math.sqrt(15.0 / (4.0 * math.pi))
C3 = math.sqrt(5.0 / (16.0 * math.pi))
#: Band of each of the 9 coefficients.
BAND = np.array([0, 1, 1, 1, 2, 2, 2, 2, 2])
#: sqrt(4 pi / (2l + 1)) per band (the ZH rotation factor).
ZH_ROTATION = np.sqrt(4.0 * math.pi / (2.0 * np.arange(3) + 1.0))
#: Lambert's (rho = 1) response per band, A_l / pi with A_0 = pi, A_1 = 2 pi/3, A_2 = pi/4
#: (Ramamoorthi-Hanrahan 2001): its transfer vector is LAMBERT_BAND_SCALE[band] * Y_k(n).
LAMBERT_BAND_SCALE = np.array([1.0, 2.0 / 3.0, 0.25])
#: mu_o floor of the quadrature (f is 0 at mu_o = 0 exactly; this gives the grazing limit).
MU_MIN = 1e-7


def basis(w: ArrayLike) -> NDArray[np.float64]:
    """The 9 real SH basis functions Y_k(w), order 2.

    Parameters
    ----------
    w : array_like, shape (..., 3)
        Unit directions.

    Returns
    -------
    ndarray, shape (..., 9)

    Examples
    --------
    >>> import numpy as np
    >>> y = basis([0.0, 0.0, 1.0])
    >>> bool(np.isclose(y[2], np.sqrt(3 / (4 * np.pi))))
    True
    """
    w = ar.directions("w", w, np.float64)
    x, y, z = w[..., 0], w[..., 1], w[..., 2]
    return np.stack(
        [
            np.full_like(x, C0),
            C1 * y,
            C1 * z,
            C1 * x,
            C2 * x * y,
            C2 * y * z,
            C3 * (3.0 * z * z - 1.0),
            C2 * x * z,
            0.5 * C2 * (x * x - y * y),
        ],
        axis=-1,
    )


def zonal_basis(mu: ArrayLike) -> NDArray[np.float64]:
    """Y_00, Y_10, Y_20 at cos(theta) = mu; shape (..., 3)."""
    mu = ar.in_range("mu", mu, np.float64, -1.0, 1.0, " (cosine to the lobe axis)")
    return np.stack([np.full_like(mu, C0), C1 * mu, C3 * (3.0 * mu * mu - 1.0)], axis=-1)


def zh_rotate(zh: ArrayLike, n: ArrayLike) -> NDArray[np.float64]:
    """Full SH vector of a zonal lobe with ZH coefficients ``zh`` turned to point along ``n``.

    E_lm(n) = sqrt(4 pi / (2l + 1)) E_l Y_lm(n) (Sloan 2008; the ``RotateZH`` listing of the
    energy-compensation post).

    Parameters
    ----------
    zh : array_like, shape (..., 3)
        E_0, E_1, E_2.
    n : array_like, shape (..., 3)
        Unit axis of the lobe.

    Returns
    -------
    ndarray, shape broadcast(...) + (9,)
    """
    zh = ar.as_float("zh", zh, np.float64)
    if zh.ndim == 0 or zh.shape[-1] != 3:
        raise ValueError(f"zh must have shape (..., 3) (E_0, E_1, E_2), got shape {zh.shape}")
    return (zh * ZH_ROTATION)[..., BAND] * basis(n)


def _gauss(n):
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (x + 1.0), 0.5 * w


def zh_project(h: Callable[[NDArray[np.float64]], ArrayLike], n: int = 64) -> NDArray[np.float64]:
    """ZH coefficients E_l = 2 pi int_0^1 Y_l0(mu) h(mu) mu dmu of the lobe h(mu) mu on H+.

    ``h`` is a callable of mu (array, shape (n,)) returning shape (n,) or (n, ...); the result
    has shape (3,) + that trailing shape.  Gauss-Legendre in mu with ``n`` nodes (exact for a
    polynomial h of degree <= 2n - 3).

    Examples
    --------
    >>> import numpy as np
    >>> zh = zh_project(lambda mu: np.full_like(mu, 1 / np.pi))     # Lambert, rho = 1
    >>> bool(np.allclose(zh * ZH_ROTATION, LAMBERT_BAND_SCALE))
    True
    """
    if not callable(h):
        raise TypeError(f"h must be a callable of mu, got {type(h).__name__}")
    if not isinstance(n, int) or n < 2:
        raise ValueError(f"n must be an integer >= 2 (Gauss-Legendre nodes), got {n!r}")
    mu, w = _gauss(n)
    v = np.asarray(h(mu), dtype=np.float64)
    Y = zonal_basis(mu)  # (n, 3)
    return 2.0 * math.pi * np.einsum("n,nl,n...->l...", w * mu, Y, v)


def _panel_nodes(edges, n):
    """Gauss-Legendre nodes and weights on consecutive panels; edges shape (N, P+1)."""
    x, w = _gauss(n)
    a, b = edges[:, :-1, None], edges[:, 1:, None]
    return (a + (b - a) * x).reshape(len(edges), -1), ((b - a) * w).reshape(len(edges), -1)


def hemisphere_nodes(mu_o: ArrayLike, n: int = 32) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Quadrature nodes wi (N, T, P, 3) and weights (N, T, P) for int_{H+} g(wi) dwi.

    wo = (sqrt(1 - mu_o^2), 0, mu_o): theta_i panels split at theta_o, phi panels at pi/2 and
    3 pi/2 (the kinks of max(mu_i, mu_o) and of the sign of s), n nodes each.
    """
    mu_o = np.atleast_1d(np.asarray(mu_o, dtype=np.float64))
    th_o = np.arccos(np.clip(mu_o, 0.0, 1.0))
    N = len(mu_o)
    t, wt = _panel_nodes(np.stack([np.zeros(N), th_o, np.full(N, 0.5 * math.pi)], axis=1), n)
    ph_edges = np.array([[-0.5 * math.pi, 0.5 * math.pi, 1.5 * math.pi]])
    p, wp = _panel_nodes(ph_edges, n)
    st, ct = np.sin(t)[:, :, None], np.cos(t)[:, :, None]
    cp, sp = np.cos(p[0])[None, None, :], np.sin(p[0])[None, None, :]
    wi = np.stack(np.broadcast_arrays(st * cp, st * sp, ct), axis=-1)
    weight = (wt * np.sin(t))[:, :, None] * wp[0][None, None, :]
    return wi, weight


def environment(env: ArrayLike, detail: str = "") -> NDArray[np.float64]:
    """``env`` as float64 SH radiance coefficients of shape (..., 9, C); ValueError otherwise
    (``detail`` follows the expected shape in its message).

    Example
    -------
    >>> environment(np.ones((9, 3))).shape
    (9, 3)
    >>> environment(np.ones(9))
    Traceback (most recent call last):
    ...
    ValueError: env must have shape (..., 9, C), got (9,)
    """
    env = ar.as_float("env", env, np.float64)
    if env.ndim < 2 or env.shape[-2] != 9:
        raise ValueError(f"env must have shape (..., 9, C){detail}, got {env.shape}")
    return env


def wo_of(mu_o: ArrayLike) -> NDArray[np.float64]:
    """wo = (sqrt(1 - mu_o^2), 0, mu_o): the local-frame view direction for ``lobe_transfer``."""
    mu_o = np.asarray(mu_o, dtype=np.float64)
    return np.stack([np.sqrt(np.maximum(0.0, 1.0 - mu_o * mu_o)), np.zeros_like(mu_o), mu_o], axis=-1)


def lobe_transfer(
    model: str,
    mu_o: ArrayLike,
    roughness: ArrayLike,
    rho: ArrayLike = 1.0,
    *,
    n: int = 24,
    color_mode: str = "reference",
    brdf: Callable[..., ArrayLike] | None = None,
) -> NDArray[np.float64]:
    """Exact SH transfer vector T_k(wo) = int Y_k(wi) f(wi, wo) mu_i dwi of a lobe.

    Local frame (normal +z) with wo = (sqrt(1 - mu_o^2), 0, mu_o); coefficients 1, 4, 5 (odd
    in y) vanish by symmetry.  T_0 / C0 is the directional albedo E(mu_o) (the "DC" response);
    T_2 (Y_10, along the normal) and T_3 (Y_11, along the view's tangent) are the linear
    response.  Lambert (rho = 1) has T = (1, 2/3, 1/4) per band times Y_k(n).

    Computed by Gauss-Legendre quadrature of ``od.evaluate`` (``hemisphere_nodes``, n nodes
    per panel, 4 panels); float64.

    Parameters
    ----------
    model : str
        A lobe model (``od.MODELS``).
    mu_o : array_like, shape (...)
        Cosine of the view angle, in [0, 1].
    roughness : array_like, shape (...)
        In the model's domain.
    rho : array_like, shape (..., C)
    n : int
        Nodes per panel (>= 4).
    brdf : callable, optional
        ``brdf(wi, wo)`` returning shape (N, T, P, C), used instead of ``od.evaluate(model, ...)``
        (for the approximate lobes of ``gotanda2012``); ``model`` is then only a label.

    Returns
    -------
    ndarray, shape broadcast(mu_o, roughness, rho leading) + (9, C)

    Examples
    --------
    >>> import numpy as np
    >>> T = lobe_transfer("lambert", 0.5, 0.0)
    >>> bool(np.allclose(T[:, 0], [C0, 0, 2 / 3 * C1, 0, 0, 0, 0.25 * 2 * C3, 0, 0], atol=1e-12))
    True
    """
    from .. import models

    if not isinstance(n, int) or n < 4:
        raise ValueError(f"n must be an integer >= 4 (quadrature nodes per panel), got {n!r}")
    mu_o = ar.in_range("mu_o", mu_o, np.float64, 0.0, 1.0, " (cosine of the view angle)")
    info = models.registry.model_info(model) if brdf is None else None
    rough = (
        ar.model_roughness(info, roughness, np.float64)
        if info is not None
        else ar.as_float("roughness", roughness, np.float64)
    )
    rho = ar.rho_array("rho", rho, np.float64)
    lead = ar.broadcast_leading(mu_o=mu_o.shape, roughness=rough.shape, rho=rho.shape[:-1])
    C = rho.shape[-1]
    # rows of the broadcast inputs (a copy only for outer products: smaller than the output)
    mu_f = np.broadcast_to(mu_o, lead).reshape(-1)
    r_f = np.broadcast_to(rough, lead).reshape(-1)
    rho_f = np.broadcast_to(rho, lead + (C,)).reshape(-1, C)
    out = np.empty((len(mu_f), 9, C))
    step = max(1, (1 << 18) // (4 * n * n))
    for s in range(0, len(mu_f), step):
        e = s + step
        mu_q = np.maximum(mu_f[s:e], MU_MIN)  # mu_o = 0: the grazing limit
        wi, weight = hemisphere_nodes(mu_q, n)
        wo = wo_of(mu_q)[:, None, None, :]
        r = r_f[s:e, None, None]
        rr = rho_f[s:e, None, None, :]
        f: ArrayLike
        if brdf is None:
            f = models.evaluate(model, wi, wo, r, rr, color_mode=color_mode)
        else:
            f = brdf(wi, np.broadcast_to(wo, wi.shape), r, rr)
        out[s:e] = _project_rows(
            np.ascontiguousarray(wi.reshape(len(wi), -1, 3)),
            np.ascontiguousarray((weight * wi[..., 2]).reshape(len(wi), -1)),
            np.ascontiguousarray(np.asarray(f, np.float64).reshape(len(wi), -1, C)),
        )
    return out.reshape(lead + (9, C))


def _project_kernel():
    from .._jit import reduction

    @reduction
    def project(wi, weight, f):
        """sum_q Y_k(wi_q) weight_q f_qc per row: the hot loop of ``lobe_transfer``."""
        N, Q, C = f.shape
        out = np.zeros((N, 9, C))
        for n in range(N):
            for q in range(Q):
                x, y, z = wi[n, q, 0], wi[n, q, 1], wi[n, q, 2]
                w = weight[n, q]
                y0, y1, y2, y3 = C0 * w, C1 * y * w, C1 * z * w, C1 * x * w
                y4, y5, y6 = C2 * x * y * w, C2 * y * z * w, C3 * (3.0 * z * z - 1.0) * w
                y7, y8 = C2 * x * z * w, 0.5 * C2 * (x * x - y * y) * w
                for c in range(C):
                    v = f[n, q, c]
                    out[n, 0, c] += y0 * v
                    out[n, 1, c] += y1 * v
                    out[n, 2, c] += y2 * v
                    out[n, 3, c] += y3 * v
                    out[n, 4, c] += y4 * v
                    out[n, 5, c] += y5 * v
                    out[n, 6, c] += y6 * v
                    out[n, 7, c] += y7 * v
                    out[n, 8, c] += y8 * v
        return out

    return project


_PROJECT = None


def _project_rows(wi, weight, f):
    """Compiled (numba) weighted SH projection; compiled on first use and cached on disk."""
    global _PROJECT
    if _PROJECT is None:
        _PROJECT = _project_kernel()
    return _PROJECT(wi, weight, f)


#: Fixed directions for exact SH rotation by least squares (64 Fibonacci points).
def _fibonacci(k=64):
    i = np.arange(k) + 0.5
    z = 1.0 - 2.0 * i / k
    phi = math.pi * (1.0 + 5**0.5) * i
    s = np.sqrt(1.0 - z * z)
    return np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=-1)


_DIRS = _fibonacci()
_PINV = np.linalg.pinv(basis(_DIRS))  # (9, 64)


def frame(normal: ArrayLike, wo: ArrayLike) -> NDArray[np.float64]:
    """Rotation R (..., 3, 3) whose columns are the local x (towards wo), y and z = normal.

    Parameters
    ----------
    normal, wo : array_like, shape (..., 3)
        Unit vectors; when wo is along the normal any tangent is used.
    """
    n = ar.directions("normal", normal, np.float64)
    v = ar.directions("wo", wo, np.float64)
    n, v = np.broadcast_arrays(n, v)
    t = v - np.sum(v * n, axis=-1, keepdims=True) * n
    tl = np.linalg.norm(t, axis=-1, keepdims=True)
    # fallback tangent: any unit vector perpendicular to n
    a = np.where(np.abs(n[..., :1]) < 0.9, np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]))
    alt = a - np.sum(a * n, axis=-1, keepdims=True) * n
    alt /= np.linalg.norm(alt, axis=-1, keepdims=True)
    t = np.where(tl > 1e-9, t / np.maximum(tl, 1e-300), alt)
    b = np.cross(n, t)
    return np.stack([t, b, n], axis=-1)


def rotate(coeffs: ArrayLike, R: ArrayLike) -> NDArray[np.float64]:
    """SH coefficients of g(R^T w) given those of g(w): the rotation of an order-2 SH vector.

    Exact (order-2 SH are closed under rotation): the rotated function is sampled at 64 fixed
    directions and projected back by least squares.

    Parameters
    ----------
    coeffs : array_like, shape (..., 9, C) or (..., 9)
    R : array_like, shape (..., 3, 3)
        Rotation taking local to world (columns: local axes in world coordinates).
    """
    coeffs = np.asarray(coeffs, dtype=np.float64)
    R = np.asarray(R, dtype=np.float64)
    if R.shape[-2:] != (3, 3):
        raise ValueError(f"R must have shape (..., 3, 3), got {R.shape}")
    squeeze = coeffs.shape[-1] == 9
    if squeeze:
        coeffs = coeffs[..., None]
    if coeffs.ndim < 2 or coeffs.shape[-2] != 9:
        raise ValueError(f"coeffs must have shape (..., 9) or (..., 9, C), got {coeffs.shape}")
    local = np.einsum("kj,...ji->...ki", _DIRS, R)  # R^T d_k
    Y = basis(local / np.linalg.norm(local, axis=-1, keepdims=True))  # (..., 64, 9)
    out = np.einsum("qk,...kj,...jc->...qc", _PINV, Y, coeffs)
    return out[..., 0] if squeeze else out


def shade(
    model: str,
    env: ArrayLike,
    normal: ArrayLike,
    wo: ArrayLike,
    roughness: ArrayLike,
    rho: ArrayLike = 1.0,
    *,
    n: int = 32,
) -> NDArray[np.float64]:
    """Outgoing radiance of a lobe lit by an order-2 SH environment, exactly (up to quadrature).

    L_o = sum_k L_k T_k^world(wo) with T from ``lobe_transfer`` rotated into the world frame.

    Parameters
    ----------
    env : array_like, shape (..., 9, C) or (9, C)
        SH coefficients of the environment radiance (world frame).
    normal, wo : array_like, shape (..., 3)
        World-space unit normal and view direction (wo above the surface).
    roughness, rho : as in ``od.evaluate``.

    Returns
    -------
    ndarray, shape (..., C)
    """
    env = environment(env, " (SH coefficients per channel)")
    R = frame(normal, wo)
    mu_o = np.clip(np.einsum("...i,...i->...", np.asarray(normal, float), np.asarray(wo, float)), 0.0, 1.0)
    T = lobe_transfer(model, mu_o, roughness, rho, n=n)
    Tw = rotate(T, R)
    return np.einsum("...kc,...kc->...c", env, Tw)
