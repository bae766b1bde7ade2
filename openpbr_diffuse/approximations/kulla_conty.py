"""Table-based energy compensation (Kulla-Conty 2017, Kelemen 2001), as in the blog post
"Energy Compensation Pt. 2" (P. Mounier, patapom.com).

The multiple-scattering (MS) lobe added to a single-scattering lobe with directional albedo
E(mu) (tabulated at rho = 1) and E_avg = 2 pi int_0^1 E(mu) mu dmu = pi <E>:

    f_ms(wi, wo) = F(rho) (1 - E(mu_o)) (1 - E(mu_i)) / (pi - E_avg)                 (post, "Sun")

so that int f_ms mu_i dwi = F(rho) (1 - E(mu_o)): white furnace 1 at rho = 1 by construction.
Here E comes from the project's reference tables (``od.reference_albedo``), for QON or any lobe.

- ``rho_factor``: the post's F(rho) = A1 (tau rho)^2 / (1 - tau rho), tau = 0.28430405702379613,
  A1 = (1 - tau)/tau^2 (so F(1) = 1).  It has the form of EON's rho_ms (EON Eq. 18) with <E>
  frozen at 1 - tau = 0.7157; ``exact_rho_factor`` is Eq. 18 with the lobe's own <E>.
- SH environment lighting: f_ms depends on wi only through mu_i, so its response is zonal:
  L_o = (1 - E(mu_o))/(pi - E_avg) * F(rho) * sum_lm L_lm sqrt(4 pi/(2l+1)) E_l Y_lm(n) with
  E_l = 2 pi int_0^1 Y_l0(mu) (1 - E(mu)) mu dmu (``zh_exact``); the post's fits E0, E1, E2 for
  Oren-Nayar (``zh_fit_oren_nayar``).
- Area lights: an LTC with M^-1 = diag(1, 1, m33(alpha)) and a magnitude approximating
  (1 - E(mu)) mu ~ magnitude * D_LTC(w) (``ltc_m33_fit``, ``ltc_magnitude_fit``,
  ``ltc_polygon_integral``; exact: ``polygon_integral_exact``).

Roughness: the post's Oren-Nayar roughness alpha in [0, 1] is QON with sigma = alpha pi/2
(``sigma_of_alpha``; the post's ``BRDF_OrenNayar`` takes sigma in [0, pi/2] and its fits match
the exact ZH coefficients only with this map — see the README errata); beta = sqrt(alpha).
"""

from __future__ import annotations

import math
from typing import Any, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _arrays as ar
from .._jit import elementwise
from . import sh

#: The post's fitted ratio of successive scattering orders (Pt. 1, "varying diffuse reflectance").
TAU = 0.28430405702379613
#: A1 = (1 - tau) / tau^2 so that sum_{n >= 2} A1 (tau rho)^n = 1 at rho = 1.
A1 = (1.0 - TAU) / TAU**2
#: The MSBRDF_View guard of the post's listing: max(0.001, pi - E_avg).
VIEW_GUARD = 1e-3

FACTORS = ("tau", "exact", "none")

# The post's fits for Oren-Nayar (rows E0, E1, E2; coefficients of beta, beta^3, beta^5, beta^7
# as its HLSL evaluates them -- its text prints beta, beta^2, beta^3, beta^4).
ZH_FIT_OREN_NAYAR = np.array(
    [
        [-0.0919559140506979, 1.467037714315657, -1.673544888379740, 0.607800523815945],
        [-0.1136684128860008, 1.901273744271233, -2.322322430339633, 0.909815621695672],
        [-0.0412482175221291, 1.093354950053632, -1.417191923789875, 0.581084435989362],
    ]
)
# The post's fits for GGX (coefficients of beta, beta^3, beta^5 as coded; beta, beta^2, beta^3 as printed).
ZH_FIT_GGX = np.array(
    [
        [-0.01792303243636725, 1.0561278339405598, -0.4865495717038784],
        [-0.06127443169094851, 1.3380225947779523, -0.6195823982255909],
        [-0.10732852337149004, 0.8686198207608287, -0.3980009298364805],
    ]
)
GGX_M33 = (21.342911007109528, 93.01620773161568, 0.4814723396401988, 143.39682026031764, 15.2)
GGX_MAG = (0.09791431592022058, -1.4272852958071647, 7.768226052923069, -4.475643330561517)
#: Pseudo-model name of the GGX lobe with F = 1 (table ``microfacet.tables.ggx_albedo``),
#: roughness = GGX alpha in [0, 1] (beta = sqrt(alpha) = OpenPBR specular_roughness).
GGX = "ggx"
# LTC fits for Oren-Nayar, polynomials in beta (m33 rational quadratic, magnitude cubic).
LTC_M33_NUM = (0.005048402287040277, -0.014928238738260345, 0.027930492034822143)
LTC_M33_DEN = (0.008420878564907999, -0.022349996757079705, 0.034343673853208634)
LTC_MAG = (0.2559021427001363, -2.7944531451217687, 8.298513748611509, -4.662218902663712)


