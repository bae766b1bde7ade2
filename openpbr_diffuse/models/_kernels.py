"""Batch drivers: one parallel loop per verb, specialised per model and channel count.

Every formula is the scalar function of its model module, inlined here (``lobe_terms``,
``albedo_terms``).  A driver is compiled for one model id and one channel count C (1, 3,
or any), both compile-time constants: the model branches fold away and the loop body is
straight-line code over flat C-contiguous buffers with constant row strides, which LLVM
vectorises (4-8 rows per instruction).  With a run-time model id, run-time C or
run-time strides it does not, and the loop runs 4-10x slower.

Rows are independent, so the loops are ``prange``; arithmetic is float64 for both input
dtypes (loads are widened, stores rounded: float32 results are the float64 ones rounded).

Inputs whose rows are all the same (a scalar roughness, one rho for every row, a fixed
direction) are tiled into a buffer of at most ``CHUNK`` rows and the driver is called
chunk by chunk, so no input is ever expanded to the full batch.  Drivers are built on
first use (``functools.cache``) and compiled lazily per dtype; numba caches them on disk.
"""
import functools

import numba
import numpy as np
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
def shade(kind, tint, up, p, g, h, avg):
    """One channel: ``rho g + m(rho) h`` (reference) or ``rho f(rho = 1)`` (white_tint); 0 unless ``up``.

    Written with selects, not branches, so that the batch loop stays vectorisable.
    """
    q = 1.0 if tint else p
    v = mix(kind, q, g, h, avg)
    v = p * v if tint else v
    return v if up else 0.0


#: Batch drivers: parallel, cached; numpy's error model (x/0 gives inf, not an exception)
#: so that rows below the horizon can be computed and then discarded without a branch.
compiled = numba.njit(parallel=True, cache=True, fastmath=FASTMATH, error_model="numpy")

_U = numba.uint64   # unsigned row offsets: lets LLVM prove the accesses are affine
_F = numba.float64
_MIX = {info.id: info.mix for info in INFO.values()}
#: Rows per driver call when an input is tiled (bounds the tiled buffers to ~3 MB).
CHUNK = 1 << 16


def _channels(C):
    """The compile-time channel count of a driver: 1, 3, or 0 for "read it from the arrays"."""
    return C if C in (1, 3) else 0


@functools.cache
def eval_driver(model, C):
    """Parallel ``evaluate`` loop for one model id and channel count (see ``_channels``).

    ``drive(tint, wi, wo, r, rho, out)``: wi, wo flat (N*3,), r (N,), rho (N*C,), out (N*C,).
    """
    kind = _MIX[model]
    nc = _channels(C)

    @compiled
    def drive(tint, wi, wo, r, rho, out):
        n = r.shape[0]
        for i in prange(n):
            j = _U(i) * _U(3)
            iz = _F(wi[j + _U(2)])
            oz = _F(wo[j + _U(2)])
            g, h, avg = lobe_terms(model, _F(wi[j]), _F(wi[j + _U(1)]), iz,
                                   _F(wo[j]), _F(wo[j + _U(1)]), oz, _F(r[i]))
            up = (iz > 0.0) & (oz > 0.0)  # f = 0 when either direction is below the horizon
            if nc == 3:
                c = _U(i) * _U(3)
                out[c] = shade(kind, tint, up, _F(rho[c]), g, h, avg)
                out[c + _U(1)] = shade(kind, tint, up, _F(rho[c + _U(1)]), g, h, avg)
                out[c + _U(2)] = shade(kind, tint, up, _F(rho[c + _U(2)]), g, h, avg)
            elif nc == 1:
                out[i] = shade(kind, tint, up, _F(rho[i]), g, h, avg)
            else:
                m = rho.shape[0] // n
                c = _U(i) * _U(m)
                for k in range(m):
                    out[c + _U(k)] = shade(kind, tint, up, _F(rho[c + _U(k)]), g, h, avg)

    return drive


