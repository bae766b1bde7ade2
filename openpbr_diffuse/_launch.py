"""Batch launch machinery shared by every compiled verb (models and sampling).

A driver is a ``prange`` loop over flat, C-contiguous buffers; ``rows`` turns an argument
broadcasting to the leading shape into such a buffer without copying what does not need
it, and ``launch`` runs a driver over all rows, in chunks when an input is the same for
every row (a tiled buffer), so no input is ever expanded to full size.
"""
import numba
import numpy as np

from ._jit import FASTMATH

#: Batch drivers: parallel, cached; numpy's error model (x/0 gives inf, not an exception)
#: so that rows below the horizon can be computed and then discarded without a branch.
compiled = numba.njit(parallel=True, cache=True, fastmath=FASTMATH, error_model="numpy")

_U = numba.uint64   # unsigned row offsets: lets LLVM prove the accesses are affine
_F = numba.float64
#: Rows per driver call when an input is tiled (bounds the tiled buffers to ~3 MB, and to
#: the output's size when that is larger than MIN_CHUNK rows' worth).
CHUNK = 1 << 16
MIN_CHUNK = 1 << 12


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


def launch(drive, head, inputs, outputs, n):
    """Run ``drive(*head, *input buffers, *output buffers)`` over n rows.

    ``inputs`` = [(buffer, k, tiled)] from ``rows``; ``outputs`` = [(flat buffer, k)].
    Tiled inputs are repeated to at most CHUNK rows and the driver is called per chunk.
    Returns the sum of what the driver calls return (the count of rows that failed the
    input checks, for drivers that check; None counts as 0).
    """
    if n == 0:
        return 0
    if n == 1 or not any(t for _, _, t in inputs):  # every buffer already holds n rows
        return drive(*head, *(b for b, _, _ in inputs), *(o for o, _ in outputs)) or 0
    # rows per call: tiled buffers stay below the output's size (and below CHUNK rows)
    out_width = sum(k for _, k in outputs)
    B = min(n, CHUNK, max(MIN_CHUNK, n * out_width // sum(k for _, k, t in inputs if t)))
    reps = []
    for b, k, t in inputs:
        if t:
            b = np.tile(b, B)
            b.flags.writeable = False
        reps.append(b)
    bad = 0
    for s in range(0, n, B):
        e = min(n, s + B)
        args = [b[:(e - s) * k] if t else b[s * k:e * k] for b, (_, k, t) in zip(reps, inputs)]
        bad += drive(*head, *args, *(o[s * k:e * k] for o, k in outputs)) or 0
    return bad
