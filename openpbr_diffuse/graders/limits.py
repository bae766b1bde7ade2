"""Run user code (a compiler, a compiled harness, a GL child) under a wall-time and memory limit.

``--cpp`` and ``--glsl`` compile and run the given code with the user's rights.  Every such
process runs here: in its own session (so its whole process group can be killed), with
``RLIMIT_AS`` set in the child, and killed -- the whole group -- when the wall-time limit
passes or when the parent is interrupted (KeyboardInterrupt, SIGTERM turned into
``SystemExit`` by the CLI, any exception while waiting).

The limits are module settings, changed by ``check --timeout SECONDS``:

>>> from openpbr_diffuse.graders import limits
>>> limits.TIMEOUT, limits.MEMORY // 2**30
(60.0, 4)
>>> limits.run_limited(["true"], label="true").returncode
0
"""

from __future__ import annotations

import atexit
import math
import os
import re
import select
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Sequence
from typing import Any

from ._gpu_child import ANSWER_HEADER, JOB_HEADER
from .errors import GraderUnavailable

#: default wall-time limit of one compile or one run of user code, seconds
TIMEOUT: float = 60.0
#: default address-space limit of one such process, bytes (4 GiB)
MEMORY: int = 4 * 2**30

_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")


def set_limits(timeout: float | None = None, memory: int | None = None) -> None:
    """Change the wall-time (seconds) and memory (bytes) limits of user code.

    >>> set_limits(timeout=60)
    >>> set_limits(timeout=0)
    Traceback (most recent call last):
    ...
    ValueError: timeout must be a positive number of seconds, got 0
    """
    global TIMEOUT, MEMORY
    if timeout is not None:
        if not isinstance(timeout, (int, float)) or not timeout > 0 or not math.isfinite(timeout):
            raise ValueError(f"timeout must be a positive number of seconds, got {timeout!r}")
        TIMEOUT = float(timeout)
    if memory is not None:
        if not isinstance(memory, int) or memory <= 0:
            raise ValueError(f"memory must be a positive number of bytes, got {memory!r}")
        MEMORY = memory


def check_identifier(name: str, option: str) -> str:
    """Return ``name`` when it is a C/GLSL identifier, else raise ValueError naming ``option``.

    >>> check_identifier("eon_f", "--function")
    'eon_f'
    >>> check_identifier("lambda x: x", "--function")
    Traceback (most recent call last):
    ...
    ValueError: --function: 'lambda x: x' is not a function name (a C identifier: letters, digits, _)
    """
    if not isinstance(name, str) or not _IDENT.match(name) or name in _RESERVED:
        raise ValueError(f"{option}: {name!r} is not a function name (a C identifier: letters, digits, _)")
    return name


def parse_defines(defines: Sequence[str] | None) -> dict[str, str]:
    """``NAME`` / ``NAME=VALUE`` strings to a dict; NAME an identifier, VALUE on one line, no ``#``.

    >>> parse_defines(["A", "B=2.0"])
    {'A': '1', 'B': '2.0'}
    >>> parse_defines(["X=1\\n#version 100"])
    Traceback (most recent call last):
    ...
    ValueError: --define: 'X=1\\n#version 100' VALUE must be one line without '#' or '\\\\'
    """
    out: dict[str, str] = {}
    for d in defines or ():
        name, _, value = str(d).partition("=")
        if not _IDENT.match(name):
            raise ValueError(f"--define: {d!r} is not NAME or NAME=VALUE (NAME a C identifier)")
        if any(c in value for c in "\n\r#\\\0"):
            raise ValueError(f"--define: {d!r} VALUE must be one line without '#' or '\\\\'")
        out[name] = value or "1"
    return out


_RESERVED = frozenset(
    {
        "lambda",
        "if",
        "else",
        "for",
        "while",
        "do",
        "return",
        "switch",
        "case",
        "break",
        "continue",
        "struct",
        "void",
        "int",
        "float",
        "double",
        "bool",
        "true",
        "false",
        "vec2",
        "vec3",
        "vec4",
        "main",
        "sizeof",
        "class",
        "new",
        "delete",
        "template",
    }
)


#: a small exec wrapper sets the limits in the child (preexec_fn is unsafe when threads run)
_WRAPPER = (
    "import os, resource, sys; m = int(sys.argv[1]); "
    "resource.setrlimit(resource.RLIMIT_AS, (m, m)); resource.setrlimit(resource.RLIMIT_CORE, (0, 0)); "
    "os.execvp(sys.argv[2], sys.argv[2:])"
)


