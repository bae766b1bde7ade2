"""Monte Carlo ground truth for a diffuse base under a dielectric layer.

``LayeredSurface`` describes the stack: a dielectric interface of relative index ``ior``
(``interface="smooth"``, or ``"ggx"`` with GGX width ``interface_alpha`` and all
microfacet inter-reflections), an absorbing slab (Beer-Lambert: optical depth
``absorption * thickness`` per unit path length along the normal, or OpenPBR's
``coat_color`` as the normal-incidence transmittance, a pass at cosine mu_t inside
transmitting coat_color^(1/mu_t)) and a diffuse base (``"lambert"`` or ``"eon"`` with
roughness r) of albedo rho.  ``simulate_layered_albedo``, ``simulate_layered_average_albedo``
and ``simulate_layered_brdf`` trace it by a position-free random walk (Guo, Hasan, Zhao
2018; ``_layered_kernels``) and return estimates with standard errors, the albedo split
into the specular part (light that never entered the slab) and the diffuse part
(everything that reached the base).

Reproducibility as for the microsurface simulator (``api``): the paths of a query are
cut into chunks of ``CHUNK_PATHS``; chunk i draws from a seed derived from (seed, kind,
the surface, the query's values, i) and chunks are summed in their own order, so a result
does not depend on the number of workers or on whether a Dask cluster ran it.

Example
-------
>>> s = LayeredSurface("smooth", 1.5, base="lambert")
>>> e = simulate_layered_albedo(s, [1.0], rho=0.8, paths=20000, seed=1)
>>> bool(abs(e.total[0, 0] - smooth_lambert_albedo(1.5, 0.8, 1.0)) < 4 * e.total_stderr[0, 0])
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _arrays as ar
from ._run import CHUNK_PATHS as CHUNK_PATHS  # public, as in ``api``: the paths per chunk
from ._run import RunOptions, albedo_queries, chunk_seed, chunk_sum, mean_err, run_chunks, run_fields

INTERFACES = ("smooth", "ggx")
BASES = ("lambert", "eon", "smith-ggx")
#: a path that reached the base more often than this is cut (counted in ``truncated``)
MAX_BOUNCES = 10_000
_KIND = {"albedo": 11, "average": 12, "brdf": 13}


def _number(name: str, v: float, lo: float, hi: float, lo_open: bool = False) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name} must be a number, got {type(v).__name__}")
    x = float(v)
    bad = not math.isfinite(x) or x > hi or (x <= lo if lo_open else x < lo)
    if bad:
        rng = f"({lo:g}, {hi:g}]" if lo_open else f"[{lo:g}, {hi:g}]"
        raise ValueError(f"{name} must be in {rng}, got {v!r}")
    return x


@dataclass(frozen=True)
class LayeredSurface:
    """A dielectric interface over an absorbing slab over a diffuse base.

    Parameters
    ----------
    interface : {"smooth", "ggx"}
    ior : float
        Relative index of refraction of the slab, in [1, 4].
    interface_alpha : float
        GGX width alpha of the rough interface (OpenPBR: alpha = coat_roughness^2), in
        [0, 1]; ignored (0) for "smooth".
    absorption, thickness : float
        Beer-Lambert absorption coefficient and slab thickness (optical depth tau =
        absorption * thickness along the normal; a pass at cosine mu transmits
        exp(-tau/mu)).  Scalars or one value per channel.
    coat_color : array_like, optional
        OpenPBR's coat_color, the transmittance of one pass at normal incidence, in [0, 1]
        (tau = -ln coat_color); exclusive with absorption/thickness.
    base : {"lambert", "eon", "smith-ggx"}
    roughness : float
        EON roughness r of the base in [0, 1] (0 for Lambert); for "smith-ggx" (a Smith GGX
        microsurface of Lambertian microfacets, simulated) its GGX alpha in [0, 2].

    Example
    -------
    >>> [round(float(t), 8) for t in LayeredSurface("smooth", 1.5, coat_color=0.5).tau]
    [0.69314718]
    """

    interface: str
    ior: float
    interface_alpha: float = 0.0
    absorption: ArrayLike = 0.0
    thickness: float = 0.0
    coat_color: ArrayLike | None = None
    base: str = "lambert"
    roughness: float = 0.0

    def __post_init__(self) -> None:
        if self.interface not in INTERFACES:
            raise ValueError(f"interface must be one of {', '.join(INTERFACES)}, got {self.interface!r}")
        if self.base not in BASES:
            raise ValueError(f"base must be one of {', '.join(BASES)}, got {self.base!r}")
        object.__setattr__(self, "ior", _number("ior", self.ior, 1.0, 4.0))
        a = _number("interface_alpha", self.interface_alpha, 0.0, 1.0)
        object.__setattr__(self, "interface_alpha", a if self.interface == "ggx" else 0.0)
        object.__setattr__(
            self, "roughness", _number("roughness", self.roughness, 0.0, 2.0 if self.base == "smith-ggx" else 1.0)
        )
        object.__setattr__(self, "thickness", _number("thickness", self.thickness, 0.0, 1e6))
        absorbing = np.any(np.asarray(self.absorption, dtype=float) != 0.0) or self.thickness != 0.0
        if self.coat_color is not None and absorbing:
            raise ValueError("give either coat_color or absorption and thickness, not both")

    @property
    def tau(self) -> np.ndarray:
        """Per-channel normal optical depth of the slab (shape (C,) or (1,))."""
        if self.coat_color is not None:
            cc = ar.rho_array("coat_color", self.coat_color, np.dtype(np.float64)).reshape(-1)
            with np.errstate(divide="ignore"):
                return np.where(cc > 0.0, -np.log(np.where(cc > 0.0, cc, 1.0)), np.inf)
        a = np.asarray(self.absorption, dtype=float).reshape(-1)
        if a.size == 0 or not np.all(np.isfinite(a)) or np.any(a < 0.0):
            raise ValueError(f"absorption must be finite and >= 0, got {self.absorption!r}")
        return a * self.thickness

    def key(self) -> list:
        """Integers identifying the surface (for the chunk seeds)."""
        vals = [self.ior, self.interface_alpha, self.roughness, *self.tau.tolist()]
        bits = np.frombuffer(np.asarray(vals, dtype=np.float64).tobytes(), dtype=np.uint32)
        return [INTERFACES.index(self.interface), BASES.index(self.base), *map(int, bits)]


def _channels(surface: LayeredSurface, rho: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    r = np.ascontiguousarray(ar.rho_array("rho", rho, np.dtype(np.float64)).reshape(-1))
    tau = surface.tau
    if r.size == 0:
        raise ValueError("rho must have at least one channel")
    C = max(r.size, tau.size)
    if r.size not in (1, C) or tau.size not in (1, C):
        raise ValueError(f"rho ({r.size} channels) and the slab ({tau.size} channels) disagree")
    return np.ascontiguousarray(np.broadcast_to(r, (C,))), np.ascontiguousarray(np.broadcast_to(tau, (C,)))


def _mu(mu: ArrayLike) -> np.ndarray:
    m = np.atleast_1d(np.asarray(mu, dtype=float))
    if m.ndim != 1 or m.size == 0 or not np.all((m > 0.0) & (m <= 1.0)):
        raise ValueError(f"mu must be cosines in (0, 1], got {mu!r}")
    return m


def _run_task(task):
    """One chunk (module-level so that Dask workers can import it)."""
    from ._layered_kernels import EON, LAMBERT, SMITH, chunk_kernel

    alpha, eta, tau, base, r, rho, wi, random_wi, wo, n, seed = task
    b = {"lambert": LAMBERT, "eon": EON, "smith-ggx": SMITH}[base]
    return chunk_kernel(b)(alpha, eta, tau, r, rho, wi, random_wi, wo, n, seed, MAX_BOUNCES)


def _run(kind, surface, queries, rho, tau, run):
    """The chunks of each query (wi, wo, key) run: results and each query's task slice."""
    identity = surface.key()
    random_wi = kind == "average"

    def task(query, i, n):
        wi, wo, key = query
        seed = chunk_seed(run.seed, _KIND[kind], identity, key, i)
        return (
            surface.interface_alpha,
            surface.ior,
            tau,
            surface.base,
            surface.roughness,
            rho,
            wi,
            random_wi,
            wo,
            n,
            seed,
        )

    return run_chunks(_run_task, queries, task, run)


