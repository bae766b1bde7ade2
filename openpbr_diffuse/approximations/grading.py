"""Grading of the approximations against exact quantities: one function per table row.

Each ``grade_*`` function returns a ``Row`` (approximation, equation, what it approximates,
the reference it was compared with, the domain, the metric, max and RMS error, where the max
is).  ``grade_all`` runs them all; ``tools/grade_approximations.py`` writes the result to
``openpbr_diffuse/data/approximation_errors.csv`` with provenance, and the report section
reads that file (and recomputes a few rows live).

Grids (``quick`` halves them): BRDF rows use Gauss-Legendre nodes in mu_i, mu_o in (0, 1),
phi in (0, pi) and sigma uniform in [0, pi/2]; RMS is the plain mean over the grid nodes.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import gotanda2012 as gt
from . import kulla_conty as kc
from . import sh

HALF_PI = 0.5 * math.pi
#: rho used when comparing BRDFs with fullON (Gotanda's Fig. 6 plots rho = 0.9).
RHO_FULL = 0.9
#: EON Listing 1's guard of 1 - <E_F> (eps = 1e-7) in the post's pi - E_avg units.
EON_GUARD = math.pi * 1e-7


@dataclass
class Row:
    id: str
    approximation: str
    equation: str
    approximates: str
    reference: str
    domain: str
    metric: str
    max_error: float
    rms_error: float
    at: str
    n: int
    note: str = ""

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def _row(id, approximation, equation, approximates, reference, domain, metric, err, where, note=""):
    err = np.asarray(err, dtype=np.float64)
    a = np.abs(err)
    k = int(np.argmax(a))
    at = where(np.unravel_index(k, err.shape)) if where else ""
    return Row(
        id,
        approximation,
        equation,
        approximates,
        reference,
        domain,
        metric,
        float(a.reshape(-1)[k]),
        float(np.sqrt(np.mean(a * a))),
        at,
        int(a.size),
        note,
    )


def _fmt(**kw):
    return ", ".join(f"{k}={v:.12g}" for k, v in kw.items())


# --------------------------------------------------------------------------- grids


def brdf_grid(
    quick: bool = False,
) -> tuple[
    tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]],
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.float64],
]:
    """Directions (mu_i, mu_o, phi) on Gauss-Legendre nodes and sigma values; arrays and wi, wo."""
    n_mu, n_phi, n_sig = (8, 12, 7) if quick else (16, 32, 17)
    x, _ = np.polynomial.legendre.leggauss(n_mu)
    mu = 0.5 * (x + 1.0)
    xp, _ = np.polynomial.legendre.leggauss(n_phi)
    phi = 0.5 * math.pi * (xp + 1.0)
    sig = np.linspace(0.0, HALF_PI, n_sig)
    MI, MO, PH, SG = np.meshgrid(mu, mu, phi, sig, indexing="ij")
    si, so = np.sqrt(1 - MI * MI), np.sqrt(1 - MO * MO)
    wi = np.stack([si * np.cos(PH), si * np.sin(PH), MI], axis=-1)
    wo = np.stack([so, np.zeros_like(so), MO], axis=-1)
    return (mu, mu, phi, sig), wi, wo, SG, MI


def _brdf_where(axes):
    mi, mo, ph, sg = axes

    def where(idx):
        i, o, p, s = idx
        return _fmt(mu_i=mi[i], mu_o=mo[o], phi=ph[p], sigma=sg[s])

    return where


# --------------------------------------------------------------------------- Gotanda


def grade_gotanda_brdfs(quick: bool = False) -> list[Row]:
    """Eq. 20, 23 against QON; Eq. 20, 24, 25 against fullON (rho = 0.9)."""
    from ..models import evaluate

    axes, wi, wo, SG, MI = brdf_grid(quick)
    where = _brdf_where(axes)
    qon = evaluate("qon", wi, wo, SG, 1.0)[..., 0]
    full = evaluate("full_on", wi, wo, SG, RHO_FULL)[..., 0] / RHO_FULL
    dom = "mu_i, mu_o in (0, 1), phi in (0, pi), sigma in [0, pi/2]"
    metric_r = "|f - f_ref| / f_ref (relative)"
    metric_l = "|pi (f - f_ref) mu_i| / rho (radiance per unit irradiance, Gotanda's L_r/E0)"
    e20 = gt.simplified_qon(wi, wo, SG)[..., 0]
    with np.errstate(divide="ignore", over="ignore"):
        shi = np.where(SG > 0, 2.0 / np.maximum(SG, 1e-300) ** 2, 1e300)
    e23 = gt.shininess_qon(wi, wo, shi)[..., 0]
    e24 = gt.improved_unsigned(wi, wo, SG)[..., 0]
    e25 = gt.improved(wi, wo, SG)[..., 0]
    ref = "od.evaluate('full_on', rho=0.9) / 0.9"
    rows = [
        _row(
            "gotanda_eq20_vs_qon",
            "Gotanda Eq. 20 (QON in dot products)",
            "Gotanda 2012 Eq. 20",
            "QON (EON Eq. 1-4)",
            "od.evaluate('qon')",
            dom,
            metric_r,
            (e20 - qon) / qon,
            where,
            "algebraically identical: rounding only",
        ),
        _row(
            "gotanda_eq23_vs_qon",
            "Gotanda Eq. 23 (shininess form)",
            "Gotanda 2012 Eq. 21-23",
            "QON (EON Eq. 1-4)",
            "od.evaluate('qon')",
            dom,
            metric_r,
            (e23 - qon) / qon,
            where,
            "2.22222 printed for 1/0.45",
        ),
        _row(
            "gotanda_eq20_vs_fullon",
            "Gotanda Eq. 20 (= QON)",
            "Gotanda 2012 Eq. 20",
            "full Oren-Nayar (rho = 0.9)",
            ref,
            dom,
            metric_l,
            math.pi * (e20 - full) * MI,
            where,
        ),
        _row(
            "gotanda_eq24_vs_fullon",
            "Gotanda Eq. 24 (slightly improved)",
            "Gotanda 2012 Eq. 24",
            "full Oren-Nayar (rho = 0.9)",
            ref,
            dom,
            metric_l,
            math.pi * (e24 - full) * MI,
            where,
            f"min f = {float(e24.min()) * math.pi:.4g}/pi: negative for backward light",
        ),
        _row(
            "gotanda_eq25_vs_fullon",
            "Gotanda Eq. 25 (improved; lobe 'gotanda')",
            "Gotanda 2012 Eq. 25",
            "full Oren-Nayar (rho = 0.9)",
            ref,
            dom,
            metric_l,
            math.pi * (e25 - full) * MI,
            where,
        ),
    ]
    return rows


def sh_grid(quick: bool = False) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    mu = np.linspace(0.0, 1.0, 11 if quick else 41)
    sig = np.linspace(0.0, HALF_PI, 7 if quick else 25)
    return mu, sig


def gotanda_exact_sh(
    quick: bool = False, model: str = "gotanda", n: int | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Exact DC and linear scales (mu x sigma grid) of ``model`` at rho = 1, by quadrature."""
    mu, sig = sh_grid(quick)
    n = n or (12 if quick else 24)
    T = sh.lobe_transfer(model, mu[:, None], sig[None, :], 1.0, n=n)[..., 0]
    return mu, sig, T[..., 0] / sh.C0, T[..., 2] / (2.0 / 3.0 * sh.C1), T[..., 3] / (2.0 / 3.0 * sh.C1)


