"""Monte Carlo ground truth: albedo and BRDF of a rough Lambertian microsurface.

``simulate_albedo``, ``simulate_average_albedo`` and ``simulate_brdf`` trace light paths on
one of ``GEOMETRIES`` (``vcavity``: Oren & Nayar's V-grooves, roughness sigma in radians;
``smith-beckmann`` / ``smith-ggx``: Heitz et al. 2016's Smith microsurface, roughness alpha)
made of Lambertian microfacets of albedo rho, and return estimates with standard errors.

Reproducibility: the paths of a query are cut into chunks of ``CHUNK_PATHS``; chunk i of
the query draws its random numbers from a seed derived from (seed, kind of query,
geometry, the query's own values (mu or wi), i).  Chunks are summed in their own order, so a
result depends on (geometry, roughness, query, rho, paths, seed) only: not on the other
queries of the call, the number of workers, or whether a Dask cluster ran it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _arrays as ar
from ._common import N_ORDERS
from ._dask import SCHEDULER_TIMEOUT_S, _client  # noqa: F401  (re-exported: the library's pool uses them)
from ._run import CHUNK_PATHS, RunOptions, albedo_queries, chunk_seed, chunk_sum, mean_err, run_chunks, run_fields

#: microgeometry name -> (roughness name, allowed range)
GEOMETRIES = {
    "vcavity": ("sigma", 0.0, math.pi / 2),
    "smith-beckmann": ("alpha", 0.0, 2.0),
    "smith-ggx": ("alpha", 0.0, 2.0),
}
#: a path still inside the surface after this many bounces is cut (counted in ``truncated``)
#: and scored rho^(MAX_BOUNCES + 1): exact at rho = 1, high by < rho^MAX_BOUNCES otherwise
#: (deep V-grooves, slope near pi/2, trap light for very many bounces)
MAX_BOUNCES = 1_000
_KIND = {"albedo": 1, "average": 2, "brdf": 3}


def _check_geometry(geometry, roughness):
    if not isinstance(geometry, str) or geometry not in GEOMETRIES:
        raise ValueError(f"geometry must be one of {', '.join(GEOMETRIES)}, got {geometry!r}")
    name, lo, hi = GEOMETRIES[geometry]
    if isinstance(roughness, bool) or not isinstance(roughness, (int, float, np.integer, np.floating)):
        raise TypeError(f"roughness must be a number ({name} in [{lo:g}, {hi:g}]), got {type(roughness).__name__}")
    r = float(roughness)
    if not (lo <= r <= hi):
        raise ValueError(f"roughness ({name} of {geometry}) must be in [{lo:g}, {hi:.6g}], got {r!r}")
    return r


def _rho(rho: ArrayLike) -> NDArray[np.float64]:
    r = ar.rho_array("rho", rho, np.dtype(np.float64))
    if r.ndim != 1:
        raise ValueError(f"rho must be a scalar or one value per channel (shape (C,)), got shape {r.shape}")
    return np.ascontiguousarray(r)


def _run_task(task):
    """One chunk (module-level so that Dask workers can import it)."""
    from ._kernels import run_chunk

    geometry, roughness, wi, random_wi, wo, rho, n, seed = task
    return run_chunk(geometry, roughness, wi, random_wi, wo, rho, n, seed, MAX_BOUNCES)


#: Smallest incident cosine simulated (below it the Smith walk's floating point underflows).
MU_MIN = 1e-100


def _run(kind, geometry, roughness, queries, rho, run):
    """The chunks of each query (wi, wo, key) run: results and each query's task slice."""
    identity = [list(GEOMETRIES).index(geometry)]
    random_wi = kind == "average"

    def task(query, i, n):
        wi, wo, key = query
        seed = chunk_seed(run.seed, _KIND[kind], identity, key, i)
        return (geometry, roughness, wi, random_wi, wo, rho, n, seed)

    return run_chunks(_run_task, queries, task, run)


