"""Hemisphere quadrature of BRDFs: directional albedo E(mu_o) and average albedo <E>.

E(wo) = int_H+ f(wi, wo) mu_i dwi is computed in spherical coordinates of wi,

    E(theta_o) = int_0^{2 pi} int_0^{pi/2} f(wi, wo) cos(theta) sin(theta) dtheta dphi,

with wo = (sin theta_o, 0, cos theta_o) in the xz-plane.  The theta parameterisation
(rather than mu_i) keeps the integrand smooth up to the horizon and at the normal.  Products
of Gauss-Legendre rules are used on panels whose edges sit on the kinks of the Oren-Nayar
family, so that each panel integrand is analytic and the rule converges geometrically:

- theta_i = theta_o: the max(mu_i, mu_o) switch (QON Eq. 1, FON Eq. 10; alpha and beta of
  the full Oren-Nayar model);
- phi = pi/2 (and 3 pi/2): the sign of s = wi.wo - mu_i mu_o = cos(phi) sin(theta_i)
  sin(theta_o) (the s > 0 branch of QON/FON, cos(dphi) >= 0 and |cos dphi| in full ON).

The [0, theta_o] panel is further split into sub-panels graded geometrically towards
theta_o with a first width of 2 (pi/2 - theta_o): full Oren-Nayar's
tan((alpha + beta)/2) has a pole at theta_i = pi - theta_o, just beyond that panel when wo
is grazing, and the grading keeps every sub-panel at least one panel width away from it.

For an isotropic BRDF (a function of theta_i, theta_o and cos(phi_i - phi_o) only) the
integrand is even in phi and phi in [0, pi] suffices (``symmetric=True``).

The error estimate of each value is |Q_n - Q_2n| with Q_2n the value returned (panel
orders n and 2n in both angles).  mu_o = 0 (grazing) is the limit mu_o -> 0: a BRDF
evaluated exactly at the horizon is 0 (single-sided), so it is Richardson-extrapolated
from mu_o = delta and 2 delta (error O(delta^2), estimated from delta, 2 delta, 4 delta).
"""
import math

import numpy as np

HALF_PI = 0.5 * math.pi

#: Default Gauss-Legendre order per panel (theta and phi).
DEFAULT_ORDER = 16
#: mu_o used for the Richardson extrapolation of the grazing limit mu_o -> 0.
GRAZING_DELTA = 1e-5
#: Points per call of the BRDF (keeps memory bounded: ~ 100 MB of float64 work arrays).
_CHUNK_POINTS = 1 << 20
#: Cap on the graded sub-panels (reached only for mu_o < 1e-15).
_MAX_GRADING = 50


def gauss_legendre(a, b, n):
    """Nodes and weights of the n-point Gauss-Legendre rule on [a, b] (arrays broadcast).

    Returns arrays of shape broadcast(a, b) + (n,); a zero-width panel has zero weights.
    """
    x, w = np.polynomial.legendre.leggauss(n)
    a = np.asarray(a, dtype=np.float64)[..., None]
    b = np.asarray(b, dtype=np.float64)[..., None]
    half = 0.5 * (b - a)
    return 0.5 * (a + b) + half * x, half * w


def _graded_count(theta_o):
    """Number of sub-panels of [0, theta_o]: 1 + #{k >= 1 : theta_o - d (2^k - 1) > 0}."""
    t = np.asarray(theta_o, dtype=np.float64)
    d = 2.0 * (HALF_PI - t)
    k = np.ones(t.shape, dtype=np.int64)
    for j in range(1, _MAX_GRADING + 1):
        k += t - d * (2.0 ** j - 1.0) > 0.0
    return k


