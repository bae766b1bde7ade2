"""Light in a V-cavity: Oren & Nayar's microgeometry, with every interreflection.

The surface is a collection of long symmetric V-grooves (Oren & Nayar 1994, Sec. 3; after
Torrance & Sparrow 1967).  A groove has two planar Lambertian facets tilted by the slope
angle theta_a, facet normals (+-sin theta_a, 0, cos theta_a) in the groove frame (x across
the groove, y along it, z up).  Per unit macro area the facet normal (theta_a, phi_a) has
Oren and Nayar's isotropic Gaussian slope-area distribution: density
P(theta_a; sigma) sin(theta_a) dtheta_a dphi_a with P a zero-mean Gaussian of standard
deviation sigma (their Eq. for L_r integrates P(theta_a) L_rp sin(theta_a) over the
hemisphere of facet normals), truncated to theta_a < pi/2; the groove azimuth is uniform.
(A half-Gaussian density of theta_a itself, without the sin(theta_a) of the solid angle,
gives single-scattering albedos ~10 % above Oren-Nayar's fitted f1 at sigma = 0.5; with it,
they agree within 0.008-0.026: ``tests/test_simulation_vcavity.py``.)  Grooves do not
shadow or mask each other: light enters and leaves through the groove's opening, which lies
in the macro plane.

A groove is infinitely long, so a path is traced in its 2-D cross-section: the facets are
z = tan(theta_a) |x|, the opening is x in [-1, 1] at z = h = tan(theta_a) (coordinates
from the vertex keep full relative precision for paths near it), and the along-groove
component of the direction is carried along (it changes the facet cosines, not which
facet is hit).  Light from wi enters at a uniform point of the opening (the irradiance of a
parallel beam is uniform over the macro plane), hits a facet, is reflected into a
cosine-distributed direction about the facet normal, and so on until it leaves through
the opening.  Masking, shadowing and interreflection are all exact for this geometry.

BRDF by next-event estimation: a bounce on facet n at point p adds
rho^k (n . wo)_+ V(p, wo) / (pi mu_o) to f(wi, wo), V = 1 if the ray from p towards wo
leaves through the opening.  (Radiance of the macro surface per unit irradiance: a
Lambertian facet element reflects rho/pi (n . wo) of the power it receives per unit solid
angle, and the macro area sees it foreshortened by mu_o.)
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from .._jit import walk_step
from ._common import HALF_PI, INV_PI, PI, cosine_about, order_class

#: Slope angles closer to pi/2 than this are redrawn (a vertical facet has no opening).
_THETA_MAX = HALF_PI - 1e-9
#: Below this slope the groove is flat: one bounce, f = rho/pi.
_FLAT = 1e-12


@walk_step
def sample_slope(sigma: float) -> float:
    """theta_a with density ~ exp(-theta^2 / (2 sigma^2)) sin(theta) on [0, pi/2).

    Rayleigh(sigma) proposal (density theta exp(-theta^2/2sigma^2) / sigma^2), accepted with
    probability sin(theta)/theta <= 1, redrawn beyond pi/2.
    """
    while True:
        t = sigma * math.sqrt(-2.0 * math.log(1.0 - np.random.random()))
        if t < _THETA_MAX and (t == 0.0 or np.random.random() * t < math.sin(t)):
            return t


@walk_step
def _nee(k, px, pz, nx, nz, st, ct, h, side, wo_g, rk, path_nee):
    """Next-event contributions of a bounce on facet ``side`` (1 = left, 2 = right) at p."""
    m = wo_g.shape[0]
    C = rk.shape[0]
    q = order_class(k)
    for j in range(m):
        ox = wo_g[j, 0]
        oz = wo_g[j, 2]
        cos_f = nx * ox + nz * oz
        if cos_f <= 0.0 or oz <= 0.0:
            continue
        # the other facet's normal and signed distance from p
        if side == 1:
            dn = -st * ox + ct * oz
            s_o = -st * px + ct * pz
        else:
            dn = st * ox + ct * oz
            s_o = st * px + ct * pz
        if dn < 0.0:
            t_other = -max(s_o, 0.0) / dn
            t_top = (h - pz) / oz
            if t_other < t_top:
                continue  # blocked by the other facet
        g = cos_f * INV_PI / oz
        for c in range(C):
            path_nee[j, q, c] += rk[c] * g


@walk_step
def walk(
    wi_x: float,
    wi_y: float,
    wi_z: float,
    wo: NDArray[np.float64],
    sigma: float,
    rho: NDArray[np.float64],
    rk: NDArray[np.float64],
    wo_g: NDArray[np.float64],
    path_nee: NDArray[np.float64],
    max_bounces: int,
) -> tuple[int, bool]:
    """Trace one path in a random groove; returns (k, escaped).

    ``rk`` (C,) and ``wo_g`` (m, 3) are scratch arrays; next-event sums are added to
    ``path_nee`` (m, 3, C).
    """
    C = rho.shape[0]
    m = wo.shape[0]
    for c in range(C):
        rk[c] = rho[c]
    ta = sample_slope(sigma)
    phi = np.random.random() * PI  # groove azimuth; [0, pi) covers both facet orders
    cp = math.cos(phi)
    sp = math.sin(phi)
    if ta < _FLAT:
        for j in range(m):
            if wo[j, 2] > 0.0:
                for c in range(C):
                    path_nee[j, 0, c] += rk[c] * INV_PI
        return 1, True
    # directions in the groove frame: x = (cp, sp, 0) across, y = (-sp, cp, 0) along
    for j in range(m):
        wo_g[j, 0] = wo[j, 0] * cp + wo[j, 1] * sp
        wo_g[j, 1] = -wo[j, 0] * sp + wo[j, 1] * cp
        wo_g[j, 2] = wo[j, 2]
    dx = -(wi_x * cp + wi_y * sp)
    dy = -(-wi_x * sp + wi_y * cp)
    dz = -wi_z
    st = math.sin(ta)
    ct = math.cos(ta)
    h = st / ct
    px = 2.0 * np.random.random() - 1.0
    pz = h
    side = 0  # 0: on the opening, 1: left facet (normal (st, ct)), 2: right (-st, ct)
    k = 0
    while True:
        t_best = math.inf
        nxt = 0
        if side != 1:
            dn = st * dx + ct * dz
            if dn < 0.0:
                t = -max(st * px + ct * pz, 0.0) / dn
                if t < t_best:
                    t_best = t
                    nxt = 1
        if side != 2:
            dn = -st * dx + ct * dz
            if dn < 0.0:
                t = -max(-st * px + ct * pz, 0.0) / dn
                if t < t_best:
                    t_best = t
                    nxt = 2
        if side != 0 and dz > 0.0:
            t = (h - pz) / dz
            if t <= t_best:
                nxt = 0
        if nxt == 0:
            return k, True
        k += 1
        if k > max_bounces:
            return k, False
        px += t_best * dx
        pz = min(pz + t_best * dz, h)
        side = nxt
        nx = st if side == 1 else -st
        if k > 1:
            for c in range(C):
                rk[c] *= rho[c]
        if m > 0:
            _nee(k, px, pz, nx, ct, st, ct, h, side, wo_g, rk, path_nee)
        dx, dy, dz = cosine_about(nx, 0.0, ct)
