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
theta_o, the first of width 2 (pi/2 - theta_o): full Oren-Nayar's tan((alpha + beta)/2)
has a pole at theta_i = pi - theta_o, just beyond that panel when wo is grazing, and the
grading keeps every sub-panel at least its own width away from it.

For an isotropic BRDF (a function of theta_i, theta_o and cos(phi_i - phi_o) only) the
integrand is even in phi and phi in [0, pi] suffices (``symmetric=True``).

Each value comes with the error estimate |Q_n - Q_2n| (Q_2n is the value returned; orders
n and 2n per panel in both angles) plus a rounding floor of 64 ulp of the value.

The grazing limit mu_o -> 0 cannot be evaluated directly (a single-sided BRDF is 0 at the
horizon).  Full Oren-Nayar's albedo behaves like E0 + a mu ln(mu) + b mu + ... there (the
tan((alpha + beta)/2) term), so the limit is extrapolated from mu_o = delta, 2 delta,
4 delta, 8 delta by fitting E0 + a mu ln(mu) + b mu + c mu^2 (error O(delta^2 ln delta), or
O(delta^3) for an albedo smooth in mu); the same fit on 2 delta .. 16 delta gives the error
estimate.
"""

import functools
import math
from collections.abc import Callable
from typing import Literal, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

HALF_PI = 0.5 * math.pi

#: Default Gauss-Legendre order per panel (theta and phi): 8/16 already agree to ~1e-14 for
#: every model of the library (see ``tests/test_reference_tables.py``).
DEFAULT_ORDER = 8
#: mu_o of the extrapolation of the grazing limit mu_o -> 0.
GRAZING_DELTA = 1e-6
#: Default number of quadrature points per BRDF call (bounds the memory of one call).
MAX_POINTS = 1 << 18
#: Rounding floor of the error estimates, relative to |E| (sums of ~1e4 terms in float64).
ROUNDING = 64 * np.finfo(np.float64).eps
#: Cap on the graded sub-panels (reached only for mu_o < 1e-15).
_MAX_GRADING = 50
#: Sub-panels of the theta_o integral of the average albedo, graded towards the horizon.
_AVERAGE_GRADING = 12


def gauss_legendre(a: ArrayLike, b: ArrayLike, n: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Nodes and weights of the n-point Gauss-Legendre rule on [a, b] (a, b broadcast).

    Returns
    -------
    nodes, weights : ndarray, shape broadcast(a, b) + (n,)
        A zero-width panel has zero weights.
    """
    x, w = _leggauss(n)
    a = np.asarray(a, dtype=np.float64)[..., None]
    b = np.asarray(b, dtype=np.float64)[..., None]
    half = 0.5 * (b - a)
    return 0.5 * (a + b) + half * x, half * w


