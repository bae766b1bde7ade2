"""Batch drivers: one serial ``nogil`` loop per verb (``sample``, ``pdf``), specialised per strategy.

The formulas are the scalar functions of ``simple``, ``ltc`` and ``mis``, inlined here.
As for the lobe models (``models/_kernels.py``; the ``driver`` decorator comes from
``_jit``, ``rows`` and ``launch`` from ``_launch``), a driver is compiled for one strategy id, a compile-time
constant, over flat C-contiguous buffers; the scalar functions are branch-free (selects)
and call no libm function, so LLVM vectorises the loop (AVX2/AVX-512).  Arithmetic is
float64 for both dtypes (float32 results are the float64 ones rounded).
"""

import functools
import math

import numpy as np

from .._jit import driver, kernel, pointer_of
from .._launch import _F, _U, launch, rows
from .ltc import (
    clip_fraction,
    from_frame,
    ltc_coeffs,
    ltc_frame,
    ltc_pdf_local,
    ltc_sample_local,
    to_frame,
)
from .mis import eon_pdf, eon_sample, pow_tenth
from .registry import CLTC, COSINE, EON, LTC, LTC_NONNEG, UNIFORM
from .simple import INV_2PI, cosine_pdf, cosine_sample_local, uniform_sample


@kernel
def strategy_pdf(strategy, ox, oy, oz, wx, wy, wz, r):
    """Solid-angle pdf of wi = (wx, wy, wz) given wo with ``strategy``; the one formula of
    both verbs.  0 when wo.z <= 0 and, except for the general LTC (whose lobe extends below
    the horizon), when wi.z <= 0."""
    mu = min(max(oz, 0.0), 1.0)  # unit vectors may exceed 1 by rounding; the fit needs [0, 1]
    if strategy == UNIFORM:
        p = INV_2PI
    elif strategy == COSINE:
        p = cosine_pdf(wz)
    else:
        Xx, Xy = ltc_frame(ox, oy)
        lx, ly = to_frame(Xx, Xy, wx, wy)
        if strategy == EON:
            p = eon_pdf(lx, ly, wz, mu, r, pow_tenth(r))
        else:
            a, b, c, d = ltc_coeffs(mu, r)
            if strategy == LTC_NONNEG:
                d = 0.0
            s = clip_fraction(d) if strategy == CLTC else 1.0
            p = ltc_pdf_local(a, b, c, d, s, lx, ly, wz)
    ok = (oz > 0.0) & ((wz > 0.0) | (strategy == LTC))
    return p if ok else 0.0


@functools.cache
def sample_driver(strategy):
    """``drive(z_min, wo, r, u, wi, pdf)``: wo (3n,), r (n,), u (2n,) -> wi (3n,), pdf (n,).

    Two guarantees, for every u in [0, 1)^2 and both dtypes:

    - the returned pdf is ``strategy_pdf`` of the direction as stored (rounded to the
      output dtype), i.e. what ``pdf(strategy, wo, wi)`` returns for it (the same formula on
      the same values; only contraction into fused multiply-adds, which LLVM may choose
      differently in the two loops, can change the last bit or two): 0 when wo
      is below the horizon (nothing to sample; the direction is that of wo.z = 0);
    - strategies other than the general LTC never return wi.z <= 0: z is floored at
      ``z_min``, the smallest normal number of the output dtype.  Only rounding reaches the
      floor -- the uniform lobe's z = u1 at u1 = 0, or a CLTC direction on the clipped
      boundary (the horizon), a few ulp below 0 -- so it moves a direction by rounding only.
    """

    @driver
    def drive(z_min, wo_rows, r_rows, u_rows, wi_rows, pdf_rows):
        n = r_rows.shape[0]
        # indexed through their data pointers (``_jit.pointer_of``: cheaper to compile)
        wo, r, u = pointer_of(wo_rows), pointer_of(r_rows), pointer_of(u_rows)
        wi, pdf = pointer_of(wi_rows), pointer_of(pdf_rows)
        for i in range(n):
            j = _U(i) * _U(3)
            k = _U(i) * _U(2)
            ox = _F(wo[j])
            oy = _F(wo[j + _U(1)])
            oz = _F(wo[j + _U(2)])
            ri = _F(r[i])
            mu = min(max(oz, 0.0), 1.0)
            u1 = _F(u[k])
            u2 = _F(u[k + _U(1)])
            if strategy == UNIFORM:
                x, y, z, _ = uniform_sample(u1, u2)
            else:
                Xx, Xy = ltc_frame(ox, oy)
                if strategy == EON:
                    x, y, z, _ = eon_sample(Xx, Xy, mu, ri, pow_tenth(ri), u1, u2)
                else:
                    if strategy == COSINE:
                        lx, ly, z, _ = cosine_sample_local(u1, u2)
                    else:
                        a, b, c, d = ltc_coeffs(mu, ri)
                        if strategy == LTC_NONNEG:
                            d = 0.0
                        s = clip_fraction(d) if strategy == CLTC else 1.0
                        lx, ly, z, _ = ltc_sample_local(a, b, c, d, s, u1, u2)
                    x, y = from_frame(Xx, Xy, lx, ly)
            if strategy != LTC:
                z = max(z, z_min)
            wi[j] = x
            wi[j + _U(1)] = y
            wi[j + _U(2)] = z
            pdf[i] = strategy_pdf(strategy, ox, oy, oz, _F(wi[j]), _F(wi[j + _U(1)]), _F(wi[j + _U(2)]), ri)

    return drive


@functools.cache
def pdf_driver(strategy):
    """``drive(wo, wi, r, out)``: out (n,) = ``strategy_pdf`` of wi given wo."""

    @driver
    def drive(wo_rows, wi_rows, r_rows, out_rows):
        n = r_rows.shape[0]
        wo, wi, r, out = pointer_of(wo_rows), pointer_of(wi_rows), pointer_of(r_rows), pointer_of(out_rows)
        for i in range(n):
            j = _U(i) * _U(3)
            out[i] = strategy_pdf(
                strategy,
                _F(wo[j]),
                _F(wo[j + _U(1)]),
                _F(wo[j + _U(2)]),
                _F(wi[j]),
                _F(wi[j + _U(1)]),
                _F(wi[j + _U(2)]),
                _F(r[i]),
            )

    return drive


def sample_rows(strategy, wo, r, u, lead, dtype):
    """(wi, pdf) for validated arrays broadcasting to ``lead``, shapes lead + (3,) and lead."""
    n = math.prod(lead)
    wi = np.empty(lead + (3,), dtype=dtype)
    p = np.empty(lead, dtype=dtype)
    wo, two = rows(wo, lead, 3)
    r, tr = rows(r, lead)
    u, tu = rows(u, lead, 2)
    z_min = float(np.finfo(dtype).tiny)
    launch(
        sample_driver(strategy),
        (z_min,),
        [(wo, 3, two), (r, 1, tr), (u, 2, tu)],
        [(wi.reshape(-1), 3), (p.reshape(-1), 1)],
        n,
    )
    return wi, p


def pdf_rows(strategy, wo, wi, r, lead, dtype):
    """pdf for validated arrays broadcasting to ``lead``, shape lead."""
    n = math.prod(lead)
    out = np.empty(lead, dtype=dtype)
    wo, two = rows(wo, lead, 3)
    wi, twi = rows(wi, lead, 3)
    r, tr = rows(r, lead)
    launch(pdf_driver(strategy), (), [(wo, 3, two), (wi, 3, twi), (r, 1, tr)], [(out.reshape(-1), 1)], n)
    return out
