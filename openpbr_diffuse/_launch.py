"""Batch launch machinery shared by every compiled verb (models and sampling).

A driver is a ``prange`` loop over flat, C-contiguous buffers; ``rows`` turns an argument
broadcasting to the leading shape into such a buffer without copying what does not need
it, and ``launch`` runs a driver over all rows, in blocks when an input is the same for
every row (a tiled buffer) or broadcasts along some axes (gathered one block at a time),
so no input is ever expanded to full size: the extra memory of a call is a few blocks of
CHUNK rows (~3 MB) beyond its output, whatever the broadcast shapes.
"""
import numba
import numpy as np

from ._jit import FASTMATH

#: Batch drivers: parallel, cached; numpy's error model (x/0 gives inf, not an exception)
#: so that rows below the horizon can be computed and then discarded without a branch.
compiled = numba.njit(parallel=True, cache=True, fastmath=FASTMATH, error_model="numpy")

_U = numba.uint64   # unsigned row offsets: lets LLVM prove the accesses are affine
_F = numba.float64
#: Rows per driver call when an input is tiled or broadcast (bounds the per-call buffers to
#: ~3 MB, and to the output's size when that is larger than MIN_CHUNK rows' worth).
CHUNK = 1 << 16
MIN_CHUNK = 1 << 12

#: How ``rows`` hands an input to ``launch``: every row already in a flat C-contiguous
#: buffer (FULL), one row for all (TILED), or a zero-stride broadcast view of shape
#: lead + (k,) whose rows are gathered chunk by chunk (BROADCAST).
FULL, TILED, BROADCAST = 0, 1, 2


def rows(a, lead, k=None):
    """``a`` (leading shape broadcasting to ``lead``; trailing axis of length k, if any) for ``launch``.

    Returns ``(buffer, mode)``: the C-contiguous (n*k,) data when ``a`` already has every
    row (FULL, no copy); its single row (TILED) when all rows are equal; otherwise the
    broadcast view itself, shape lead + (k,) (BROADCAST), never expanded: ``launch`` copies
    one chunk of its rows at a time.  Buffers are read-only so that each driver has one
    signature per dtype whatever the caller's flags.
    """
    full, width = (lead, 1) if k is None else (lead + (k,), k)
    if a.size == width:
        buf, mode = np.ascontiguousarray(a).reshape(-1), TILED
    elif a.size == int(np.prod(full)) and a.flags.c_contiguous:  # same size: nothing to broadcast
        buf, mode = a.reshape(-1), FULL
    else:
        buf, mode = np.broadcast_to(a.reshape(a.shape + (1,)) if k is None else a, lead + (width,)), BROADCAST
    buf = buf.view()
    buf.flags.writeable = False
    return buf, mode


def row_blocks(lead, size):
    """Split the rows of ``lead`` (C order) into blocks of at most ``size`` rows.

    Yields ``(start, stop, index)``: flat row range and the basic index (ints and one
    slice) that selects exactly those rows of an array of shape ``lead`` (+ trailing axes),
    so that a broadcast view can be gathered block by block.  Blocks are slices of the
    outermost axis whose inner rows fit, iterated over the axes outside it.
    """
    lead = tuple(int(d) for d in lead)
    if not lead:
        yield 0, 1, ()
        return
    inner = 1
    p = len(lead) - 1
    while p > 0 and inner * lead[p] <= size:  # axes p.. fit in one block
        inner *= lead[p]
        p -= 1
    step = max(1, size // inner)
    start = 0
    for outer in np.ndindex(*lead[:p]):
        for a in range(0, lead[p], step):
            b = min(lead[p], a + step)
            yield start, start + (b - a) * inner, outer + (slice(a, b),)
            start += (b - a) * inner


def gather(view, index):
    """Rows ``index`` (from ``row_blocks``) of a broadcast view, as a flat C-contiguous copy."""
    block = np.ascontiguousarray(view[index]).reshape(-1)
    block.flags.writeable = False
    return block


def launch(drive, head, inputs, outputs, n):
    """Run ``drive(*head, *input buffers, *output buffers)`` over n rows.

    ``inputs`` = [(buffer, k, mode)] from ``rows``; ``outputs`` = [(flat buffer, k)].
    With only FULL inputs the driver runs once over all rows.  Otherwise it runs per block
    of at most CHUNK rows: TILED inputs are repeated to one block's rows, BROADCAST ones are
    gathered block by block (``row_blocks``), so the extra memory is a few blocks of input
    whatever the broadcast shape.  Returns the sum of what the driver calls return (the count
    of rows that failed the input checks, for drivers that check; None counts as 0).
    """
    if n == 0:
        return 0
    if n == 1 or all(m == FULL for _, _, m in inputs):  # every buffer already holds n rows
        return drive(*head, *(b for b, _, _ in inputs), *(o for o, _ in outputs)) or 0
    # rows per call: per-call buffers stay below the output's size (and below CHUNK rows)
    out_width = sum(k for _, k in outputs)
    B = min(n, CHUNK, max(MIN_CHUNK, n * out_width // sum(k for _, k, m in inputs if m != FULL)))
    reps = []
    lead = None
    for b, k, m in inputs:
        if m == TILED:
            b = np.tile(b, B)
            b.flags.writeable = False
        elif m == BROADCAST:
            lead = b.shape[:-1]
        reps.append(b)
    blocks = row_blocks(lead, B) if lead is not None else ((s, min(n, s + B), None) for s in range(0, n, B))
    bad = 0
    for s, e, index in blocks:
        args = [b[:(e - s) * k] if m == TILED else gather(b, index) if m == BROADCAST else b[s * k:e * k]
                for b, (_, k, m) in zip(reps, inputs)]
        bad += drive(*head, *args, *(o[s * k:e * k] for o, k in outputs)) or 0
    return bad