@functools.lru_cache(maxsize=64)
def _leggauss(n: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``numpy.polynomial.legendre.leggauss(n)``, computed once per n (read-only arrays)."""
    x, w = np.polynomial.legendre.leggauss(n)
    x.flags.writeable = w.flags.writeable = False
    return x, w


#: 2^k - 1 for k = 1 .. _MAX_GRADING
_GRADES = 2.0 ** np.arange(1, _MAX_GRADING + 1) - 1.0


def _graded_count(theta_o):
    """Number K of sub-panels of [0, theta_o]: 1 + #{k >= 1 : theta_o - d (2^k - 1) > 0}."""
    t = np.asarray(theta_o, dtype=np.float64)
    d = 2.0 * (HALF_PI - t)
    return 1 + np.count_nonzero(t[..., None] - d[..., None] * _GRADES > 0.0, axis=-1).astype(np.int64)


def _theta_breaks(theta_o, kinks):
    """Panel edges in theta_i, shape (G, K + 2 + len(kinks)), for theta_o (G,) sharing K.

    [0, theta_o] is split at theta_o - d (2^k - 1), k = 1 .. K - 1, d = 2 (pi/2 - theta_o);
    [theta_o, pi/2] is one panel; the fixed ``kinks`` are extra edges.
    """
    d = 2.0 * (HALF_PI - theta_o)
    K = int(_graded_count(theta_o[:1])[0])
    kk = np.arange(1, K, dtype=np.float64)
    inner = theta_o[:, None] - d[:, None] * (2.0**kk - 1.0)  # descending, all > 0
    edges = np.concatenate(
        [
            np.zeros_like(theta_o)[:, None],
            inner[:, ::-1],
            theta_o[:, None],
            np.full_like(theta_o, HALF_PI)[:, None],
            np.broadcast_to(kinks, (len(theta_o), len(kinks))),
        ],
        axis=1,
    )
    return np.sort(edges, axis=1)


def _nodes(theta_o, n, symmetric, kinks):
    """Directions wi (G, T, P, 3) and weights (G, T, P) of the rule for theta_o (G,)."""
    breaks = _theta_breaks(theta_o, kinks)
    th, wt = gauss_legendre(breaks[:, :-1], breaks[:, 1:], n)  # (G, K + 1, n)
    th = th.reshape(len(theta_o), -1)
    wt = wt.reshape(len(theta_o), -1)
    phi_edges = np.arange(3 if symmetric else 5) * HALF_PI
    ph, wp = gauss_legendre(phi_edges[:-1], phi_edges[1:], n)
    ph, wp = ph.ravel(), wp.ravel()
    if symmetric:
        wp = 2.0 * wp  # phi in [pi, 2 pi] mirrors [0, pi]
    st, ct = np.sin(th), np.cos(th)
    wi = np.empty(th.shape + ph.shape + (3,))
    wi[..., 0] = st[:, :, None] * np.cos(ph)
    wi[..., 1] = st[:, :, None] * np.sin(ph)
    wi[..., 2] = ct[:, :, None]
    # f mu_i dwi = f cos(theta) sin(theta) dtheta dphi
    return wi, (wt * ct * st)[:, :, None] * wp


def _integrate(brdf, theta_o, n, symmetric, max_points, kinks):
    """Q_n(theta_o) for theta_o (M,) in [0, pi/2): grouped by panel count, chunked."""
    keys = _graded_count(theta_o)
    out = None
    for key in np.unique(keys):
        idx = np.flatnonzero(keys == key)
        per_row = int(key + 1 + len(kinks)) * n * (2 if symmetric else 4) * n
        step = max(1, max_points // per_row)
        for start in range(0, len(idx), step):
            rows = idx[start : start + step]
            t = theta_o[rows]
            wi, w = _nodes(t, n, symmetric, kinks)
            wo = np.stack([np.sin(t), np.zeros_like(t), np.cos(t)], axis=-1)[:, None, None, :]
            f = np.asarray(brdf(wi, np.broadcast_to(wo, wi.shape)), dtype=np.float64)
            if f.shape[:3] != wi.shape[:3]:
                raise ValueError(f"brdf returned shape {f.shape}; expected {wi.shape[:3]} + (...)")
            q = np.einsum("gtp,gtp...->g...", w, f)
            if out is None:
                out = np.empty((len(theta_o),) + q.shape[1:])
            out[rows] = q
    return out


def _grazing_weights(mu):
    """Weights w with E0 = sum w_k E(mu_k) for E = E0 + a mu ln(mu) + b mu + c mu^2 (4 points)."""
    A = np.stack([np.ones_like(mu), mu * np.log(mu), mu, mu * mu], axis=1)
    return np.linalg.solve(A.T, np.eye(4)[0])


#: A vectorised BRDF ``brdf(wi, wo)`` (see ``hemisphere_albedo``).
Brdf = Callable[..., ArrayLike]


@overload
def hemisphere_albedo(
    brdf: Brdf,
    mu_o: ArrayLike,
    n: int = ...,
    *,
    symmetric: bool = ...,
    error: Literal[False] = ...,
    delta: float = ...,
    max_points: int = ...,
    kinks: ArrayLike = ...,
) -> NDArray[np.float64]: ...
@overload
def hemisphere_albedo(
    brdf: Brdf,
    mu_o: ArrayLike,
    n: int = ...,
    *,
    symmetric: bool = ...,
    error: Literal[True],
    delta: float = ...,
    max_points: int = ...,
    kinks: ArrayLike = ...,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]: ...
def hemisphere_albedo(
    brdf: Brdf,
    mu_o: ArrayLike,
    n: int = DEFAULT_ORDER,
    *,
    symmetric: bool = True,
    error: bool = False,
    delta: float = GRAZING_DELTA,
    max_points: int = MAX_POINTS,
    kinks: ArrayLike = (),
) -> NDArray[np.float64] | tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Directional albedo E(mu_o) = int f(wi, wo) mu_i dwi of any vectorised BRDF.

    Parameters
    ----------
    brdf : callable
        ``brdf(wi, wo)`` with wi, wo of shape (G, T, P, 3) (local frame, normal +z, both
        pointing away from the surface, wo in the xz-plane with wo.x >= 0) returning f
        without the cosine factor, shape (G, T, P) or (G, T, P, ...) (e.g. channels).
    mu_o : array_like
        Cosines of the outgoing direction in [0, 1].  mu_o = 0 returns the limit mu_o -> 0.
    n : int
        Gauss-Legendre order per panel; the value uses 2n, the error estimate n vs 2n.
    symmetric : bool
        The BRDF depends on the azimuth only through cos(phi_i - phi_o): integrate phi over
        [0, pi] and double.  Otherwise [0, 2 pi] in four panels.
    error : bool
        Also return the error estimate.
    delta : float
        Smallest mu_o of the extrapolation of the grazing limit.
    max_points : int
        Directions per ``brdf`` call (memory bound; divide by any trailing size of f).
    kinks : sequence of float
        Further theta_i (radians) where the integrand has a kink independent of wo (e.g. a
        clamp on a function of mu_i); they become panel edges.

    Returns
    -------
    E : ndarray, shape mu_o.shape + trailing shape of f
    err : ndarray, same shape (only with ``error=True``)
        |Q_n - Q_2n| + 64 ulp; at mu_o = 0 plus the extrapolation error estimate.

    Examples
    --------
    >>> import numpy as np
    >>> lambert = lambda wi, wo: np.full(wi.shape[:-1], 1.0 / np.pi)
    >>> round(float(hemisphere_albedo(lambert, 0.3)), 12)
    1.0
    """
    mu = np.asarray(mu_o, dtype=np.float64)
    if not np.all((mu >= 0.0) & (mu <= 1.0)):
        raise ValueError("mu_o must lie in [0, 1]")
    if not (isinstance(n, (int, np.integer)) and n >= 1):
        raise ValueError(f"n must be a positive integer, got {n!r}")
    flat = mu.ravel()
    grazing = flat == 0.0
    mus = flat[~grazing]
    ladder = delta * 2.0 ** np.arange(5)
    if grazing.any():
        mus = np.concatenate([mus, ladder])
    theta = np.arccos(mus)
    kinks = np.asarray(kinks, dtype=np.float64).ravel()
    if not np.all((kinks > 0.0) & (kinks < HALF_PI)):
        raise ValueError("kinks must lie in (0, pi/2)")
    hi = _integrate(brdf, theta, 2 * n, symmetric, max_points, kinks)
    lo = _integrate(brdf, theta, n, symmetric, max_points, kinks)
    err = np.abs(hi - lo) + ROUNDING * np.abs(hi)
    trail = hi.shape[1:]
    E = np.empty((flat.size,) + trail)
    dE = np.empty((flat.size,) + trail)
    if grazing.any():
        w1 = _grazing_weights(ladder[:4])
        r1 = np.tensordot(w1, hi[-5:-1], axes=(0, 0))
        r2 = np.tensordot(_grazing_weights(ladder[1:]), hi[-4:], axes=(0, 0))
        E[grazing] = r1
        # fit error estimate (second ladder) + the ladder's quadrature errors through the weights
        dE[grazing] = np.abs(r1 - r2) + np.tensordot(np.abs(w1), err[-5:-1], axes=(0, 0))
        hi, err = hi[:-5], err[:-5]
    E[~grazing] = hi
    dE[~grazing] = err
    E = E.reshape(mu.shape + trail)
    dE = dE.reshape(mu.shape + trail)
    return (E, dE) if error else E


@overload
def hemisphere_average_albedo(
    brdf: Brdf,
    n: int = ...,
    *,
    n_mu: int = ...,
    symmetric: bool = ...,
    error: Literal[False] = ...,
    max_points: int = ...,
    kinks: ArrayLike = ...,
) -> NDArray[np.float64]: ...
@overload
def hemisphere_average_albedo(
    brdf: Brdf,
    n: int = ...,
    *,
    n_mu: int = ...,
    symmetric: bool = ...,
    error: Literal[True],
    max_points: int = ...,
    kinks: ArrayLike = ...,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]: ...
def hemisphere_average_albedo(
    brdf: Brdf,
    n: int = DEFAULT_ORDER,
    *,
    n_mu: int = DEFAULT_ORDER,
    symmetric: bool = True,
    error: bool = False,
    max_points: int = MAX_POINTS,
    kinks: ArrayLike = (),
) -> NDArray[np.float64] | tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Average albedo <E> = 2 int_0^1 E(mu) mu dmu = (1/pi) int int f mu_i mu_o dwi dwo.

    Gauss-Legendre in theta_o with weight 2 cos(theta_o) sin(theta_o), on panels graded
    geometrically towards the horizon (pi/2 - theta_o in [0, 2^-12 pi/2], ..., [pi/4, pi/2]):
    full Oren-Nayar's E has a mu ln(mu) term there, which the grading integrates at the
    geometric rate.  Value from 2 ``n_mu`` nodes per panel, error estimate n_mu vs 2 n_mu plus
    the propagated error of the inner integrals.  ``kinks`` (theta angles) are panel edges
    of both the inner and the outer integral (a kink in mu_i is one in mu_o by reciprocity).

    Returns
    -------
    avg : ndarray, trailing shape of f
    err : ndarray (only with ``error=True``)

    Examples
    --------
    >>> import numpy as np
    >>> lambert = lambda wi, wo: np.full(wi.shape[:-1], 1.0 / np.pi)
    >>> round(float(hemisphere_average_albedo(lambert)), 12)
    1.0
    """
    kinks = np.asarray(kinks, dtype=np.float64).ravel()
    x_edges = np.unique(np.concatenate([[0.0], HALF_PI * 0.5 ** np.arange(_AVERAGE_GRADING, -1, -1), HALF_PI - kinks]))
    results = []
    for m in (n_mu, 2 * n_mu):
        x, w = gauss_legendre(x_edges[:-1], x_edges[1:], m)
        t = HALF_PI - x.ravel()
        E, dE = hemisphere_albedo(
            brdf, np.cos(t), n, symmetric=symmetric, error=True, max_points=max_points, kinks=kinks
        )
        wt = 2.0 * w.ravel() * np.cos(t) * np.sin(t)
        results.append((np.tensordot(wt, E, axes=(0, 0)), np.tensordot(wt, dE, axes=(0, 0))))
    (lo, _), (hi, inner) = results
    err = np.abs(hi - lo) + inner
    return (hi, err) if error else hi
