"""Options of the commands that read many material files (``report``, ``eval --jsonl``):
worker processes, cache, Dask cluster, previews."""

from __future__ import annotations

import argparse
import os
from collections.abc import Callable
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..library import LibraryOptions


def _whole(low: int, bound: str) -> Callable[[str], int]:
    """An argparse type: a whole number of at least ``low`` (``bound`` says so in the message)."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be a whole number, got {text!r}") from None
        if value < low:
            raise argparse.ArgumentTypeError(f"must be {bound}, got {value}")
        return value

    return parse


_positive = _whole(1, "at least 1")
_count = _whole(0, "0 or more")


def add_library_options(p: argparse.ArgumentParser, previews: bool = False) -> None:
    """``--jobs``, ``--cache-dir``, ``--no-cache``, ``--scheduler`` (and ``--previews``)."""
    from ..library import PREVIEWS

    g = p.add_argument_group("many files (see docs/guide/report.md, Large libraries)")
    g.add_argument(
        "--jobs",
        type=_positive,
        default=None,
        metavar="N",
        help="worker processes reading the files (default: the cores this process may use); processes, "
        "not threads: usd-core and MaterialX are not safe to share between threads",
    )
    g.add_argument(
        "--cache-dir",
        metavar="DIR",
        default=None,
        help="keep each file's results here, reused while the file and every file it uses are unchanged "
        "(default: $OPENPBR_DIFFUSE_CACHE_DIR, else $XDG_CACHE_HOME/openpbr-diffuse/library)",
    )
    g.add_argument("--no-cache", action="store_true", help="read every file again and keep nothing")
    g.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        default=None,
        help="read the files on this Dask scheduler (tcp://HOST:PORT); the workers need this package "
        "and the files at the same paths",
    )
    if previews:
        g.add_argument(
            "--previews",
            type=_count,
            default=PREVIEWS,
            metavar="N",
            help=f"draw a preview and an albedo plot of at most N materials, failing and flagged first "
            f"(default {PREVIEWS})",
        )


def library_options(args: argparse.Namespace, progress: str) -> LibraryOptions:
    """The options as ``args`` give them; connects to ``--scheduler`` now (before any work).

    Raises
    ------
    ValueError
        ``--cache-dir`` names something that is not a folder, or is given with ``--no-cache``.
    ConnectionError
        No Dask scheduler answered at ``--scheduler``.
    """
    from ..library import Cache, LibraryOptions, default_cache_dir, usable_cores

    if args.no_cache and args.cache_dir:
        raise ValueError("--no-cache and --cache-dir: give one of them")
    cache = None
    if not args.no_cache:
        folder = args.cache_dir or default_cache_dir()
        if os.path.lexists(folder) and not os.path.isdir(folder):
            raise ValueError(f"--cache-dir {folder} exists and is not a folder")
        cache = Cache(folder)
    client = None
    if args.scheduler:
        from ..simulation.api import _client

        client, _ = _client(None, args.scheduler)
    return LibraryOptions(
        jobs=args.jobs or usable_cores(),
        cache=cache,
        scheduler=args.scheduler,
        client=client,
        progress=progress,
        previews=getattr(args, "previews", LibraryOptions.previews),
        own_client=client is not None,
    )


__all__ = ["add_library_options", "library_options"]