def grade_gotanda_sh(quick: bool = False) -> list[Row]:
    rows = []
    for model, label in (
        ("gotanda", "Eq. 25 lobe (rho = 1), exact SH projection"),
        ("full_on", "full Oren-Nayar (rho = 1), exact SH projection"),
    ):
        mu, sig, dc, lin, _ = gotanda_exact_sh(quick, model)
        M, S = np.meshgrid(mu, sig, indexing="ij")

        def where(idx):
            return _fmt(mu_o=mu[idx[0]], sigma=sig[idx[1]])

        dom = "mu_o in [0, 1], sigma in [0, pi/2]"
        ref = f"Gauss-Legendre quadrature of od.evaluate('{model}') x Y_lm (sh.lobe_transfer)"
        tag = "e25" if model == "gotanda" else "fullon"
        rows += [
            _row(
                f"gotanda_eq27_vs_{tag}",
                "Gotanda Eq. 27 (DC scale)",
                "Gotanda 2012 Eq. 27",
                f"DC scale = E(mu_o): {label}",
                ref,
                dom,
                "|scale - exact|",
                gt.dc_scale_eq27(M, S) - dc,
                where,
            ),
            _row(
                f"gotanda_eq28_vs_{tag}",
                "Gotanda Eq. 28 (DC scale, no arccos)",
                "Gotanda 2012 Eq. 28",
                f"DC scale = E(mu_o): {label}",
                ref,
                dom,
                "|scale - exact|",
                gt.dc_scale_eq28(M, S) - dc,
                where,
            ),
            _row(
                f"gotanda_eq29_vs_{tag}",
                "Gotanda Eq. 29 (linear scale)",
                "Gotanda 2012 Eq. 29",
                f"linear scale = T_10 / (2/3 Y_10): {label}",
                ref,
                dom,
                "|scale - exact|",
                gt.linear_scale_eq29(M, S) - lin,
                where,
            ),
        ]
    return rows


