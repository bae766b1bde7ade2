"""Batch launch machinery shared by every compiled verb (models, sampling, the surface).

One launch model: a driver is a serial ``nogil`` loop over flat, C-contiguous buffers, and a
call of at least ``SPLIT_ROWS`` rows is cut into contiguous runs of rows that the one thread
pool of the package (``executor``, sized to numba's configured thread count) runs at once.
No driver is compiled with ``parallel=True``: numba's ``prange`` lowering compiles every
loop body twice (a serial and a parallel version), which doubled the cold start, and a
serial ``nogil`` body serves both the small call on the calling thread and the large one on
the pool.  ``rows`` turns an argument
broadcasting to the leading shape into such a buffer without copying what does not need
it, and ``launch`` runs a driver over all rows, in blocks when an input is the same for
every row (a tiled buffer) or broadcasts along some axes (gathered one block at a time),
so no input is ever expanded to full size: the extra memory of a call is a few blocks of
CHUNK rows (~3 MB) beyond its output, whatever the broadcast shapes.
"""

from __future__ import annotations

import concurrent.futures
import itertools
import math
import os
import threading
from collections.abc import Callable, Iterable, Iterator, Sequence
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

#: Below this many rows a surface call runs on the calling thread alone: handing runs to the
#: pool costs tens of microseconds, more than a small batch (the surface's rows cost 30-80 ns).
SERIAL_ROWS = 4096
#: The same for ``launch``'s drivers, whose rows cost a few ns: below this many rows the
#: pool's hand-off costs more than the second thread saves.
SPLIT_ROWS = 1 << 15

_PREFIX = "openpbr-diffuse"
_pool_lock = threading.Lock()
_pool = None  # (pool, threads, pid)


def threads() -> int:
    """The number of threads a large call runs on: numba's configured thread count
    (``NUMBA_NUM_THREADS``, ``numba.set_num_threads``)."""
    return numba.get_num_threads()


def executor(count: int) -> concurrent.futures.ThreadPoolExecutor:
    """The package's one thread pool, of ``count`` workers; rebuilt when the count changes,
    and in a forked child (which inherits the pool object but not its threads)."""
    global _pool
    with _pool_lock:
        if _pool is None or _pool[1] != count or _pool[2] != os.getpid():
            if _pool is not None and _pool[2] == os.getpid():
                _pool[0].shutdown(wait=False)
            _pool = (concurrent.futures.ThreadPoolExecutor(count, thread_name_prefix=_PREFIX), count, os.getpid())
        return _pool[0]


