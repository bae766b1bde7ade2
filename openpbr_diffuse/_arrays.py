"""Input checking and broadcasting: the one place where public arguments are validated.

Conventions (``spec/api.md``): directions are (..., 3) unit vectors in the local frame
(normal +z); ``rho`` is (..., C) with the channel axis last (a scalar is grey, C = 1);
``roughness`` broadcasts with the leading axes.  float32 in gives float32 out, float64 gives
float64, mixed gives float64; Python scalars and lists do not promote.

Every error is a ``ValueError`` (or ``TypeError`` for wrong types) whose message names the
argument and the allowed range.
"""
import numbers

import numba
import numpy as np
from numba import prange

#: |w.w - 1| allowed for a "unit" direction.  Loose enough for float32-normalised input,
#: tight enough to catch vectors that were never normalised.
UNIT_TOL = 1e-4


def result_dtype(*values):
    """float64 unless every floating ndarray among ``values`` is float32 (or smaller)."""
    kinds = [v.dtype for v in values if isinstance(v, (np.ndarray, np.generic)) and v.dtype.kind == "f"]
    if kinds and all(d.itemsize <= 4 for d in kinds):
        return np.dtype(np.float32)
    return np.dtype(np.float64)


def as_float(name, value, dtype):
    """``value`` as an ndarray of ``dtype``; TypeError naming ``name`` if it is not numeric."""
    if isinstance(value, np.ndarray):
        arr = value
    elif isinstance(value, (numbers.Real, list, tuple)) and not isinstance(value, bool):
        try:
            arr = np.asarray(value)
        except ValueError as exc:  # ragged lists
            raise ValueError(f"{name}: {exc}") from None
    else:
        raise TypeError(f"{name} must be a real number or an array of them, got {type(value).__name__}")
    if arr.dtype.kind not in "fiu" or arr.dtype == np.bool_:
        raise TypeError(f"{name} must hold real numbers, got dtype {arr.dtype}")
    return np.asarray(arr, dtype=dtype)


@numba.njit(cache=True, parallel=True)
def _count_not_unit(w, tol):
    bad = 0
    for i in prange(w.shape[0]):
        n2 = w[i, 0] * w[i, 0] + w[i, 1] * w[i, 1] + w[i, 2] * w[i, 2]
        if not abs(n2 - 1.0) <= tol:  # NaN compares false: counted
            bad += 1
    return bad


def directions(name, value, dtype):
    """A (..., 3) array of finite unit vectors."""
    w = as_float(name, value, dtype)
    if w.ndim == 0 or w.shape[-1] != 3:
        raise ValueError(f"{name} must have shape (..., 3) (unit direction vectors), got shape {w.shape}")
    flat = w.reshape(-1, 3)
    if flat.shape[0] and _count_not_unit(flat, UNIT_TOL):
        n2 = np.einsum("ij,ij->i", flat, flat, dtype=np.float64)
        i = int(np.flatnonzero(~(np.abs(n2 - 1.0) <= UNIT_TOL))[0])
        idx = np.unravel_index(i, w.shape[:-1])
        what = "is not finite" if not np.isfinite(flat[i]).all() else f"has length {np.sqrt(n2[i]):.6g}"
        raise ValueError(f"{name}{list(idx)} = {flat[i].tolist()} {what}; "
                         f"directions must be finite unit vectors (|w| = 1 within {UNIT_TOL:g})")
    return w


def in_range(name, value, dtype, lo, hi, what="", lo_open=False, hi_open=False):
    """An array of finite values in [lo, hi] (open ends on request)."""
    a = as_float(name, value, dtype)
    if a.size:
        if not np.isfinite(a).all():
            raise ValueError(f"{name} must be finite{what}; got {a[~np.isfinite(a)].ravel()[0]}")
        amin, amax = a.min(), a.max()
        bad_lo = amin <= lo if lo_open else amin < lo
        bad_hi = amax >= hi if hi_open else amax > hi
        if bad_lo or bad_hi:
            lb, hb = "(" if lo_open else "[", ")" if hi_open else "]"
            val = amin if bad_lo else amax
            raise ValueError(f"{name} must lie in {lb}{lo:g}, {hi:g}{hb}{what}; got {float(val):g}")
    return a


def rho_array(name, value, dtype):
    """Colour / albedo with the channel axis last, values in [0, 1]; a scalar is grey (C = 1)."""
    a = in_range(name, value, dtype, 0.0, 1.0, " (albedo per channel)")
    if a.ndim == 0:
        a = a.reshape(1)
    if a.shape[-1] == 0:
        raise ValueError(f"{name} needs at least one channel, got shape {a.shape}")
    return a


def broadcast_leading(**shapes):
    """Broadcast the leading shapes of named arguments; ValueError naming them on failure."""
    try:
        return np.broadcast_shapes(*shapes.values())
    except ValueError:
        listed = ", ".join(f"{k} {v}" for k, v in shapes.items())
        raise ValueError(f"leading shapes do not broadcast: {listed} "
                         "(directions (..., 3), rho (..., C), roughness (...))") from None


def flat(a, lead, k=None):
    """View ``a`` broadcast to ``lead`` (+ its trailing axis of length k) as 1-D/2-D rows.

    Broadcasting gives zero strides, which reshape keeps whenever the broadcast axes are
    the outer ones; only genuinely outer-product inputs are copied.
    """
    if k is None:
        return np.broadcast_to(a, lead).reshape(-1)
    return np.broadcast_to(a, lead + (k,)).reshape(-1, k)


def unit_samples(name, value, dtype):
    """Uniform random numbers u of shape (..., 2) in [0, 1)."""
    u = in_range(name, value, dtype, 0.0, 1.0, " (uniform random numbers)", hi_open=True)
    if u.ndim == 0 or u.shape[-1] != 2:
        raise ValueError(f"{name} must have shape (..., 2), got shape {u.shape}")
    return u
