"""Input checking and broadcasting: the one place where public arguments are validated.

Conventions (``spec/api.md``): directions are (..., 3) unit vectors in the local frame
(normal +z); ``rho`` is (..., C) with the channel axis last (a scalar is grey, C = 1);
``roughness`` broadcasts with the leading axes.  float32 in gives float32 out, float64 gives
float64, mixed gives float64; Python scalars and lists do not promote.

Every error is a ``ValueError`` (or ``TypeError`` for wrong types) whose message names the
argument and the allowed range.
"""

from __future__ import annotations

import math
import numbers
import os
from typing import Any, Protocol

# The parallel kernels run on numba's OpenMP layer (GNU libgomp).  Its idle workers spin
# for ~300k iterations between parallel regions; on a machine with other busy processes
# the spinning workers take the cores the working ones need, and a 10^6-row call measured
# 3-8x slower than with sleeping workers (and up to 100x for 10^5 rows), while on an idle
# machine sleeping costs ~10%.  Set only when the user has not chosen, and only effective
# when libgomp has not started yet (it reads the variable once).
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

import numba  # noqa: E402
import numpy as np  # noqa: E402
from numpy.typing import ArrayLike, DTypeLike, NDArray  # noqa: E402

from ._jit import driver, predicate  # noqa: E402
from ._launch import FULL, launch  # noqa: E402


class _RoughnessDomain(Protocol):
    """What :func:`model_roughness` reads of a model (``models.registry.ModelInfo`` has it)."""

    @property
    def name(self) -> str: ...
    @property
    def roughness_name(self) -> str: ...
    @property
    def roughness_max(self) -> float: ...


#: ||w| - 1| allowed for a "unit" direction.  Loose enough for float32-normalised input,
#: tight enough to catch vectors that were never normalised.  The kernels compare |w|^2
#: with the squared bounds (no square root per row); the test is the same as on |w|.
UNIT_TOL = 1e-4
_N2_LO = (1.0 - UNIT_TOL) ** 2
_N2_HI = (1.0 + UNIT_TOL) ** 2
#: float16 directions carry ~5e-4 rounding per component, more than UNIT_TOL: they are
#: checked against this tolerance instead and renormalised in the result dtype (float32).
UNIT_TOL_FLOAT16 = 2e-3


def show(value: float, dtype: DTypeLike | None = None) -> str:
    """A number as its shortest round-trip text in ``dtype`` (default float64).

    Messages print values at full precision, so that an out-of-range value never looks
    in range (1.0000001 is not "1", pi/2 is not "1.5708").
    """
    v = float(value)
    if v.is_integer() and abs(v) < 1e15:
        return str(int(v)) if v or not math.copysign(1.0, v) < 0 else "-0"
    if dtype is None or np.dtype(dtype).itemsize >= 8 or not np.isfinite(v):
        return repr(v)
    # shortest text that reads back to this float32/16; format_float_* ignore NumPy's print
    # options (colour-science sets legacy="1.13" on import, under which str() gives "1.0")
    dt: np.dtype[Any] = np.dtype(dtype)
    x = dt.type(v)
    if 1e-4 <= abs(v) < 1e16:
        return np.format_float_positional(x, unique=True, trim="-")
    return np.format_float_scientific(x, unique=True, trim="-")


def result_dtype(*values: object) -> np.dtype[Any]:
    """float64 unless every floating ndarray among ``values`` is float32 (or smaller)."""
    kinds = [v.dtype for v in values if isinstance(v, (np.ndarray, np.generic)) and v.dtype.kind == "f"]
    if kinds and all(d.itemsize <= 4 for d in kinds):
        return np.dtype(np.float32)
    return np.dtype(np.float64)


def as_float(name: str, value: ArrayLike, dtype: DTypeLike) -> NDArray[Any]:
    """``value`` as an ndarray of ``dtype``; TypeError naming ``name`` if it is not numeric.

    Masked arrays: a mask with masked entries is refused (ValueError) rather than dropped
    silently -- the library cannot know what a masked direction or colour should give;
    an array whose mask is empty is used as its data.
    """
    if isinstance(value, np.ma.MaskedArray):
        if np.ma.is_masked(value):
            raise ValueError(
                f"{name} is a masked array with {int(np.ma.count_masked(value))} masked "
                f"value(s); masks are not supported: fill them ({name}.filled(v)) "
                "or keep only the unmasked rows"
            )
        value = np.ma.getdata(value)
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


