"""Input checking and broadcasting: the one place where public arguments are validated.

Conventions (``spec/api.md``): directions are (..., 3) unit vectors in the local frame
(normal +z); ``rho`` is (..., C) with the channel axis last (a scalar is grey, C = 1);
``roughness`` broadcasts with the leading axes.  float32 in gives float32 out, float64 gives
float64, mixed gives float64; Python scalars and lists do not promote.

Every error is a ``ValueError`` (or ``TypeError`` for wrong types) whose message names the
argument and the allowed range.
"""
import numbers
import os

# The parallel kernels run on numba's OpenMP layer (GNU libgomp).  Its idle workers spin
# for ~300k iterations between parallel regions; on a machine with other busy processes
# the spinning workers take the cores the working ones need, and a 10^6-row call measured
# 3-8x slower than with sleeping workers (and up to 100x for 10^5 rows), while on an idle
# machine sleeping costs ~10%.  Set only when the user has not chosen, and only effective
# when libgomp has not started yet (it reads the variable once).
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

import numba  # noqa: E402
import numpy as np  # noqa: E402
from numba import prange  # noqa: E402

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


#: Below this many values the checks run in NumPy: a parallel kernel's start-up (~10 us)
#: would dominate.  Above it, one fused parallel pass replaces NumPy's several passes and
#: temporaries (the checks read every input once; at 10^6 rows that is most of the cost
#: of a call after the kernel itself).
_PARALLEL_MIN = 1 << 14
_U = numba.uint64

# The per-value predicates, written once: the check passes below use them, and so do the
# batch kernels that fuse the checks into their own loop (``check=False`` below).
_predicate = numba.njit(cache=True, error_model="numpy", forceinline=True)


@_predicate
def is_unit(x, y, z):
    """|w|^2 within ``UNIT_TOL`` of 1, computed in float64; False for NaN or Inf."""
    x, y, z = 1.0 * x, 1.0 * y, 1.0 * z
    return abs(x * x + y * y + z * z - 1.0) <= UNIT_TOL  # NaN compares false


@_predicate
def is_within(x, lo, hi, lo_open, hi_open):
    """x finite and in [lo, hi] (open ends on request); compares in the type of x, lo, hi.

    Callers pass ``lo``, ``hi`` in the array's dtype, so that the comparisons are those of
    NumPy (a float32 array against a Python float compares in float32).
    """
    above = x > lo if lo_open else x >= lo
    below = x < hi if hi_open else x <= hi
    return (abs(x) < np.inf) & above & below  # NaN fails every comparison


@numba.njit(cache=True, parallel=True, error_model="numpy")
def _count_not_unit(w):
    """Number of rows of a flat C-contiguous (3n,) array that are not finite unit vectors."""
    bad = 0
    for i in prange(w.shape[0] // 3):
        j = _U(i) * _U(3)
        bad += 0 if is_unit(w[j], w[j + _U(1)], w[j + _U(2)]) else 1
    return bad


def _norms2(flat):
    return np.einsum("ij,ij->i", flat, flat, dtype=np.float64)


def directions(name, value, dtype, check=True):
    """A (..., 3) array of finite unit vectors.

    ``check=False`` checks type and shape only; the caller then owes the value check,
    either by calling again with ``check=True`` or with ``is_unit`` fused into its own
    loop (calling again to report when that fails).
    """
    w = as_float(name, value, dtype)
    if w.ndim == 0 or w.shape[-1] != 3:
        raise ValueError(f"{name} must have shape (..., 3) (unit direction vectors), got shape {w.shape}")
    if not check:
        return w
    if w.size >= _PARALLEL_MIN and w.flags.c_contiguous:
        ok = not _count_not_unit(w.reshape(-1))
    else:
        ok = bool((np.abs(_norms2(w.reshape(-1, 3)) - 1.0) <= UNIT_TOL).all())
    if not ok:
        flat = w.reshape(-1, 3)
        n2 = _norms2(flat)
        i = int(np.flatnonzero(~(np.abs(n2 - 1.0) <= UNIT_TOL))[0])
        idx = [int(j) for j in np.unravel_index(i, w.shape[:-1])]
        what = "is not finite" if not np.isfinite(flat[i]).all() else f"has length {np.sqrt(n2[i]):.6g}"
        raise ValueError(f"{name}{idx} = {flat[i].tolist()} {what}; "
                         f"directions must be finite unit vectors (|w| = 1 within {UNIT_TOL:g})")
    return w


@numba.njit(cache=True, parallel=True, error_model="numpy")
def _count_outside(a, lo, hi, lo_open, hi_open):
    """Number of values of a flat C-contiguous array that fail ``is_within``."""
    bad = 0
    for i in prange(a.shape[0]):
        bad += 0 if is_within(a[i], lo, hi, lo_open, hi_open) else 1
    return bad


def in_range(name, value, dtype, lo, hi, what="", lo_open=False, hi_open=False, check=True):
    """An array of finite values in [lo, hi] (open ends on request).

    ``check=False``: type only; the value check is owed as for ``directions`` (``is_within``).
    """
    a = as_float(name, value, dtype)
    if not check:
        return a
    if a.size >= _PARALLEL_MIN and a.flags.c_contiguous:
        t = a.dtype.type
        if not _count_outside(a.reshape(-1), t(lo), t(hi), lo_open, hi_open):
            return a
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


def model_roughness(info, roughness, dtype, check=True):
    """Roughness in a lobe model's domain: sigma in [0, max] radians or r in [0, max].

    ``info`` is the model's ``models.registry.ModelInfo`` (name, roughness_name, roughness_max).
    """
    unit = "radians (sigma)" if info.roughness_name == "sigma" else "(r, a weight)"
    return in_range("roughness", roughness, dtype, 0.0, info.roughness_max,
                    f" for model {info.name!r}, {unit}", check=check)


#: EON colour modes: "reference" (chromatic rho inside rho_ms) and "white_tint".
COLOR_MODES = ("reference", "white_tint")


def white_tint(color_mode):
    """True for ``color_mode="white_tint"``, False for "reference"; ValueError otherwise."""
    if color_mode not in COLOR_MODES:
        raise ValueError(f"color_mode must be one of {', '.join(COLOR_MODES)}; got {color_mode!r}")
    return color_mode == "white_tint"


def rho_array(name, value, dtype, check=True):
    """Colour / albedo with the channel axis last, values in [0, 1]; a scalar is grey (C = 1).

    ``check=False``: type and shape only (see ``in_range``).
    """
    a = in_range(name, value, dtype, 0.0, 1.0, " (albedo per channel)", check=check)
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