@dataclass
class LayeredAlbedo:
    """Directional (or average) albedo of a layered surface, split into parts.

    Arrays (n, C): ``specular`` (first-interface reflection), ``diffuse`` (light that
    reached the base), ``total``, and their ``*_stderr``.  ``mu`` is None for the average
    albedo (n = 1).  ``base_events``: mean base events per path; ``truncated``: paths cut.
    """

    surface: LayeredSurface
    mu: np.ndarray | None
    rho: np.ndarray
    paths: int
    seed: int
    specular: np.ndarray
    specular_stderr: np.ndarray
    diffuse: np.ndarray
    diffuse_stderr: np.ndarray
    total: np.ndarray
    total_stderr: np.ndarray
    base_events: np.ndarray
    truncated: np.ndarray

    def to_dict(self) -> dict:
        """JSON-ready form: the surface, and one row per mu."""
        s = self.surface
        rows = [
            {
                "mu": None if self.mu is None else float(self.mu[i]),
                "specular": self.specular[i].tolist(),
                "specular_stderr": self.specular_stderr[i].tolist(),
                "diffuse": self.diffuse[i].tolist(),
                "diffuse_stderr": self.diffuse_stderr[i].tolist(),
                "total": self.total[i].tolist(),
                "total_stderr": self.total_stderr[i].tolist(),
                "base_events_per_path": float(self.base_events[i]),
                "truncated": int(self.truncated[i]),
            }
            for i in range(self.total.shape[0])
        ]
        return {
            "interface": s.interface,
            "ior": s.ior,
            "interface_alpha": s.interface_alpha,
            "tau": s.tau.tolist(),
            "base": s.base,
            "roughness": s.roughness,
            **run_fields(self.rho, self.paths, self.seed, self.mu, rows),
        }


