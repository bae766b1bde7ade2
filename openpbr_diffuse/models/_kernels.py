"""Batch drivers: one parallel loop per verb, dispatching on the model id.

The model id is loop-invariant, so the branch costs nothing measurable; every formula is
the scalar function of its model module, inlined here.  Arrays arrive as 2-D (N, k)
views that may have zero strides (broadcast inputs are never copied); rows are
independent, so the loops are ``prange``.
"""
import numba
from numba import prange

from ._jit import FASTMATH, INV_PI, kernel
from .eon import eon_albedo_terms, eon_average_terms, eon_terms, rho_ms
from .fon import C2, G_fon, G_qon, fon_A, fon_terms
from .fujii import fujii_coeffs, fujii_terms
from .full_on import full_on_terms
from .gotanda import gotanda_AB, gotanda_terms
from .lambert import lambert_terms
from .qon import QON_AVG_G, qon_AB, qon_terms
from .registry import INFO, MIX_LINEAR, MIX_RHO2, MIX_RHO_MS
from .van_ouwerkerk import van_ouwerkerk_terms

LAMBERT, QON, QON_FOOTNOTE, QON_VO, QON_FUJII, FON, FULL_ON, GOTANDA, EON, EON_APPROX = (
    INFO[n].id for n in ("lambert", "qon", "qon_footnote", "qon_van_ouwerkerk", "qon_fujii",
                         "fon", "full_on", "gotanda", "eon", "eon_approx"))


@kernel
def lobe_terms(model, ix, iy, iz, ox, oy, oz, r):
    """(g, h, <E_F>) of f = rho g + m(rho) h at one pair of directions (both above the horizon)."""
    s = ix * ox + iy * oy + iz * oz - iz * oz
    if model == EON or model == EON_APPROX:
        return eon_terms(iz, oz, s, r, model == EON_APPROX)
    if model == FON:
        return fon_terms(iz, oz, s, r), 0.0, 0.0
    if model == QON or model == QON_FOOTNOTE:
        A, B = qon_AB(r, 0.33 if model == QON else 0.57)
        return qon_terms(iz, oz, s, A, B), 0.0, 0.0
    if model == QON_VO:
        return van_ouwerkerk_terms(ix, iy, iz, ox, oy, oz, r), 0.0, 0.0
    if model == QON_FUJII:
        g, h = fujii_terms(iz, oz, s, r)
        return g, h, 0.0
    if model == FULL_ON:
        g, h = full_on_terms(iz, oz, s, r)
        return g, h, 0.0
    if model == GOTANDA:
        return gotanda_terms(iz, oz, s, r), 0.0, 0.0
    return lambert_terms(), 0.0, 0.0


@kernel
def albedo_terms(model, mu, r, average):
    """(e_g, e_h, <E_F>) of E = rho e_g + m(rho) e_h; the average <E> when ``average``.

    QON family: E = A + B G(mu)/pi (Eq. 8), <E> = A + (2/3 - 64/(45 pi)) B (Eq. 9).
    Models of FON's shape f = (A + B s/t)/pi (FON, Gotanda, Fujii): E = A + B G_F(mu)/pi
    (Eq. 12-13 with A_F, B_F replaced) and <E> = A + c2 B (Eq. 15).
    """
    if model == EON or model == EON_APPROX:
        if average:
            return eon_average_terms(r, model == EON_APPROX)
        return eon_albedo_terms(mu, r, model == EON_APPROX)
    if model == QON or model == QON_FOOTNOTE or model == QON_VO:
        A, B = qon_AB(r, 0.57 if model == QON_FOOTNOTE else 0.33)
        if average:
            return A + QON_AVG_G * B, 0.0, 0.0
        return A + B * G_qon(mu) * INV_PI, 0.0, 0.0
    h = 0.0
    if model == FON:
        A = fon_A(r)
        B = r * A
    elif model == GOTANDA:
        A, B = gotanda_AB(r)
    elif model == QON_FUJII:
        A, B, h = fujii_coeffs(r)
    else:  # Lambert
        return 1.0, 0.0, 0.0
    if average:
        return A + C2 * B, h, 0.0
    return A + B * G_fon(mu) * INV_PI, h, 0.0


@kernel
def mix_kind(model):
    """The registry's MIX_* of a model id."""
    if model == QON_FUJII or model == FULL_ON:
        return MIX_RHO2
    if model == EON or model == EON_APPROX:
        return MIX_RHO_MS
    return MIX_LINEAR


@kernel
def mix(kind, rho, g, h, avg):
    """rho g + m(rho) h for the model's rho dependence ``kind`` (registry MIX_*)."""
    if kind == MIX_RHO_MS:
        return rho * g + rho_ms(rho, avg) * h
    if kind == MIX_RHO2:
        return rho * g + rho * rho * h
    return rho * g


@kernel
def mix_row(kind, tint, rho, i, g, h, avg, out):
    """Write one output row: reference colour, or white-then-tint (rho * f(rho = 1))."""
    if tint:
        white = mix(kind, 1.0, g, h, avg)
        for k in range(out.shape[1]):
            out[i, k] = rho[i, k] * white
    else:
        for k in range(out.shape[1]):
            out[i, k] = mix(kind, rho[i, k], g, h, avg)


# Compiled lazily per dtype (float32, float64) and cached on disk.  Inputs always arrive
# as read-only broadcast views (``_arrays.flat``), so each dtype has one specialisation.
compiled = numba.njit(parallel=True, cache=True, fastmath=FASTMATH)


@compiled
def eval_kernel(model, tint, wi, wo, r, rho, out):
    """out[i] = f(wi[i], wo[i]) for one model; 0 when either direction is below the horizon."""
    kind = mix_kind(model)
    for i in prange(out.shape[0]):
        iz = wi[i, 2]
        oz = wo[i, 2]
        if iz <= 0.0 or oz <= 0.0:
            for k in range(out.shape[1]):
                out[i, k] = 0.0
            continue
        g, h, avg = lobe_terms(model, wi[i, 0], wi[i, 1], iz, wo[i, 0], wo[i, 1], oz, r[i])
        mix_row(kind, tint, rho, i, g, h, avg, out)


@compiled
def albedo_kernel(model, tint, average, mu, r, rho, out):
    """out[i] = E(mu[i]) (or <E> when ``average``); at mu = 0 the limit mu -> 0."""
    kind = mix_kind(model)
    for i in prange(out.shape[0]):
        eg, eh, avg = albedo_terms(model, mu[i], r[i], average)
        mix_row(kind, tint, rho, i, eg, eh, avg, out)
