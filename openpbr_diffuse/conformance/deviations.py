"""Known deviations of published implementations, as predictors of their output.

Each entry of :data:`DEVIATIONS` maps a name to a :class:`Deviation`: calling it on a
:class:`~.vectors.VectorSet` returns (n, 3) -- what an implementation with that deviation
returns for those rows (BRDF value, or directional albedo).  Rows the deviation does not
affect get the reference value.  Every prediction is built from the library's own models
(``evaluate`` / ``directional_albedo``), never from a re-typed formula; :func:`reference`
is the conforming answer.

A prediction is NaN where it is undefined (a mixed-up roughness beyond the domain of the
model, e.g. sigma' = sigma^2 > pi/2): the grader fits the other rows.  Some deviations come
in a few variants (e.g. which way a roughness mix-up goes); the
grader fits every variant and reports the best.

The deviations (each found in a published implementation named below; see the guide page
"Graded implementations"):

- ``no_energy_compensation_qon``: QON (sigma = the given r) where EON is asked for -- the
  MaterialX OSL backend ignores ``energy_compensation``;
- ``no_energy_compensation_fon``: FON (EON's single-scattering lobe) without f_ms;
- ``rho_ms_extra_inv_pi``: f_ms with an extra 1/pi, as printed in the OpenPBR 1.1 spec text
  (fails the white furnace: E = 0.945 at mu = 0.3, r = 1);
- ``rho_ms_extra_rho``: f_ms multiplied by rho once more (Blender Cycles): coloured albedo
  too dark, white furnace still passes;
- ``ldotv_clamped``: L.V clamped to [eps, 1] before s = L.V - mu_i mu_o (MaterialX GLSL):
  changes FON/EON's s <= 0 branch (L.V < 0); the albedo (closed form) is unaffected;
- ``white_tint``: evaluated at rho = 1 and multiplied by rho (OpenPBR-viewer): no colour
  shift;
- ``times_cos_theta_i``: the BRDF multiplied by cos(theta_i) (a radiance response instead
  of f); albedo queries unaffected (variant: also multiplied by their mu);
- ``roughness_sigma_vs_r``: the roughness read in the other parameterisation, converted
  linearly between r in [0, 1] and sigma in [0, pi/2] (either direction: two variants);
- ``roughness_squared``: the roughness squared (or its square root) before use.

Examples
--------
>>> from openpbr_diffuse.conformance.vectors import default_vectors
>>> v = default_vectors()
>>> eon = v.subset((v.model == "eon") & (v.kind == "albedo") & (v.mu == 0.3) & (v.roughness == 1.0))
>>> ref, spec = reference(eon), DEVIATIONS["rho_ms_extra_inv_pi"](eon)
>>> round(float(ref[0, 0]), 4), round(float(spec[0, 0]), 3)    # white: furnace fails
(1.0, 0.945)
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from .vectors import VectorSet

#: MaterialX GLSL clamps L.V to [M_FLOAT_EPS, 1] (M_FLOAT_EPS = 1e-8).
LDOTV_EPS = 1e-8
_HALF_PI = 0.5 * math.pi
_EON_MODELS = ("eon", "eon_approx")


def _roughness_of(vectors):
    return np.where(np.isnan(vectors.roughness), 0.0, vectors.roughness)


def _predict(
    vectors, *, model_map=None, roughness_map=None, color_mode="reference", wi=None, wo=None, rho=None, mu=None
):
    """Evaluate the library for every row: (n, 3).

    ``model_map``: {vector model: model used}; ``roughness_map(model_used, roughness)`` ->
    roughness used (clipped to that model's domain); ``wi`` replaces the rows' wi.
    """
    from ..models import directional_albedo, evaluate
    from ..models.registry import model_info

    n = len(vectors)
    out = np.zeros((n, 3))
    wi = vectors.wi if wi is None else wi
    wo = vectors.wo if wo is None else wo
    rho = vectors.rho if rho is None else rho
    mu = vectors.mu if mu is None else mu
    rough = _roughness_of(vectors)
    for name in np.unique(vectors.model):
        used = (model_map or {}).get(str(name), str(name))
        info = model_info(used)
        sel = vectors.model == name
        r = rough[sel]
        outside = np.zeros(r.shape, bool)
        if roughness_map is not None and used != "lambert":
            r = roughness_map(info, r)
            hi = min(info.roughness_max, _HALF_PI)
            outside = (r < 0.0) | (r > hi * (1.0 + 1e-12))
            r = np.clip(r, 0.0, hi)
        brdf = sel & (vectors.kind == "brdf")
        alb = sel & (vectors.kind == "albedo")
        kb, ka = vectors.kind[sel] == "brdf", vectors.kind[sel] == "albedo"
        if brdf.any():
            out[brdf] = evaluate(used, wi[brdf], wo[brdf], r[kb], rho[brdf], color_mode=color_mode)
        if alb.any():
            out[alb] = directional_albedo(used, mu[alb], r[ka], rho[alb], color_mode=color_mode)
        out[np.flatnonzero(sel)[outside]] = np.nan  # beyond the model's domain: no prediction
    return out


def reference(vectors: VectorSet) -> np.ndarray:
    """The conforming result of every row (float64): ``evaluate`` / ``directional_albedo``."""
    return _predict(vectors)


def _single_scattering(vectors):
    """EON rows: the FON lobe (f_ss, or rho E_F); other rows: the reference."""
    return _predict(vectors, model_map={m: "fon" for m in _EON_MODELS})


def _ms_scaled(vectors, scale):
    """EON rows: f_ss + scale(rho) * f_ms, with f_ms = f_EON - f_FON; others: reference."""
    ref = reference(vectors)
    ss = _single_scattering(vectors)
    return ss + scale(vectors.rho) * (ref - ss)


def _no_ec(model):
    def predict(vectors):
        return _predict(vectors, model_map={m: model for m in _EON_MODELS})

    return predict


def _rho_ms_extra_inv_pi(vectors):
    return _ms_scaled(vectors, lambda rho: 1.0 / math.pi)


def _rho_ms_extra_rho(vectors):
    return _ms_scaled(vectors, lambda rho: rho)


def _ldotv_clamped(vectors):
    """BRDF rows with L.V < eps: wi turned about the normal so that s = eps - mu_i mu_o.

    f depends on wi only through mu_i and s = sin(theta_i) sin(theta_o) cos(dphi), so a
    direction with the same mu_i and the clamped s is evaluated by the library itself.
    """
    wi, wo = vectors.wi.copy(), vectors.wo
    brdf = vectors.kind == "brdf"
    with np.errstate(invalid="ignore"):
        ldotv = np.einsum("ij,ij->i", wi, wo)
        si = np.hypot(wi[:, 0], wi[:, 1])
        so = np.hypot(wo[:, 0], wo[:, 1])
        change = brdf & (ldotv < LDOTV_EPS) & (wi[:, 2] > 0) & (wo[:, 2] > 0) & (si * so > 0)
        s_new = LDOTV_EPS - wi[:, 2] * wo[:, 2]
        cos_dphi = np.clip(s_new / np.where(change, si * so, 1.0), -1.0, 1.0)
        phi_o = np.arctan2(wo[:, 1], wo[:, 0])
        dphi = np.arccos(cos_dphi)
    new = np.stack([si * np.cos(phi_o + dphi), si * np.sin(phi_o + dphi), wi[:, 2]], axis=-1)
    wi[change] = new[change]
    return _predict(vectors, wi=wi)


def _white_tint(vectors):
    return _predict(vectors, color_mode="white_tint")


def _times_cos(vectors):
    out = reference(vectors)
    brdf = vectors.kind == "brdf"
    out[brdf] *= np.maximum(vectors.wi[brdf, 2], 0.0)[:, None]
    return out


def _times_cos_albedo_too(vectors):
    """Also the albedo queries multiplied by their cosine mu."""
    out = _times_cos(vectors)
    alb = vectors.kind == "albedo"
    out[alb] *= vectors.mu[alb, None]
    return out


def _rough(mapping):
    def predict(vectors):
        return _predict(vectors, roughness_map=mapping)

    return predict


def _read_as_other(info, x):
    """The implementation converts as if x were in the other parameterisation."""
    return x * (2.0 / math.pi) if info.roughness_name == "r" else x * _HALF_PI


def _read_as_other_inverse(info, x):
    return x * _HALF_PI if info.roughness_name == "r" else x * (2.0 / math.pi)


def _squared(info, x):
    if info.roughness_name == "r":
        return x * x
    return _HALF_PI * (x / _HALF_PI) ** 2


def _squared_radians(info, x):
    return x * x


def _sqrt(info, x):
    if info.roughness_name == "r":
        return np.sqrt(x)
    return _HALF_PI * np.sqrt(x / _HALF_PI)


def _ms_scaled_brdf(scale):
    """f_ms scaled in the BRDF rows only (the albedo computed by a separate, right formula)."""

    def predict(vectors):
        out = _ms_scaled(vectors, lambda rho: scale)
        alb = vectors.kind == "albedo"
        out[alb] = reference(vectors.subset(alb))
        return out

    return predict


def _ms_times_pi(vectors):
    return _ms_scaled(vectors, lambda rho: math.pi)


def _divided_by_cos(vectors):
    """The BRDF divided by cos(theta_i) (a cosine "divided out" twice)."""
    out = reference(vectors)
    brdf = vectors.kind == "brdf"
    with np.errstate(divide="ignore", invalid="ignore"):
        mu_i = vectors.wi[brdf, 2]
        out[brdf] = np.where((mu_i > 0)[:, None], out[brdf] / np.where(mu_i > 0, mu_i, 1.0)[:, None], 0.0)
    return out


def _degrees(info, x):
    """A value in radians (or r) converted as if it were degrees."""
    return x * (math.pi / 180.0)


def _radians_to_degrees(info, x):
    return x * (180.0 / math.pi)


def srgb_encode(x: np.ndarray) -> np.ndarray:
    """The sRGB transfer function (IEC 61966-2-1): linear -> encoded.

    >>> round(float(srgb_encode(np.array(0.5))), 5)
    0.73536
    """
    x = np.asarray(x, dtype=np.float64)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(np.maximum(x, 0.0), 1.0 / 2.4) - 0.055)


def srgb_decode(x: np.ndarray) -> np.ndarray:
    """The inverse sRGB transfer function (IEC 61966-2-1): encoded -> linear.

    >>> round(float(srgb_decode(np.array(0.5))), 5)
    0.21404
    """
    x = np.asarray(x, dtype=np.float64)
    return np.where(x <= 0.04045, x / 12.92, np.power((np.maximum(x, 0.0) + 0.055) / 1.055, 2.4))


def _rho_mapped(fn):
    def predict(vectors):
        return _predict(vectors, rho=fn(vectors.rho))

    return predict


def _lambert_for_eon(vectors):
    return _predict(vectors, model_map={m: "lambert" for m in _EON_MODELS})


def _predict_qon_scaled(vectors):
    out = reference(vectors)
    eon = np.isin(vectors.model, _EON_MODELS)
    if eon.any():
        sub = vectors.subset(eon)
        sub = type(sub)(
            sub.id,
            sub.kind,
            np.full(len(sub), "qon"),
            sub.wi,
            sub.wo,
            sub.mu,
            np.minimum(_roughness_of(sub) * _HALF_PI, _HALF_PI),
            sub.rho,
            sub.version,
        )
        out[eon] = _predict(sub)
    return out


def _eq14(listing_albedo):
    """EON rows computed with the Eq. 14 fit of E_F.  The albedo rows: Listing 1's
    E_EON(exact = false) = rho E_F~ + rho_ms (1 - E_F~) (``listing_albedo``), or the
    exact albedo of the approximate lobe."""

    def predict(vectors):
        from ..models.eon import rho_ms
        from ..models.fon import E_F_approx, E_F_avg

        out = _predict(vectors, model_map={"eon": "eon_approx"})
        alb = (vectors.kind == "albedo") & (vectors.model == "eon")
        if listing_albedo and alb.any():
            r = _roughness_of(vectors)[alb]
            ef = np.vectorize(E_F_approx, otypes=[float])(vectors.mu[alb], r)[:, None]
            avg = np.vectorize(E_F_avg, otypes=[float])(r)[:, None]
            rho = vectors.rho[alb]
            out[alb] = rho * ef + np.vectorize(rho_ms, otypes=[float])(rho, avg) * (1.0 - ef)
        return out

    return predict


def _mu_floor_inputs(vectors, floors):
    """The inputs an implementation that raises mu to a floor evaluates, for each of
    ``floors`` (k,): (changed rows, infeasible rows) (k, n), wi, wo (k, n, 3), mu (k, n).
    mu_i, mu_o (and the albedo's mu) become max(mu, floor) while L.V is kept: the
    directions are rebuilt with z = max(mu, floor) and the azimuth that gives the
    implementation's s = L.V - mu_i' mu_o'."""
    fl = np.asarray(floors, dtype=np.float64)[:, None]
    wiz, woz = vectors.wi[:, 2], vectors.wo[:, 2]
    brdf = vectors.kind == "brdf"
    albedo = vectors.kind == "albedo"
    with np.errstate(invalid="ignore", divide="ignore"):
        ldotv = np.einsum("ij,ij->i", vectors.wi, vectors.wo)
        up = (brdf & (wiz > 0) & (woz > 0)) & ((wiz < fl) | (woz < fl))
        mi, mo = np.maximum(wiz, fl), np.maximum(woz, fl)
        si, so = np.sqrt(np.maximum(0.0, 1.0 - mi * mi)), np.sqrt(np.maximum(0.0, 1.0 - mo * mo))
        cos_dphi = (ldotv - mi * mo) / np.where(si * so > 0, si * so, 1.0)
        # no direction pair has these mu and this L.V: no prediction for that row
        infeasible = up & ((np.abs(cos_dphi) > 1.0 + 1e-12) | (si * so == 0))
        dphi = np.arccos(np.clip(cos_dphi, -1.0, 1.0))
        changed = up | (albedo & (vectors.mu < fl))
    new_wo = np.stack([so, np.zeros_like(so), mo], axis=-1)
    new_wi = np.stack([si * np.cos(dphi), si * np.sin(dphi), mi], axis=-1)
    wi = np.where(up[..., None], new_wi, vectors.wi)
    wo = np.where(up[..., None], new_wo, vectors.wo)
    mu = np.where(albedo, np.maximum(vectors.mu, fl), vectors.mu)
    return changed, infeasible, wi, wo, mu


def _mu_floor_predictions(vectors, floors, base):
    """``_mu_floor_predict`` at each of ``floors`` (k, n, 3), from one evaluation of the
    library over the rows that some floor changes (``base``: the reference of ``vectors``)."""
    out = np.repeat(np.asarray(base, dtype=np.float64)[None], len(floors), axis=0)
    top = float(np.max(floors))
    with np.errstate(invalid="ignore"):  # the rows with a mu below some floor (NaN: none)
        low = np.flatnonzero((vectors.wi[:, 2] < top) | (vectors.wo[:, 2] < top) | (vectors.mu < top))
    sub = vectors.subset(low)
    changed, infeasible, wi, wo, mu = _mu_floor_inputs(sub, floors)
    k, i = np.nonzero(changed)
    if i.size:
        out[k, low[i]] = _predict(sub.subset(i), wi=wi[k, i], wo=wo[k, i], mu=mu[k, i])
    k, i = np.nonzero(infeasible)
    out[k, low[i]] = np.nan
    return out


def _mu_floor_predict(vectors, floor, base=None):
    """mu_i, mu_o (and the albedo's mu) raised to ``floor`` while L.V is kept
    (``_mu_floor_inputs``).  Only the rows with a mu below the floor are evaluated; the
    others are ``base`` (the reference of ``vectors``, computed when None)."""
    base = reference(vectors) if base is None else base
    return _mu_floor_predictions(vectors, [floor], base)[0]


def _over_sqrt2(info, x):
    return x / math.sqrt(2.0)


def _times_sqrt2(info, x):
    return x * math.sqrt(2.0)


def _predict_swap_qon_fujii(vectors):
    return _predict(vectors, model_map={"qon": "qon_fujii", "qon_fujii": "qon"})


#: Rec. 709 / sRGB luminance weights.
LUMINANCE_709 = (0.2126, 0.7152, 0.0722)
#: Listing 1's guard of f_ms.
_EPS = 1e-7


def _eon_parts(vectors):
    """For the EON rows (mask): the FON part ``ss`` (n, 3), E_F(mu_i), E_F(mu_o) (albedo rows:
    E_F(mu)) (n,) -- exact for "eon", the Eq. 14 fit for "eon_approx" -- <E_F> (n,), and
    the reference (n, 3).  Built from the library's FON (its albedo at rho = 1 is E_F)."""
    from ..models.fon import E_F_approx, E_F_avg

    ref = reference(vectors)
    eon = np.isin(vectors.model, _EON_MODELS)
    ss = _single_scattering(vectors)
    r = _roughness_of(vectors)
    brdf = vectors.kind == "brdf"
    mu_o = np.where(brdf, vectors.wo[:, 2], vectors.mu)
    mu_i = np.where(brdf, vectors.wi[:, 2], 1.0)
    e = {}
    for key, mu in (("i", mu_i), ("o", mu_o)):
        val = np.ones(len(vectors))
        up = eon & (mu > 0)
        exact = up & (vectors.model == "eon")
        if exact.any():
            from ..models import directional_albedo

            val[exact] = directional_albedo("fon", mu[exact], r[exact], np.ones((int(exact.sum()), 3)))[:, 0]
        approx = up & (vectors.model == "eon_approx")
        if approx.any():
            val[approx] = np.vectorize(E_F_approx, otypes=[float])(mu[approx], r[approx])
        e[key] = val
    avg = np.asarray(E_F_avg(r), dtype=np.float64)
    return eon, ss, e["i"], e["o"], avg, ref


def _with_ms(vectors, parts, rho_ms_of, drop_mu_i=False, lobe_albedo=False, avg_used=None):
    """EON rows rebuilt as f_ss + f_ms with the given rho_ms (``rho_ms_of(rho, avg)``), <E_F>
    (``avg_used``), and optionally f_ms without its (1 - E_F(mu_i)) factor."""
    eon, ss, e_i, e_o, avg, ref = parts
    avg = avg if avg_used is None else avg_used
    out = ref.copy()
    if not eon.any():
        return out
    brdf = vectors.kind == "brdf"
    with np.errstate(divide="ignore", invalid="ignore"):
        rms = rho_ms_of(vectors.rho, avg[:, None])
        fo = np.maximum(_EPS, 1.0 - e_o)
        fi = np.ones_like(fo) if drop_mu_i else np.maximum(_EPS, 1.0 - e_i)
        den = np.maximum(_EPS, 1.0 - avg)
        up = brdf & (vectors.wi[:, 2] > 0) & (vectors.wo[:, 2] > 0)
        f_ms = np.where(up[:, None], rms / math.pi * (fo * fi / den)[:, None], 0.0)
        a_ms = rms * (1.0 - e_o)[:, None]
        if lobe_albedo:  # the albedo of the lobe without the mu_i factor: int mu dw / pi = 1
            a_ms = rms * (fo / den)[:, None]
    sel_b, sel_a = eon & brdf, eon & ~brdf
    out[sel_b] = ss[sel_b] + f_ms[sel_b]
    out[sel_a] = ss[sel_a] + a_ms[sel_a]
    return out


def _rho_ms_formula(rho, avg):
    from ..models.eon import rho_ms

    return rho_ms(rho, avg)


def _rho_ms_scalar(weights):
    w = np.asarray(weights, dtype=np.float64)

    def predict(vectors):
        def scalar_rho_ms(rho, avg):
            grey = np.repeat((rho @ w)[:, None], 3, axis=1)
            return _rho_ms_formula(grey, avg)

        return _with_ms(vectors, _eon_parts(vectors), scalar_rho_ms)

    return predict


def _ms_no_mu_i(lobe_albedo):
    def predict(vectors):
        return _with_ms(vectors, _eon_parts(vectors), _rho_ms_formula, drop_mu_i=True, lobe_albedo=lobe_albedo)

    return predict


def _avg_of(vectors, c):
    from ..models.fon import C1

    r = _roughness_of(vectors)
    return (1.0 + c * r) / (1.0 + C1 * r)


def _avg_constant_predict(vectors, c, parts=None):
    parts = _eon_parts(vectors) if parts is None else parts
    return _with_ms(vectors, parts, _rho_ms_formula, avg_used=_avg_of(vectors, c))


def _avg_label(c):
    from ..models.fon import C2

    return f"<E_F> = A_F (1 + c r) with c = {c:.5g} (the reference c2 = {C2:.7g})"


def _robust_score(out, pred, weight):
    """A residual continuous in the fitted parameter (capped per value at 1e3 tolerances)."""
    e = np.abs(out - pred) * weight
    return float(np.sum(np.minimum(np.where(np.isfinite(e), e, 1e3), 1e3) ** 2))


def _grid_fit(score, lo, hi, n=65, refinements=3):
    """argmin of ``score`` on a grid over [lo, hi], the best cell refined ``refinements`` times."""
    grid = np.linspace(lo, hi, n)
    for _ in range(refinements + 1):
        s = [score(x) for x in grid]
        k = int(np.argmin(s))
        a, b = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
        grid = np.linspace(a, b, 17)
    return float(grid[int(np.argmin([score(x) for x in grid]))])


def _avg_constant_fit(vectors, out, ref, weight):
    parts = _eon_parts(vectors)
    if not parts[0].any():
        return 0.0, ref.copy()
    c = _grid_fit(lambda c: _robust_score(out, _avg_constant_predict(vectors, c, parts), weight), -0.3, 1.0)
    return c, _avg_constant_predict(vectors, c, parts)


def _rough_floor_predict(vectors, floor):
    return _predict(vectors, roughness_map=lambda info, x: np.maximum(x, floor))


def _rough_floor_label(b):
    return f"x' = max(x, {b:.4g})"


def _rough_floor_predictions(vectors, floors, base):
    """``_rough_floor_predict`` at each of ``floors`` (k, n, 3) from one evaluation of the
    library over the rows whose roughness is below some floor."""
    from .vectors import VectorSet

    out = np.repeat(np.asarray(base, dtype=np.float64)[None], len(floors), axis=0)
    r = vectors.roughness
    with np.errstate(invalid="ignore"):
        low = np.flatnonzero((vectors.model != "lambert") & (r < float(np.max(floors))))
    if low.size == 0:
        return out
    fl = np.asarray(floors, dtype=np.float64)
    k, j = np.nonzero(r[low][None, :] < fl[:, None])
    if k.size == 0:
        return out
    sub = vectors.subset(low[j])
    sub = VectorSet(sub.id, sub.kind, sub.model, sub.wi, sub.wo, sub.mu, fl[k], sub.rho, sub.version)
    out[k, low[j]] = _predict(sub)
    return out


def _rough_floor_fit(vectors, out, ref, weight):
    r = vectors.roughness[(vectors.model != "lambert") & np.isfinite(vectors.roughness)]
    pos = r[r > 0]
    if r.size == 0 or not (r == 0).any():
        return 0.0, ref.copy()
    top = float(pos.min()) if pos.size else 0.5
    base = reference(vectors)
    grid = np.linspace(0.0, top, 65)[1:]
    for _ in range(4):
        preds = _rough_floor_predictions(vectors, grid, base)
        s = [_robust_score(out, p, weight) for p in preds]
        k = int(np.argmin(s))
        a, b = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
        grid = np.linspace(a, b, 17)
    b = float(grid[8])
    return b, _rough_floor_predictions(vectors, [b], base)[0]


def _below(vectors):
    return (vectors.kind == "brdf") & ((vectors.wi[:, 2] <= 0) | (vectors.wo[:, 2] <= 0))


def _below_predict(vectors, _=0.0):
    """A two-sided lobe: the rows below the horizon evaluated with z -> |z|."""
    wi, wo = vectors.wi.copy(), vectors.wo.copy()
    wi[:, 2], wo[:, 2] = np.abs(wi[:, 2]), np.abs(wo[:, 2])
    return _predict(vectors, wi=wi, wo=wo)


def _below_fit(vectors, out, ref, weight):
    """The submitted values themselves at the rows below the horizon where they are not 0."""
    bad = _below(vectors)[:, None] & np.isfinite(out) & (np.abs(out - ref) * weight > 1.0)
    return float(bad.any(axis=1).sum()), np.where(bad, out, ref)


def _below_label(n):
    return f"f != 0 at {int(n)} rows below the horizon"


class Fitted:
    """A deviation variant with one fitted parameter: ``fit(vectors, out, ref, weight)``
    returns (parameter, prediction); ``label(parameter)`` describes it; calling it with
    ``vectors`` alone predicts at ``default``."""

    def __init__(self, fit: Callable, predict: Callable, label: Callable, default: float) -> None:
        self.fit, self.predict, self.label, self.default = fit, predict, label, default

    def __call__(self, vectors: VectorSet) -> np.ndarray:
        return self.predict(vectors, self.default)


_NAMED_FACTORS = (
    (math.pi, "1/pi forgotten"),
    (1.0 / math.pi, "an extra 1/pi"),
    (2.0, "x 2"),
    (0.5, "x 1/2"),
    (2.0 * math.pi, "1/(2 pi) forgotten"),
    (1.0 / (2.0 * math.pi), "an extra 1/(2 pi)"),
    (4.0 * math.pi, "1/(4 pi) forgotten"),
)


def factor_name(k: float) -> str:
    """The sentence for a fitted constant factor.

    >>> factor_name(3.14159)
    'every value x 3.1416 (1/pi forgotten)'
    """
    for value, why in _NAMED_FACTORS:
        if abs(k - value) <= 2e-4 * value:
            return f"every value x {k:.5g} ({why})"
    return f"every value x {k:.5g}"


def _scale_predict(kinds):
    def predict(vectors, k):
        out = reference(vectors)
        sel = np.isin(vectors.kind, kinds)
        out[sel] *= k
        return out

    return predict


def _scale_fit(kinds):
    predict = _scale_predict(kinds)

    def fit(vectors, out, ref, weight):
        sel = np.isin(vectors.kind, kinds)[:, None] & np.isfinite(out) & np.isfinite(ref)
        w2 = np.where(sel, weight, 0.0) ** 2
        den = float(np.sum(w2 * ref * ref))
        k = float(np.sum(w2 * np.where(sel, out, 0.0) * ref) / den) if den > 0 else 1.0
        if not math.isfinite(k):
            k = 1.0
        return k, predict(vectors, k)

    return fit, predict


def _floor_fit(vectors, out, ref, weight):
    """The floor that matches the most values: a grid in log mu, then the best cell refined
    by finer grids (each grid one batched evaluation of the library)."""
    mus = np.concatenate([vectors.wi[:, 2], vectors.wo[:, 2], vectors.mu])
    mus = mus[np.isfinite(mus) & (mus > 0) & (mus < 0.5)]
    if mus.size == 0:
        return 0.0, ref.copy()

    base = reference(vectors)  # the rows above every floor tried keep their reference value

    def scores(floors):  # a robust residual, continuous in m (capped per value at 1e3 tolerances)
        e = np.abs(out[None] - _mu_floor_predictions(vectors, floors, base)) * weight[None]
        return np.sum(np.minimum(np.where(np.isfinite(e), e, 1e3), 1e3) ** 2, axis=(1, 2))

    grid = np.geomspace(1e-4, 0.3, 60)
    for _ in range(_FLOOR_REFINEMENTS + 1):
        k = int(np.argmin(scores(grid)))
        lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
        grid = np.linspace(lo, hi, _FLOOR_GRID)
    m = 0.5 * (lo + hi)
    return float(m), _mu_floor_predict(vectors, m, base)


#: The floor fit's refinements of its best grid cell: each a grid of ``_FLOOR_GRID`` points
#: over the two cells around the best point, so the bracket shrinks 16-fold per refinement
#: (3 refinements: to 1/2000 of a cell of the first grid, whose cells are 14 % apart in mu:
#: the fitted floor to better than 1e-4 relative, finer than the 4 digits it is reported with).
_FLOOR_REFINEMENTS = 3
_FLOOR_GRID = 33


@dataclass(frozen=True)
class Deviation:
    """A known deviation: ``variants`` is a tuple of (label, predictor); calling the
    deviation runs the first variant."""

    name: str
    description: str
    source: str
    variants: tuple[tuple[str, Callable], ...]

    def __call__(self, vectors: VectorSet) -> np.ndarray:
        return self.variants[0][1](vectors)


_TABLE: tuple[tuple[str, str, str, tuple[tuple[str, Callable], ...]], ...] = (
    (
        "no_energy_compensation_qon",
        "QON (sigma = the given r) instead of EON: no energy compensation",
        "MaterialX OSL backend (ignores energy_compensation)",
        (("qon with sigma = r", _no_ec("qon")), ("qon with sigma = r pi/2", _predict_qon_scaled)),
    ),
    (
        "no_energy_compensation_fon",
        "FON instead of EON: the single-scattering lobe without f_ms",
        "EON without its Eq. 16-19 compensation term",
        (("fon", _no_ec("fon")),),
    ),
    (
        "rho_ms_extra_inv_pi",
        "rho_ms with an extra 1/pi in f_ms (white furnace fails)",
        "OpenPBR specification text v1.1",
        (("f_ms / pi", _rho_ms_extra_inv_pi),),
    ),
    (
        "rho_ms_extra_rho",
        "f_ms multiplied by rho once more (coloured albedo too dark)",
        "Blender Cycles",
        (("rho f_ms", _rho_ms_extra_rho),),
    ),
    (
        "ldotv_clamped",
        "L.V clamped to [eps, 1] before s = L.V - mu_i mu_o (changes the s <= 0 branch)",
        "MaterialX GLSL",
        (("clamp(L.V, 1e-8, 1)", _ldotv_clamped),),
    ),
    (
        "white_tint",
        "evaluated at rho = 1 then multiplied by rho (no colour shift)",
        "OpenPBR-viewer",
        (("rho f(rho = 1)", _white_tint),),
    ),
    (
        "times_cos_theta_i",
        "the BRDF multiplied by cos(theta_i) (a radiance response, not f)",
        "common integration mistake",
        (("f mu_i", _times_cos), ("f mu_i, albedo E mu", _times_cos_albedo_too)),
    ),
    (
        "roughness_sigma_vs_r",
        "roughness read in the other parameterisation (sigma in [0, pi/2] vs r in [0, 1])",
        "parameter mix-up between QON (sigma) and FON/EON (r)",
        (
            ("r' = 2r/pi, sigma' = sigma pi/2", _rough(_read_as_other)),
            ("r' = r pi/2, sigma' = 2 sigma/pi", _rough(_read_as_other_inverse)),
        ),
    ),
    (
        "roughness_squared",
        "roughness squared (or square-rooted) before use",
        "perceptual-roughness convention mix-up",
        (
            ("r' = r^2 (sigma normalised to [0, 1])", _rough(_squared)),
            ("sigma' = sigma^2 (radians)", _rough(_squared_radians)),
            ("r' = sqrt(r)", _rough(_sqrt)),
        ),
    ),
    (
        "no_energy_compensation_lambert",
        "Lambert instead of EON: rho/pi, no roughness",
        "EON rows answered by a Lambertian lobe",
        (("lambert", _lambert_for_eon),),
    ),
    (
        "eq14_fit_for_exact",
        "the Eq. 14 fit of E_F where the exact E_F (Eq. 12-13) is claimed",
        "Listing 1 with exact = false: grade such code as eon_approx (fill the eon_approx rows, "
        "check --model eon_approx)",
        (("E_F~ in f_ms, Listing 1 albedo", _eq14(True)), ("E_F~ in f_ms, the lobe's albedo", _eq14(False))),
    ),
    (
        "constant_factor",
        "every value multiplied by a constant factor",
        "a 1/pi forgotten or added, a factor 2",
        (
            ("{}", Fitted(_scale_fit(("brdf", "albedo"))[0], _scale_predict(("brdf", "albedo")), factor_name, math.pi)),
            (
                "{} (BRDF rows only)",
                Fitted(
                    _scale_fit(("brdf",))[0],
                    _scale_predict(("brdf",)),
                    lambda k: factor_name(k).replace("every value", "every BRDF value"),
                    math.pi,
                ),
            ),
        ),
    ),
    (
        "ms_missing_inv_pi",
        "f_ms without its 1/pi (multiple scattering x pi)",
        "Eq. 17 with the 1/pi dropped",
        (("f_ms x pi", _ms_times_pi), ("f_ms x pi, albedo right", _ms_scaled_brdf(math.pi))),
    ),
    (
        "divided_by_cos_theta_i",
        "the BRDF divided by cos(theta_i) (the cosine divided out)",
        "a cosine removed that was never in f",
        (("f / mu_i", _divided_by_cos),),
    ),
    (
        "roughness_degrees",
        "roughness converted between degrees and radians",
        "a radians value read as degrees (or the reverse)",
        (("x' = x pi/180", _rough(_degrees)), ("x' = x 180/pi", _rough(_radians_to_degrees))),
    ),
    (
        "rho_srgb_encoded",
        "rho used sRGB-encoded instead of linear",
        "a colour texture or swatch read without (or with a second) sRGB decode",
        (("rho' = srgb_encode(rho)", _rho_mapped(srgb_encode)), ("rho' = srgb_decode(rho)", _rho_mapped(srgb_decode))),
    ),
    (
        "mu_floor",
        "mu_i, mu_o clamped at a floor",
        "max(mu, floor) against grazing division",
        (("mu' = max(mu, {:.4g})", Fitted(_floor_fit, _mu_floor_predict, lambda m: f"mu' = max(mu, {m:.4g})", 0.01)),),
    ),
)

_TABLE += (
    (
        "roughness_sigma_over_sqrt2",
        "roughness mapped as sigma = r/sqrt(2) (or r sqrt(2)): pass the roughness through unchanged",
        "Mitsuba/Arnold-style alpha -> sigma = alpha/sqrt(2) (OpenPBR discussion #159)",
        (("x' = x/sqrt(2)", _rough(_over_sqrt2)), ("x' = x sqrt(2)", _rough(_times_sqrt2))),
    ),
    (
        "qon_fujii_constants",
        "Fujii's QON (A + 0.17 rho sigma^2/(sigma^2 + 0.13), negative s kept) where QON is asked for, "
        "or QON where qon_fujii is: use the model's own A and s/t",
        "Fujii 2013 and Oren-Nayar 1994 QON confused (grade Fujii's code with --model qon_fujii)",
        (("qon <-> qon_fujii", _predict_swap_qon_fujii),),
    ),
    (
        "rho_ms_from_scalar_rho",
        "rho_ms (Eq. 18) computed from one scalar of rho instead of per channel: compute it per channel",
        "a grey rho_ms from the luminance or the mean of a colour",
        (
            ("rho_ms(luminance(rho)), Rec. 709 weights", _rho_ms_scalar(LUMINANCE_709)),
            ("rho_ms(mean(rho))", _rho_ms_scalar((1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0))),
        ),
    ),
    (
        "ms_missing_mu_i_factor",
        "f_ms without its (1 - E_F(mu_i)) factor (not reciprocal): multiply f_ms by max(eps, 1 - E_F(mu_i))",
        "Eq. 16 with one of its two albedo factors dropped",
        (
            ("f_ms without (1 - E_F(mu_i)), albedo Eq. 20", _ms_no_mu_i(False)),
            ("f_ms without (1 - E_F(mu_i)), the lobe's albedo", _ms_no_mu_i(True)),
        ),
    ),
    (
        "avg_albedo_constant",
        "<E_F> (Eq. 15) computed with another constant c2 in A_F (1 + c2 r): use c2 = 2/3 - 28/(15 pi)",
        "a mistyped c2 (reference 0.0724882125)",
        (
            (
                "<E_F> = A_F (1 + c r), c = {:.6g}",
                Fitted(_avg_constant_fit, _avg_constant_predict, _avg_label, 0.724882125),
            ),
        ),
    ),
    (
        "roughness_floor",
        "roughness raised to a floor before use: pass roughness 0 (and small values) through",
        "max(roughness, floor) against a singular smooth limit",
        (("x' = max(x, {:.4g})", Fitted(_rough_floor_fit, _rough_floor_predict, _rough_floor_label, 0.05)),),
    ),
    (
        "nonzero_below_horizon",
        "f non-zero for a direction below the horizon: return 0 when wi.z <= 0 or wo.z <= 0 (single-sided)",
        "a missing or inverted horizon test (a two-sided lobe)",
        (("f != 0 below the horizon", Fitted(_below_fit, _below_predict, _below_label, 0.0)),),
    ),
)

#: name -> Deviation (predictor of such an implementation's output).
DEVIATIONS = {name: Deviation(name, desc, src, variants) for name, desc, src, variants in _TABLE}

__all__ = ["DEVIATIONS", "Deviation", "Fitted", "reference", "LDOTV_EPS", "srgb_encode", "srgb_decode", "factor_name"]