def _theta_breaks(theta_o):
    """Panel edges in theta_i for a group of theta_o with the same sub-panel count K.

    [0, theta_o] is split at theta_o - d (2^k - 1), k = 1 .. K - 1, d = 2 (pi/2 - theta_o);
    [theta_o, pi/2] is one panel.  Returns shape (G, K + 2).
    """
    d = 2.0 * (HALF_PI - theta_o)
    K = int(_graded_count(theta_o[:1])[0])
    kk = np.arange(1, K, dtype=np.float64)
    inner = theta_o[:, None] - d[:, None] * (2.0 ** kk - 1.0)       # descending, all > 0
    return np.concatenate([np.zeros_like(theta_o)[:, None], inner[:, ::-1], theta_o[:, None],
                           np.full_like(theta_o, HALF_PI)[:, None]], axis=1)


def _nodes(theta_o, n, symmetric):
    """Quadrature points: wi (G, T, P, 3) and weights (G, T, P) for theta_o of shape (G,)."""
    breaks = _theta_breaks(theta_o)                                  # (G, K + 2)
    th, wt = gauss_legendre(breaks[:, :-1], breaks[:, 1:], n)         # (G, K + 1, n)
    th = th.reshape(len(theta_o), -1)
    wt = wt.reshape(len(theta_o), -1)
    phi_edges = np.arange(3 if symmetric else 5) * HALF_PI
    ph, wp = gauss_legendre(phi_edges[:-1], phi_edges[1:], n)
    ph, wp = ph.ravel(), wp.ravel()
    if symmetric:
        wp = 2.0 * wp          # phi in [pi, 2 pi] mirrors [0, pi]
    st, ct = np.sin(th), np.cos(th)
    wi = np.empty(th.shape + ph.shape + (3,))
    wi[..., 0] = st[:, :, None] * np.cos(ph)
    wi[..., 1] = st[:, :, None] * np.sin(ph)
    wi[..., 2] = ct[:, :, None]
    # f mu_i dwi = f cos(theta) sin(theta) dtheta dphi
    w = (wt * ct * st)[:, :, None] * wp
    return wi, w