def _alpha(alpha: ArrayLike) -> NDArray[Any]:
    return ar.in_range("alpha", alpha, np.float64, 0.0, 1.0, " (the post's roughness; beta = sqrt(alpha))")


def sigma_of_alpha(alpha: ArrayLike) -> NDArray[np.float64]:
    """QON sigma of the post's Oren-Nayar roughness: sigma = alpha pi/2 (alpha in [0, 1])."""
    return 0.5 * math.pi * _alpha(alpha)


def rho_factor(rho: ArrayLike) -> NDArray[np.float64]:
    """The post's F(rho) = A1 (tau rho)^2 / (1 - tau rho) (Pt. 1 "varying diffuse reflectance"; Pt. 2 listings).

    Parameters
    ----------
    rho : array_like, shape (..., C)
        Albedo in [0, 1].

    Examples
    --------
    >>> round(float(rho_factor(1.0)[0]), 12)
    1.0
    """
    rho = ar.rho_array("rho", rho, np.float64)
    t = TAU * rho
    return A1 * t * t / (1.0 - t)


def exact_rho_factor(rho: ArrayLike, average_albedo: ArrayLike) -> NDArray[np.float64]:
    """The multiple-scattering factor implied by the lobe's own <E>: rho^2 <E> / (1 - rho (1 - <E>)).

    EON Eq. 18 (the library's ``rho_ms``): the sum over scattering orders n >= 2 of
    <E> (1 - <E>)^(n-2) rho^n, i.e. ``rho_factor`` with tau = 1 - <E>.

    Parameters
    ----------
    rho : array_like, shape (..., C)
    average_albedo : array_like, shape (...)
        <E> of the single-scattering lobe, in (0, 1].
    """
    from ..models.eon import rho_ms

    rho = ar.rho_array("rho", rho, np.float64)
    avg = ar.in_range("average_albedo", average_albedo, np.float64, 0.0, 1.0, " (<E>)", lo_open=True)
    return cast("NDArray[np.float64]", elementwise(rho_ms, rho, np.asarray(avg)[..., None]))


def _factor(kind, rho, avg):
    if kind == "tau":
        return rho_factor(rho)
    if kind == "exact":
        return exact_rho_factor(rho, np.minimum(avg, 1.0))
    if kind == "none":
        return ar.rho_array("rho", rho, np.float64) * 0.0 + 1.0
    raise ValueError(f"factor must be one of {', '.join(FACTORS)}; got {kind!r}")


def _roughness(model: str, roughness: ArrayLike) -> NDArray[Any]:
    """Roughness checked in ``model``'s domain (GGX: alpha in [0, 1])."""
    if model == GGX:
        return ar.in_range("roughness", roughness, np.float64, 0.0, 1.0, " for 'ggx' (GGX alpha)")
    from ..models.registry import model_info

    return ar.model_roughness(model_info(model), roughness, np.float64)


def single_scattering_albedo(model: str, mu: ArrayLike, roughness: ArrayLike) -> NDArray[np.float64]:
    """E(mu) of ``model`` at rho = 1 from the reference tables (``od.reference_albedo``).

    ``model="ggx"``: the GGX lobe with F = 1 (height-correlated Smith), from the specular
    tables of ``microfacet.tables`` (E1 at specular_roughness = sqrt(alpha)).
    """
    if model == GGX:
        from ..microfacet.tables import ggx_albedo

        mu = ar.in_range("mu", mu, np.float64, 0.0, 1.0, " (cosine of the view angle)")
        return ggx_albedo(mu, np.sqrt(_roughness(model, roughness)))
    from ..albedo.tables import reference_albedo

    return reference_albedo(model, mu, roughness, 1.0)[..., 0]