def kill_group(proc: subprocess.Popen) -> None:
    """SIGKILL the process group of ``proc`` (started with ``start_new_session``) and reap it."""
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass
    try:
        proc.wait(timeout=5)
    except subprocess.TimeoutExpired:  # pragma: no cover - SIGKILL is not ignorable
        pass


def script_command(path: os.PathLike[str] | str, *args: str) -> list[str]:
    """The command that runs the Python file ``path`` as ``__main__`` (``sys.argv[1:]`` =
    ``args``) in a child, without importing the package it belongs to (``python -m
    package.module`` would import the package first: numba and the models, 0.4 s of a GL
    child's 0.55 s) and without putting the file's folder on ``sys.path`` (where its sibling
    modules would shadow others).

    >>> script_command("/x/child.py", "gl")[1:]
    ['-c', "import runpy; runpy.run_path('/x/child.py', run_name='__main__')", 'gl']
    """
    return [sys.executable, "-c", f"import runpy; runpy.run_path({str(path)!r}, run_name='__main__')", *args]


def run_limited(
    cmd: Sequence[str],
    input: bytes | None = None,
    *,
    label: str,
    timeout: float | None = None,
    memory: int | None = None,
    env: dict[str, str] | None = None,
) -> subprocess.CompletedProcess:
    """Run ``cmd`` in a new session under the limits; its whole group is killed on timeout/interrupt.

    Returns the CompletedProcess (stdout/stderr bytes).  A timeout raises GraderUnavailable with
    one line; so does a run killed by the memory limit (seen as a failed allocation: the caller
    reads ``returncode`` and ``stderr``).
    """
    timeout = TIMEOUT if timeout is None else timeout
    memory = MEMORY if memory is None else memory
    proc = subprocess.Popen(
        [sys.executable, "-c", _WRAPPER, str(int(memory)), *cmd],
        stdin=subprocess.PIPE if input is not None else subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        start_new_session=True,
        env=env,
    )
    try:
        out, err = proc.communicate(input, timeout=timeout)
    except subprocess.TimeoutExpired:
        kill_group(proc)
        raise GraderUnavailable(
            f"{label} did not finish within {timeout:g} s (the time limit of user code; "
            "raise it with --timeout SECONDS): killed"
        ) from None
    except BaseException:
        kill_group(proc)
        raise
    # the leader finished: anything it left in its group goes too
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass
    return subprocess.CompletedProcess(list(cmd), proc.returncode, out, err)


