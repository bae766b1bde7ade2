"""Chunk kernel of the layered-surface simulator: a position-free random walk.

The surface: a dielectric interface of relative index ``eta`` (smooth, or a rough GGX
microsurface of width ``alpha``) over a non-scattering absorbing slab of per-channel
normal optical depth ``tau`` (a pass at cosine mu transmits exp(-tau/mu)) over a diffuse
base (Lambert, or EON used as the base's BRDF).  Local frame, normal +z; ``wi`` points
to the light, directions of travel inside the walk are written ``d``.

Position-free walk (Guo, Hasan, Zhao, "Position-free Monte Carlo simulation for
arbitrary layered BSDFs", ACM TOG 37(6), 2018): a laterally infinite, homogeneous
layer makes the exit point irrelevant, so a path is a sequence of directions only; in
a non-scattering slab the depth of each event is fixed (top or bottom), and each
crossing is weighted by its transmittance.

- smooth interface: Fresnel splitting by expected value -- from outside, the specular
  part is F(mu_i) exactly and (1 - F) enters; from inside, (1 - F) of the weight leaves
  (tallied as diffuse part) and F is reflected back down (no random choice);
- rough interface: Heitz, Hanika, d'Eon, Dachsbacher 2016's random walk on the
  dielectric Smith microsurface (both sides, uniform heights, GGX visible normals,
  reflection or refraction chosen with probability F): energy-conserving, all
  inter-reflections between microfacets included;
- base: Lambert (cosine sampling, weight rho), EON (the library's EON sampler and its
  pdf, weight f mu / pdf per channel, ``sampling.mis``), or the Smith GGX microsurface of
  Lambertian microfacets (Heitz et al. 2016's walk, as ``smith``; weight rho^k);
- BRDF by next-event estimation (smooth interface only): at every base event the
  radiance towards the refracted direction of wo is carried up through the slab and out,
  f += W f_base T(mu_t) (1 - F(mu_o)) / eta^2 (radiance is divided by eta^2 when it
  leaves the denser medium);
- Russian roulette on the largest channel weight below ``RR_WEIGHT`` (unbiased).
"""

import functools
import math

import numpy as np

from .._jit import walk, walk_step
from ..microfacet.fresnel import dielectric
from ..microfacet.kernels import ggx_visible_normal
from ..models.eon import eon_terms, rho_ms
from ..sampling.ltc import ltc_frame
from ..sampling.mis import eon_sample, pow_tenth
from ._common import INV_PI, cosine_about, cosine_hemisphere
from .smith import GGX, sample_height, sample_visible_normal

LAMBERT = 0
EON = 1
SMITH = 2
#: Russian roulette starts below this largest channel weight
RR_WEIGHT = 0.05
#: a rough-interface walk longer than this many microfacet events is cut (counted)
MAX_INTERFACE_EVENTS = 256


@walk_step
def refract(ix, iy, iz, mx, my, mz, c, e):
    """Refraction of the direction i (pointing away from the facet, i.m = c > 0) through
    the facet m into the medium of relative index e; None-free: caller checks TIR."""
    ct2 = 1.0 - (1.0 - c * c) / (e * e)
    ct = -math.sqrt(max(ct2, 0.0))
    a = c / e + ct
    return a * mx - ix / e, a * my - iy / e, a * mz - iz / e


@walk_step
def rough_interface(dx, dy, dz, outside, alpha, eta):
    """Walk a ray travelling along d through the rough dielectric microsurface.

    ``outside``: the ray arrives from above (True) or from inside the slab (False).
    Returns (dx, dy, dz, up, events, cut): the leaving direction, whether it left above
    the interface, the microfacet events, and whether the walk was cut."""
    h = math.inf if outside else -math.inf
    for ev in range(MAX_INTERFACE_EVENTS):
        if outside:
            h = sample_height(dz, h, alpha, GGX)
            if h == math.inf:
                return dx, dy, dz, True, ev, False
        else:
            h = -sample_height(-dz, -h, alpha, GGX)
            if h == -math.inf:
                return dx, dy, dz, False, ev, False
        ix, iy, iz = -dx, -dy, -dz
        if outside:
            mx, my, mz = ggx_visible_normal(ix, iy, iz, alpha, np.random.random(), np.random.random())
            e = eta
        else:
            mx, my, mz = ggx_visible_normal(dx, dy, dz, alpha, np.random.random(), np.random.random())
            mx, my, mz = -mx, -my, -mz
            e = 1.0 / eta
        c = ix * mx + iy * my + iz * mz
        c = min(max(c, 0.0), 1.0)
        F = dielectric(c, e)
        if np.random.random() < F:
            dx, dy, dz = 2.0 * c * mx - ix, 2.0 * c * my - iy, 2.0 * c * mz - iz
        else:
            dx, dy, dz = refract(ix, iy, iz, mx, my, mz, c, e)
            outside = not outside
        n = 1.0 / math.sqrt(dx * dx + dy * dy + dz * dz)
        dx, dy, dz = dx * n, dy * n, dz * n
    return dx, dy, dz, outside, MAX_INTERFACE_EVENTS, True


