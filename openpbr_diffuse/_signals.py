"""Termination signals as exceptions, remembered even when the exception is swallowed.

The command line installs :func:`install` first thing: SIGINT raises ``KeyboardInterrupt``
(as Python's default handler does), SIGTERM and SIGHUP raise :class:`Terminated`, and every
signal received is recorded.  Code that is about to make a change visible (the report's
publication step) calls :func:`raise_if_received`: an interrupt that some library swallowed
(in a finaliser, a thread, a broad ``except``) still stops the run before anything is replaced.

Examples
--------
>>> received()
()
"""
from __future__ import annotations

import signal
import threading

#: The signals turned into exceptions: (signal, what it is called in messages).
SIGNALS = tuple(s for s in (signal.SIGINT, getattr(signal, "SIGTERM", None), getattr(signal, "SIGHUP", None))
                if s is not None)

_received: list[int] = []


class Terminated(BaseException):
    """SIGTERM or SIGHUP received (a ``BaseException``, like ``KeyboardInterrupt``)."""

    def __init__(self, signum: int):
        super().__init__(f"terminated by {signal.Signals(signum).name}")
        self.signum = signum


def _handler(signum, frame):
    _received.append(signum)
    if signum == signal.SIGINT:
        raise KeyboardInterrupt
    raise Terminated(signum)


def _exit_now(signum, frame):
    import os
    import sys

    name = "interrupted" if signum == signal.SIGINT else f"terminated by {signal.Signals(signum).name}"
    sys.stderr.write(f"openpbr-diffuse: {name}\n")
    os._exit(128 + signum)


def install_for_start_up() -> None:
    """While the command line is still importing (nothing written yet): a signal exits at once.

    Installed from the package's ``__init__`` only when the process is the command line
    (``openpbr-diffuse`` or ``python -m openpbr_diffuse``), so that a Ctrl-C during the imports
    ends the command with its exit status and one line, not a traceback; :func:`install`
    replaces it when the command starts.
    """
    import os
    import sys

    argv0 = sys.argv[0] if sys.argv else ""
    if (argv0 != "-m" and os.path.basename(argv0) != "openpbr-diffuse") or \
            threading.current_thread() is not threading.main_thread():
        return
    for s in SIGNALS:
        if signal.getsignal(s) in (signal.default_int_handler, signal.SIG_DFL):
            signal.signal(s, _exit_now)


def install() -> None:
    """Turn SIGINT/SIGTERM/SIGHUP into exceptions (main thread only; elsewhere a no-op)."""
    if threading.current_thread() is not threading.main_thread():
        return
    for s in SIGNALS:
        signal.signal(s, _handler)


def received() -> tuple[int, ...]:
    """The termination signals received so far (in order)."""
    return tuple(_received)


def raise_if_received() -> None:
    """Raise the exception of the first signal received, if any was (even if it was swallowed)."""
    if _received:
        s = _received[0]
        if s == signal.SIGINT:
            raise KeyboardInterrupt
        raise Terminated(s)


class blocked:
    """Context manager: the termination signals are held (not lost) while the block runs.

    Used around a step that must either complete or not start, such as swapping a finished
    report into place; a signal that arrives meanwhile is delivered when the block ends.
    """

    def __enter__(self):
        self._on = threading.current_thread() is threading.main_thread() and hasattr(signal, "pthread_sigmask")
        if self._on:
            self._old = signal.pthread_sigmask(signal.SIG_BLOCK, set(SIGNALS))
        return self

    def __exit__(self, *exc):
        if self._on:
            signal.pthread_sigmask(signal.SIG_SETMASK, self._old)
        return False


__all__ = ["Terminated", "install", "received", "raise_if_received", "blocked", "SIGNALS"]
