"""GGX microfacet reflection and the Fresnel factors of the OpenPBR base.

Frame and conventions (stated once): local shading frame with the normal +z; ``wo`` (to
the viewer) and ``wi`` (to the light) point away from the surface; ``h`` is the half vector
normalize(wi + wo); ``alpha`` is the GGX width (OpenPBR: alpha = specular_roughness^2).
All functions are NumPy ufunc-style: leading axes broadcast, directions have a trailing
axis of 3, scalars per direction have none.

Microfacet model (Walter et al. 2007; Heitz 2014):

- GGX normal distribution D(h) = alpha^2 / (pi (mu_h^2 (alpha^2 - 1) + 1)^2)   (W07 Eq. 33)
- Smith Lambda(w) = (-1 + sqrt(1 + alpha^2 tan^2 theta)) / 2   (H14, GGX's Lambda)
- masking G1(w) = 1 / (1 + Lambda(w)) (W07 Eq. 34); height-correlated masking-shadowing
  G2(wi, wo) = 1 / (1 + Lambda(wi) + Lambda(wo))                 (H14, height-correlated G2)
- f(wi, wo) = F(wo.h) D(h) G2 / (4 mu_i mu_o)                                   (W07 Eq. 20)

Sampling: visible normals (Heitz 2018, "Sampling the GGX distribution of visible normals",
JCGT 7(4), Listing 1) with pdf(wi) = G1(wo) D(h) / (4 mu_o), or the plain NDF
(W07 Eq. 35-36) with pdf(wi) = D(h) mu_h / (4 wo.h).  Both are densities of the reflected
direction over the whole sphere: a reflection below the horizon is a valid sample whose
BRDF value is 0, so the VNDF pdf integrates to 1 over the sphere, not the hemisphere.  An
NDF-sampled h with wo.h <= 0 reflects nothing (the sample fails, pdf 0): the NDF pdf
integrates to the probability of success.

References
----------
Walter, Marschner, Li, Torrance, "Microfacet models for refraction through rough
surfaces", EGSR 2007 (W07).  Heitz, "Understanding the masking-shadowing function in
microfacet-based BRDFs", JCGT 3(2), 2014 (H14).  Heitz, JCGT 7(4), 2018.
Kutz, Hasan, Edmondson, "Novel aspects of the Adobe Standard Material", 2021 (F82-tint).
"""
import math

import numpy as np

#: Smallest GGX alpha used.  alpha = 0 is a mirror (a delta lobe with no density); like
#: the OpenPBR viewer we clamp instead of adding a degenerate branch.
ALPHA_MIN = 1e-4

#: cos(theta) of the F82-tint reference angle, mu_bar = 1/7 (theta ~ 81.8 degrees).
MU_BAR = 1.0 / 7.0

SAMPLING_METHODS = ("vndf", "ndf")


def alpha_of(roughness):
    """GGX alpha = max(roughness^2, ALPHA_MIN) (OpenPBR's perceptual mapping)."""
    return np.maximum(np.square(np.asarray(roughness, dtype=np.float64)), ALPHA_MIN)


def _dot(a, b):
    return np.einsum("...k,...k->...", a, b)


def _normalize(v):
    n = np.sqrt(_dot(v, v))
    with np.errstate(invalid="ignore", divide="ignore"):
        return v / n[..., None], n


# --------------------------------------------------------------------------- microfacets
def ndf(mu_h, alpha):
    """GGX D(h) for the cosine mu_h = h.z (0 for mu_h <= 0)."""
    a2 = np.square(alpha)
    c2 = np.square(mu_h)
    d = c2 * (a2 - 1.0) + 1.0
    return np.where(mu_h > 0.0, a2 / (math.pi * d * d), 0.0)


def smith_lambda(mu, alpha):
    """Smith Lambda for GGX, written with alpha^2 tan^2 = alpha^2 (1 - mu^2)/mu^2 (mu > 0)."""
    mu2 = np.square(mu)
    with np.errstate(divide="ignore", invalid="ignore"):
        t2 = np.square(alpha) * (1.0 - mu2) / mu2
    return 0.5 * (np.sqrt(1.0 + t2) - 1.0)


