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
#: > 0 inside :class:`blocked`: the handler records a signal and raises nothing
_deferred = 0


class Terminated(KeyboardInterrupt):
    """A termination signal arrived; ``signum`` is its number (exit status 128 + signum)."""

    def __init__(self, signum: int) -> None:
        super().__init__(f"interrupted by {signal.Signals(signum).name}")
        self.signum = signum


def _handler(signum: int, frame: object) -> None:
    _received.append(signum)
    if _deferred:
        return
    raise Terminated(signum)


def _exit_now(signum: int, frame: object) -> None:
    import os
    import sys

    sys.stderr.write(f"openpbr-diffuse: interrupted by {signal.Signals(signum).name}\n")
    os._exit(128 + signum)


def is_command_line() -> bool:
    """Whether this process is the command line: ``openpbr-diffuse``, or ``python -m
    openpbr_diffuse``, whose ``sys.argv[0]`` is ``-m`` while the package is imported.

    Example
    -------
    >>> is_command_line()   # a test or an interpreter session
    False
    """
    import os
    import sys

    argv0 = sys.argv[0] if sys.argv else ""
    return argv0 == "-m" or os.path.basename(argv0) == "openpbr-diffuse"


def install_for_start_up() -> None:
    """While the command line is still importing (nothing written yet), a signal exits at once.

    Called from the package's ``__init__``; acts only when the process is the command line
    (``is_command_line``), so that a Ctrl-C during the imports ends the command with one
    line and exit 128 + signum instead of a traceback.  :func:`install` replaces it.
    """
    if not is_command_line():
        return
    if threading.current_thread() is not threading.main_thread():
        return
    for s in SIGNALS:
        if signal.getsignal(s) in (signal.default_int_handler, signal.SIG_DFL):
            signal.signal(s, _exit_now)


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

    A signal that arrives meanwhile raises nothing inside the block and is delivered when
    the block ends (as :class:`Terminated`, unless the block ends with an exception of its
    own).  The main thread's mask holds the signals; but in a process with other threads
    (the package's thread pool) the kernel may hand a signal to one of those, and Python
    then runs the handler in the main thread at once, mask or not: so the handler itself
    only records a signal that arrives inside a block, and the block's end raises it.
    """

    def __enter__(self) -> blocked:
        global _deferred
        self._old = None
        self._seen = len(_received)
        _deferred += 1
        if hasattr(signal, "pthread_sigmask") and threading.current_thread() is threading.main_thread():
            self._old = signal.pthread_sigmask(signal.SIG_BLOCK, SIGNALS)
        return self

    def __exit__(self, exc_type: object, *exc: object) -> None:
        global _deferred
        if self._old is not None:
            signal.pthread_sigmask(signal.SIG_SETMASK, self._old)
        _deferred -= 1
        if exc_type is None and not _deferred and len(_received) > self._seen:
            raise Terminated(_received[-1])