def average_term(model: str, roughness: ArrayLike) -> NDArray[np.float64]:
    """E_avg = pi <E> of ``model`` at rho = 1 (the post's convention), from the reference tables.

    ``model="ggx"``: 2 pi int E mu dmu by Gauss-Legendre (96 nodes in theta) of the GGX table.
    """
    if model == GGX:
        r = _roughness(model, roughness)
        x, w = np.polynomial.legendre.leggauss(96)
        th = 0.25 * math.pi * (x + 1.0)
        wt = 0.25 * math.pi * w * np.sin(th) * np.cos(th)
        E = single_scattering_albedo(GGX, np.cos(th), r[..., None])
        return 2.0 * math.pi * np.sum(wt * E, axis=-1)
    from ..albedo.tables import reference_average_albedo

    return math.pi * reference_average_albedo(model, roughness, 1.0)[..., 0]


def view_term(model: str, mu_o: ArrayLike, roughness: ArrayLike) -> NDArray[np.float64]:
    """(1 - E(mu_o)) / max(0.001, pi - E_avg): the view-dependent part (the post's MSBRDF_View)."""
    E = single_scattering_albedo(model, mu_o, roughness)
    return (1.0 - E) / np.maximum(VIEW_GUARD, math.pi - average_term(model, roughness))


def ms_lobe(
    model: str,
    wi: ArrayLike,
    wo: ArrayLike,
    roughness: ArrayLike,
    rho: ArrayLike = 1.0,
    *,
    factor: str = "tau",
    guard: float = VIEW_GUARD,
) -> NDArray[np.float64]:
    """The multiple-scattering lobe f_ms = F(rho) (1 - E(mu_o)) (1 - E(mu_i)) / (pi - E_avg).

    Kulla-Conty 2017 / the post's ``MSBRDF``, with E and E_avg of ``model`` from the project's
    reference tables.  Directions below the horizon give 0.

    Parameters
    ----------
    model : str
        Single-scattering lobe (any of ``od.MODELS``; the post's is "qon").
    wi, wo : array_like, shape (..., 3)
    roughness : array_like, shape (...)
        In the model's domain.
    rho : array_like, shape (..., C)
    factor : {"tau", "exact", "none"}
        F(rho): the post's tau fit, the lobe's own series (``exact_rho_factor``), or 1.
    guard : float
        Denominator floor max(guard, pi - E_avg): the listing's 0.001 by default (it makes the
        lobe lose energy where pi - E_avg < 0.001, QON sigma < 0.027, FON r < 0.0015; the loss
        is at most |1 - E(mu_o)| < 0.02 there); EON's Listing 1 uses pi * 1e-7.

    Returns
    -------
    ndarray, shape broadcast(...) + (C,)

    Notes
    -----
    Where the single-scattering albedo exceeds 1 (QON at grazing view for small sigma: up to
    1.0152) the factor 1 - E is negative, and f_ms < 0 when one direction is grazing and the
    other steep; the white
    furnace still holds (the integral of (1 - E) mu over H+ is pi - E_avg).

    Examples
    --------
    >>> import numpy as np
    >>> f = ms_lobe("qon", [0.0, 0.0, 1.0], [0.0, 0.0, 1.0], 1.0)
    >>> bool(f[0] > 0)
    True
    """
    wi = ar.directions("wi", wi, np.float64)
    wo = ar.directions("wo", wo, np.float64)
    rho = ar.rho_array("rho", rho, np.float64)
    r = _roughness(model, roughness)
    lead = ar.broadcast_leading(wi=wi.shape[:-1], wo=wo.shape[:-1], roughness=r.shape, rho=rho.shape[:-1])
    mu_i = np.clip(wi[..., 2], 0.0, 1.0)
    mu_o = np.clip(wo[..., 2], 0.0, 1.0)
    # tables at the distinct (mu, roughness) pairs only
    Ei = _table_E(model, np.broadcast_to(mu_i, lead), np.broadcast_to(r, lead))
    Eo = _table_E(model, np.broadcast_to(mu_o, lead), np.broadcast_to(r, lead))
    avg = average_term(model, r)
    F = _factor(factor, rho, avg / math.pi)
    up = (wi[..., 2] > 0.0) & (wo[..., 2] > 0.0)
    h = np.where(up, (1.0 - Eo) * (1.0 - Ei) / np.maximum(guard, math.pi - avg), 0.0)
    return np.broadcast_to(h, lead)[..., None] * F


