"""EON, FON and QON written again in vectorised NumPy from the formulas of the spec
(models.md: Eq. 10-20 of the EON paper, Oren-Nayar's QON, Fujii 2013), with switches that
introduce the deviations the conformance grader names.  A test subject, independent of the
library and of the deviation predictors: nothing here calls ``openpbr_diffuse``.
"""

import numpy as np

PI = np.pi
C1 = 0.5 - 2.0 / (3.0 * PI)
C2 = 2.0 / 3.0 - 28.0 / (15.0 * PI)
EPS = 1e-7


def _sig(x, digits):
    """x rounded to ``digits`` significant digits (None: unchanged)."""
    if digits is None:
        return x
    x = np.asarray(x, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        e = np.floor(np.log10(np.abs(np.where(x == 0, 1.0, x))))
        q = 10.0 ** (digits - 1 - e)
        return np.where(x == 0, 0.0, np.round(x * q) / q)


def e_f(mu, r, guarded=True, digits=None):
    """E_F(mu) of Eq. 12-13; ``guarded=False``: (S/mu)(1 - S^3) as printed (NaN at mu = 0)."""
    mu = np.asarray(mu, dtype=np.float64)
    S = _sig(np.sqrt(np.maximum(0.0, 1.0 - mu * mu)), digits)
    with np.errstate(divide="ignore", invalid="ignore"):
        if guarded:
            t = S * mu * (1.0 + S + S * S) / (1.0 + S)
        else:
            t = (S / mu) * (1.0 - S**3)
    g = _sig(S * (np.arccos(np.clip(mu, -1.0, 1.0)) - S * mu) + (2.0 / 3.0) * (t - S), digits)
    af = 1.0 / (1.0 + C1 * r)
    return _sig(af + r * af / PI * g, digits)


def eon(
    v,
    *,
    rough=lambda r: r,
    rho_ms_of=None,
    drop_mu_i=False,
    c2=C2,
    horizon="<=",
    guarded=True,
    digits=None,
    with_ms=True,
    mu_floor=None,
    s_y_sign=1.0,
    extra_rho_ms=False,
    ldotv_clamp=False,
):
    """(n, 3) EON answers for the EON rows of VectorSet ``v`` (brdf and albedo rows).

    rough: the roughness the code uses; rho_ms_of(rho (n, 3), avg (n,)) -> (n, 3) replaces
    Eq. 18 (e.g. from a grey rho); drop_mu_i: f_ms without (1 - E_F(mu_i)); c2: the constant
    of <E_F>; horizon "<=" (reference), "<" (a z = 0 direction is evaluated) or "none" (a
    two-sided lobe: z -> |z|); guarded: E_F as a guarded expression; digits: every
    intermediate rounded to that many significant digits; mu_floor: mu_i, mu_o (and the
    albedo's mu) raised to max(mu, mu_floor) inside the formulas; s_y_sign: -1 writes s with
    the y products subtracted (wi.x wo.x - wi.y wo.y), not symmetric in the azimuth;
    extra_rho_ms: f_ms and the albedo's ms part times rho once more; ldotv_clamp: s from
    clamp(L.V, 1e-8, 1) (MaterialX GLSL).
    """
    n = len(v)
    r = rough(np.where(np.isnan(v.roughness), 0.0, v.roughness))
    rho = v.rho
    af = 1.0 / (1.0 + C1 * r)
    avg = _sig(af * (1.0 + c2 * r), digits)
    with np.errstate(divide="ignore", invalid="ignore"):
        if rho_ms_of is None:
            rms = _sig(rho * rho * avg[:, None] / (1.0 - rho * (1.0 - avg[:, None])), digits)
        else:
            rms = rho_ms_of(rho, avg)
        brdf = v.kind == "brdf"
        wi, wo = v.wi.copy(), v.wo.copy()
        if horizon == "none":
            wi[:, 2], wo[:, 2] = np.abs(wi[:, 2]), np.abs(wo[:, 2])
        mi, mo = wi[:, 2], wo[:, 2]
        s = _sig(wi[:, 0] * wo[:, 0] + s_y_sign * wi[:, 1] * wo[:, 1], digits)
        if ldotv_clamp:
            s = np.clip(s + mi * mo, 1e-8, 1.0) - mi * mo
        if mu_floor is not None:
            mi, mo = np.where(mi > 0, np.maximum(mi, mu_floor), mi), np.where(mo > 0, np.maximum(mo, mu_floor), mo)
        if extra_rho_ms:
            rms = rms * rho
        st = np.where(s > 0, s / np.maximum(mi, mo), s)
        f_ss = _sig(rho / PI * (af * (1.0 + r * st))[:, None], digits)
        ei, eo = e_f(mi, r, guarded, digits), e_f(mo, r, guarded, digits)
        fi = np.ones(n) if drop_mu_i else np.maximum(EPS, 1.0 - ei)
        f_ms = _sig(rms / PI * (np.maximum(EPS, 1.0 - eo) * fi / np.maximum(EPS, 1.0 - avg))[:, None], digits)
        f = f_ss + (f_ms if with_ms else 0.0)
        below = (mi < 0) | (mo < 0) if horizon == "<" else (mi <= 0) | (mo <= 0)
        f = np.where(below[:, None], 0.0, f)
        ea = e_f(v.mu if mu_floor is None else np.maximum(v.mu, mu_floor), r, guarded, digits)
        alb = rho * ea[:, None] + (rms * (1.0 - ea)[:, None] if with_ms else 0.0)
    return _sig(np.where(brdf[:, None], f, alb), digits)


def rho_ms_grey(weights):
    """Eq. 18 evaluated on one grey value w . rho for all three channels."""
    w = np.asarray(weights, dtype=np.float64)

    def of(rho, avg):
        g = (rho @ w)[:, None]
        return np.repeat(g * g * avg[:, None] / (1.0 - g * (1.0 - avg[:, None])), 3, axis=1)

    return of


def qon(v, *, fujii=False):
    """(n, 3) QON answers (sigma in radians) for the rows of ``v``; ``fujii``: Fujii 2013's A
    (+ 0.17 rho sigma^2/(sigma^2 + 0.13)) and s/t with negative s kept."""
    sg = np.where(np.isnan(v.roughness), 0.0, v.roughness)
    s2 = sg * sg
    a = (1.0 - 0.5 * s2 / (s2 + 0.33))[:, None] + (0.17 * v.rho * (s2 / (s2 + 0.13))[:, None] if fujii else 0.0)
    b = (0.45 * s2 / (s2 + 0.09))[:, None]
    mi, mo = v.wi[:, 2], v.wo[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.einsum("ij,ij->i", v.wi, v.wo) - mi * mo
        if fujii:
            st = np.where(s > 0, s / np.maximum(mi, mo), s)
        else:
            st = np.maximum(0.0, s) / np.maximum(mi, mo)
        f = v.rho / PI * (a + b * st[:, None])
        f = np.where(((mi <= 0) | (mo <= 0))[:, None], 0.0, f)
        mu = v.mu
        S = np.sqrt(np.maximum(0.0, 1.0 - mu * mu))
        th = np.arccos(np.clip(mu, -1.0, 1.0))
        if fujii:  # the FON G_F (s/t with negative s), guarded at mu = 0
            g = S * (th - S * mu) + (2.0 / 3.0) * (S * mu * (1.0 + S + S * S) / (1.0 + S) - S)
        else:  # Eq. 5: G = sin(th - sin cos) + (2/3) tan (1 - sin^3); G -> pi/2 at mu = 0
            tan_part = np.where(mu > 0, (S / np.where(mu > 0, mu, 1.0)) * (1.0 - S**3), 0.0)
            g = S * (th - S * mu) + (2.0 / 3.0) * tan_part
            g = np.where(mu == 0, PI / 2, g)
        alb = v.rho * (a + b / PI * g[:, None])
    return np.where((v.kind == "brdf")[:, None], f, alb)