# --------------------------------------------------------------------------- Kulla-Conty


def kc_white_furnace(
    model: str = "qon", quick: bool = False, factor: str = "tau"
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Albedo of f_ss + f_ms at rho = 1 by 2-D quadrature (mu x roughness grid)."""
    mu = np.array([0.0, 0.05, 0.2, 0.5, 0.8, 1.0]) if quick else np.linspace(0.0, 1.0, 11)
    rmax = HALF_PI if model != "fon" else 1.0
    r = np.linspace(0.0, rmax, 4 if quick else 7)

    def brdf(wi, wo, rr, rho):
        return kc.compensated(model, wi, wo, rr, rho, factor=factor)

    T = sh.lobe_transfer(f"{model}+ms", mu[:, None], r[None, :], 1.0, n=12 if quick else 20, brdf=brdf)
    return mu, r, T[..., 0, 0] / sh.C0


def eon_white_furnace(quick: bool = False) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    mu = np.array([0.0, 0.05, 0.2, 0.5, 0.8, 1.0]) if quick else np.linspace(0.0, 1.0, 11)
    r = np.linspace(0.0, 1.0, 4 if quick else 7)
    T = sh.lobe_transfer("eon", mu[:, None], r[None, :], 1.0, n=12 if quick else 20)
    return mu, r, T[..., 0, 0] / sh.C0


def grade_kc_furnace(quick: bool = False) -> list[Row]:
    rows = []
    mu, r, E = kc_white_furnace("qon", quick)

    def where(idx):
        return _fmt(mu_o=mu[idx[0]], roughness=r[idx[1]])

    rows.append(
        _row(
            "kc_qon_white_furnace",
            "Kulla-Conty f_ms on QON (reference tables)",
            "post: f_ms",
            "white furnace: albedo 1 at rho = 1",
            "2-D Gauss-Legendre quadrature of f_qon + f_ms",
            "mu_o in [0, 1], sigma in [0, pi/2]",
            "|E - 1|",
            E - 1.0,
            where,
            "table interpolation error only",
        )
    )
    mu, r, E = eon_white_furnace(quick)
    rows.append(
        _row(
            "eon_white_furnace",
            "EON analytic compensation (for comparison)",
            "EON Eq. 16-20",
            "white furnace: albedo 1 at rho = 1",
            "2-D Gauss-Legendre quadrature of od.evaluate('eon')",
            "mu_o in [0, 1], r in [0, 1]",
            "|E - 1|",
            E - 1.0,
            where,
        )
    )
    return rows


def grade_kc_vs_eon(quick: bool = False) -> list[Row]:
    """K-C on FON's tables with EON's rho_ms factor against od.evaluate('eon'): the same lobe."""
    from ..models import evaluate

    axes, wi, wo, SG, MI = brdf_grid(True if quick else False)
    r = SG / HALF_PI
    rho = np.array([0.9, 0.5, 0.2])
    f_kc = kc.compensated("fon", wi, wo, r, rho, factor="exact", guard=EON_GUARD)
    f_eon = evaluate("eon", wi, wo, r, rho)
    err = (f_kc - f_eon) * math.pi * MI[..., None]
    mi, mo, ph, sg = axes

    def where(idx):
        return _fmt(mu_i=mi[idx[0]], mu_o=mo[idx[1]], phi=ph[idx[2]], r=sg[idx[3]] / HALF_PI, channel=idx[4])

    return [
        _row(
            "kc_fon_exact_vs_eon",
            "Kulla-Conty on FON tables, factor = EON rho_ms",
            "post: f_ms with EON Eq. 18",
            "EON (Eq. 16-20)",
            "od.evaluate('eon')",
            "mu_i, mu_o in (0, 1), phi in (0, pi), r in [0, 1], rho = (0.9, 0.5, 0.2)",
            "|pi (f - f_ref) mu_i|",
            err,
            where,
            "identical up to table interpolation",
        )
    ]


def grade_kc_factor(quick: bool = False) -> list[Row]:
    """tau factor against the exact series factor of QON's own <E>, at the albedo level."""
    from ..albedo.tables import reference_albedo, reference_average_albedo

    rho = np.linspace(0.0, 1.0, 11 if quick else 41)
    sig = np.linspace(0.0, HALF_PI, 7 if quick else 25)
    mu = np.linspace(0.0, 1.0, 6 if quick else 21)
    avg = reference_average_albedo("qon", sig, 1.0)[..., 0]  # (S,)
    F_tau = kc.rho_factor(rho[:, None])[..., 0]  # (P,)
    F_ex = kc.exact_rho_factor(rho[:, None, None], avg[None, :])[..., 0]  # (P, S)
    one_minus_E = 1.0 - reference_albedo("qon", mu[:, None], sig[None, :], 1.0)[..., 0]  # (M, S)
    err = (F_tau[:, None, None] - F_ex[:, None, :]) * one_minus_E[None, :, :]  # (P, M, S)

    def where(idx):
        return _fmt(rho=rho[idx[0]], mu_o=mu[idx[1]], sigma=sig[idx[2]])

    rows = [
        _row(
            "kc_tau_factor_albedo",
            "rho factor A1 (tau rho)^2/(1 - tau rho), tau = 0.2843",
            "post Pt. 1-2 (tau = 0.28430405702379613)",
            "exact series factor rho^2 <E>/(1 - rho (1 - <E>)) of QON's <E> (EON Eq. 18 form)",
            "reference tables (albedo_qon.csv)",
            "rho in [0, 1], mu_o in [0, 1], sigma in [0, pi/2]",
            "|albedo(tau) - albedo(exact factor)| = |F_tau - F_exact| (1 - E(mu_o))",
            err,
            where,
        )
    ]
    return rows


def alpha_grid(quick: bool = False) -> NDArray[np.float64]:
    return np.linspace(0.0, 1.0, 21 if quick else 401)


def grade_kc_zh(quick: bool = False) -> list[Row]:
    a = alpha_grid(quick)
    ggx_note = "GGX table accuracy <= 6e-4 (3e-3 for alpha < 0.04)"
    # (row id prefix, lobe, its ZH fit, exact ZH, what the fit approximates (per l), reference,
    # the notes of the "code" and "text" forms of the fit)
    lobes = (
        (
            "kc_zh",
            "Oren-Nayar",
            kc.zh_fit_oren_nayar,
            kc.zh_exact("qon", kc.sigma_of_alpha(a)),
            "E_{l} = 2 pi int Y_{l}0 (1 - E(mu)) mu dmu of QON, sigma = alpha pi/2",
            "Gauss-Legendre (64) of the QON reference table",
            (
                "as the post's HLSL evaluates it: beta (c0 + c1 a + c2 a^2 + c3 a^3)",
                "as the post's text prints it: c0 b + c1 b^2 + c2 b^3 + c3 b^4 (erratum)",
            ),
        ),
        (
            "kc_ggx_zh",
            "GGX",
            kc.zh_fit_ggx,
            kc.zh_exact(kc.GGX, a),
            "E_{l} of the GGX (F = 1) MS lobe, alpha = GGX alpha",
            "Gauss-Legendre (64) of the GGX albedo table (microfacet.tables, E1)",
            (ggx_note, ggx_note),
        ),
    )
    rows = []
    for prefix, lobe, zh_fit, exact, approximates, reference, notes in lobes:
        for form, tag, note in zip(("code", "text"), ("", "_text"), notes):
            fit = zh_fit(a, form=form)
            for l in range(3):
                rows.append(
                    _row(
                        f"{prefix}_E{l}{tag}",
                        f"ZH fit E{l}(beta), {lobe} ({form} form)",
                        "post Pt. 2 SH fits",
                        approximates.format(l=l),
                        reference,
                        "alpha in [0, 1]",
                        "|fit - exact|",
                        fit[:, l] - exact[:, l],
                        lambda idx: _fmt(alpha=a[idx[0]]),
                        note,
                    )
                )
    return rows


def sh_test_environments(k: int = 8, seed: int = 14) -> NDArray[np.float64]:
    """Order-2 SH radiance environments (9, 1): a sky-like gradient plus seeded random ones.

    Each is made non-negative in the mean (L_00 large enough) so the irradiance is positive.
    """
    rng = np.random.default_rng(seed)
    envs = rng.normal(0.0, 0.35, (k, 9))
    envs[:, 0] = 1.0 / sh.C0 * 0.5  # mean radiance 0.5
    envs[0] = 0.0
    envs[0, 0], envs[0, 2] = 0.5 / sh.C0, 0.4 / sh.C1  # L(w) = 0.5 + 0.4 z (sky)
    return envs[..., None]


def grade_kc_sh_response(quick: bool = False) -> list[Row]:
    """MS response to SH environments with the fitted ZH, against brute-force quadrature."""
    a = np.linspace(0.05, 1.0, 5 if quick else 12)
    sig = kc.sigma_of_alpha(a)
    mu = np.array([0.1, 0.5, 0.9]) if quick else np.array([0.0, 0.1, 0.3, 0.5, 0.7, 0.9, 1.0])
    envs = sh_test_environments(4 if quick else 8)
    up = np.array([0.0, 0.0, 1.0])

    def ms(wi, wo, r, rho):
        return kc.ms_lobe("qon", wi, wo, r, rho, factor="none")

    T = sh.lobe_transfer("qon ms", mu[:, None], sig[None, :], 1.0, n=12 if quick else 20, brdf=ms)[..., 0]  # (M, A, 9)
    brute = np.einsum("mak,ek->mae", T, envs[..., 0])
    lam = np.einsum("k,ek->e", sh.LAMBERT_BAND_SCALE[sh.BAND] * sh.basis(up), envs[..., 0])  # white Lambert
    zh_fit = kc.zh_fit_oren_nayar(a)
    rows = []
    for tag, zh, note in (
        ("fit", zh_fit, "fit ZH (code form), with the listing's max(0, .)"),
        ("exact", None, "exact ZH: the SH route itself is exact for order-2 light"),
    ):
        est = kc.sh_response(
            "qon",
            envs[None, None, :, :, :],
            up,
            mu[:, None, None],
            sig[None, :, None],
            1.0,
            zh=None if zh is None else zh[None, :, None, :],
            factor="none",
        )[..., 0]
        err = (est - brute) / lam

        def where(idx):
            return _fmt(mu_o=mu[idx[0]], alpha=a[idx[1]], env=idx[2])

        rows.append(
            _row(
                f"kc_sh_response_{tag}",
                f"MS response to SH environment ({tag} ZH)",
                "post Pt. 2 (SH)",
                "int L(wi) f_ms mu_i dwi for order-2 SH radiance (QON, sigma = alpha pi/2)",
                "2-D Gauss-Legendre quadrature of f_ms x Y_lm",
                "alpha in [0.05, 1], mu_o in [0, 1], 8 environments",
                "|L_o - L_o,exact| / L_o,Lambert (white Lambert's response)",
                err,
                where,
                note,
            )
        )
    return rows


def rectangles(k: int = 12, seed: int = 1414) -> NDArray[np.float64]:
    """Seeded rectangular lights above the horizon: (k, 4, 3) corners (centre, two half-axes)."""
    rng = np.random.default_rng(seed)
    out: list[NDArray[np.float64]] = []
    while len(out) < k:
        c = rng.normal(0.0, 1.0, 3)
        c[2] = abs(c[2]) + 0.3
        c *= rng.uniform(1.0, 3.0) / np.linalg.norm(c)
        u = rng.normal(0.0, 1.0, 3)
        u -= u @ c / (c @ c) * c
        u /= np.linalg.norm(u)
        v = np.cross(c / np.linalg.norm(c), u)
        hu, hv = rng.uniform(0.2, 1.5, 2)
        q = np.array([c + hu * u + hv * v, c - hu * u + hv * v, c - hu * u - hv * v, c + hu * u - hv * v])
        if np.all(q[:, 2] > 0.05):
            out.append(q)
    return np.array(out)


def grade_kc_ltc(quick: bool = False) -> list[Row]:
    a = np.linspace(0.05, 1.0, 6 if quick else 20)
    a = np.union1d(a, [0.25])
    sig = kc.sigma_of_alpha(a)
    rects = rectangles(4 if quick else 12)
    exact = np.stack([kc.polygon_integral_exact("qon", q, sig, n=24 if quick else 48) for q in rects])  # (k, A)
    m33 = kc.ltc_m33_fit(a)
    mag = kc.ltc_magnitude_fit(a)
    ltc = np.stack([kc.ltc_polygon_integral(np.broadcast_to(q, (len(a), 4, 3)), m33) for q in rects])  # (k, A)
    total = math.pi - kc.average_term("qon", sig)  # (A,)

    def where(idx):
        return _fmt(rect=idx[0], alpha=a[idx[1]])

    a_all = alpha_grid(quick)
    rows = [
        _row(
            "kc_ltc_magnitude",
            "LTC magnitude fit mag(beta), Oren-Nayar",
            "post Pt. 2 (area lights)",
            "int (1 - E(mu)) mu dw = pi - E_avg of QON, sigma = alpha pi/2",
            "reference table <E>",
            "alpha in [0, 1]",
            "|mag - (pi - E_avg)|",
            kc.ltc_magnitude_fit(a_all) - (math.pi - kc.average_term("qon", kc.sigma_of_alpha(a_all))),
            lambda idx: _fmt(alpha=a_all[idx[0]]),
            "mag(0) = 0.256 where the exact value is 0",
        ),
        _row(
            "kc_ltc_rect",
            "LTC (m33, magnitude fits) over rectangle lights",
            "post Pt. 2 (area lights)",
            "int_P (1 - E(mu)) mu dw of QON, sigma = alpha pi/2",
            "Gauss-Legendre on the rectangle (48 x 48)",
            "alpha in [0.05, 1], 12 seeded rectangles above the horizon",
            "|mag int_P D_LTC - exact| / (pi - E_avg)",
            (mag * ltc - exact) / total,
            where,
        ),
        _row(
            "kc_ltc_rect_rough",
            "LTC (m33, magnitude fits), alpha >= 0.25",
            "post Pt. 2 (area lights)",
            "int_P (1 - E(mu)) mu dw of QON, sigma = alpha pi/2",
            "Gauss-Legendre on the rectangle (48 x 48)",
            "alpha in [0.25, 1] (perceptual roughness >= 0.5), 12 seeded rectangles",
            "|mag int_P D_LTC - exact| / (pi - E_avg)",
            ((mag * ltc - exact) / total)[:, a >= 0.25],
            lambda idx: _fmt(rect=idx[0], alpha=a[a >= 0.25][idx[1]]),
        ),
        _row(
            "kc_ltc_rect_shape",
            "LTC shape only (m33 fit, exact magnitude)",
            "post Pt. 2 (area lights)",
            "int_P (1 - E(mu)) mu dw of QON, sigma = alpha pi/2",
            "Gauss-Legendre on the rectangle (48 x 48)",
            "alpha in [0.05, 1], 12 seeded rectangles above the horizon",
            "|(pi - E_avg) int_P D_LTC - exact| / (pi - E_avg)",
            (total * ltc - exact) / total,
            where,
        ),
    ]
    # GGX (F = 1): magnitude and rectangles for alpha >= 0.25
    ag = a[a >= 0.25]
    exact_g = np.stack([kc.polygon_integral_exact(kc.GGX, q, ag, n=24 if quick else 48) for q in rects])
    ltc_g = np.stack(
        [kc.ltc_polygon_integral(np.broadcast_to(q, (len(ag), 4, 3)), kc.ltc_m33_fit(ag, "ggx")) for q in rects]
    )
    total_g = math.pi - kc.average_term(kc.GGX, ag)
    rows += [
        _row(
            "kc_ggx_ltc_magnitude",
            "LTC magnitude fit mag(beta), GGX",
            "post Pt. 2 (area lights)",
            "int (1 - E(mu)) mu dw = pi - E_avg of GGX (F = 1), alpha = GGX alpha",
            "GGX albedo table",
            "alpha in [0, 1]",
            "|mag - (pi - E_avg)|",
            kc.ltc_magnitude_fit(a_all, "ggx") - (math.pi - kc.average_term(kc.GGX, a_all)),
            lambda idx: _fmt(alpha=a_all[idx[0]]),
        ),
        _row(
            "kc_ggx_ltc_rect_rough",
            "LTC (m33, magnitude fits), GGX, alpha >= 0.25",
            "post Pt. 2 (area lights)",
            "int_P (1 - E(mu)) mu dw of GGX (F = 1)",
            "Gauss-Legendre on the rectangle (48 x 48)",
            "alpha in [0.25, 1], 12 seeded rectangles",
            "|mag int_P D_LTC - exact| / (pi - E_avg)",
            (kc.ltc_magnitude_fit(ag, "ggx") * ltc_g - exact_g) / total_g,
            lambda idx: _fmt(rect=idx[0], alpha=ag[idx[1]]),
        ),
    ]
    return rows


GRADERS = (
    grade_gotanda_brdfs,
    grade_gotanda_sh,
    grade_kc_furnace,
    grade_kc_vs_eon,
    grade_kc_factor,
    grade_kc_zh,
    grade_kc_sh_response,
    grade_kc_ltc,
)


def grade_all(quick: bool = False, progress: Callable[[str], object] | None = None) -> list[Row]:
    """Every row, in table order."""
    rows = []
    for g in GRADERS:
        if progress:
            progress(g.__name__)
        rows += g(quick)
    return rows


# --------------------------------------------------------------------------- colour shift


def colour_shift(
    rho: ArrayLike = (0.8, 0.5, 0.2), mu: float = 0.5
) -> list[tuple[str, NDArray[np.float64], NDArray[np.float64]]]:
    """Albedo per channel at the roughest setting for EON, K-C(QON, tau), K-C(QON, exact factor).

    Returns a list of (name, albedo (C,), albedo / rho (C,)) for the reference mode and for
    the white-tint mode (rho * E(rho = 1), no colour shift).
    """
    from ..models import directional_albedo

    rho = np.asarray(rho, dtype=np.float64)
    out = []
    E = directional_albedo("eon", mu, 1.0, rho)
    out.append(("EON, r = 1", E))
    out.append(("EON white tint, r = 1", directional_albedo("eon", mu, 1.0, rho, color_mode="white_tint")))
    out.append(("K-C on QON, tau factor, sigma = pi/2", kc.compensated_albedo("qon", mu, HALF_PI, rho, factor="tau")))
    out.append(
        ("K-C on QON, exact factor, sigma = pi/2", kc.compensated_albedo("qon", mu, HALF_PI, rho, factor="exact"))
    )
    # F(rho) = rho (the post's "no saturation" switch): E = rho E_ss + rho (1 - E_ss) = rho
    out.append(("K-C on QON, F = rho (no saturation), sigma = pi/2", rho.copy()))
    return [(name, np.asarray(e, dtype=np.float64).reshape(-1), np.asarray(e).reshape(-1) / rho) for name, e in out]
