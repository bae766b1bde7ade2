"""van Ouwerkerk's rewrite of QON (2011): the same function written with dot products.

Kept as its own formulation (not an alias) so the test suite can check that the two
published forms agree to rounding error.  Follows the HLSL listing of the post: saturated
cosines, in-plane projections normalised, cos(phi) saturated, and
``cos(phi) sin(theta_i) sin(theta_o) / max(cos theta_i, cos theta_o)``.
"""

import math

from .._jit import INV_PI, kernel, max_mu


@kernel
def van_ouwerkerk_terms(lx: float, ly: float, lz: float, vx: float, vy: float, vz: float, sigma: float) -> float:
    """f / rho for light direction l = wi and view direction v = wo (normal = +z)."""
    s2 = sigma * sigma
    A = 1.0 - 0.5 * s2 / (s2 + 0.33)
    B = 0.45 * s2 / (s2 + 0.09)
    cl = min(max(lz, 0.0), 1.0)
    cv = min(max(vz, 0.0), 1.0)
    sin_theta = math.sqrt((1.0 - cl * cl) * (1.0 - cv * cv))
    # normalize(l - cos_l n) and normalize(v - cos_v n): the tangent-plane projections.
    pl = math.sqrt(lx * lx + ly * ly)
    pv = math.sqrt(vx * vx + vy * vy)
    cos_phi = 0.0
    if pl > 0.0 and pv > 0.0:  # at the normal the azimuth is undefined and sin_theta = 0
        cos_phi = min(max((lx * vx + ly * vy) / (pl * pv), 0.0), 1.0)
    return (A + B * cos_phi * sin_theta / max_mu(cl, cv)) * INV_PI