def _integrate(brdf, theta_o, n, symmetric):
    """Q_n(theta_o) for theta_o (M,), grouped by panel count and chunked for memory."""
    keys = _graded_count(theta_o)
    out = None
    for key in np.unique(keys):
        idx = np.flatnonzero(keys == key)
        per_row = (key + 1) * n * (2 if symmetric else 4) * n
        step = max(1, _CHUNK_POINTS // per_row)
        for start in range(0, len(idx), step):
            rows = idx[start:start + step]
            t = theta_o[rows]
            wi, w = _nodes(t, n, symmetric)
            wo = np.stack([np.sin(t), np.zeros_like(t), np.cos(t)], axis=-1)[:, None, None, :]
            f = np.asarray(brdf(wi, np.broadcast_to(wo, wi.shape)), dtype=np.float64)
            if f.shape[:3] != wi.shape[:3]:
                raise ValueError(f"brdf returned shape {f.shape}; expected {wi.shape[:3]} (+ channels)")
            q = np.einsum("gtp,gtp...->g...", w, f)
            if out is None:
                out = np.empty((len(theta_o),) + q.shape[1:])
            out[rows] = q
    return out


def _albedo_theta(brdf, theta_o, n, symmetric):
    """(Q_2n, |Q_n - Q_2n|) for theta_o strictly inside [0, pi/2)."""
    lo = _integrate(brdf, theta_o, n, symmetric)
    hi = _integrate(brdf, theta_o, 2 * n, symmetric)
    return hi, np.abs(hi - lo)


def hemisphere_albedo(brdf, mu_o, n=DEFAULT_ORDER, *, symmetric=True, error=False,
                      delta=GRAZING_DELTA):
    """Directional albedo E(mu_o) = int f(wi, wo) mu_i dwi of any vectorised BRDF.

    Parameters
    ----------
    brdf : callable
        ``brdf(wi, wo)`` with wi, wo of shape (..., 3) (local frame, normal +z, both
        pointing away from the surface, wo in the xz-plane) returning f without the cosine
        factor, shape (...) or (..., C).  Must be vectorised (called with ~1e6 directions).
    mu_o : array_like
        Cosines of the outgoing direction in [0, 1].  mu_o = 0 returns the grazing limit.
    n : int
        Gauss-Legendre order per panel; the value uses 2n, the error estimate n vs 2n.
    symmetric : bool
        The BRDF depends on the azimuth only through cos(phi_i - phi_o) (isotropic and
        reciprocal in the plane of incidence): integrate phi over [0, pi] and double.
    error : bool
        Also return the error estimate.
    delta : float
        mu_o of the Richardson extrapolation of the grazing limit.

    Returns
    -------
    E : ndarray, shape mu_o.shape (+ (C,))
    err : ndarray, same shape (only with ``error=True``)
        |Q_n - Q_2n| (plus the extrapolation error estimate at mu_o = 0).

    Examples
    --------
    >>> import numpy as np
    >>> lambert = lambda wi, wo: np.full(wi.shape[:-1], 1.0 / np.pi)
    >>> float(hemisphere_albedo(lambert, 0.3))
    1.0
    """
    mu = np.asarray(mu_o, dtype=np.float64)
    if not np.all((mu >= 0.0) & (mu <= 1.0)):
        raise ValueError("mu_o must lie in [0, 1]")
    if not (isinstance(n, (int, np.integer)) and n >= 1):
        raise ValueError(f"n must be a positive integer, got {n!r}")
    flat = mu.ravel()
    grazing = flat == 0.0
    # Rows to integrate: every mu > 0, plus delta, 2 delta, 4 delta once if any mu = 0.
    mus = flat[~grazing]
    if grazing.any():
        mus = np.concatenate([mus, [delta, 2.0 * delta, 4.0 * delta]])
    val, err = _albedo_theta(brdf, np.arccos(np.clip(mus, 0.0, 1.0)), n, symmetric)
    trail = val.shape[1:]
    E = np.empty((flat.size,) + trail)
    dE = np.empty((flat.size,) + trail)
    if grazing.any():
        e1, e2, e4 = val[-3], val[-2], val[-1]
        r1 = 2.0 * e1 - e2                    # E(0) + O(delta^2)
        r2 = 2.0 * e2 - e4
        E[grazing] = r1
        dE[grazing] = np.abs(r1 - r2) / 3.0 + 3.0 * np.max(err[-3:], axis=0)
        val, err = val[:-3], err[:-3]
    E[~grazing] = val
    dE[~grazing] = err
    E = E.reshape(mu.shape + trail)
    dE = dE.reshape(mu.shape + trail)
    return (E, dE) if error else E


def hemisphere_average_albedo(brdf, n_mu=32, n=DEFAULT_ORDER, *, symmetric=True, error=False):
    """Average albedo <E> = 2 int_0^1 E(mu) mu dmu (= (1/pi) int int f mu_i mu_o dwi dwo).

    Gauss-Legendre in theta_o on [0, pi/2] (E is smooth in theta_o) with weight
    2 cos(theta_o) sin(theta_o); value from 2 ``n_mu`` nodes, error estimate from n_mu vs
    2 n_mu plus the propagated error of the inner integrals.

    Examples
    --------
    >>> import numpy as np
    >>> lambert = lambda wi, wo: np.full(wi.shape[:-1], 1.0 / np.pi)
    >>> round(float(hemisphere_average_albedo(lambert)), 12)
    1.0
    """
    results = []
    for m in (n_mu, 2 * n_mu):
        t, w = gauss_legendre(0.0, HALF_PI, m)
        E, dE = hemisphere_albedo(brdf, np.cos(t), n, symmetric=symmetric, error=True)
        wt = 2.0 * w * np.cos(t) * np.sin(t)
        results.append((np.tensordot(wt, E, axes=(0, 0)), np.tensordot(wt, dE, axes=(0, 0))))
    (lo, _), (hi, inner) = results
    err = np.abs(hi - lo) + inner
    return (hi, err) if error else hi