@dataclass
class LayeredBRDF:
    """Diffuse part of the BRDF f(wi, wo) (no cosine) by next-event estimation, (n, C)."""

    surface: LayeredSurface
    wi: np.ndarray
    wo: np.ndarray
    rho: np.ndarray
    paths: int
    seed: int
    f: np.ndarray
    stderr: np.ndarray


def _albedo(kind, surface, mu, rho, paths, seed, workers, client, scheduler):
    if not isinstance(surface, LayeredSurface):
        raise TypeError(f"surface must be a LayeredSurface, got {type(surface).__name__}")
    run = RunOptions.check(paths, seed, workers, client, scheduler, min_paths=2)
    r, tau = _channels(surface, rho)
    results, spans = _run(kind, surface, albedo_queries(None if kind == "average" else mu), r, tau, run)
    n, C = len(spans), r.size
    out = {k: np.empty((n, C)) for k in ("s", "se", "d", "de", "t", "te")}
    ev = np.empty(n)
    tr = np.empty(n, dtype=np.int64)
    for q, span in enumerate(spans):
        s1, s2, st = chunk_sum(results, span, 0), chunk_sum(results, span, 1), chunk_sum(results, span, 4)
        N = int(st[0])
        for row, (m_, e_) in enumerate((("s", "se"), ("d", "de"), ("t", "te"))):
            out[m_][q], out[e_][q] = mean_err(s1[row], s2[row], N)
        ev[q] = st[1] / N
        tr[q] = st[2]
    return LayeredAlbedo(
        surface,
        None if kind == "average" else mu,
        r,
        run.paths,
        run.seed,
        out["s"],
        out["se"],
        out["d"],
        out["de"],
        out["t"],
        out["te"],
        ev,
        tr,
    )


def simulate_layered_albedo(
    surface: LayeredSurface,
    mu: ArrayLike,
    rho: ArrayLike = 1.0,
    paths: int = 1_000_000,
    seed: int = 0,
    *,
    workers: int | None = None,
    client: Any = None,
    scheduler: str | None = None,
) -> LayeredAlbedo:
    """Directional albedo E(mu) of a layered surface, split into specular and diffuse parts.

    Parameters
    ----------
    surface : LayeredSurface
    mu : array_like, shape (n,)
        Cosines of the incident (equivalently, by reciprocity, viewing) direction, (0, 1].
    rho : array_like, shape (C,)
        Base albedo per channel in [0, 1].
    paths, seed : int
        Paths per mu; non-negative seed (results reproducible per (seed, query, chunk)).
    workers : int, optional
        Local threads (default: all cores); a Dask ``client`` or ``scheduler`` address
        runs the chunks on a cluster instead, with bit-identical results.

    Returns
    -------
    LayeredAlbedo

    Example
    -------
    >>> e = simulate_layered_albedo(LayeredSurface("smooth", 1.0), [0.5], rho=0.7, paths=1000)
    >>> round(float(e.total[0, 0]), 12), float(e.specular[0, 0])
    (0.7, 0.0)
    """
    return _albedo("albedo", surface, _mu(mu), rho, paths, seed, workers, client, scheduler)


