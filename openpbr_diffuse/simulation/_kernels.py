"""The chunk kernel: trace ``n_paths`` paths of one query and return their sums."""
import math

import numpy as np

from . import smith, vcavity
from ._common import N_ORDERS, cosine_hemisphere, jit, tally_path

#: geometry name -> kernel id
GEOMETRY_IDS = {"vcavity": 0, "smith-beckmann": 1, "smith-ggx": 2}


@jit
def run_chunk(geometry, roughness, wi, random_wi, wo, rho, n_paths, seed, max_bounces):
    """Trace ``n_paths`` paths from ``wi`` (or cosine-distributed wi if ``random_wi``).

    Returns
    -------
    alb_s1, alb_s2 : (3, C) sums of rho^k and rho^2k over the paths, per order class
    nee_s1, nee_s2 : (m, 4, C) sums of the per-path next-event estimates of f(wi, wo_j) and
        their squares, per order class (index 3: all orders)
    stats : (3,) int64: paths, bounces, paths cut at ``max_bounces``
    """
    np.random.seed(seed)
    C = rho.shape[0]
    m = wo.shape[0]
    alb_s1 = np.zeros((N_ORDERS, C))
    alb_s2 = np.zeros((N_ORDERS, C))
    nee_s1 = np.zeros((m, N_ORDERS + 1, C))
    nee_s2 = np.zeros((m, N_ORDERS + 1, C))
    path_nee = np.zeros((m, N_ORDERS, C))
    rk = np.empty(C)
    wo_g = np.empty((m, 3))
    stats = np.zeros(3, dtype=np.int64)
    wx, wy, wz = wi[0], wi[1], wi[2]
    for _ in range(n_paths):
        if random_wi:
            wx, wy, wz = cosine_hemisphere()
        if geometry == 0:
            k, escaped = vcavity.walk(wx, wy, wz, wo, roughness, rho, rk, wo_g, path_nee, max_bounces)
        else:
            k, escaped = smith.walk(wx, wy, wz, wo, roughness, geometry - 1, rho, rk, path_nee, max_bounces)
        stats[0] += 1
        stats[1] += min(k, max_bounces)
        if not escaped:
            stats[2] += 1
        tally_path(k, escaped, rho, path_nee, alb_s1, alb_s2, nee_s1, nee_s2)
    return alb_s1, alb_s2, nee_s1, nee_s2, stats
