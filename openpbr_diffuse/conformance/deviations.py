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

The deviations (``models.md``, "Known deviations"):

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
from dataclasses import dataclass
from typing import Callable

import numpy as np

#: MaterialX GLSL clamps L.V to [M_FLOAT_EPS, 1] (M_FLOAT_EPS = 1e-8).
LDOTV_EPS = 1e-8
_HALF_PI = 0.5 * math.pi
_EON_MODELS = ("eon", "eon_approx")


def _roughness_of(vectors):
    return np.where(np.isnan(vectors.roughness), 0.0, vectors.roughness)


def _predict(vectors, *, model_map=None, roughness_map=None, color_mode="reference", wi=None):
    """Evaluate the library for every row: (n, 3).

    ``model_map``: {vector model: model used}; ``roughness_map(model_used, roughness)`` ->
    roughness used (clipped to that model's domain); ``wi`` replaces the rows' wi.
    """
    from ..models import directional_albedo, evaluate
    from ..models.registry import model_info

    n = len(vectors)
    out = np.zeros((n, 3))
    wi = vectors.wi if wi is None else wi
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
            out[brdf] = evaluate(used, wi[brdf], vectors.wo[brdf], r[kb], vectors.rho[brdf], color_mode=color_mode)
        if alb.any():
            out[alb] = directional_albedo(used, vectors.mu[alb], r[ka], vectors.rho[alb], color_mode=color_mode)
        out[np.flatnonzero(sel)[outside]] = np.nan  # beyond the model's domain: no prediction
    return out


def reference(vectors):
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


@dataclass(frozen=True)
class Deviation:
    """A known deviation: ``variants`` is a tuple of (label, predictor); calling the
    deviation runs the first variant."""

    name: str
    description: str
    source: str
    variants: tuple[tuple[str, Callable], ...]

    def __call__(self, vectors):
        return self.variants[0][1](vectors)


_TABLE = (
    ("no_energy_compensation_qon", "QON (sigma = the given r) instead of EON: no energy compensation",
     "MaterialX OSL backend (ignores energy_compensation)", (("qon with sigma = r", _no_ec("qon")),)),
    ("no_energy_compensation_fon", "FON instead of EON: the single-scattering lobe without f_ms",
     "EON without its Eq. 16-19 compensation term", (("fon", _no_ec("fon")),)),
    ("rho_ms_extra_inv_pi", "rho_ms with an extra 1/pi in f_ms (white furnace fails)",
     "OpenPBR specification text v1.1", (("f_ms / pi", _rho_ms_extra_inv_pi),)),
    ("rho_ms_extra_rho", "f_ms multiplied by rho once more (coloured albedo too dark)",
     "Blender Cycles", (("rho f_ms", _rho_ms_extra_rho),)),
    ("ldotv_clamped", "L.V clamped to [eps, 1] before s = L.V - mu_i mu_o (changes the s <= 0 branch)",
     "MaterialX GLSL", (("clamp(L.V, 1e-8, 1)", _ldotv_clamped),)),
    ("white_tint", "evaluated at rho = 1 then multiplied by rho (no colour shift)",
     "OpenPBR-viewer", (("rho f(rho = 1)", _white_tint),)),
    ("times_cos_theta_i", "the BRDF multiplied by cos(theta_i) (a radiance response, not f)",
     "common integration mistake", (("f mu_i", _times_cos), ("f mu_i, albedo E mu", _times_cos_albedo_too))),
    ("roughness_sigma_vs_r", "roughness read in the other parameterisation (sigma in [0, pi/2] vs r in [0, 1])",
     "parameter mix-up between QON (sigma) and FON/EON (r)",
     (("r' = 2r/pi, sigma' = sigma pi/2", _rough(_read_as_other)),
      ("r' = r pi/2, sigma' = 2 sigma/pi", _rough(_read_as_other_inverse)))),
    ("roughness_squared", "roughness squared (or square-rooted) before use",
     "perceptual-roughness convention mix-up",
     (("r' = r^2 (sigma normalised to [0, 1])", _rough(_squared)),
      ("sigma' = sigma^2 (radians)", _rough(_squared_radians)),
      ("r' = sqrt(r)", _rough(_sqrt)))),
)

#: name -> Deviation (predictor of such an implementation's output).
DEVIATIONS = {name: Deviation(name, desc, src, variants) for name, desc, src, variants in _TABLE}

__all__ = ["DEVIATIONS", "Deviation", "reference", "LDOTV_EPS"]