class Worker:
    """A child process that runs jobs one after the other under the limits of user code.

    Started on the first :meth:`request` with ``cmd`` (through the same wrapper as
    :func:`run_limited`: its own session, ``RLIMIT_AS``, the current environment), it reads
    length-prefixed job frames on stdin and answers each with a status and a payload (the
    protocol of ``_gpu_child``: ``JOB_HEADER``, ``ANSWER_HEADER``).
    The time limit is per job: a job that has not answered within it is killed with the
    child's whole process group, as is the child when the parent is interrupted while it
    waits; a child that died (a crash, the memory limit) is reported once, as
    :func:`run_limited` reports a failed run, and started again for the next job.  The child
    ends when its stdin closes: with the parent, or at :meth:`stop` (run at exit).

    Example
    -------
    A child that answers one job with its payload reversed:

    >>> code = ("import struct, sys; i, o = sys.stdin.buffer, sys.stdout.buffer; "
    ...         "n = struct.unpack('<Q', i.read(8))[0]; d = i.read(n); "
    ...         "o.write(struct.pack('<iQ', 0, n) + d[::-1]); o.flush()")
    >>> w = Worker([sys.executable, "-c", code])
    >>> w.request(b"abc", label="reverse").stdout
    b'cba'
    >>> w.stop()
    """

    def __init__(self, cmd: Sequence[str]) -> None:
        self.cmd = list(cmd)
        self.proc: subprocess.Popen | None = None
        self.memory: int | None = None
        self.env: dict[str, str] | None = None
        self._stderr: Any = None
        self._lock = threading.Lock()

    def _start(self, memory: int, env: dict[str, str]) -> subprocess.Popen:
        self._stderr = tempfile.TemporaryFile()
        self.proc = subprocess.Popen(
            [sys.executable, "-c", _WRAPPER, str(int(memory)), *self.cmd],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=self._stderr,
            start_new_session=True,
            env=env,
        )
        self.memory, self.env = memory, env
        return self.proc

    def stop(self) -> None:
        """End the child (and its group) if it runs."""
        if self.proc is not None:
            for stream in (self.proc.stdin, self.proc.stdout):
                try:
                    stream.close()  # type: ignore[union-attr]
                except OSError:
                    pass
            kill_group(self.proc)
            self.proc = None
        if self._stderr is not None:
            self._stderr.close()
            self._stderr = None

    def _stderr_text(self) -> bytes:
        self._stderr.seek(0)
        return self._stderr.read()[-20000:]

    def request(
        self, payload: bytes, *, label: str, timeout: float | None = None, memory: int | None = None
    ) -> subprocess.CompletedProcess:
        """Send one job; return its answer as a CompletedProcess: ``returncode`` the job's status
        (0, or the child's failure status when it died: then ``stderr`` is the child's), and
        ``stdout`` the payload.  A job past the time limit raises GraderUnavailable, as
        :func:`run_limited`."""
        timeout = TIMEOUT if timeout is None else timeout
        memory = MEMORY if memory is None else memory
        env = dict(os.environ)
        with self._lock:
            proc = self.proc
            # a child runs under the limits and environment of its first job: another memory
            # limit or a changed environment starts a new one, as a run of its own would see
            if proc is None or proc.poll() is not None or self.memory != memory or self.env != env:
                self.stop()
                proc = self._start(memory, env)
            deadline = time.monotonic() + timeout
            try:
                try:
                    proc.stdin.write(JOB_HEADER.pack(len(payload)) + payload)  # type: ignore[union-attr]
                    proc.stdin.flush()  # type: ignore[union-attr]
                    status, n = ANSWER_HEADER.unpack(_read_until(proc, ANSWER_HEADER.size, deadline))
                    data = _read_until(proc, n, deadline)
                except (BrokenPipeError, EOFError):  # the child died
                    try:
                        code = proc.wait(timeout=max(0.0, deadline - time.monotonic()))
                    except subprocess.TimeoutExpired:
                        raise TimeoutError from None
                    err = self._stderr_text()
                    self.stop()
                    return subprocess.CompletedProcess(self.cmd, code if code else 1, b"", err)
            except TimeoutError:
                self.stop()
                raise GraderUnavailable(
                    f"{label} did not finish within {timeout:g} s (the time limit of user code; "
                    "raise it with --timeout SECONDS): killed"
                ) from None
            except BaseException:
                self.stop()
                raise
            if status != 0:
                return subprocess.CompletedProcess(self.cmd, status, b"", data)
            return subprocess.CompletedProcess(self.cmd, 0, data, b"")


_WORKERS: dict[tuple[str, ...], Worker] = {}


def _read_until(proc: subprocess.Popen, n: int, deadline: float) -> bytes:
    """n bytes from the child's stdout before ``deadline`` (TimeoutError), or EOFError when it
    closes first."""
    fd = proc.stdout.fileno()  # type: ignore[union-attr]
    chunks, got = [], 0
    while got < n:
        left = deadline - time.monotonic()
        if left <= 0 or not select.select([fd], [], [], left)[0]:
            raise TimeoutError
        chunk = os.read(fd, min(n - got, 1 << 20))
        if not chunk:
            raise EOFError
        chunks.append(chunk)
        got += len(chunk)
    return b"".join(chunks)


def worker(cmd: Sequence[str]) -> Worker:
    """The process's :class:`Worker` for ``cmd`` (made on first use, stopped at exit)."""
    key = tuple(cmd)
    w = _WORKERS.get(key)
    if w is None:
        w = _WORKERS[key] = Worker(cmd)
    return w


@atexit.register
def stop_workers() -> None:
    """End every :class:`Worker` child of the process (run at exit)."""
    for w in _WORKERS.values():
        w.stop()


def memory_message(stderr: bytes | str) -> bool:
    """True when a child's stderr says it ran out of memory (the RLIMIT_AS limit).

    >>> memory_message(b"cc1plus: out of memory allocating 65536 bytes")
    True
    """
    text = stderr.decode(errors="replace") if isinstance(stderr, bytes) else stderr
    low = text.lower()
    return any(
        s in low
        for s in (
            "out of memory",
            "cannot allocate memory",
            "std::bad_alloc",
            "memory exhausted",
            "virtual memory exhausted",
        )
    )
