"""The run options every ``simulate_*`` function takes, checked in one place, and the runner
of their chunk tasks (local threads or a Dask cluster).

``paths``, ``seed``, ``workers``, ``client``, ``scheduler`` and ``progress`` mean the same in
the microsurface simulator (``api``) and the layered one (``layered``): :meth:`RunOptions.check`
validates them (TypeError / ValueError naming the argument) and :func:`execute` runs a list of
chunk tasks with them, results in task order.

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


__all__ = ["RunOptions", "check_count", "execute"]
