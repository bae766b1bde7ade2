"""Chi-square goodness of fit of a sampler's directions against a pdf (Mitsuba 3's design).

Directions are binned over (cos theta, phi) on the upper hemisphere; the expected count of each
bin is n times the integral of the pdf over the bin (Gauss-Legendre in both coordinates, the
pdf called on the nodes — here, the implementation's own pdf).  Bins expected to hold fewer than
5 samples are pooled, and the p-value is the chi-square survival function (scipy.special.chdtrc).

Examples
--------
Cosine-distributed directions pass against the cosine pdf and fail against the uniform one:

>>> import numpy as np
>>> import openpbr_diffuse as od
>>> wo = np.array([0.0, 0.0, 1.0])
>>> wi, _ = od.sample_rng("cosine", wo, 0.5, 7, shape=(50_000,))
>>> chi2_test(wi, lambda d: od.pdf("cosine", wo, d, 0.5))["p"] > 0.01
True
>>> chi2_test(wi, lambda d: od.pdf("uniform", wo, d, 0.5))["p"] < 1e-10
True
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

MIN_EXPECTED = 5.0


def _nodes(edges, nq):
    x, w = np.polynomial.legendre.leggauss(nq)
    lo, hi = edges[:-1, None], edges[1:, None]
    return 0.5 * (lo + hi) + 0.5 * (hi - lo) * x, 0.5 * (hi - lo) * w


def bin_masses(
    pdf: Callable[[NDArray[np.float64]], ArrayLike], z_edges: ArrayLike, phi_edges: ArrayLike, nq: int = 4
) -> NDArray[np.float64]:
    """Integral of ``pdf(wi (m,3)) -> (m,)`` over each (cos theta, phi) bin: (nz, nphi)."""
    zn, zw = _nodes(z_edges, nq)
    pn, pw = _nodes(phi_edges, nq)
    Z = np.broadcast_to(zn[:, None, :, None], (zn.shape[0], pn.shape[0], nq, nq))
    P = np.broadcast_to(pn[None, :, None, :], Z.shape)
    S = np.sqrt(np.clip(1.0 - Z * Z, 0.0, None))
    wi = np.stack([S * np.cos(P), S * np.sin(P), Z], axis=-1)
    p = np.asarray(pdf(wi.reshape(-1, 3)), dtype=np.float64).reshape(Z.shape)
    return np.einsum("ijab,ia,jb->ij", p, zw, pw)


def histogram(wi: ArrayLike, z_edges: NDArray[np.float64], phi_edges: NDArray[np.float64]) -> NDArray[np.float64]:
    wi = np.asarray(wi, dtype=np.float64)
    phi = np.mod(np.arctan2(wi[:, 1], wi[:, 0]), 2.0 * np.pi)
    counts, _, _ = np.histogram2d(wi[:, 2], phi, bins=[z_edges, phi_edges])
    return counts


def pearson(observed: ArrayLike, expected: ArrayLike, min_expected: float = MIN_EXPECTED) -> tuple[float, float, int]:
    """(p-value, chi2, dof): :func:`openpbr_diffuse.sampling.quality.pearson_chi2`."""
    from ..sampling.quality import pearson_chi2

    return pearson_chi2(observed, expected, min_expected)


def chi2_test(
    samples: ArrayLike, pdf: Callable[[NDArray[np.float64]], ArrayLike], res: tuple[int, int] = (16, 32), nq: int = 4
) -> dict[str, Any]:
    """Test directions ``samples`` (n,3) against ``pdf``; returns a dict with p, chi2, dof,
    the pdf's mass over the hemisphere and the number of samples outside it."""
    samples = np.asarray(samples, dtype=np.float64)
    inside = samples[:, 2] >= 0.0
    z_edges = np.linspace(0.0, 1.0, res[0] + 1)
    phi_edges = np.linspace(0.0, 2.0 * np.pi, res[1] + 1)
    mass = bin_masses(pdf, z_edges, phi_edges, nq)
    observed = histogram(samples[inside], z_edges, phi_edges)
    n = samples.shape[0]
    p, chi2, dof = pearson(observed, n * mass)
    return {"p": p, "chi2": chi2, "dof": dof, "mass": float(mass.sum()), "outside": int((~inside).sum()), "n": int(n)}
