"""The chunk kernels: trace ``n_paths`` paths of one query and return their sums.

One compiled kernel per microgeometry (so that using one compiles only its own walk)."""

import functools

import numpy as np

from .._jit import walk
from . import smith, vcavity
from ._common import N_ORDERS, cosine_hemisphere, tally_path

#: geometry name -> Smith slope distribution (None: V-cavity)
GEOMETRY_IDS = {"vcavity": -1, "smith-beckmann": smith.BECKMANN, "smith-ggx": smith.GGX}

_DOC = """Trace ``n_paths`` paths from ``wi`` (or cosine-distributed wi if ``random_wi``).

    Returns
    -------
    alb_s1, alb_s2 : (3, C) sums of rho^k and rho^2k over the paths, per order class
    nee_s1, nee_s2 : (m, 4, C) sums of the per-path next-event estimates of f(wi, wo_j) and
        their squares, per order class (index 3: all orders)
    stats : (3,) int64: paths, bounces, paths cut at ``max_bounces``
    """


@walk
def _buffers(m, C):
    return (
        np.zeros((N_ORDERS, C)),
        np.zeros((N_ORDERS, C)),
        np.zeros((m, N_ORDERS + 1, C)),
        np.zeros((m, N_ORDERS + 1, C)),
        np.zeros((m, N_ORDERS, C)),
        np.empty(C),
        np.zeros(3, dtype=np.int64),
    )


@functools.cache
def _chunk_kernel(dist):
    """The chunk kernel of one microgeometry (a value of ``GEOMETRY_IDS``), a compile-time
    constant: the kernel compiles its own walk only."""
    vcav = dist < 0

    @walk
    def run(roughness, wi, random_wi, wo, rho, n_paths, seed, max_bounces):
        np.random.seed(seed)
        m, C = wo.shape[0], rho.shape[0]
        alb_s1, alb_s2, nee_s1, nee_s2, path_nee, rk, stats = _buffers(m, C)
        wo_g = np.empty((m, 3))  # the V-cavity walk's scratch
        wx, wy, wz = wi[0], wi[1], wi[2]
        for _ in range(n_paths):
            if random_wi:
                wx, wy, wz = cosine_hemisphere()
            if vcav:
                k, escaped = vcavity.walk(wx, wy, wz, wo, roughness, rho, rk, wo_g, path_nee, max_bounces)
            else:
                k, escaped = smith.walk(wx, wy, wz, wo, roughness, dist, rho, rk, path_nee, max_bounces)
            stats[0] += 1
            stats[1] += min(k, max_bounces)
            stats[2] += 0 if escaped else 1
            tally_path(k, escaped, rho, path_nee, alb_s1, alb_s2, nee_s1, nee_s2)
        return alb_s1, alb_s2, nee_s1, nee_s2, stats

    return run


def run_chunk(geometry, roughness, wi, random_wi, wo, rho, n_paths, seed, max_bounces):
    """One chunk on ``geometry`` (a name of ``GEOMETRY_IDS``)."""
    return _chunk_kernel(GEOMETRY_IDS[geometry])(roughness, wi, random_wi, wo, rho, n_paths, seed, max_bounces)


run_chunk.__doc__ = (run_chunk.__doc__ or "") + "\n\n    " + _DOC
