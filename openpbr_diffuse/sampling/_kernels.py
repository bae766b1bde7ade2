"""Batch drivers: one parallel loop per verb (``sample``, ``pdf``), dispatching on the strategy id.

The strategy id is loop-invariant, so the branch costs nothing measurable; the formulas
are the scalar functions of ``simple``, ``ltc`` and ``mis``, inlined here.

The drivers are compiled for explicit signatures (float32 and float64; inputs as
read-only 'A'-layout views, outputs C-contiguous): the inputs arrive as broadcast views
(``_arrays.flat``) that are C-contiguous or strided depending on the caller's shapes,
and one specialisation per dtype accepts all of them (no recompilation per layout).
"""
import numba
from numba import prange, types

from ..models._jit import FASTMATH, kernel
from .ltc import clip_fraction, from_frame, ltc_coeffs, ltc_frame, ltc_pdf_local, ltc_sample_local, to_frame
from .mis import eon_pdf, eon_sample
from .registry import CLTC, COSINE, EON, LTC, LTC_NONNEG, UNIFORM
from .simple import INV_2PI, cosine_pdf, cosine_sample_local, uniform_sample


@kernel
def sample_one(strategy, ox, oy, mu, r, u1, u2):
    """Return (x, y, z, pdf) of one sample in the local frame; ``mu`` = wo.z clamped to [0, 1]."""
    if strategy == UNIFORM:
        return uniform_sample(u1, u2)
    Xx, Xy = ltc_frame(ox, oy)
    if strategy == EON:
        return eon_sample(Xx, Xy, mu, r, u1, u2)
    if strategy == COSINE:
        lx, ly, lz, p = cosine_sample_local(u1, u2)
    else:
        a, b, c, d = ltc_coeffs(mu, r)
        if strategy == LTC_NONNEG:
            d = 0.0
        s = clip_fraction(d) if strategy == CLTC else 1.0
        lx, ly, lz, p = ltc_sample_local(a, b, c, d, s, u1, u2)
    wx, wy = from_frame(Xx, Xy, lx, ly)
    return wx, wy, lz, p


@kernel
def pdf_one(strategy, ox, oy, mu, r, wx, wy, wz):
    """Solid-angle pdf of wi = (wx, wy, wz); wz > 0 unless the strategy is the general LTC."""
    if strategy == UNIFORM:
        return INV_2PI
    if strategy == COSINE:
        return cosine_pdf(wz)
    Xx, Xy = ltc_frame(ox, oy)
    lx, ly = to_frame(Xx, Xy, wx, wy)
    if strategy == EON:
        return eon_pdf(lx, ly, wz, mu, r)
    a, b, c, d = ltc_coeffs(mu, r)
    if strategy == LTC_NONNEG:
        d = 0.0
    s = clip_fraction(d) if strategy == CLTC else 1.0
    return ltc_pdf_local(a, b, c, d, s, lx, ly, wz)


def _signatures(verb):
    sigs = []
    for f in (types.float32, types.float64):
        ro2 = types.Array(f, 2, "A", readonly=True)
        ro1 = types.Array(f, 1, "A", readonly=True)
        out2 = types.Array(f, 2, "C")
        out1 = types.Array(f, 1, "C")
        if verb == "sample":  # (strategy, wo, r, u, wi, pdf)
            sigs.append(types.void(types.int64, ro2, ro1, ro2, out2, out1))
        else:                 # (strategy, wo, wi, r, pdf)
            sigs.append(types.void(types.int64, ro2, ro2, ro1, out1))
    return sigs


@numba.njit(_signatures("sample"), parallel=True, cache=True, fastmath=FASTMATH)
def sample_kernel(strategy, wo, r, u, wi, pdf):
    """wi[i], pdf[i] = sample of ``strategy`` given wo[i], r[i], u[i]; pdf 0 when wo[i] is below the horizon."""
    for i in prange(pdf.shape[0]):
        oz = 1.0 * wo[i, 2]
        mu = min(max(oz, 0.0), 1.0)  # unit vectors may exceed 1 by rounding; the fit needs [0, 1]
        wx, wy, wz, p = sample_one(strategy, 1.0 * wo[i, 0], 1.0 * wo[i, 1], mu, 1.0 * r[i],
                                   1.0 * u[i, 0], 1.0 * u[i, 1])
        wi[i, 0] = wx
        wi[i, 1] = wy
        wi[i, 2] = wz
        pdf[i] = p if oz > 0.0 else 0.0


@numba.njit(_signatures("pdf"), parallel=True, cache=True, fastmath=FASTMATH)
def pdf_kernel(strategy, wo, wi, r, out):
    """out[i] = pdf of sampling wi[i] given wo[i]; 0 below the horizon (except wi for the general LTC)."""
    for i in prange(out.shape[0]):
        oz = 1.0 * wo[i, 2]
        wz = 1.0 * wi[i, 2]
        if oz <= 0.0 or (wz <= 0.0 and strategy != LTC):
            out[i] = 0.0
            continue
        out[i] = pdf_one(strategy, 1.0 * wo[i, 0], 1.0 * wo[i, 1], min(oz, 1.0), 1.0 * r[i],
                         1.0 * wi[i, 0], 1.0 * wi[i, 1], wz)