def _table_E(model, mu, r):
    """Table E at (mu, r) pairs, looked up once per distinct pair."""
    pairs = np.stack([mu.reshape(-1), r.reshape(-1)], axis=-1)
    uniq, inv = np.unique(pairs, axis=0, return_inverse=True)
    E = single_scattering_albedo(model, uniq[:, 0], uniq[:, 1])
    return E[inv.reshape(-1)].reshape(mu.shape)


def compensated(
    model: str,
    wi: ArrayLike,
    wo: ArrayLike,
    roughness: ArrayLike,
    rho: ArrayLike = 1.0,
    *,
    factor: str = "tau",
    guard: float = VIEW_GUARD,
    color_mode: str = "reference",
) -> NDArray[np.float64]:
    """f = f_ss + f_ms: the single-scattering lobe (``od.evaluate``) plus ``ms_lobe``."""
    from ..models import evaluate

    return evaluate(model, wi, wo, roughness, rho, color_mode=color_mode) + ms_lobe(
        model, wi, wo, roughness, rho, factor=factor, guard=guard
    )


def compensated_albedo(
    model: str, mu: ArrayLike, roughness: ArrayLike, rho: ArrayLike = 1.0, *, factor: str = "tau"
) -> NDArray[np.float64]:
    """Directional albedo of ``compensated``: E_ss(mu; rho) + F(rho) (1 - E(mu)), from the tables.

    (int f_ms mu_i dwi = F(rho) (1 - E(mu_o)) because int (1 - E) mu dw = pi - E_avg.)
    """
    from ..albedo.tables import reference_albedo, reference_average_albedo

    Ess = reference_albedo(model, mu, roughness, rho)
    E1 = reference_albedo(model, mu, roughness, 1.0)
    avg = reference_average_albedo(model, roughness, 1.0)[..., 0]
    return Ess + _factor(factor, rho, avg) * (1.0 - E1)


# --------------------------------------------------------------------------- SH environment


def zh_exact(model: str, roughness: ArrayLike, *, n: int = 64) -> NDArray[np.float64]:
    """Exact E_l(roughness) = 2 pi int_0^1 Y_l0(mu) (1 - E(mu)) mu dmu, l = 0, 1, 2 (the post's ZH).

    Gauss-Legendre in mu (``sh.zh_project``) of the reference-table E of ``model``.

    Parameters
    ----------
    roughness : array_like, shape (...)
        In the model's domain (for the post's alpha use ``sigma_of_alpha``).

    Returns
    -------
    ndarray, shape (..., 3)
    """
    r = _roughness(model, roughness)
    rf = r.reshape(-1)

    def h(mu):
        return 1.0 - single_scattering_albedo(model, mu[:, None], rf[None, :])

    return np.moveaxis(sh.zh_project(h, n), 0, -1).reshape(r.shape + (3,))


def zh_fit_oren_nayar(alpha: ArrayLike, *, form: str = "code") -> NDArray[np.float64]:
    """The post's fits E0, E1, E2 for Oren-Nayar, clamped to [0, 1] as its listing does.

    ``form="code"``: as its HLSL evaluates them, beta (c0 + c1 alpha + c2 alpha^2 + c3 alpha^3)
    (the reading that matches the exact ZH); ``form="text"``: as its text prints them,
    c0 beta + c1 beta^2 + c2 beta^3 + c3 beta^4.  beta = sqrt(alpha).

    Returns
    -------
    ndarray, shape alpha.shape + (3,)

    Examples
    --------
    >>> zh_fit_oren_nayar(1.0).round(4).tolist()
    [0.3093, 0.3751, 0.216]
    """
    a = _alpha(alpha)
    b = np.sqrt(a)
    if form == "code":
        powers = np.stack([b, b * a, b * a * a, b * a**3], axis=-1)
    elif form == "text":
        powers = np.stack([b, b**2, b**3, b**4], axis=-1)
    else:
        raise ValueError(f"form must be 'code' or 'text'; got {form!r}")
    return np.clip(powers @ ZH_FIT_OREN_NAYAR.T, 0.0, 1.0)


def zh_fit_ggx(alpha: ArrayLike, *, form: str = "code") -> NDArray[np.float64]:
    """The post's fits E0, E1, E2 for GGX, clamped to [0, 1] as its listing does.

    ``form="code"``: beta (c0 + c1 alpha + c2 alpha^2) as its HLSL evaluates them;
    ``form="text"``: c0 beta + c1 beta^2 + c2 beta^3 as printed.  beta = sqrt(alpha).
    """
    a = _alpha(alpha)
    b = np.sqrt(a)
    if form == "code":
        powers = np.stack([b, b * a, b * a * a], axis=-1)
    elif form == "text":
        powers = np.stack([b, b**2, b**3], axis=-1)
    else:
        raise ValueError(f"form must be 'code' or 'text'; got {form!r}")
    return np.clip(powers @ ZH_FIT_GGX.T, 0.0, 1.0)


