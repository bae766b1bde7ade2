"""An implementation of the vector queries written from the paper, independent of the library.

Used by the conformance tests as "another implementation": the formulas are typed here from
the EON paper (Eq. 1-4, 8, 10-13, 14, 16-20, Listing 1) in plain NumPy, in the dtype asked
for (float32 computes every step in float32, like a GLSL shader), with switches that put in
each known deviation the way such an implementation would -- never through
``openpbr_diffuse.conformance.deviations``.
"""

import numpy as np

PI = np.pi
C1 = 0.5 - 2.0 / (3.0 * PI)
C2 = 2.0 / 3.0 - 28.0 / (15.0 * PI)
G1, G2, G3, G4 = 0.0571085289, 0.491881867, -0.332181442, 0.0714429953


def _qon_ab(sigma):
    s2 = sigma * sigma
    return 1.0 - 0.5 * s2 / (s2 + 0.33), 0.45 * s2 / (s2 + 0.09)


def _ef_exact(mu, r, t):
    mu = np.asarray(mu, t)
    af = t(1.0) / (t(1.0) + t(C1) * r)
    bf = r * af
    safe = np.where(mu > 0, mu, t(1.0))
    si = np.sqrt(np.maximum(t(0.0), t(1.0) - mu * mu))
    g = si * (np.arccos(mu) - si * mu) + t(2.0 / 3.0) * ((si / safe) * (t(1.0) - si * si * si) - si)
    g = np.where(mu > 0, g, t(PI / 2 - 2.0 / 3.0))  # the grazing limit (E_F -> 1)
    return af + (bf / t(PI)) * g


def _ef_approx(mu, r, t):
    m = t(1.0) - mu
    gp = m * (t(G1) + m * (t(G2) + m * (t(G3) + m * t(G4))))
    return (t(1.0) + r * gp) / (t(1.0) + t(C1) * r)


def _qon_g(mu, t):
    th = np.arccos(mu)
    s, c = np.sin(th), np.cos(th)
    tan = np.where(c > 0, s / np.where(c > 0, c, t(1.0)), t(0.0))
    g = s * (th - s * c) + t(2.0 / 3.0) * tan * (t(1.0) - s * s * s)
    return np.where(mu > 0, g, t(PI / 2))


def _map_roughness(model, x, how):
    """How a mixed-up implementation reads the roughness it is given."""
    if how is None:
        return x
    r_model = model in ("fon", "eon", "eon_approx")
    if how == "sigma_vs_r":  # it believes the value is in the other parameterisation
        return x / (PI / 2) if r_model else x * (PI / 2)
    if how == "squared":
        return x * x
    if how == "degrees":  # a radians value (or r) converted as if it were degrees
        return x * (PI / 180.0)
    raise ValueError(how)


def srgb_encode(x):
    """IEC 61966-2-1 encoding (linear -> sRGB)."""
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.maximum(x, 0) ** (1 / 2.4) - 0.055)


def srgb_decode(x):
    """IEC 61966-2-1 decoding (sRGB -> linear)."""
    return np.where(x <= 0.04045, x / 12.92, ((np.maximum(x, 0) + 0.055) / 1.055) ** 2.4)


