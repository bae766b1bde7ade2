"""How a library run is carried out: workers, cache, cluster, progress, pictures."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from .pool import Runner

#: Materials drawn (preview render and albedo plot) by default: failing first, then flagged.
PREVIEWS = 24


@dataclass
class LibraryOptions:
    """What ``report`` (``--jobs``, ``--cache-dir`` / ``--no-cache``, ``--scheduler``,
    ``--previews``) and ``eval --jsonl`` pass to the work over many files.

    Parameters
    ----------
    jobs : int
        Worker processes (1: in the command's own process).
    cache : Cache, optional
        Where results are kept (None: no cache).
    scheduler : str, optional
        A Dask scheduler's address; or ``client``, a ``distributed.Client``.
    progress : {"bar", "lines", "none"}
        How progress is shown on stderr (:mod:`.progress`).
    previews : int
        At most this many materials get a preview render and an albedo plot.

    Examples
    --------
    >>> opts = LibraryOptions(jobs=2)
    >>> with opts.runner() as r:
    ...     r.jobs
    2
    """

    jobs: int = 1
    cache: Any = None
    scheduler: str | None = None
    client: Any = None
    progress: str = "none"
    previews: int = PREVIEWS
    #: whether ``client`` was made for these options (:meth:`close` closes it)
    own_client: bool = False

    def runner(self) -> Runner:
        """A :class:`.pool.Runner` with these workers, cache and cluster."""
        return Runner(self.jobs, self.cache, None if self.client is not None else self.scheduler, self.client)

    def close(self) -> None:
        """Close the Dask client made for these options (if any)."""
        if self.own_client and self.client is not None:
            self.client.close()
            self.client = None


__all__ = ["LibraryOptions", "PREVIEWS"]