def sh_response(
    model: str,
    env: ArrayLike,
    normal: ArrayLike,
    mu_o: ArrayLike,
    roughness: ArrayLike,
    rho: ArrayLike = 1.0,
    *,
    zh: ArrayLike | None = None,
    factor: str = "tau",
    clamp: bool = True,
) -> NDArray[np.float64]:
    """MS response to an order-2 SH environment (the post's ``EstimateMSIrradiance_SH``).

    L_o = F(rho) (1 - E(mu_o))/(pi - E_avg) max(0, sum_k L_k E_k(n)), E_k = ``sh.zh_rotate(zh, n)``.

    Parameters
    ----------
    env : array_like, shape (..., 9, C)
        SH coefficients of the radiance (world frame).
    normal : array_like, shape (..., 3)
    mu_o : array_like, shape (...)
    roughness : array_like, shape (...)
        In the model's domain.
    zh : array_like, shape (..., 3), optional
        ZH coefficients to use (e.g. ``zh_fit_oren_nayar``); default ``zh_exact``.
    clamp : bool
        Apply the listing's max(0, .).

    Returns
    -------
    ndarray, shape (..., C)
    """
    env = sh.environment(env)
    mu_o = ar.in_range("mu_o", mu_o, np.float64, 0.0, 1.0, " (cosine of the view angle)")
    if zh is None:
        zh = zh_exact(model, roughness)
    E = sh.zh_rotate(zh, normal)  # (..., 9)
    irr = np.einsum("...k,...kc->...c", E, env)
    if clamp:
        irr = np.maximum(irr, 0.0)
    avg = average_term(model, roughness)
    F = _factor(factor, rho, avg / math.pi)
    return F * (view_term(model, mu_o, roughness)[..., None] * irr)


# --------------------------------------------------------------------------- area lights (LTC)


def ltc_m33_fit(alpha: ArrayLike, lobe: str = "oren_nayar") -> NDArray[np.float64]:
    """The post's m33(beta): Oren-Nayar (a0 + a1 beta + a2 beta^2) / (b0 + b1 beta + b2 beta^2);
    ``lobe="ggx"``: min(15.2, (a0 + a1 beta^2) / (b0 + b1 beta^2))."""
    b = np.sqrt(_alpha(alpha))
    if lobe == "ggx":
        a0, a1, b0, b1, cap = GGX_M33
        return np.minimum(cap, (a0 + a1 * b * b) / (b0 + b1 * b * b))
    if lobe != "oren_nayar":
        raise ValueError(f"lobe must be 'oren_nayar' or 'ggx'; got {lobe!r}")
    n0, n1, n2 = LTC_M33_NUM
    d0, d1, d2 = LTC_M33_DEN
    return (n0 + b * (n1 + b * n2)) / (d0 + b * (d1 + b * d2))


def ltc_magnitude_fit(alpha: ArrayLike, lobe: str = "oren_nayar") -> NDArray[np.float64]:
    """The post's magnitude(beta): Oren-Nayar max(0, c0 + c1 beta + c2 beta^2 + c3 beta^3);
    ``lobe="ggx"``: c1 beta + c2 beta^2 + c3 beta^3 + c4 beta^4.

    Approximates int (1 - E(mu)) mu dw = pi - E_avg (the LTC integrates to 1).
    """
    b = np.sqrt(_alpha(alpha))
    if lobe == "ggx":
        c1, c2, c3, c4 = GGX_MAG
        return b * (c1 + b * (c2 + b * (c3 + b * c4)))
    if lobe != "oren_nayar":
        raise ValueError(f"lobe must be 'oren_nayar' or 'ggx'; got {lobe!r}")
    c0, c1, c2, c3 = LTC_MAG
    return np.maximum(0.0, c0 + b * (c1 + b * (c2 + b * c3)))