def smith_g1(mu, alpha):
    """Masking G1 = 1/(1 + Lambda); 0 for mu <= 0."""
    with np.errstate(divide="ignore", invalid="ignore"):
        g = 1.0 / (1.0 + smith_lambda(mu, alpha))
    return np.where(mu > 0.0, g, 0.0)


def smith_g2(mu_i, mu_o, alpha):
    """Height-correlated masking-shadowing G2 = 1/(1 + Lambda_i + Lambda_o); 0 below the horizon."""
    ok = (mu_i > 0.0) & (mu_o > 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        g = 1.0 / (1.0 + smith_lambda(mu_i, alpha) + smith_lambda(mu_o, alpha))
    return np.where(ok, g, 0.0)


def half_vector(wi, wo):
    """(h, wo.h); h = normalize(wi + wo), undefined (NaN-free zeros) when wi = -wo."""
    h, n = _normalize(np.asarray(wi) + np.asarray(wo))
    h = np.where((n > 0.0)[..., None], h, 0.0)
    return h, _dot(wo, h)


def microfacet_terms(wi, wo, alpha):
    """Return (D G2 / (4 mu_i mu_o), wo.h): the BRDF without its Fresnel factor.

    The first term is 0 unless both directions are above the horizon and the half vector
    faces the normal.
    """
    wi = np.asarray(wi, dtype=np.float64)
    wo = np.asarray(wo, dtype=np.float64)
    mu_i, mu_o = wi[..., 2], wo[..., 2]
    h, c = half_vector(wi, wo)
    ok = (mu_i > 0.0) & (mu_o > 0.0) & (h[..., 2] > 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        val = ndf(h[..., 2], alpha) * smith_g2(mu_i, mu_o, alpha) / (4.0 * mu_i * mu_o)
    return np.where(ok, val, 0.0), np.clip(c, 0.0, 1.0)


# --------------------------------------------------------------------------- Fresnel
def fresnel_dielectric(c, eta):
    """Exact unpolarised Fresnel reflectance of a dielectric interface (W07 Eq. 22).

    Parameters
    ----------
    c : array_like
        Cosine between the incident direction and the microfacet normal, in [0, 1].
    eta : array_like
        Relative index n_transmitted / n_incident (> 0).  eta < 1 gives total internal
        reflection (F = 1) below the critical angle; eta = 1 gives F = 0 exactly.
    """
    c = np.asarray(c, dtype=np.float64)
    g2 = np.square(eta) - 1.0 + np.square(c)
    g = np.sqrt(np.maximum(g2, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        a = (g - c) / (g + c)
        b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0)
        F = 0.5 * a * a * (1.0 + b * b)
    # g2 <= 0: total internal reflection (eta < 1), F = 1 -- except the index-matched
    # interface, whose g2 = c^2 vanishes at grazing c = 0 but which reflects nothing
    return np.where(eta == 1.0, 0.0, np.where(g2 > 0.0, F, 1.0))


def f0_of_eta(eta):
    """Normal-incidence reflectance F0 = ((eta - 1)/(eta + 1))^2."""
    eta = np.asarray(eta, dtype=np.float64)
    return np.square((eta - 1.0) / (eta + 1.0))


#: Upper clamp of specular_weight * F0 in the OpenPBR reference graph
#: (open_pbr_surface.mtlx, node ``scaled_specular_F0_clamped``): keeps eta' finite.
XI_MAX = 0.99999


def modulated_ior_parameter(specular_weight, ior):
    """x = sign(eta - 1) sqrt(clamp(specular_weight F0(eta), 0, XI_MAX)); eta' = (1 + x)/(1 - x).

    OpenPBR's specular_weight scales the normal-incidence reflectance F0 of the dielectric
    and the Fresnel factor is then the exact one of the modulated index eta' that has
    that F0 (OpenPBR spec, specular_weight; the MaterialX reference graph's nodes
    ``scaled_specular_F0`` .. ``modulated_eta_s``).  x is the signed sqrt(F0'); |x| is the
    coordinate of the albedo table.  x = 0 (specular_weight = 0 or eta = 1) is an
    index-matched interface, F = 0.
    """
    eta = np.asarray(ior, dtype=np.float64)
    xi = np.clip(np.asarray(specular_weight, dtype=np.float64) * f0_of_eta(eta), 0.0, XI_MAX)
    return np.sign(eta - 1.0) * np.sqrt(xi)


def eta_of_parameter(x):
    """eta' = (1 + x)/(1 - x) (inverse of F0 = x^2 with the side of 1 given by sign(x))."""
    x = np.asarray(x, dtype=np.float64)
    with np.errstate(divide="ignore"):
        return (1.0 + x) / (1.0 - x)


def fresnel_schlick(c, F0):
    """Schlick's F0 + (1 - F0)(1 - c)^5 (c broadcast against F0's channel axis by the caller)."""
    return F0 + (1.0 - F0) * (1.0 - c) ** 5


def f82_coefficient(F0, tint):
    """a of the F82-tint model: F(mu_bar) = tint * F_Schlick(mu_bar) fixes
    a = F_Schlick(mu_bar)(1 - tint) / (mu_bar (1 - mu_bar)^6)  (Kutz et al. 2021; OpenPBR "Metal")."""
    fs_bar = fresnel_schlick(MU_BAR, F0)
    return fs_bar * (1.0 - tint) / (MU_BAR * (1.0 - MU_BAR) ** 6)


def fresnel_f82_tint(c, F0, tint):
    """F82-tint conductor Fresnel: F_Schlick(c) - a c (1 - c)^6 (Kutz et al. 2021).

    ``c`` has shape (...) and is broadcast over the channel axis of ``F0``/``tint``
    (shape (..., C)).  Not clamped: with both F0 and tint near 0 it dips slightly below 0
    near c = 0.5, as the published formula does; OpenPBR materials stay far from that corner.
    """
    c = np.asarray(c, dtype=np.float64)[..., None]
    return fresnel_schlick(c, F0) - f82_coefficient(F0, tint) * c * (1.0 - c) ** 6


# --------------------------------------------------------------------------- sampling
def _reflect(wo, h):
    return 2.0 * _dot(wo, h)[..., None] * h - wo


def sample_vndf_normal(wo, alpha, u1, u2):
    """Visible-normal sample h for wo (mu_o > 0), Heitz 2018 Listing 1."""
    a = np.asarray(alpha, dtype=np.float64)
    Vh, _ = _normalize(np.stack([a * wo[..., 0], a * wo[..., 1], wo[..., 2]], axis=-1))
    lensq = Vh[..., 0] ** 2 + Vh[..., 1] ** 2
    inv = np.where(lensq > 0.0, 1.0 / np.sqrt(np.where(lensq > 0.0, lensq, 1.0)), 0.0)
    T1 = np.where((lensq > 0.0)[..., None],
                  np.stack([-Vh[..., 1] * inv, Vh[..., 0] * inv, np.zeros_like(inv)], axis=-1),
                  np.array([1.0, 0.0, 0.0]))
    T2 = np.cross(Vh, T1)
    r = np.sqrt(u1)
    phi = 2.0 * math.pi * u2
    t1 = r * np.cos(phi)
    t2 = r * np.sin(phi)
    s = 0.5 * (1.0 + Vh[..., 2])
    t2 = (1.0 - s) * np.sqrt(np.maximum(0.0, 1.0 - t1 * t1)) + s * t2
    Nh = (t1[..., None] * T1 + t2[..., None] * T2
          + np.sqrt(np.maximum(0.0, 1.0 - t1 * t1 - t2 * t2))[..., None] * Vh)
    Ne, _ = _normalize(np.stack([a * Nh[..., 0], a * Nh[..., 1], np.maximum(0.0, Nh[..., 2])], axis=-1))
    return Ne


def sample_ndf_normal(alpha, u1, u2):
    """h distributed as D(h) mu_h: tan^2 theta_h = alpha^2 u1/(1 - u1), phi = 2 pi u2 (W07 Eq. 35-36)."""
    a2 = np.square(alpha)
    cos2 = (1.0 - u1) / (1.0 + (a2 - 1.0) * u1)
    ct = np.sqrt(cos2)
    st = np.sqrt(np.maximum(0.0, 1.0 - cos2))
    phi = 2.0 * math.pi * u2
    return np.stack([st * np.cos(phi), st * np.sin(phi), ct], axis=-1)


def reflection_pdf(wo, wi, alpha, method="vndf"):
    """Solid-angle pdf of the reflected direction wi (whole sphere) given wo.

    vndf: G1(wo) D(h) / (4 mu_o);  ndf: D(h) mu_h / (4 wo.h).  0 if mu_o <= 0 or the half
    vector is below the horizon (no microfacet produces that reflection).
    """
    wo = np.asarray(wo, dtype=np.float64)
    h, c = half_vector(wi, wo)
    mu_o = wo[..., 2]
    D = ndf(h[..., 2], alpha)
    with np.errstate(divide="ignore", invalid="ignore"):
        if method == "vndf":
            p = smith_g1(mu_o, alpha) * D / (4.0 * mu_o)
        else:
            p = D * h[..., 2] / (4.0 * c)
    return np.where((mu_o > 0.0) & (c > 0.0) & (h[..., 2] > 0.0), p, 0.0)


def sample_reflection(wo, alpha, u1, u2, method="vndf"):
    """Return (wi, pdf): wi = reflect(wo, h) with h from the visible normals or the NDF.

    wi may lie below the horizon (the BRDF is then 0; the pdf is still reported).  pdf = 0
    marks a failed sample: mu_o <= 0 (wi is then the normal), or an NDF-sampled h with
    wo.h <= 0.
    """
    wo = np.asarray(wo, dtype=np.float64)
    if method == "vndf":
        h = sample_vndf_normal(wo, alpha, u1, u2)
    elif method == "ndf":
        h = sample_ndf_normal(np.broadcast_to(alpha, np.shape(u1)), u1, u2)
    else:
        raise ValueError(f"specular_sampling must be one of {', '.join(SAMPLING_METHODS)}; got {method!r}")
    wi = _reflect(wo, h)
    wi, _ = _normalize(wi)  # removes rounding drift; |reflect| = 1 analytically
    pdf = reflection_pdf(wo, wi, alpha, method)
    ok = wo[..., 2] > 0.0
    wi = np.where(ok[..., None], wi, np.array([0.0, 0.0, 1.0]))
    return wi, np.where(ok, pdf, 0.0)


# --------------------------------------------------------------------------- albedo quadrature
def _gauss(a, b, n):
    x, w = np.polynomial.legendre.leggauss(n)
    a = np.asarray(a, dtype=np.float64)[..., None]
    b = np.asarray(b, dtype=np.float64)[..., None]
    return 0.5 * (a + b) + 0.5 * (b - a) * x, 0.5 * (b - a) * w


def _phi_panels(mu_o, so):
    """Panel edges in phi on [0, pi], graded towards pi/2.

    The horizon cut theta_max(phi) = (delta + pi/2)/2 with delta = atan2(so cos phi, mu_o)
    swings from ~pi/2 to ~0 within |phi - pi/2| ~ mu_o/so: at grazing mu_o that is a
    near-step, resolved by panels of width (mu_o/so) 4^k on both sides of pi/2.
    """
    half = 0.5 * math.pi
    widths = []
    w = mu_o / max(so, 1e-300)
    while w < 0.25 * math.pi:
        widths.append(w)
        w *= 4.0
    inner = [half - w for w in reversed(widths)] + [half] + [half + w for w in widths]
    return np.array([0.0] + inner + [math.pi])


def _v_of_theta(theta, alpha):
    """v = 1 - sqrt(1 - t(theta)) = 1 - alpha cos / sqrt(alpha^2 cos^2 + sin^2) (t: GGX CDF)."""
    c, s = np.cos(theta), np.sin(theta)
    return 1.0 - alpha * c / np.sqrt(alpha * alpha * c * c + s * s)


def albedo_quadrature(mu_o, alpha, fresnels, n_t=64, n_phi=64):
    """Directional albedos int F D G2/(4 mu_i mu_o) mu_i dwi of one GGX lobe for several F.

    Half-vector quadrature, independent of the samplers and of ``microfacet_terms``: with dwi = 4 (wo.h) dh and
    t = CDF of D(h) mu_h in theta_h (tan^2 theta_h = alpha^2 t/(1 - t)),

        E(mu_o) = (1/2pi) int_0^2pi int_0^1 F(wo.h) G2 (wo.h) / (mu_o mu_h) dt dphi .

    Every source of non-smoothness is put on a panel edge, so Gauss-Legendre converges fast:

    - the horizon: for each phi_h the reflected direction is above the horizon exactly for
      theta_h < (delta + pi/2)/2, delta = atan2(sin theta_o cos phi_h, mu_o) (mu_i =
      R cos(2 theta_h - delta)): the t-range is cut there;
    - 1/mu_h ~ 1/sqrt(1 - t) as theta_h -> pi/2 (grazing mu_o): t = 1 - (1 - v)^2;
    - the near-step of that cut in phi at grazing mu_o: graded phi panels (``_phi_panels``).

    F must be smooth in wo.h (true for eta >= 1; total internal reflection, eta < 1, puts a
    kink inside the panels and slows convergence).

    The integrand is even in phi: phi in [0, pi], doubled.

    Parameters
    ----------
    mu_o, alpha : float
    fresnels : callable
        ``fresnels(c)`` -> array (K, ...) of K Fresnel-like factors at cosines c = wo.h.
    n_t, n_phi : int
        Gauss-Legendre orders per panel.

    Returns
    -------
    ndarray (K,)
    """
    mu_o = float(mu_o)
    alpha = float(alpha)
    so = math.sqrt(max(0.0, 1.0 - mu_o * mu_o))
    pe = _phi_panels(mu_o, so)
    phi, wphi = _gauss(pe[:-1], pe[1:], n_phi)
    phi, wphi = phi.ravel(), wphi.ravel()
    cphi = np.cos(phi)
    delta = np.arctan2(so * cphi, mu_o)
    theta_max = 0.5 * (delta + 0.5 * math.pi)
    edges = np.stack([np.zeros_like(phi), theta_max], axis=-1)         # (P, 2)
    ve = _v_of_theta(edges, alpha)
    v, wv = _gauss(ve[:, :-1], ve[:, 1:], n_t)                         # (P, E-1, n_t)
    v = v.reshape(len(phi), -1)
    w = wv.reshape(len(phi), -1) * wphi[:, None] * 2.0 * (1.0 - v)     # dt = 2 (1 - v) dv
    one_v = 1.0 - v
    u = alpha * alpha * v * (2.0 - v) / np.square(one_v)              # tan^2 theta_h
    mu_h = 1.0 / np.sqrt(1.0 + u)
    sin_h = np.sqrt(u) * mu_h
    h = np.stack([sin_h * cphi[:, None], sin_h * np.sin(phi)[:, None], mu_h], axis=-1)
    c = h @ np.array([so, 0.0, mu_o])
    mu_i = 2.0 * c * mu_h - mu_o
    g = smith_g2(mu_i, mu_o, alpha) * c / (mu_o * mu_h)
    F = np.asarray(fresnels(np.clip(c, 0.0, 1.0)))
    # 1/(2 pi) of the phi average, times 2 for phi in [pi, 2 pi]
    return np.einsum("kpt,pt->k", F * g, w) / math.pi