def answer(
    vectors,
    dtype=np.float64,
    *,
    energy="eon",
    ms_scale=None,
    clamp_ldotv=False,
    white_tint=False,
    times_cos=False,
    roughness=None,
    scale=None,
    scale_brdf_only=False,
    divide_cos=False,
    cos_wo=False,
    rho_srgb=None,
    mu_floor=None,
    ef_fit=False,
    c1=C1,
):
    """(n, 3) results of this hand implementation for the rows of ``vectors``.

    energy: "eon" (reference), "qon" (QON with sigma = r for EON rows) or "fon" (no f_ms);
    ms_scale: None, "inv_pi" or "rho"; clamp_ldotv: s from clamp(L.V, 1e-8, 1);
    white_tint: rho * f(rho = 1); times_cos: f * mu_i; roughness: None, "sigma_vs_r", "squared",
    "degrees"; scale: every value (or every BRDF value) times this; ms_scale "times_pi": f_ms
    without its 1/pi; divide_cos: f / mu_i; cos_wo: f * mu_o (the cosine of the wrong
    direction); rho_srgb "encode"/"decode": rho passed through the sRGB curve first; mu_floor:
    mu_i, mu_o, mu raised to it (L.V kept); ef_fit: the Eq. 14 fit in EON; energy "lambert";
    c1: the A_F coefficient of FON (a mutant when not C1).
    """
    t = np.dtype(dtype).type
    n = len(vectors)
    out = np.zeros((n, 3), dtype)
    for i in range(n):  # a plain per-row loop: this is a test subject, not library code
        model = str(vectors.model[i])
        rho = vectors.rho[i].astype(dtype)
        if rho_srgb == "encode":
            rho = srgb_encode(rho).astype(dtype)
        elif rho_srgb == "decode":
            rho = srgb_decode(rho).astype(dtype)
        x = vectors.roughness[i]
        x = t(0.0) if np.isnan(x) else t(x)
        x = t(_map_roughness(model, x, roughness))
        if model in ("eon", "eon_approx") and energy in ("qon", "lambert"):
            model = energy
        kind = str(vectors.kind[i])
        rho_eval = np.ones(3, dtype) if (white_tint and model in ("eon", "eon_approx")) else rho
        if kind == "brdf":
            wi, wo = vectors.wi[i].astype(dtype), vectors.wo[i].astype(dtype)
            mi, mo = wi[2], wo[2]
            if mi <= 0 or mo <= 0:
                continue
            ldotv = wi @ wo
            if mu_floor is not None:
                mi, mo = max(mi, t(mu_floor)), max(mo, t(mu_floor))
            if clamp_ldotv:
                ldotv = np.clip(ldotv, t(1e-8), t(1.0))
            s = ldotv - mi * mo
            if model == "lambert":
                f = rho_eval / t(PI)
            elif model == "qon":
                a, b = _qon_ab(x)
                f = rho_eval / t(PI) * (a + b * max(t(0.0), s) / max(mi, mo))
            else:
                st = s / max(mi, mo) if s > 0 else s
                af = t(1.0) / (t(1.0) + t(c1) * x)
                f = rho_eval / t(PI) * af * (t(1.0) + x * st)
                if model in ("eon", "eon_approx") and energy == "eon":
                    ef = _ef_exact if (model == "eon" and not ef_fit) else _ef_approx
                    efo, efi = ef(mo, x, t), ef(mi, x, t)
                    avg = af * (t(1.0) + t(C2) * x)
                    rho_ms = rho_eval * rho_eval * avg / (t(1.0) - rho_eval * (t(1.0) - avg))
                    eps = t(1e-7)
                    fms = rho_ms / t(PI) * max(eps, t(1.0) - efo) * max(eps, t(1.0) - efi) / max(eps, t(1.0) - avg)
                    if ms_scale == "inv_pi":
                        fms = fms / t(PI)
                    elif ms_scale == "times_pi":
                        fms = fms * t(PI)
                    elif ms_scale == "rho":
                        fms = fms * rho_eval
                    f = f + fms
            if times_cos:
                f = f * mi
            if cos_wo:
                f = f * mo
            if divide_cos:
                f = f / mi
        else:
            mu = t(vectors.mu[i])
            if mu_floor is not None:
                mu = max(mu, t(mu_floor))
            if model == "lambert":
                f = rho_eval.copy()
            elif model == "qon":
                a, b = _qon_ab(x)
                f = rho_eval * (a + b / t(PI) * _qon_g(mu, t))
            else:
                ef = _ef_approx(mu, x, t) if (ef_fit and model == "eon") else _ef_exact(mu, x, t)
                f = rho_eval * ef
                if model == "eon" and energy == "eon":
                    af = t(1.0) / (t(1.0) + t(C1) * x)
                    avg = af * (t(1.0) + t(C2) * x)
                    rho_ms = rho_eval * rho_eval * avg / (t(1.0) - rho_eval * (t(1.0) - avg))
                    ms = rho_ms * (t(1.0) - ef)
                    if ms_scale == "inv_pi":
                        ms = ms / t(PI)
                    elif ms_scale == "times_pi":
                        ms = ms * t(PI)
                    elif ms_scale == "rho":
                        ms = ms * rho_eval
                    f = f + ms
        if white_tint and str(vectors.model[i]) in ("eon", "eon_approx"):
            f = f * rho
        if scale is not None and (kind == "brdf" or not scale_brdf_only):
            f = f * t(scale)
        out[i] = f
    return out