def simulate_layered_average_albedo(
    surface: LayeredSurface,
    rho: ArrayLike = 1.0,
    paths: int = 1_000_000,
    seed: int = 0,
    *,
    workers: int | None = None,
    client: Any = None,
    scheduler: str | None = None,
) -> LayeredAlbedo:
    """Cosine-weighted average albedo <E> = 2 int E(mu) mu dmu (paths from cosine-distributed wi).

    Example
    -------
    >>> e = simulate_layered_average_albedo(LayeredSurface("ggx", 1.5, 0.3), rho=1.0, paths=2000)
    >>> bool(abs(e.total[0, 0] - 1.0) < 1e-12)
    True
    """
    return _albedo("average", surface, None, rho, paths, seed, workers, client, scheduler)


def _dirs(name: str, v: ArrayLike) -> NDArray[np.float64]:
    a = np.asarray(v, dtype=float)
    if a.ndim == 1:
        a = a[None]
    if a.ndim != 2 or a.shape[1] != 3 or not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be unit vectors of shape (3,) or (n, 3)")
    nrm = np.linalg.norm(a, axis=1)
    if np.any(np.abs(nrm - 1.0) > 1e-6) or np.any(a[:, 2] <= 0.0):
        raise ValueError(f"{name} must be unit vectors above the surface (z > 0)")
    return np.ascontiguousarray(a / nrm[:, None])


def simulate_layered_brdf(
    surface: LayeredSurface,
    wi: ArrayLike,
    wo: ArrayLike,
    rho: ArrayLike = 1.0,
    paths: int = 1_000_000,
    seed: int = 0,
    *,
    workers: int | None = None,
    client: Any = None,
    scheduler: str | None = None,
) -> LayeredBRDF:
    """Diffuse part of the BRDF f(wi, wo) of a smooth-interface layered surface, by NEE.

    (The specular part of a smooth interface is a Dirac delta.)  wi, wo: unit vectors (n, 3)
    or (3,), paired by row.

    Example
    -------
    >>> s = LayeredSurface("smooth", 1.0)
    >>> b = simulate_layered_brdf(s, [0, 0, 1.0], [0.6, 0, 0.8], rho=0.5, paths=2000)
    >>> bool(abs(b.f[0, 0] - 0.5 / np.pi) < 1e-12)
    True
    """
    if surface.interface != "smooth":
        raise ValueError(
            "simulate_layered_brdf needs interface='smooth' (NEE through a rough interface is not implemented)"
        )
    if surface.base == "smith-ggx":
        raise ValueError(
            "simulate_layered_brdf needs base 'lambert' or 'eon' (the microsurface base has no closed-form BRDF)"
        )
    run = RunOptions.check(paths, seed, workers, client, scheduler, min_paths=2)
    wi, wo = _dirs("wi", wi), _dirs("wo", wo)
    if wi.shape != wo.shape:
        raise ValueError(f"wi and wo must have the same shape, got {wi.shape} and {wo.shape}")
    r, tau = _channels(surface, rho)
    queries = [(wi[i], wo[i : i + 1].copy(), [*wi[i], *wo[i]]) for i in range(wi.shape[0])]
    results, spans = _run("brdf", surface, queries, r, tau, run)
    f = np.empty((len(spans), r.size))
    se = np.empty_like(f)
    for q, span in enumerate(spans):
        s1, s2, st = chunk_sum(results, span, 2), chunk_sum(results, span, 3), chunk_sum(results, span, 4)
        f[q], se[q] = mean_err(s1[0], s2[0], int(st[0]))
    return LayeredBRDF(surface, wi, wo, r, run.paths, run.seed, f, se)


# ---------------------------------------------------------------------------------------
# closed form: smooth interface over a Lambertian base (any absorption)
# ---------------------------------------------------------------------------------------


def _gauss_legendre(n: int = 256) -> tuple[np.ndarray, np.ndarray]:
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (x + 1.0), 0.5 * w


def _fresnel(c, eta):
    from ..microfacet.fresnel import fresnel_dielectric

    return np.asarray(fresnel_dielectric(np.asarray(c, dtype=float), float(eta)), dtype=float)