def _call(drive, head, args, widths, n, split=True):
    """``drive(*head, *args)`` over n rows, each of ``args`` holding ``widths[i]`` values a row:
    on the calling thread for a small call, else cut into one contiguous run of rows per
    thread, run on the pool.  Returns the sum of what the runs return (None counts as 0)."""
    count = threads()
    # a run already on the pool runs its rows itself (waiting on the pool from the pool deadlocks)
    if not split or n < SPLIT_ROWS or count == 1 or threading.current_thread().name.startswith(_PREFIX):
        return drive(*head, *args) or 0
    cuts = [n * t // count for t in range(count + 1)]
    pool = executor(count)
    runs = list(itertools.pairwise(cuts))
    jobs = [pool.submit(drive, *head, *(a[s * k : e * k] for a, k in zip(args, widths))) for s, e in runs[1:]]
    s, e = runs[0]  # the calling thread takes the first run (one hand-off fewer)
    bad = drive(*head, *(a[s * k : e * k] for a, k in zip(args, widths))) or 0
    return bad + sum(job.result() or 0 for job in jobs)


_U = numba.uint64  # unsigned row offsets: lets LLVM prove the accesses are affine
_F = numba.float64
#: Rows per driver call when an input is tiled or broadcast (bounds the per-call buffers to
#: ~3 MB, and to the output's size when that is larger than MIN_CHUNK rows' worth).
CHUNK = 1 << 16
MIN_CHUNK = 1 << 12

#: How ``rows`` hands an input to ``launch``: every row already in a flat C-contiguous
#: buffer (FULL), one row for all (TILED), or a zero-stride broadcast view of shape
#: lead + (k,) whose rows are gathered chunk by chunk (BROADCAST).
FULL, TILED, BROADCAST = 0, 1, 2


def rows(a: NDArray[Any], lead: tuple[int, ...], k: int | None = None) -> tuple[NDArray[Any], int]:
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
    elif a.size == math.prod(full) and a.flags.c_contiguous:  # same size: nothing to broadcast
        buf, mode = a.reshape(-1), FULL
    else:
        buf, mode = np.broadcast_to(a.reshape(a.shape + (1,)) if k is None else a, lead + (width,)), BROADCAST
    buf = buf.view()
    buf.flags.writeable = False
    return buf, mode


def row_blocks(lead: Sequence[int], size: int) -> Iterator[tuple[int, int, tuple[int | slice, ...]]]:
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


def gather(view: NDArray[Any], index: tuple[int | slice, ...]) -> NDArray[Any]:
    """Rows ``index`` (from ``row_blocks``) of a broadcast view, as a flat C-contiguous copy."""
    block = np.ascontiguousarray(view[index]).reshape(-1)
    block.flags.writeable = False
    return block


def launch(
    drive: Callable[..., int | None],
    head: tuple[Any, ...],
    inputs: list[tuple[NDArray[Any], int, int]],
    outputs: list[tuple[NDArray[Any], int]],
    n: int,
    split: bool = True,
) -> int:
    """Run ``drive(*head, *input buffers, *output buffers)`` over n rows.

    ``inputs`` = [(buffer, k, mode)] from ``rows``; ``outputs`` = [(flat buffer, k)].
    With only FULL inputs the driver runs once over all rows.  Otherwise it runs per block
    of at most CHUNK rows: TILED inputs are repeated to one block's rows, BROADCAST ones are
    gathered block by block (``row_blocks``), so the extra memory is a few blocks of input
    whatever the broadcast shape.  A call (or block) of at least ``SPLIT_ROWS`` rows is cut
    into a run of rows per thread on the pool, unless ``split`` is false (a ``drive`` that
    runs its rows on the pool itself: the surface's block runners).  Returns the sum of what the driver calls return (the count
    of rows that failed the input checks, for drivers that check; None counts as 0).
    """
    if n == 0:
        return 0
    widths = [k for _, k, _ in inputs] + [k for _, k in outputs]
    if n == 1 or all(m == FULL for _, _, m in inputs):  # every buffer already holds n rows
        return _call(drive, head, [b for b, _, _ in inputs] + [o for o, _ in outputs], widths, n, split)
    # rows per call: per-call buffers stay below the output's size (and below CHUNK rows)
    out_width = sum(k for _, k in outputs)
    B = min(n, CHUNK, max(MIN_CHUNK, n * out_width // sum(k for _, k, m in inputs if m != FULL)))
    reps = []
    lead = None
    for b, _k, m in inputs:
        if m == TILED:
            b = np.tile(b, B)
            b.flags.writeable = False
        elif m == BROADCAST:
            lead = b.shape[:-1]
        reps.append(b)
    blocks: Iterable[tuple[int, int, Any]] = (
        row_blocks(lead, B) if lead is not None else ((s, min(n, s + B), None) for s in range(0, n, B))
    )
    bad = 0
    for s, e, index in blocks:
        args = [
            b[: (e - s) * k] if m == TILED else gather(b, index) if m == BROADCAST else b[s * k : e * k]
            for b, (_, k, m) in zip(reps, inputs)
        ]
        bad += _call(drive, head, args + [o[s * k : e * k] for o, k in outputs], widths, e - s, split)
    return bad
