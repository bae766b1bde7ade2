"""The run options every ``simulate_*`` function takes, checked in one place, and the run
skeleton they share: chunks, their seeds, the runner of the chunk tasks (local threads or a
Dask cluster) and the sums of the chunks' results.

``paths``, ``seed``, ``workers``, ``client``, ``scheduler`` and ``progress`` mean the same in
the microsurface simulator (``api``) and the layered one (``layered``): :meth:`RunOptions.check`
validates them (TypeError / ValueError naming the argument) and :func:`execute` runs a list of
chunk tasks with them, results in task order.  :func:`run_chunks` cuts each query's paths into
chunks of ``CHUNK_PATHS`` and executes them; :func:`chunk_seed` is the seed of one chunk;
:func:`chunk_sum` and :func:`mean_err` turn a query's chunk sums into an estimate.

Example
-------
>>> o = RunOptions.check(paths=1e6, seed=0, workers=2)
>>> o.paths, o.seed, o.workers
(1000000, 0, 2)
>>> execute(lambda t: t * t, [1, 2, 3], o)
[1, 4, 9]
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: paths per chunk (the unit of work and of reproducibility)
CHUNK_PATHS = 1 << 15


def check_count(name: str, value: Any, minimum: int) -> int:
    """``value`` as an int >= ``minimum`` (a float with an integer value is accepted:
    ``paths=1e6``); TypeError / ValueError naming ``name`` otherwise.

    >>> check_count("paths", 1e3, 1)
    1000
    >>> check_count("seed", -1, 0)
    Traceback (most recent call last):
    ...
    ValueError: seed must be an integer >= 0, got -1
    """
    if isinstance(value, (float, np.floating)) and math.isfinite(value) and float(value).is_integer():
        value = int(value)
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name} must be an integer >= {minimum}, got {value!r}")
    if value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value}")
    return int(value)


@dataclass(frozen=True)
class RunOptions:
    """How a simulation runs: ``paths`` per query, ``seed``, local ``workers`` (threads), a
    Dask ``client`` or ``scheduler`` address (the chunks then run on the cluster, with the
    same results), and a ``progress`` bar on stderr (local runs)."""

    paths: int
    seed: int
    workers: int
    client: Any = None
    scheduler: str | None = None
    progress: bool = False

    @classmethod
    def check(
        cls,
        paths: Any,
        seed: Any,
        workers: Any = None,
        client: Any = None,
        scheduler: str | None = None,
        progress: bool = False,
        *,
        min_paths: int = 1,
    ) -> RunOptions:
        """The options, checked: ``paths`` >= ``min_paths``, ``seed`` >= 0, ``workers`` >= 1
        (default: all cores), not both ``client`` and ``scheduler``.

        >>> RunOptions.check(10, 0, client=object(), scheduler="tcp://h:8786")
        Traceback (most recent call last):
        ...
        ValueError: give either client or scheduler, not both
        """
        if client is not None and scheduler is not None:
            raise ValueError("give either client or scheduler, not both")
        return cls(
            check_count("paths", paths, min_paths),
            check_count("seed", seed, 0),
            (os.cpu_count() or 1) if workers is None else check_count("workers", workers, 1),
            client,
            scheduler,
            bool(progress),
        )


def _bar(iterable, progress, total=None):
    """``iterable`` wrapped in a tqdm bar on stderr when ``progress`` (chunks done)."""
    if not progress:
        return iterable
    from tqdm.auto import tqdm

    return tqdm(iterable, total=total, desc="simulate", unit="chunk", leave=False)


def execute(run_task: Callable[[Any], Any], tasks: Sequence[Any], options: RunOptions) -> list:
    """``run_task`` over the chunk ``tasks`` (locally on ``options.workers`` threads, or on a
    Dask cluster: ``run_task`` must then be a module-level function), results in task order."""
    from ._dask import _client  # connects to a scheduler address (_dask.SCHEDULER_TIMEOUT_S)

    cl, own = _client(options.client, options.scheduler)
    if cl is not None:
        try:
            return cl.gather(cl.map(run_task, tasks, pure=False))
        finally:
            if own:
                cl.close()
    if options.workers == 1 or len(tasks) == 1:
        return [run_task(t) for t in _bar(tasks, options.progress)]
    with ThreadPoolExecutor(max_workers=options.workers) as pool:  # the kernels release the GIL
        return list(_bar(pool.map(run_task, tasks), options.progress, total=len(tasks)))


def chunk_seed(seed: int, kind: int, identity: Sequence[int], key: ArrayLike, chunk: int) -> int:
    """The seed of chunk ``chunk`` of a query, derived from (``seed``, the ``kind`` of query,
    the ``identity`` integers of the simulated surface, the bits of the query's own float64
    values ``key``, ``chunk``): a chunk draws the same numbers whatever else the call runs.

    >>> chunk_seed(0, 1, [2], [0.5], 3) == chunk_seed(0, 1, [2], [0.5], 3) != chunk_seed(0, 1, [2], [0.5], 4)
    True
    """
    bits = np.frombuffer(np.asarray(key, dtype=np.float64).tobytes(), dtype=np.uint32)
    entropy = [int(seed), kind, *identity, *map(int, bits), int(chunk)]
    return int(np.random.SeedSequence(entropy).generate_state(1)[0])


def albedo_queries(mu: NDArray[np.float64] | None) -> list[tuple[NDArray[np.float64], NDArray[np.float64], list]]:
    """The queries (wi, wo, key) of the directional albedo at each cosine ``mu`` (wi in the
    xz-plane, no wo), or of the average albedo when ``mu`` is None (one query, key -1: the
    chunk kernels draw a cosine-distributed wi per path).

    >>> [(wi.tolist(), key) for wi, _, key in albedo_queries(np.array([0.6]))]
    [([0.8, 0.0, 0.6], [np.float64(0.6)])]
    """
    no_wo = np.zeros((0, 3))
    if mu is None:
        return [(np.array([0.0, 0.0, 1.0]), no_wo, [-1.0])]
    return [(np.array([math.sqrt(max(0.0, 1.0 - m * m)), 0.0, m]), no_wo, [m]) for m in mu]


def run_chunks(
    run_task: Callable[[Any], Any],
    queries: Sequence[Any],
    task: Callable[[Any, int, int], Any],
    options: RunOptions,
) -> tuple[list, list[tuple[int, int]]]:
    """Cut each query's ``options.paths`` into chunks of ``CHUNK_PATHS``, ``task(query, i, n)``
    the task of its chunk i (n paths), and :func:`execute` them all with ``run_task``: the
    results in task order and each query's (start, stop) among them.

    >>> run_chunks(lambda t: t, ["a", "b"], lambda q, i, n: (q, i, n), RunOptions.check(CHUNK_PATHS + 1, 0, 1))
    ([('a', 0, 32768), ('a', 1, 1), ('b', 0, 32768), ('b', 1, 1)], [(0, 2), (2, 4)])
    """
    tasks: list[Any] = []
    spans: list[tuple[int, int]] = []
    n_chunks = -(-options.paths // CHUNK_PATHS)
    for query in queries:
        start = len(tasks)
        for i in range(n_chunks):
            tasks.append(task(query, i, min(CHUNK_PATHS, options.paths - i * CHUNK_PATHS)))
        spans.append((start, len(tasks)))
    return execute(run_task, tasks, options), spans


def chunk_sum(results: Sequence[Sequence[Any]], span: tuple[int, int], index: int) -> Any:
    """The sum of item ``index`` of the chunk results ``results[start:stop]`` (``span``), in
    chunk order.

    >>> chunk_sum([(np.ones(2),), (np.full(2, 2.0),)], (0, 2), 0).tolist()
    [3.0, 3.0]
    """
    out = results[span[0]][index].copy()
    for r in results[span[0] + 1 : span[1]]:
        out += r[index]
    return out


def mean_err(s1: Any, s2: Any, n: int) -> tuple[Any, Any]:
    """Mean and standard error of the mean of ``n`` samples with sum ``s1`` and sum of
    squares ``s2``.

    >>> mean_err(np.array(6.0), np.array(14.0), 3)
    (np.float64(2.0), np.float64(0.5773502691896257))
    """
    mean = s1 / n
    var = np.maximum(s2 - s1 * s1 / n, 0.0) / max(n - 1, 1)
    return mean, np.sqrt(var / n)


def run_fields(rho: NDArray[np.float64], paths: int, seed: int, mu: Any, rows: list) -> dict[str, Any]:
    """The fields that end the JSON form (``to_dict``) of every albedo estimate: ``rho``,
    ``paths``, ``seed``, ``average`` (``mu`` is None) and the per-query ``rows``.

    >>> run_fields(np.array([0.5]), 10, 0, None, [])
    {'rho': [0.5], 'paths': 10, 'seed': 0, 'average': True, 'rows': []}
    """
    return {"rho": rho.tolist(), "paths": paths, "seed": seed, "average": mu is None, "rows": rows}


__all__ = [
    "CHUNK_PATHS",
    "RunOptions",
    "albedo_queries",
    "check_count",
    "chunk_seed",
    "chunk_sum",
    "execute",
    "mean_err",
    "run_chunks",
    "run_fields",
]