@functools.cache
def albedo_driver(model, C, average):
    """Parallel ``directional_albedo`` (or ``average_albedo``) loop; ``drive(tint, mu, r, rho, out)``.

    E(mu) at mu = 0 is the limit mu -> 0; with ``average`` mu is not read.
    """
    kind = _MIX[model]
    nc = _channels(C)

    @compiled
    def drive(tint, mu, r, rho, out):
        n = r.shape[0]
        for i in prange(n):
            eg, eh, avg = albedo_terms(model, _F(mu[i]), _F(r[i]), average)
            if nc == 3:
                c = _U(i) * _U(3)
                out[c] = shade(kind, tint, True, _F(rho[c]), eg, eh, avg)
                out[c + _U(1)] = shade(kind, tint, True, _F(rho[c + _U(1)]), eg, eh, avg)
                out[c + _U(2)] = shade(kind, tint, True, _F(rho[c + _U(2)]), eg, eh, avg)
            elif nc == 1:
                out[i] = shade(kind, tint, True, _F(rho[i]), eg, eh, avg)
            else:
                m = rho.shape[0] // n
                c = _U(i) * _U(m)
                for k in range(m):
                    out[c + _U(k)] = shade(kind, tint, True, _F(rho[c + _U(k)]), eg, eh, avg)

    return drive


def rows(a, lead, k=None):
    """``a`` (leading shape broadcasting to ``lead``; trailing axis of length k, if any) as a flat buffer.

    Returns ``(buffer, tiled)``: the C-contiguous (n*k,) data when ``a`` already has every
    row (no copy); its single row with ``tiled`` True when all rows are equal; otherwise a
    copy expanded to every row.  Buffers are read-only views so that each driver has one
    signature per dtype whatever the caller's flags.
    """
    full, width = (lead, 1) if k is None else (lead + (k,), k)
    if a.size == width:
        buf, tiled = np.ascontiguousarray(a).reshape(-1), True
    elif a.size == int(np.prod(full)) and a.flags.c_contiguous:  # same size: nothing to broadcast
        buf, tiled = a.reshape(-1), False
    else:
        buf, tiled = np.ascontiguousarray(np.broadcast_to(a, full)).reshape(-1), False
    buf = buf.view()
    buf.flags.writeable = False
    return buf, tiled


def launch(drive, head, inputs, n, out, C):
    """Run ``drive(*head, *buffers, out)`` over n rows; ``inputs`` = [(buffer, k, tiled)].

    Tiled inputs are repeated to min(n, CHUNK) rows and the driver is called per chunk.
    """
    if n == 0:
        return
    if n == 1 or not any(t for _, _, t in inputs):  # every buffer already holds n rows
        drive(*head, *(b for b, _, _ in inputs), out)
        return
    B = min(n, CHUNK)
    reps = []
    for b, k, t in inputs:
        if t:
            b = np.tile(b, B)
            b.flags.writeable = False
        reps.append(b)
    for s in range(0, n, B):
        e = min(n, s + B)
        args = [b[:(e - s) * k] if t else b[s * k:e * k] for b, (_, k, t) in zip(reps, inputs)]
        drive(*head, *args, out[s * C:e * C])


def evaluate_rows(model, tint, wi, wo, r, rho, lead, C, dtype):
    """f for validated arrays broadcasting to ``lead``; returns the (prod(lead)*C,) output."""
    n = int(np.prod(lead))
    out = np.empty(n * C, dtype=dtype)
    wi, twi = rows(wi, lead, 3)
    wo, two = rows(wo, lead, 3)
    r, tr = rows(r, lead)
    rho, trho = rows(rho, lead, C)
    launch(eval_driver(model, C), (tint,), [(wi, 3, twi), (wo, 3, two), (r, 1, tr), (rho, C, trho)],
           n, out, C)
    return out


def albedo_rows(model, tint, average, mu, r, rho, lead, C, dtype):
    """E(mu) (or <E>) for validated arrays broadcasting to ``lead``; flat (prod(lead)*C,) output."""
    n = int(np.prod(lead))
    out = np.empty(n * C, dtype=dtype)
    r, tr = rows(r, lead)
    mu, tmu = (r, tr) if average else rows(mu, lead)  # average: mu is not read
    rho, trho = rows(rho, lead, C)
    launch(albedo_driver(model, C, average), (tint,), [(mu, 1, tmu), (r, 1, tr), (rho, C, trho)],
           n, out, C)
    return out
