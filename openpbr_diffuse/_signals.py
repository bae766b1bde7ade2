"""Termination signals as exceptions, so that every command cleans up and exits 128+signum.

:func:`install` turns SIGINT, SIGTERM and SIGHUP into :class:`Terminated` (a
``KeyboardInterrupt``) raised in the main thread; :func:`received` tells whether one
arrived since, even when the exception was swallowed somewhere (a finalizer, an
``except`` around an import), so that an output is never published after a signal.

Example
-------
>>> from openpbr_diffuse import _signals
>>> issubclass(_signals.Terminated, KeyboardInterrupt)
True
"""
from __future__ import annotations

import signal
import threading

SIGNALS = tuple(getattr(signal, n) for n in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, n))
_received: list[int] = []


class Terminated(KeyboardInterrupt):
    """A termination signal arrived; ``signum`` is its number (exit status 128 + signum)."""

    def __init__(self, signum: int) -> None:
        super().__init__(f"interrupted by {signal.Signals(signum).name}")
        self.signum = signum


def _handler(signum: int, frame: object) -> None:
    _received.append(signum)
    raise Terminated(signum)


def install() -> None:
    """Raise :class:`Terminated` on SIGINT/SIGTERM/SIGHUP (main thread only; else a no-op)."""
    if threading.current_thread() is not threading.main_thread():
        return
    _received.clear()  # a new command starts (main() may run several times in one process)
    for s in SIGNALS:
        signal.signal(s, _handler)


def received() -> int | None:
    """The first termination signal received since :func:`install`, or ``None``."""
    return _received[0] if _received else None


def check() -> None:
    """Raise :class:`Terminated` again if a signal arrived (its exception may have been lost)."""
    if _received:
        raise Terminated(_received[0])


class blocked:
    """Context manager: hold SIGINT/SIGTERM/SIGHUP during a short critical step.

    Signals that arrive meanwhile are delivered when the block ends.
    """

    def __enter__(self):
        self._old = None
        if hasattr(signal, "pthread_sigmask") and threading.current_thread() is threading.main_thread():
            self._old = signal.pthread_sigmask(signal.SIG_BLOCK, SIGNALS)
        return self

    def __exit__(self, *exc: object) -> None:
        if self._old is not None:
            signal.pthread_sigmask(signal.SIG_SETMASK, self._old)