def smooth_lambert_terms(ior: float, tau: ArrayLike = 0.0, n: int = 400) -> tuple[np.ndarray, np.ndarray]:
    """(e_out, r_in): of cosine-distributed light leaving the base upwards, the fraction
    that leaves the surface (e_out = int 2 mu T(mu) (1 - F_int(mu)) dmu) and the fraction
    that returns to the base after one internal reflection (r_in = int 2 mu T(mu)^2
    F_int(mu) dmu), T(mu) = exp(-tau/mu), F_int the Fresnel factor from inside (1/ior).

    Without absorption r_in = 1 - (1 - r_e)/ior^2 with r_e the hemispherical Fresnel
    reflectance from outside (Lekner & Dorf 1988), and e_out = 1 - r_in.  Integrated
    piecewise (split at the critical angle, square-root edge substituted) by Gauss-Legendre.

    Example
    -------
    >>> e, r = smooth_lambert_terms(1.5)
    >>> round(float(r[0]), 4), round(float(e[0] + r[0]), 12)
    (0.5963, 1.0)
    """
    tau = np.atleast_1d(np.asarray(tau, dtype=float))
    x, w = _gauss_legendre(n)
    mc = math.sqrt(max(0.0, 1.0 - 1.0 / ior**2))  # cosine of the critical angle inside
    # [0, mc]: total internal reflection; [mc, 1]: partial
    mu1, w1 = mc * x, mc * w
    # mu = mc + (1 - mc) t^2: F_int has a square-root edge at the critical angle
    mu2, w2 = mc + (1.0 - mc) * x * x, 2.0 * (1.0 - mc) * x * w
    mu = np.concatenate([mu1, mu2])
    ww = np.concatenate([w1, w2])
    F = _fresnel(mu, 1.0 / ior)
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        T = np.where(mu[None] > 0.0, np.exp(-tau[:, None] / mu[None]), 0.0)
    e_out = (2 * mu * T * (1 - F) * ww).sum(axis=1)
    r_in = (2 * mu * T * T * F * ww).sum(axis=1)
    return e_out, r_in


def smooth_lambert_albedo(ior: float, rho: ArrayLike, mu: ArrayLike, tau: ArrayLike = 0.0) -> np.ndarray:
    """Exact directional albedo of a smooth dielectric over an absorbing slab over a
    Lambertian base, all internal reflections included:

        E(mu) = F(mu) + (1 - F(mu)) T(mu_t) rho e_out / (1 - rho r_in)

    (the light entering, the geometric series of base bounces; ``smooth_lambert_terms``).
    Without absorption this is the classical result with r_in = 1 - (1 - r_e)/n^2
    (Saunderson 1942; Lekner & Dorf 1988, "Why some things are darker when wet").

    Example
    -------
    >>> round(float(smooth_lambert_albedo(1.5, 1.0, 0.3)), 12)
    1.0
    """
    mu = np.asarray(mu, dtype=float)
    rho = np.asarray(rho, dtype=float)
    tau_a = np.atleast_1d(np.asarray(tau, dtype=float))
    e_out, r_in = smooth_lambert_terms(ior, tau_a)
    if tau_a.size == 1:
        e_out, r_in, tau_a = e_out[0], r_in[0], tau_a[0]
    F = _fresnel(mu, ior)
    mut = np.sqrt(1.0 - (1.0 - mu * mu) / ior**2)
    T = np.exp(-tau_a / mut)
    return F + (1.0 - F) * T * rho * e_out / (1.0 - rho * r_in)


def smooth_lambert_brdf(
    ior: float, rho: ArrayLike, mu_i: ArrayLike, mu_o: ArrayLike, tau: ArrayLike = 0.0
) -> np.ndarray:
    """Exact diffuse BRDF of the same stack (no cosine; the specular part is a delta):

        f = rho (1 - F(mu_i)) (1 - F(mu_o)) T(mu_ti) T(mu_to) / (pi n^2 (1 - rho r_in)).

    Example
    -------
    >>> round(float(smooth_lambert_brdf(1.0, 0.5, 0.3, 0.9)) * np.pi, 12)
    0.5
    """
    tau = float(np.asarray(tau, dtype=float).reshape(-1)[0])
    _, r_in = smooth_lambert_terms(ior, tau)
    mi, mo = np.asarray(mu_i, dtype=float), np.asarray(mu_o, dtype=float)
    ti = np.sqrt(1 - (1 - mi * mi) / ior**2)
    to = np.sqrt(1 - (1 - mo * mo) / ior**2)
    T = np.exp(-tau / ti) * np.exp(-tau / to)
    return (
        np.asarray(rho)
        * (1 - _fresnel(mi, ior))
        * (1 - _fresnel(mo, ior))
        * T
        / (math.pi * ior**2 * (1 - np.asarray(rho) * r_in[0]))
    )
