"""How good a sampling strategy is: throughput-weight statistics, chi-square, normalisation.

The throughput weight of a sample is w = f_EON(wi, wo; rho = 1) mu_i / pdf(wi) (0 where
pdf = 0).  Its mean is the albedo the strategy sees (1 for an unbiased strategy: EON passes
the white furnace) and its variance the noise per sample (EON paper Fig. 10-12).

- :func:`weight_stats`: Monte Carlo (variance, max, mean, standard error) from ``sample``;
- :func:`exact_weight_moments`: the same mean and variance by quadrature of
  ``f^2 mu_i^2 / pdf`` over the hemisphere (the library's panel Gauss-Legendre rule with the
  Oren-Nayar kinks as panel edges) -- no sampling noise, for the "about 100x" claim;
- :func:`chi2_test`: Pearson chi-square of sampled directions binned over cos(theta) x phi
  against the bin integrals of ``pdf`` (Mitsuba's pooling rule); also returns the total
  binned pdf mass (the pdf's normalisation);
- :func:`pdf_mass`: the integral of ``pdf`` over the hemisphere (the sphere for "ltc").

Examples
--------
>>> mean, var = exact_weight_moments("cosine", 1.0, 0.0)     # r = 0 (Lambert), cosine sampling
>>> round(mean, 6), round(var, 6)
(1.0, 0.0)
>>> mean, var = exact_weight_moments("cosine", 0.02, 1.0)    # grazing, r = 1 (README: 1.2055)
>>> round(mean, 6), round(var, 4)
(1.0, 1.2055)
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: rho = 1 as RGB: the same values as a scalar rho, and the driver the report's other sections
#: compile (a model's driver is compiled per channel count).
_WHITE = (1.0, 1.0, 1.0)


def wo_of(mu_o: float, phi: float = 0.0) -> NDArray[np.float64]:
    """Unit outgoing direction with cosine ``mu_o`` at azimuth ``phi``."""
    s = math.sqrt(max(0.0, 1.0 - mu_o * mu_o))
    return np.array([s * math.cos(phi), s * math.sin(phi), mu_o])


def weight_stats(strategy: str, mu_o: float, r: float, n: int, seed: int | None) -> tuple[float, float, float, float]:
    """(variance, max, mean, standard error of the mean) of the throughput weight, n samples."""
    from ..models import evaluate
    from .api import sample_rng

    wo = wo_of(mu_o)
    wi, p = sample_rng(strategy, wo, r, seed, shape=(n,))
    f = evaluate("eon", wi, wo, r, _WHITE)[:, 0]
    ok = p > 0.0
    w = np.where(ok, f * np.maximum(wi[:, 2], 0.0) / np.where(ok, p, 1.0), 0.0)
    var = float(w.var())
    return var, float(w.max()), float(w.mean()), math.sqrt(var / n)


def exact_weight_moments(strategy: str, mu_o: float, r: float, n: int = 16) -> tuple[float, float]:
    """(mean, variance) of the throughput weight by quadrature, no sampling.

    mean = int_{pdf > 0} f mu_i dwi, second moment = int_{pdf > 0} (f mu_i)^2 / pdf dwi,
    integrated with :func:`openpbr_diffuse.albedo.quadrature.hemisphere_albedo` (which
    multiplies by mu_i: the integrands are passed divided by it).
    """
    from ..albedo.quadrature import hemisphere_albedo
    from ..models import evaluate
    from .api import pdf

    def integrand(second: bool) -> Callable[[NDArray[np.float64], NDArray[np.float64]], NDArray[np.float64]]:
        def g(wi: NDArray[np.float64], wo: NDArray[np.float64]) -> NDArray[np.float64]:
            f = evaluate("eon", wi, wo, r, _WHITE)[..., 0]
            p = pdf(strategy, wo, wi, r)
            ok = p > 0.0
            if not second:
                return np.where(ok, f, 0.0)
            return np.where(ok, f * f * wi[..., 2] / np.where(ok, p, 1.0), 0.0)

        return g

    mu = float(mu_o)
    m1 = float(hemisphere_albedo(integrand(False), mu, n))
    m2 = float(hemisphere_albedo(integrand(True), mu, n))
    return m1, max(0.0, m2 - m1 * m1)


def _gl_nodes(edges, nq):
    x, w = np.polynomial.legendre.leggauss(nq)
    lo, hi = edges[:-1, None], edges[1:, None]
    return 0.5 * (lo + hi) + 0.5 * (hi - lo) * x, 0.5 * (hi - lo) * w


def bin_mass(
    strategy: str, wo: ArrayLike, r: ArrayLike, z_edges: ArrayLike, phi_edges: ArrayLike, nq: int = 6
) -> NDArray[np.float64]:
    """Integral of ``pdf`` over each (cos theta, phi) bin (Gauss-Legendre nq x nq per bin)."""
    from .api import pdf

    zn, zw = _gl_nodes(np.asarray(z_edges, float), nq)
    pn, pw = _gl_nodes(np.asarray(phi_edges, float), nq)
    Z = zn[:, None, :, None]
    P = pn[None, :, None, :]
    S = np.sqrt(np.maximum(0.0, 1.0 - Z * Z))
    wi = np.stack(np.broadcast_arrays(S * np.cos(P), S * np.sin(P), Z), axis=-1)
    p = pdf(strategy, wo, wi, r)
    return np.einsum("ijab,ia,jb->ij", p, zw, pw)


def pdf_mass(strategy: str, mu_o: float, r: float, res: tuple[int, int] = (48, 96)) -> float:
    """Integral of ``pdf`` over the hemisphere (the whole sphere for "ltc")."""
    sphere = strategy == "ltc"
    z = np.linspace(-1.0 if sphere else 0.0, 1.0, (2 if sphere else 1) * res[0] + 1)
    phi = np.linspace(0.0, 2.0 * math.pi, res[1] + 1)
    return float(bin_mass(strategy, wo_of(mu_o, 0.7), r, z, phi).sum())


def pearson_chi2(observed: ArrayLike, expected: ArrayLike, min_expected: float = 5.0) -> tuple[float, float, int]:
    """(p-value, chi2, dof) of Pearson's goodness-of-fit statistic, sparse bins pooled.

    Mitsuba 3's rule (``mitsuba.chi2``): bins sorted by expected count; consecutive bins
    expected to hold fewer than ``min_expected`` samples are merged until the pool reaches it;
    a remainder that never does counts as one more bin (its expectation floored at
    ``min_expected``).  Samples in bins where the pdf expects none give chi2 = inf (p = 0): a
    sampler that puts directions where its pdf is 0 fails.  dof = bins - 1.  The loop runs
    over the bins of a histogram (a few hundred), not over samples.  This is the one
    implementation: the report, the graders and the test suite all call it.
    """
    from scipy.special import chdtrc  # the chi-square survival function (scipy.stats.chi2.sf's)

    order = np.argsort(expected, axis=None)
    obs = np.asarray(observed, dtype=np.float64).ravel()[order]
    exp = np.asarray(expected, dtype=np.float64).ravel()[order]
    chi2, dof = 0.0, 0
    pool_o = pool_e = 0.0
    for o, e in zip(obs, exp):
        if e < min_expected:
            pool_o += o
            pool_e += e
            if pool_e >= min_expected:
                chi2 += (pool_o - pool_e) ** 2 / pool_e
                dof += 1
                pool_o = pool_e = 0.0
        else:
            chi2 += (o - e) ** 2 / e
            dof += 1
    if pool_e > 0.0:
        chi2 += (pool_o - pool_e) ** 2 / max(pool_e, min_expected)
        dof += 1
    elif pool_o > 0.0:
        chi2 = math.inf
    dof = max(dof - 1, 1)
    return float(chdtrc(dof, chi2)), float(chi2), dof


def chi2_test(
    strategy: str, mu_o: float, r: float, n: int, seed: int | None, res: tuple[int, int] = (16, 32)
) -> tuple[float, float, int, float]:
    """(p-value, chi2, dof, binned pdf mass) of n samples of ``strategy`` against its pdf."""
    from .api import sample_rng

    wo = wo_of(mu_o, 0.7)
    sphere = strategy == "ltc"
    z_edges = np.linspace(-1.0 if sphere else 0.0, 1.0, (2 if sphere else 1) * res[0] + 1)
    phi_edges = np.linspace(0.0, 2.0 * math.pi, res[1] + 1)
    wi, _ = sample_rng(strategy, wo, r, seed, shape=(n,))
    phi = np.mod(np.arctan2(wi[:, 1], wi[:, 0]), 2.0 * math.pi)
    observed, _, _ = np.histogram2d(wi[:, 2], phi, bins=[z_edges, phi_edges])
    mass = bin_mass(strategy, wo, r, z_edges, phi_edges)
    p, chi2, dof = pearson_chi2(observed, n * mass)
    return p, chi2, dof, float(mass.sum())


__all__ = ["weight_stats", "exact_weight_moments", "chi2_test", "pdf_mass", "bin_mass", "pearson_chi2", "wo_of"]