@dataclass
class AlbedoEstimate:
    """Directional albedo E(mu) of a simulated microsurface, total and by bounce order.

    Arrays: ``albedo``/``stderr`` (n, C); ``albedo_by_order``/``stderr_by_order`` (n, 3, C)
    for orders 1, 2 and >= 3.  ``bounces``: mean bounces per path (n,); ``truncated``: paths
    cut at ``MAX_BOUNCES`` (scored as if they left then: exact at rho = 1, an overestimate
    by less than rho^MAX_BOUNCES each otherwise).  For ``simulate_average_albedo`` the
    leading axis has length 1 and ``mu`` is None.
    """

    geometry: str
    roughness: float
    mu: np.ndarray | None
    rho: np.ndarray
    paths: int
    seed: int
    albedo: np.ndarray
    stderr: np.ndarray
    albedo_by_order: np.ndarray
    stderr_by_order: np.ndarray
    bounces: np.ndarray = field(repr=False)
    truncated: np.ndarray = field(repr=False)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form: ``rows`` with mu, albedo, albedo_by_order, stderr per query."""
        rows = []
        for i in range(self.albedo.shape[0]):
            rows.append(
                {
                    "mu": None if self.mu is None else float(self.mu[i]),
                    "albedo": self.albedo[i].tolist(),
                    "albedo_by_order": {
                        "1": self.albedo_by_order[i, 0].tolist(),
                        "2": self.albedo_by_order[i, 1].tolist(),
                        ">=3": self.albedo_by_order[i, 2].tolist(),
                    },
                    "stderr": self.stderr[i].tolist(),
                    "stderr_by_order": {
                        "1": self.stderr_by_order[i, 0].tolist(),
                        "2": self.stderr_by_order[i, 1].tolist(),
                        ">=3": self.stderr_by_order[i, 2].tolist(),
                    },
                    "bounces_per_path": float(self.bounces[i]),
                    "truncated": int(self.truncated[i]),
                }
            )
        name = GEOMETRIES[self.geometry][0]
        return {
            "geometry": self.geometry,
            name: self.roughness,
            "roughness": self.roughness,
            **run_fields(self.rho, self.paths, self.seed, self.mu, rows),
        }


@dataclass
class BRDFEstimate:
    """BRDF values f(wi, wo) (no cosine) by next-event estimation, total and by order.

    Arrays: ``f``/``stderr`` (n, C); ``f_by_order``/``stderr_by_order`` (n, 3, C).
    """

    geometry: str
    roughness: float
    wi: np.ndarray
    wo: np.ndarray
    rho: np.ndarray
    paths: int
    seed: int
    f: np.ndarray
    stderr: np.ndarray
    f_by_order: np.ndarray
    stderr_by_order: np.ndarray


def _albedo(geometry, roughness, mu, rho, run):
    """The directional albedo at each ``mu``, or the average albedo (``mu`` None)."""
    results, spans = _run("average" if mu is None else "albedo", geometry, roughness, albedo_queries(mu), rho, run)
    n, C = len(spans), rho.shape[0]
    E = np.empty((n, C))
    se = np.empty((n, C))
    Eo = np.empty((n, N_ORDERS, C))
    seo = np.empty((n, N_ORDERS, C))
    bounces = np.empty(n)
    trunc = np.empty(n, dtype=np.int64)
    for q, span in enumerate(spans):
        s1, s2, stats = chunk_sum(results, span, 0), chunk_sum(results, span, 1), chunk_sum(results, span, 4)
        N = int(stats[0])
        Eo[q], seo[q] = mean_err(s1, s2, N)
        E[q], se[q] = mean_err(s1.sum(axis=0), s2.sum(axis=0), N)  # classes are disjoint
        bounces[q] = stats[1] / N
        trunc[q] = stats[2]
    return AlbedoEstimate(geometry, roughness, mu, rho, run.paths, run.seed, E, se, Eo, seo, bounces, trunc)


def simulate_albedo(
    geometry: str,
    roughness: float,
    mu: ArrayLike,
    rho: ArrayLike = 1.0,
    paths: int = 1_000_000,
    seed: int = 0,
    *,
    workers: int | None = None,
    client: Any = None,
    scheduler: str | None = None,
    progress: bool = False,
) -> AlbedoEstimate:
    """Directional albedo E(mu) of a rough Lambertian microsurface, by Monte Carlo.

    Parameters
    ----------
    geometry : {"vcavity", "smith-beckmann", "smith-ggx"}
    roughness : float
        sigma (radians, std of the facet slope angle, [0, pi/2]) for "vcavity"; alpha
        ([0, 2]) for the Smith surfaces.
    mu : array_like, shape (n,)
        Cosines of the incident direction, in [MU_MIN, 1] (``MU_MIN`` = 1e-100: below it
        the Smith path tracer's floating point underflows; E(mu) is continuous there).
    rho : array_like, shape (C,)
        Microfacet albedo per channel in [0, 1]; all channels share the same paths.
    paths : int
        Paths per mu.
    seed : int
        Non-negative seed; results are reproducible per (seed, query, chunk).
    workers : int, optional
        Local threads (default: all cores); ignored when a Dask ``client``/``scheduler``
        (address) is given.  A ``scheduler`` address must answer within
        ``SCHEDULER_TIMEOUT_S`` seconds, else ``ConnectionError``.
    progress : bool
        Show a tqdm progress bar on stderr (local runs).

    Returns
    -------
    AlbedoEstimate

    References
    ----------
    Oren & Nayar 1994 (V-cavities); Heitz, Hanika, d'Eon, Dachsbacher 2016 (Smith random walk).

    Examples
    --------
    >>> est = simulate_albedo("vcavity", 0.0, [0.5], rho=[0.8, 0.4], paths=1000, seed=1)
    >>> est.albedo.round(12).tolist()  # a flat surface: Lambert, one bounce
    [[0.8, 0.4]]
    """
    roughness = _check_geometry(geometry, roughness)
    mu = np.atleast_1d(ar.as_float("mu", mu, np.dtype(np.float64))).astype(np.float64)
    if mu.ndim != 1:
        raise ValueError(f"mu must be a scalar or a 1-D list of cosines, got shape {mu.shape}")
    bad = ~((mu >= MU_MIN) & (mu <= 1.0))
    if bad.any():
        raise ValueError(
            f"mu must be in [1e-100, 1] (cosine of the incident angle; MU_MIN = 1e-100), got {mu[bad][0]!r}"
        )
    rho = _rho(rho)
    return _albedo(geometry, roughness, mu, rho, RunOptions.check(paths, seed, workers, client, scheduler, progress))


def simulate_average_albedo(
    geometry: str,
    roughness: float,
    rho: ArrayLike = 1.0,
    paths: int = 1_000_000,
    seed: int = 0,
    *,
    workers: int | None = None,
    client: Any = None,
    scheduler: str | None = None,
    progress: bool = False,
) -> AlbedoEstimate:
    """Average albedo <E> = 2 int_0^1 E(mu) mu dmu (incident directions cosine-distributed).

    Same parameters as ``simulate_albedo`` without ``mu``; the result's arrays have a
    leading axis of length 1 and ``mu`` is None.

    Examples
    --------
    >>> est = simulate_average_albedo("smith-ggx", 0.5, rho=1.0, paths=2000, seed=3)
    >>> float(est.albedo[0, 0])  # every path leaves the surface
    1.0
    """
    roughness = _check_geometry(geometry, roughness)
    rho = _rho(rho)
    return _albedo(geometry, roughness, None, rho, RunOptions.check(paths, seed, workers, client, scheduler, progress))


def simulate_brdf(
    geometry: str,
    roughness: float,
    wi: ArrayLike,
    wo: ArrayLike,
    rho: ArrayLike = 1.0,
    paths: int = 1_000_000,
    seed: int = 0,
    *,
    workers: int | None = None,
    client: Any = None,
    scheduler: str | None = None,
    progress: bool = False,
) -> BRDFEstimate:
    """BRDF f(wi, wo) (without the cosine) of the microsurface, by next-event estimation.

    Light paths start from ``wi``; every bounce adds its exact contribution towards ``wo``
    (the facet's Lambertian lobe times the probability that ``wo`` leaves the surface from
    there), so the estimate is unbiased for each (wi, wo), with no angular binning.

    Parameters
    ----------
    wi, wo : array_like, shape (n, 3) or (3,)
        Unit directions above the horizon (z > 0), broadcast against each other; rows that
        share the same wi share the same paths.
    geometry, roughness, rho, paths, seed, workers, client, scheduler
        As ``simulate_albedo``; ``paths`` per distinct wi.

    Returns
    -------
    BRDFEstimate

    Examples
    --------
    >>> est = simulate_brdf("vcavity", 0.0, [0.0, 0.0, 1.0], [0.6, 0.0, 0.8], rho=0.5, paths=100)
    >>> round(float(est.f[0, 0]) * 3.141592653589793, 12)  # flat: Lambert rho/pi
    0.5
    """
    roughness = _check_geometry(geometry, roughness)
    dt = np.dtype(np.float64)
    wi = ar.directions("wi", wi, dt).astype(np.float64)
    wo = ar.directions("wo", wo, dt).astype(np.float64)
    if wi.ndim == 1:
        wi = wi[None]
    if wo.ndim == 1:
        wo = wo[None]
    if wi.ndim != 2 or wo.ndim != 2:
        raise ValueError("wi and wo must have shape (3,) or (n, 3)")
    n = max(len(wi), len(wo))
    wi = np.broadcast_to(wi, (n, 3))
    wo = np.broadcast_to(wo, (n, 3))
    for name, w in (("wi", wi), ("wo", wo)):
        if (w[:, 2] <= 0.0).any():
            raise ValueError(f"{name} must be above the horizon (z > 0)")
    rho = _rho(rho)
    run = RunOptions.check(paths, seed, workers, client, scheduler, progress)
    uniq, inverse = np.unique(wi, axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    queries, rows = [], []
    for g in range(len(uniq)):
        idx = np.flatnonzero(inverse == g)
        rows.append(idx)
        queries.append((np.ascontiguousarray(uniq[g]), np.ascontiguousarray(wo[idx]), uniq[g]))
    results, spans = _run("brdf", geometry, roughness, queries, rho, run)
    C = rho.shape[0]
    f = np.empty((n, C))
    se = np.empty((n, C))
    fo = np.empty((n, N_ORDERS, C))
    seo = np.empty((n, N_ORDERS, C))
    for idx, span in zip(rows, spans):
        s1, s2, N = chunk_sum(results, span, 2), chunk_sum(results, span, 3), int(chunk_sum(results, span, 4)[0])
        mean, err = mean_err(s1, s2, N)
        f[idx], se[idx] = mean[:, N_ORDERS], err[:, N_ORDERS]
        fo[idx], seo[idx] = mean[:, :N_ORDERS], err[:, :N_ORDERS]
    return BRDFEstimate(geometry, roughness, np.array(wi), np.array(wo), rho, run.paths, run.seed, f, se, fo, seo)


__all__ = [
    "GEOMETRIES",
    "CHUNK_PATHS",
    "MAX_BOUNCES",
    "AlbedoEstimate",
    "BRDFEstimate",
    "simulate_albedo",
    "simulate_average_albedo",
    "simulate_brdf",
]
