"""Run the work of many material files: serially, over worker processes, or on Dask.

:func:`run` takes (file, task) pairs and yields one :class:`Outcome` per pair **in the order
given**, whichever way the work ran, so that a parallel, cached or distributed run gives the
same result as a serial one:

- a file whose result is in the cache (:class:`.cache.Cache`) is not read at all;
- ``jobs > 1``: the other files go to a pool of ``jobs`` worker **processes** (usd-core and
  MaterialX are not safe to share between threads); a worker that dies (a crash inside a
  native library) loses no other file: the files it may have been reading are run again,
  each alone, and the one that crashes is reported as such;
- ``scheduler`` (``tcp://HOST:PORT``) or ``client``: the files go to a Dask cluster (the
  client is made as ``simulate --scheduler`` makes it); a file a worker cannot read is
  reported as such for that file;
- fewer than :data:`MIN_PARALLEL` files to compute run in this process (starting workers
  would cost more than it saves).

At most a few files per worker are in flight, and results that arrive out of order wait
only for the ones before them, so memory does not grow with the number of files.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import os
import sys
from collections.abc import Iterator, Sequence
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from typing import Any

from .worker import Task, _init_worker, process_file

#: Fewer files than this to compute (not in the cache) run in this process.
MIN_PARALLEL = 8
#: Seconds between two looks at the progress while waiting for a file.
TICK_S = 1.0


def usable_cores() -> int:
    """The number of cores this process may run on (its CPU affinity), at least 1.

    >>> usable_cores() >= 1
    True
    """
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)


@dataclass
class Outcome:
    """The result of one (file, task): ``payload`` as :func:`.worker.process_file` returns it
    (``{"records": [...], "error": str | None}``), ``cached`` when it came from the cache."""

    index: int
    path: str
    payload: dict
    cached: bool = False
    elapsed_s: float = 0.0


def _failed(path: str, message: str) -> dict[str, Any]:
    return {"path": path, "payload": {"records": [], "error": f"{path}: {message}"}, "cacheable": False}


CRASHED = (
    "the worker process reading it ended abruptly (a crash inside usd-core, MaterialX or OpenImageIO); "
    "the other files were read"
)


class _Serial:
    """In this process: each file is done when it is submitted."""

    window = 1

    def __init__(self, work: Any = process_file) -> None:
        self.work = work

    def submit(self, path: str, task: Task) -> Any:
        f: cf.Future = cf.Future()
        try:
            f.set_result(self.work(path, task))
        except Exception as exc:  # noqa: BLE001 -- process_file reports file problems itself
            f.set_exception(exc)
        return f

    def wait(self, handles: list, timeout: float) -> list:
        return list(handles)

    def result(self, handle: Any, path: str) -> dict[str, Any]:
        try:
            return handle.result()
        except Exception as exc:  # noqa: BLE001 -- an internal error names the file
            return _failed(path, f"not processed ({type(exc).__name__}: {exc})")

    def close(self) -> None:
        pass


@contextlib.contextmanager
def _no_main() -> Iterator[None]:
    """Start worker processes without the parent's ``__main__``: they run the package's
    :func:`.worker.process_file` only, so a script that calls the library without an
    ``if __name__ == "__main__"`` guard (or a script read from stdin) is not run again in
    each worker, as ``spawn`` would otherwise do."""
    main = sys.modules.get("__main__")
    saved: dict[str, Any] = {k: main.__dict__[k] for k in ("__file__", "__spec__") if main and k in main.__dict__}
    try:
        if main is not None:
            main.__dict__.pop("__file__", None)
            main.__dict__["__spec__"] = None
        yield
    finally:
        if main is not None:
            main.__dict__.pop("__spec__", None)
            main.__dict__.update(saved)


class _Processes:
    """A pool of ``jobs`` worker processes (spawned: no state inherited from this process)."""

    def __init__(self, jobs: int, work: Any = process_file) -> None:
        self.jobs, self.work = jobs, work
        self.window = 2 * jobs
        self.pool: cf.ProcessPoolExecutor | None = None

    def _pool(self) -> cf.ProcessPoolExecutor:
        if self.pool is None:
            import multiprocessing

            self.pool = cf.ProcessPoolExecutor(
                self.jobs, mp_context=multiprocessing.get_context("spawn"), initializer=_init_worker
            )
        return self.pool

    def submit(self, path: str, task: Task) -> Any:
        with _no_main():  # the first submit starts the workers
            return self._pool().submit(self.work, path, task)

    def wait(self, handles: list, timeout: float) -> list:
        done, _ = cf.wait(handles, timeout=timeout, return_when=cf.FIRST_COMPLETED)
        return list(done)

    def result(self, handle: Any, path: str) -> dict[str, Any]:
        return handle.result()  # BrokenProcessPool is handled by run()

    def reset(self) -> None:
        """Drop a broken pool (the next submit starts a new one)."""
        if self.pool is not None:
            self.pool.shutdown(wait=False, cancel_futures=True)
            self.pool = None

    def one_by_one(self, items: list[tuple[int, str, Task]]) -> dict[int, dict[str, Any]]:
        """Run the files one at a time in a worker of their own: a crash is the file's.

        The worker is kept from one file to the next and replaced only when one crashes it."""
        import multiprocessing

        out: dict[int, dict[str, Any]] = {}
        pool = None
        try:
            for i, path, task in items:
                if pool is None:
                    pool = cf.ProcessPoolExecutor(
                        1, mp_context=multiprocessing.get_context("spawn"), initializer=_init_worker
                    )
                try:
                    with _no_main():
                        future = pool.submit(self.work, path, task)
                    out[i] = future.result()
                except BrokenProcessPool:
                    out[i] = _failed(path, CRASHED)
                    pool.shutdown(wait=False, cancel_futures=True)
                    pool = None
        finally:
            if pool is not None:
                pool.shutdown(wait=True)
        return out

    def close(self) -> None:
        if self.pool is not None:
            _terminate(self.pool)
            self.pool = None


def _terminate(pool: cf.ProcessPoolExecutor) -> None:
    """Shut ``pool`` down without waiting for the files in flight (their workers are ended)."""
    processes = list(getattr(pool, "_processes", {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for p in processes:
        if p.is_alive():
            p.terminate()
    for p in processes:
        p.join(timeout=5)


class _Dask:
    """A Dask cluster: ``client``, or one made for ``scheduler`` (closed at the end)."""

    def __init__(self, client: Any, scheduler: str | None, work: Any = process_file) -> None:
        from ..simulation.api import _client

        self.work = work
        self.client, self.own = _client(client, scheduler)
        try:
            threads = sum(self.client.nthreads().values())
        except Exception:  # noqa: BLE001 -- the count only sizes the window
            threads = 1
        self.window = max(4, 2 * threads)

    def submit(self, path: str, task: Task) -> Any:
        return self.client.submit(self.work, path, task, pure=False)

    def wait(self, handles: list, timeout: float) -> list:
        from distributed import wait

        try:
            wait(handles, timeout=timeout, return_when="FIRST_COMPLETED")
        except (TimeoutError, OSError):
            pass
        return [h for h in handles if h.done()]

    def result(self, handle: Any, path: str) -> dict[str, Any]:
        try:
            return handle.result()
        except Exception as exc:  # noqa: BLE001 -- a worker lost, a task that failed: this file's
            text = " ".join(str(exc).split())[:300]
            return _failed(path, f"the Dask cluster could not process it ({type(exc).__name__}: {text})")

    def close(self) -> None:
        if self.own:
            self.client.close()


class Runner:
    """Runs batches of (file, task) pairs with one set of workers (see the module docstring).

    The worker processes (or the Dask client) are made when a batch first needs them and
    kept for the next batch until :meth:`close` (or the end of a ``with`` block).

    Parameters
    ----------
    jobs : int
        Worker processes (1: in this process).
    cache : Cache, optional
        Results are looked up there first and stored there.
    scheduler : str, optional
        Address of a Dask scheduler; or ``client``, a ``distributed.Client`` (not closed here).
    work : callable, optional
        ``work(path, task) -> dict`` as :func:`.worker.process_file` (the default) returns it;
        a module-level function (worker processes and Dask import it by name).

    Raises
    ------
    ValueError
        ``jobs`` is not a positive integer.

    Examples
    --------
    >>> from openpbr_diffuse.readers import BUNDLED_MATERIALS
    >>> clay = str(BUNDLED_MATERIALS / "clay_rough.mtlx")
    >>> with Runner(jobs=1) as runner:
    ...     first = [o.payload["records"][0]["verdict"] for o in runner.run([(clay, Task())])]
    ...     again = [o.payload["records"][0].get("verdict") for o in runner.run([(clay, Task(kind="eval"))])]
    >>> first, again, runner.computed
    (['pass'], [None], 2)
    """

    def __init__(
        self,
        jobs: int = 1,
        cache: Any = None,
        scheduler: str | None = None,
        client: Any = None,
        work: Any = process_file,
    ) -> None:
        if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
            raise ValueError(f"jobs must be a positive integer, got {jobs!r}")
        if not callable(work):
            raise TypeError(f"work must be callable, got {type(work).__name__}")
        self.jobs, self.cache, self.scheduler, self.client, self.work = jobs, cache, scheduler, client, work
        self.backend: Any = None
        #: files read (not from the cache) and files from the cache, over every batch
        self.computed = self.cached = 0

    @property
    def remote(self) -> bool:
        return self.scheduler is not None or self.client is not None

    def _backend(self, misses: int) -> Any:
        if self.backend is not None and not isinstance(self.backend, _Serial):
            return self.backend
        if self.remote:
            self.backend = _Dask(self.client, self.scheduler, self.work)
        elif self.jobs > 1 and misses >= MIN_PARALLEL:
            self.backend = _Processes(self.jobs, self.work)
        else:
            self.backend = _Serial(self.work)
        return self.backend

    def run(self, items: Sequence[tuple[str, Task]], progress: Any = None) -> Iterator[Outcome]:
        """Do each (path, task) of ``items``; yield their :class:`Outcome` in the order given.

        ``progress`` (a :class:`.progress.Progress`) is told the files done and cached.

        Raises
        ------
        ConnectionError
            No Dask scheduler answered at ``scheduler``.
        """
        items = list(items)
        cache = self.cache
        if cache is not None:
            cache.forget()
        # worker processes only when enough files are not in the cache
        misses = 0 if self.remote else sum(1 for p, t in items if cache is None or not cache.holds(p, t))
        backend = self._backend(misses)
        queue = iter(enumerate(items))
        pending: dict[Any, tuple[int, str, Task]] = {}
        done: dict[int, Outcome] = {}
        n_done = n_cached = nxt = 0
        exhausted = False
        backlog = max(64, 4 * backend.window)
        while True:
            while not exhausted and len(pending) < backend.window and len(done) < backlog:
                item = next(queue, None)
                if item is None:
                    exhausted = True
                    break
                i, (path, task) = item
                hit = cache.get(path, task) if cache is not None else None
                if hit is None:
                    pending[backend.submit(path, task)] = (i, path, task)
                    continue
                done[i] = Outcome(i, path, hit, cached=True)
                n_done += 1
                n_cached += 1
                if i == nxt:
                    break  # hand it over at once
            if pending:
                finished = backend.wait(list(pending), TICK_S)
                broken = []
                for h in finished:
                    i, path, task = pending.pop(h)
                    try:
                        outcome = backend.result(h, path)
                    except BrokenProcessPool:
                        broken.append((i, path, task))
                        continue
                    done[i] = _record(i, path, task, outcome, cache)
                    n_done += 1
                if broken:  # the pool died: every file in flight may be the cause
                    broken += list(pending.values())
                    pending.clear()
                    backend.reset()
                    outcomes = backend.one_by_one(sorted(broken))
                    for i, path, task in sorted(broken):
                        done[i] = _record(i, path, task, outcomes[i], cache)
                        n_done += 1
            if progress is not None:
                progress.update(n_done, n_cached)
            while nxt in done:
                yield done.pop(nxt)
                nxt += 1
            if exhausted and not pending and not done:
                break
        self.computed += n_done - n_cached
        self.cached += n_cached

    def close(self) -> None:
        """End the worker processes (the files in flight are abandoned) or the own Dask client."""
        if self.backend is not None:
            self.backend.close()
            self.backend = None

    def __enter__(self) -> Runner:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def run(
    items: Sequence[tuple[str, Task]],
    *,
    jobs: int = 1,
    cache: Any = None,
    scheduler: str | None = None,
    client: Any = None,
    progress: Any = None,
    work: Any = process_file,
) -> Iterator[Outcome]:
    """Do each (path, task) of ``items``; yield their :class:`Outcome` in the order given
    (one batch of a :class:`Runner`, closed at the end).

    Examples
    --------
    >>> from openpbr_diffuse.readers import BUNDLED_MATERIALS
    >>> files = [str(BUNDLED_MATERIALS / n) for n in ("clay_rough.mtlx", "missing.mtlx")]
    >>> [(o.index, o.payload["error"] is None) for o in run([(f, Task()) for f in files])]
    [(0, True), (1, False)]
    """
    with Runner(jobs, cache, scheduler, client, work) as runner:
        yield from runner.run(items, progress)


def _record(i: int, path: str, task: Task, outcome: dict[str, Any], cache: Any) -> Outcome:
    if cache is not None and outcome.get("cacheable"):
        cache.put(path, task, outcome)
    return Outcome(i, path, outcome["payload"], cached=False, elapsed_s=float(outcome.get("elapsed_s", 0.0)))


__all__ = ["CRASHED", "MIN_PARALLEL", "Outcome", "Runner", "run", "usable_cores"]