@walk_step
def smith_base(dx, dy, dz, alpha, max_bounces):
    """Walk the Smith GGX microsurface of Lambertian microfacets (Heitz et al. 2016, as
    ``smith.walk``) from the direction of travel d; returns (wx, wy, wz, k, escaped): the
    leaving direction and the number of facet bounces (the path carries rho^k)."""
    h = math.inf
    k = 0
    while True:
        h = sample_height(dz, h, alpha, GGX)
        if h == math.inf:
            return dx, dy, dz, k, True
        k += 1
        if k > max_bounces:
            return dx, dy, dz, k, False
        mx, my, mz = sample_visible_normal(-dx, -dy, -dz, alpha, GGX)
        dx, dy, dz = cosine_about(mx, my, mz)


@walk_step
def base_f(base, vx, vy, vz, wx, wy, wz, r, rho, c):
    """Base BRDF f(v, w) (no cosine) in channel c, v and w pointing up from the base."""
    if base == LAMBERT:
        return rho[c] * INV_PI
    s = vx * wx + vy * wy  # v.w - mu_v mu_w (FON's s)
    g, hh, avg = eon_terms(wz, vz, s, r, False)
    return rho[c] * g + rho_ms(rho[c], avg) * hh


@functools.cache
def chunk_kernel(base):
    """The chunk kernel of one base (LAMBERT, EON or SMITH), a compile-time constant: a walk
    compiles its own base's scattering only (the report's layered checks, over Lambert, do
    not compile the Smith microsurface's walk nor the EON sampler)."""
    if base not in (LAMBERT, EON, SMITH):
        raise ValueError(f"base: expected LAMBERT, EON or SMITH ({LAMBERT}, {EON}, {SMITH}), got {base!r}")

    @walk
    def run_chunk(alpha, eta, tau, r, rho, wi, random_wi, wo, n_paths, seed, max_bounces):
        """Trace ``n_paths`` paths from ``wi`` (cosine-distributed if ``random_wi``).

        Returns
        -------
        s1, s2 : (3, C) sums of the per-path albedo estimates and their squares, for the
            specular part, the diffuse part and the total
        nee_s1, nee_s2 : (m, C) sums of the per-path NEE estimates of the diffuse f(wi, wo_j)
            and their squares (zeros for a rough interface)
        stats : (4,) int64: paths, base events, paths cut at ``max_bounces``, interface walks cut
        """
        np.random.seed(seed)
        C = rho.shape[0]
        m = wo.shape[0]
        s1 = np.zeros((3, C))
        s2 = np.zeros((3, C))
        nee_s1 = np.zeros((m, C))
        nee_s2 = np.zeros((m, C))
        stats = np.zeros(4, dtype=np.int64)
        w = np.empty(C)
        diff = np.empty(C)
        pn = np.zeros((m, C))
        smooth = alpha <= 0.0
        # NEE connections: refracted wo (inside, pointing up) and its per-channel factor
        wt = np.zeros((m, 3))
        kt = np.zeros((m, C))
        if smooth:
            for j in range(m):
                oz = wo[j, 2]
                if oz <= 0.0:
                    continue
                st = math.sqrt(max(0.0, 1.0 - oz * oz)) / eta
                sp = math.sqrt(max(0.0, 1.0 - oz * oz))
                tz = math.sqrt(max(0.0, 1.0 - st * st))
                sc = st / sp if sp > 0.0 else 0.0
                wt[j, 0], wt[j, 1], wt[j, 2] = wo[j, 0] * sc, wo[j, 1] * sc, tz
                for c in range(C):
                    kt[j, c] = (1.0 - dielectric(oz, eta)) * math.exp(-tau[c] / tz) / (eta * eta)
        r10 = pow_tenth(r)
        wx, wy, wz = wi[0], wi[1], wi[2]
        for _ in range(n_paths):
            if random_wi:
                wx, wy, wz = cosine_hemisphere()
            stats[0] += 1
            for c in range(C):
                diff[c] = 0.0
                w[c] = 1.0
            spec = 0.0
            inside = True
            if smooth:
                F = dielectric(wz, eta)
                spec = F
                st = math.sqrt(max(0.0, 1.0 - wz * wz)) / eta
                sp = math.sqrt(max(0.0, 1.0 - wz * wz))
                sc = st / sp if sp > 0.0 else 0.0
                dx, dy, dz = -wx * sc, -wy * sc, -math.sqrt(max(0.0, 1.0 - st * st))
                for c in range(C):
                    w[c] = 1.0 - F
            else:
                dx, dy, dz, up, _, cut = rough_interface(-wx, -wy, -wz, True, alpha, eta)
                stats[3] += 1 if cut else 0
                if up:
                    spec = 1.0
                    inside = False
            k = 0
            while inside:
                # down through the slab to the base
                mu = -dz
                for c in range(C):
                    w[c] *= math.exp(-tau[c] / mu) if mu > 0.0 else 0.0
                k += 1
                if k > max_bounces:
                    stats[2] += 1
                    break
                vx, vy, vz = -dx, -dy, -dz
                for j in range(m):
                    if wt[j, 2] == 0.0:
                        continue
                    for c in range(C):
                        pn[j, c] += w[c] * base_f(base, vx, vy, vz, wt[j, 0], wt[j, 1], wt[j, 2], r, rho, c) * kt[j, c]
                # scatter at the base
                if base == LAMBERT:
                    ux, uy, uz = cosine_hemisphere()
                    for c in range(C):
                        w[c] *= rho[c]
                elif base == SMITH:
                    ux, uy, uz, kb, esc = smith_base(dx, dy, dz, r, max_bounces)
                    if not esc or uz <= 0.0:
                        stats[2] += 0 if esc else 1
                        break
                    for c in range(C):
                        w[c] *= rho[c] ** kb
                else:
                    Xx, Xy = ltc_frame(vx, vy)
                    ux, uy, uz, p = eon_sample(
                        Xx, Xy, min(max(vz, 0.0), 1.0), r, r10, np.random.random(), np.random.random()
                    )
                    if uz <= 0.0 or p <= 0.0:
                        break
                    for c in range(C):
                        w[c] *= base_f(base, vx, vy, vz, ux, uy, uz, r, rho, c) * uz / p
                # up through the slab
                wmax = 0.0
                for c in range(C):
                    w[c] *= math.exp(-tau[c] / uz)
                    wmax = max(wmax, w[c])
                if wmax <= 0.0:
                    break
                if wmax < RR_WEIGHT:
                    q = wmax / RR_WEIGHT
                    if np.random.random() >= q:
                        break
                    for c in range(C):
                        w[c] /= q
                # the interface from inside
                if smooth:
                    F = dielectric(uz, 1.0 / eta)
                    for c in range(C):
                        diff[c] += w[c] * (1.0 - F)
                        w[c] *= F
                    if F <= 0.0:
                        break
                    dx, dy, dz = ux, uy, -uz
                else:
                    dx, dy, dz, up, _, cut = rough_interface(ux, uy, uz, False, alpha, eta)
                    stats[3] += 1 if cut else 0
                    if up:
                        for c in range(C):
                            diff[c] += w[c]
                        break
            stats[1] += min(k, max_bounces)
            for c in range(C):
                tot = spec + diff[c]
                s1[0, c] += spec
                s2[0, c] += spec * spec
                s1[1, c] += diff[c]
                s2[1, c] += diff[c] * diff[c]
                s1[2, c] += tot
                s2[2, c] += tot * tot
            for j in range(m):
                for c in range(C):
                    v = pn[j, c]
                    nee_s1[j, c] += v
                    nee_s2[j, c] += v * v
                    pn[j, c] = 0.0
        return s1, s2, nee_s1, nee_s2, stats

    return run_chunk
