"""Single-bounce albedo of Oren-Nayar V-grooves by quadrature, written independently of the
simulator: Torrance-Sparrow's closed-form V-groove shadowing for the lit part of each facet
and Hottel's crossed-strings view factor for the light that leaves after one bounce."""

import numpy as np


def _gl(n, a, b):
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (b - a) * x + 0.5 * (b + a), 0.5 * (b - a) * w


def single_bounce_albedo(mu, sigma, n_theta=64, n_phi=512, n_u=24):
    """E_1(mu) / rho of V-grooves, slope density ~ exp(-theta^2/2sigma^2) sin(theta) on [0, pi/2).

    Returns (E_1 / rho, fraction of the beam that reaches a facet: must be 1)."""
    top = min(np.pi / 2, 9.0 * sigma)
    ta, wta = _gl(n_theta, 0.0, top)
    pdf = np.exp(-0.5 * (ta / sigma) ** 2) * np.sin(ta)  # Gaussian over the normals' solid angle
    wta = wta * pdf / np.sum(wta * pdf)
    phi = (np.arange(n_phi) + 0.5) * np.pi / n_phi  # groove azimuth, midpoints
    sin_i = np.sqrt(1.0 - mu * mu)
    T, P = np.meshgrid(ta, phi, indexing="ij")
    st, ct = np.sin(T), np.cos(T)
    h = st / ct
    wx = sin_i * np.cos(P)  # across the groove
    wz = mu * np.ones_like(P)
    norm2 = np.hypot(wx, wz)
    px, pz = wx / norm2, wz / norm2  # in-plane unit direction
    E = np.zeros_like(T)
    incident = np.zeros_like(T)
    for sgn in (1.0, -1.0):
        # facet with normal (sgn st, ct): points (-sgn u, u h), u in [0, 1] from the vertex
        nx, nz = sgn * st, ct
        cos_in = nx * wx + nz * wz  # 3-D cosine (n has no along-groove part)
        n_dot_p = nx * px + nz * pz
        facing = sgn * px > 0  # tilted towards the light
        G = np.where(facing, np.minimum(1.0, 2.0 * ct * pz / np.maximum(n_dot_p, 1e-300)), 1.0)
        G = np.where(cos_in > 0, G, 0.0)  # lit fraction, lit part u in [1-G, 1]
        U, wU = _gl(n_u, 0.0, 1.0)
        u = (1.0 - G)[..., None] + G[..., None] * U
        qx, qz = -sgn * u, u * h[..., None]
        ex, ez = -sgn * ct[..., None], st[..., None]  # along the facet to its own rim
        vx, vz = sgn * 1.0 - qx, h[..., None] - qz  # to the opposite rim
        vn = np.hypot(vx, vz)
        esc = 0.5 * (1.0 - (ex * vx + ez * vz) / vn)  # crossed strings
        L = 1.0 / ct
        E += np.maximum(cos_in, 0.0) * L * G * np.sum(wU * esc, axis=-1)
        incident += np.maximum(cos_in, 0.0) * L * G
    E /= 2.0 * mu  # beam power through the opening (width 2)
    incident /= 2.0 * mu
    mean = lambda a: np.sum(wta[:, None] * a) / n_phi
    return mean(E), mean(incident)