def ltc_distribution(w: ArrayLike, m33: ArrayLike) -> NDArray[np.float64]:
    """D(w) of the LTC with M^-1 = diag(1, 1, m33): m33^2 max(0, z) / (pi (1 - z^2 + m33^2 z^2)^2).

    Heitz et al. 2016 Eq. 1 with D_o the clamped cosine; integrates to 1 over the sphere.
    """
    w = ar.directions("w", w, np.float64)
    m = ar.in_range("m33", m33, np.float64, 0.0, math.inf, " (LTC diagonal)", lo_open=True, hi_open=True)
    z = w[..., 2]
    return m * m * np.maximum(z, 0.0) / (math.pi * (1.0 - z * z + m * m * z * z) ** 2)


def _check_corners(corners: ArrayLike) -> NDArray[np.float64]:
    c = ar.as_float("corners", corners, np.float64)
    if c.ndim < 2 or c.shape[-1] != 3 or c.shape[-2] < 3:
        raise ValueError(f"corners must have shape (..., V, 3) with V >= 3 polygon vertices, got {c.shape}")
    if not np.all(c[..., 2] > 0.0):
        raise ValueError(
            "corners: every polygon vertex must be above the horizon (z > 0); horizon clipping is not implemented"
        )
    return c


def polygon_irradiance(corners: ArrayLike) -> NDArray[np.float64]:
    """(1/pi) int_P max(0, z) dw of a spherical polygon above the horizon (Lambert's edge formula).

    E = (1/(2 pi)) |sum_i acos(v_i . v_j) (v_i x v_j).z / |v_i x v_j||, v = normalised corners.
    """
    c = _check_corners(corners)
    v = c / np.linalg.norm(c, axis=-1, keepdims=True)
    vn = np.roll(v, -1, axis=-2)
    cr = np.cross(v, vn)
    ang = np.arccos(np.clip(np.sum(v * vn, axis=-1), -1.0, 1.0))
    crz = cr[..., 2] / np.maximum(np.linalg.norm(cr, axis=-1), 1e-300)
    return np.abs(np.sum(ang * crz, axis=-1)) / (2.0 * math.pi)


def ltc_polygon_integral(corners: ArrayLike, m33: ArrayLike) -> NDArray[np.float64]:
    """int_P D_LTC(w) dw for M^-1 = diag(1, 1, m33): the polygon irradiance of M^-1 P (Heitz 2016)."""
    c = _check_corners(corners)
    m = np.asarray(m33, dtype=np.float64)
    scale = np.stack(np.broadcast_arrays(np.ones_like(m), np.ones_like(m), m), axis=-1)
    return polygon_irradiance(c * scale[..., None, :])


def polygon_integral_exact(model: str, corners: ArrayLike, roughness: ArrayLike, *, n: int = 48) -> NDArray[np.float64]:
    """Brute force: int_P (1 - E(mu)) mu dw over planar parallelograms, Gauss-Legendre on their area.

    Parameters
    ----------
    corners : array_like, shape (..., 4, 3)
        Parallelogram corners in order (the post's rectangle lights), above the horizon.
    roughness : array_like, shape (R,)
        Roughness values (in the model's domain).
    n : int
        Gauss-Legendre nodes per side.

    Returns
    -------
    ndarray, shape (...) + (R,)
    """
    c = _check_corners(corners)
    if c.shape[-2:] != (4, 3):
        raise ValueError(f"corners must have shape (..., 4, 3) (parallelograms), got {c.shape}")
    if not isinstance(n, int) or n < 2:
        raise ValueError(f"n must be an integer >= 2, got {n!r}")
    x, w = sh._gauss(n)
    c0 = c[..., 0, None, None, :]
    e1, e2 = c[..., 1, :] - c[..., 0, :], c[..., 3, :] - c[..., 0, :]
    p = c0 + x[:, None, None] * e1[..., None, None, :] + x[None, :, None] * e2[..., None, None, :]  # (..., n, n, 3)
    d = np.linalg.norm(p, axis=-1)
    wdir = p / d[..., None]
    normal = np.cross(e1, e2)
    area = np.linalg.norm(normal, axis=-1)
    cos_l = np.abs(np.einsum("...abk,...k->...ab", wdir, normal / area[..., None]))
    dw = np.outer(w, w) * area[..., None, None] * cos_l / (d * d)
    mu = wdir[..., 2]
    r = np.atleast_1d(np.asarray(roughness, dtype=np.float64))
    E = single_scattering_albedo(model, mu.reshape(-1)[:, None], r[None, :]).reshape(mu.shape + r.shape)
    return np.einsum("...ab,...abr->...r", dw * mu, 1.0 - E)