@predicate
def is_unit(x: float, y: float, z: float) -> bool:
    """|w| within ``UNIT_TOL`` of 1 (as |w|^2 in [(1 - tol)^2, (1 + tol)^2], float64);
    False for NaN or Inf."""
    x, y, z = 1.0 * x, 1.0 * y, 1.0 * z
    n2 = x * x + y * y + z * z
    return (n2 >= _N2_LO) & (n2 <= _N2_HI)  # NaN compares false


@predicate
def is_within(x: float, lo: float, hi: float, lo_open: bool, hi_open: bool) -> bool:
    """x finite and in [lo, hi] (open ends on request); compares in the type of x, lo, hi.

    Callers pass ``lo``, ``hi`` in the array's dtype, so that the comparisons are those of
    NumPy (a float32 array against a Python float compares in float32).
    """
    above = x > lo if lo_open else x >= lo
    below = x < hi if hi_open else x <= hi
    return (abs(x) < np.inf) & above & below  # NaN fails every comparison


@driver
def _not_unit_rows(w):
    bad = 0
    for i in range(w.shape[0] // 3):
        j = _U(i) * _U(3)
        bad += 0 if is_unit(w[j], w[j + _U(1)], w[j + _U(2)]) else 1
    return bad


def _count_not_unit(w):
    """Number of rows of a flat C-contiguous (3n,) array that are not finite unit vectors
    (a serial ``nogil`` loop, run on the thread pool as the drivers are: ``_launch.launch``)."""
    return launch(_not_unit_rows, (), [(_read_only(w), 3, FULL)], [], w.shape[0] // 3)


def _norms2(flat):
    return np.einsum("ij,ij->i", flat, flat, dtype=np.float64)


def _first_not_unit(name, w, tol, shown_dtype):
    """ValueError naming the first row of ``w`` whose length is not within ``tol`` of 1."""
    flat = w.reshape(-1, 3)
    n = np.sqrt(_norms2(flat))
    i = int(np.flatnonzero(~(np.abs(n - 1.0) <= tol))[0])
    where = "".join(f"[{int(j)}]" for j in np.unravel_index(i, w.shape[:-1])) if w.ndim > 1 else ""
    what = "is not finite" if not np.isfinite(flat[i]).all() else f"has length {show(n[i], shown_dtype)}"
    vec = ", ".join(show(c, shown_dtype) for c in flat[i])
    dt = f" ({np.dtype(shown_dtype).name} input)" if np.dtype(shown_dtype).itemsize < 8 else ""
    return ValueError(
        f"{name}{where} = [{vec}] {what}; directions must be finite unit vectors (|w| = 1 within {tol:g}{dt})"
    )


def directions(name: str, value: ArrayLike, dtype: DTypeLike, check: bool = True) -> NDArray[Any]:
    """A (..., 3) array of finite unit vectors.

    ``check=False`` checks type and shape only; the caller then owes the value check,
    either by calling again with ``check=True`` or with ``is_unit`` fused into its own
    loop (calling again to report when that fails).  float16 input is always checked
    here, against ``UNIT_TOL_FLOAT16`` (its own precision), and renormalised in ``dtype``.
    """
    src = value.dtype if isinstance(value, np.ndarray) else None
    w = as_float(name, value, dtype)
    if w.ndim == 0 or w.shape[-1] != 3:
        raise ValueError(f"{name} must have shape (..., 3) (unit direction vectors), got shape {w.shape}")
    if src == np.float16 and w.size:
        n = np.sqrt(_norms2(w.reshape(-1, 3))).reshape(w.shape[:-1] + (1,))
        if not (np.abs(n - 1.0) <= UNIT_TOL_FLOAT16).all():
            raise _first_not_unit(name, w, UNIT_TOL_FLOAT16, np.float16)
        return (w / n).astype(dtype)
    if not check:
        return w
    if w.size >= _PARALLEL_MIN and w.flags.c_contiguous:
        ok = not _count_not_unit(w.reshape(-1))
    else:
        n2 = _norms2(w.reshape(-1, 3))
        ok = bool(((n2 >= _N2_LO) & (n2 <= _N2_HI)).all())
    if not ok:
        raise _first_not_unit(name, w, UNIT_TOL, w.dtype)
    return w


@driver
def _outside_values(lo, hi, lo_open, hi_open, a):
    bad = 0
    for i in range(a.shape[0]):
        bad += 0 if is_within(a[i], lo, hi, lo_open, hi_open) else 1
    return bad


def _count_outside(a, lo, hi, lo_open, hi_open):
    """Number of values of a flat C-contiguous array that fail ``is_within`` (as ``_count_not_unit``)."""
    return launch(_outside_values, (lo, hi, bool(lo_open), bool(hi_open)), [(_read_only(a), 1, FULL)], [], a.shape[0])


def _read_only(a):
    """A read-only view: one compiled signature per dtype, whatever the caller's flags."""
    v = a.view()
    v.flags.writeable = False
    return v


def in_range(
    name: str,
    value: ArrayLike,
    dtype: DTypeLike,
    lo: float,
    hi: float,
    what: str = "",
    lo_open: bool = False,
    hi_open: bool = False,
    check: bool = True,
) -> NDArray[Any]:
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
        t = a.dtype.type
        finite = np.isfinite(a)
        above = a > t(lo) if lo_open else a >= t(lo)
        below = a < t(hi) if hi_open else a <= t(hi)
        bad = ~(finite & above & below)
        if bad.any():
            i = int(np.flatnonzero(bad.reshape(-1))[0])
            where = " at " + name + "".join(f"[{int(j)}]" for j in np.unravel_index(i, a.shape)) if a.ndim else ""
            val = a.reshape(-1)[i]
            if not finite.reshape(-1)[i]:
                raise ValueError(f"{name} must be finite{what}; got {show(val)}{where}")
            lb, hb = "(" if lo_open else "[", ")" if hi_open else "]"
            raise ValueError(
                f"{name} must lie in {lb}{show(lo)}, {show(hi)}{hb}{what}; got {show(val, a.dtype)}{where}"
            )
    return a


def model_roughness(info: _RoughnessDomain, roughness: ArrayLike, dtype: DTypeLike, check: bool = True) -> NDArray[Any]:
    """Roughness in a lobe model's domain: sigma in [0, max] radians or r in [0, max].

    ``info`` is the model's ``models.registry.ModelInfo`` (name, roughness_name, roughness_max).
    """
    unit = "radians (sigma)" if info.roughness_name == "sigma" else "(r, a weight)"
    return in_range(
        "roughness", roughness, dtype, 0.0, info.roughness_max, f" for model {info.name!r}, {unit}", check=check
    )


#: EON colour modes: "reference" (chromatic rho inside rho_ms) and "white_tint".
COLOR_MODES = ("reference", "white_tint")


def white_tint(color_mode: str) -> bool:
    """True for ``color_mode="white_tint"``, False for "reference"; ValueError otherwise."""
    if color_mode not in COLOR_MODES:
        raise ValueError(f"color_mode must be one of {', '.join(COLOR_MODES)}; got {color_mode!r}")
    return color_mode == "white_tint"


def rho_array(name: str, value: ArrayLike, dtype: DTypeLike, check: bool = True) -> NDArray[Any]:
    """Colour / albedo with the channel axis last, values in [0, 1]; a scalar is grey (C = 1).

    ``check=False``: type and shape only (see ``in_range``).
    """
    a = in_range(name, value, dtype, 0.0, 1.0, " (albedo per channel)", check=check)
    if a.ndim == 0:
        a = a.reshape(1)
    if a.shape[-1] == 0:
        raise ValueError(f"{name} needs at least one channel, got shape {a.shape}")
    return a


def broadcast_leading(**shapes: tuple[int, ...]) -> tuple[int, ...]:
    """Broadcast the leading shapes of named arguments; ValueError naming them on failure."""
    try:
        return np.broadcast_shapes(*shapes.values())
    except ValueError:
        listed = ", ".join(f"{k} {v}" for k, v in shapes.items())
        raise ValueError(
            f"leading shapes do not broadcast: {listed} (directions (..., 3), rho (..., C), roughness (...))"
        ) from None


def unit_samples(name: str, value: ArrayLike, dtype: DTypeLike) -> NDArray[Any]:
    """Uniform random numbers u of shape (..., 2) in [0, 1)."""
    u = in_range(name, value, dtype, 0.0, 1.0, " (uniform random numbers)", hi_open=True)
    if u.ndim == 0 or u.shape[-1] != 2:
        raise ValueError(f"{name} must have shape (..., 2), got shape {u.shape}")
    return u
