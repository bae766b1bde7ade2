"""Run user code (a compiler, a compiled harness, a GL child) under a wall-time and memory limit.

``--cpp`` and ``--glsl`` compile and run the given code with the user's rights.  Every such
process runs here, under a supervisor (``_supervisor.py``) that owns the run's whole process
tree: a child subreaper, so processes of the run that leave their session still end up below
it; it ends with this process (``PR_SET_PDEATHSIG``, and ``getppid()`` checked), even after a
SIGKILL of it.  The run ends when its program exits -- what its descendants still run is
killed then, and a process that keeps the output pipes open cannot hold the run -- when the
wall-time limit passes, or when this process is interrupted (KeyboardInterrupt, SIGTERM turned
into ``SystemExit`` by the CLI, any exception while waiting).  Each limit (``RLIMIT_AS``,
``RLIMIT_NPROC``, ``RLIMIT_CORE``) is the smaller of the one asked for and the one in force.

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
import resource
import select
import selectors
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ._gpu_child import ANSWER_HEADER, JOB_HEADER
from .errors import GraderUnavailable

#: default wall-time limit of one compile or one run of user code, seconds
TIMEOUT: float = 60.0
#: default address-space limit of one such process, bytes (4 GiB)
MEMORY: int = 4 * 2**30
#: a ``ulimit -v`` (KiB) under which a correct file still grades with --cpp and --glsl (the tool
#: itself, g++ and the GL child on llvmpipe; measured on 2 cores: ~490000 KiB is the lowest)
MEMORY_FLOOR_KIB = 524288

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


#: the supervisor of every run of user code (run as a script: the standard library only)
SUPERVISOR = Path(__file__).resolve().with_name("_supervisor.py")
#: processes (threads, as RLIMIT_NPROC counts) a run may add to those its user has at its start
NPROC_EXTRA = 64
#: seconds past the time limit after which a supervisor ends its run by itself
BACKSTOP = 2.0
#: seconds to read what the pipes of a run still hold once its supervisor has exited
DRAIN = 1.0
#: stderr kept of one run: its first and last this many bytes
STDERR_KEEP = 1 << 20


def memory_in_force(memory: int | None = None) -> int:
    """The address-space limit user code gets: ``memory`` (default :data:`MEMORY`) or the
    limit in force in this process (``ulimit -v``), whichever is lower.

    >>> memory_in_force(2**20) <= 2**20
    True
    """
    limit = MEMORY if memory is None else memory
    for current in resource.getrlimit(resource.RLIMIT_AS):
        if current != resource.RLIM_INFINITY:
            limit = min(limit, current)
    return limit


def memory_failure(what: str, program: str, status: int, memory: int | None = None) -> str:
    """One line for a run of ``program`` that ran out of memory or was killed.

    When the caller's own limit (``ulimit -v``) is below the limit of user code, the line
    says so and names the floor of :data:`MEMORY_FLOOR_KIB`; otherwise it names the limit.

    >>> memory_failure("compiling x.cpp", "g++", -9, memory=2**30)
    'compiling x.cpp exceeded the memory limit of user code (1 GiB) or was killed (status -9)'
    """
    asked = MEMORY if memory is None else memory
    limit = memory_in_force(asked)
    if limit < asked:
        return (
            f"{what}: the memory limit in force (ulimit -v {limit // 1024} KiB) is too low for {program} "
            f"(status {status}); {raise_hint(limit, asked)}"
        )
    return f"{what} exceeded the memory limit of user code ({asked / 2**30:g} GiB) or was killed (status {status})"


def raise_hint(limit: int, asked: int) -> str:
    """How to raise a caller's memory limit of ``limit`` bytes, below the ``asked`` bytes.

    >>> raise_hint(2**28, 2**32)
    'raise it to at least 524288 KiB (a correct file grades from there), e.g. ulimit -v unlimited'
    """
    if limit < MEMORY_FLOOR_KIB * 1024:
        return (
            f"raise it to at least {MEMORY_FLOOR_KIB} KiB (a correct file grades from there), e.g. ulimit -v unlimited"
        )
    return f"raise it (user code may use up to {asked / 2**30:g} GiB), e.g. ulimit -v unlimited"


def _supervised(
    cmd: Sequence[str], *, memory: int, backstop: float, stdin: Any, stdout: Any, stderr: Any, env: Any
) -> subprocess.Popen:
    """Start ``cmd`` under its supervisor (``_supervisor.py``), in a session of its own."""
    return subprocess.Popen(
        [
            sys.executable,
            "-I",
            "-S",
            str(SUPERVISOR),
            str(os.getpid()),
            f"{backstop:g}",
            str(int(memory)),
            str(NPROC_EXTRA),
            *cmd,
        ],
        stdin=stdin,
        stdout=stdout,
        stderr=stderr,
        start_new_session=True,
        env=env,
    )


def kill_group(proc: subprocess.Popen, patience: float = 5.0) -> None:
    """End the supervised run ``proc`` and reap it: SIGTERM to its supervisor, which kills and
    reaps every process of the run before it exits; SIGKILL to its process group when it has
    not exited within ``patience`` seconds."""
    if proc.poll() is not None:
        return
    try:
        os.kill(proc.pid, signal.SIGTERM)
        proc.wait(timeout=patience)
        return
    except ProcessLookupError:
        return
    except subprocess.TimeoutExpired:
        pass
    try:  # the supervisor is not reaped yet: its pid (and group id) cannot have been reused
        os.killpg(proc.pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass
    try:
        proc.wait(timeout=5)
    except subprocess.TimeoutExpired:  # pragma: no cover - SIGKILL is not ignorable
        pass


def close_streams(*streams: Any) -> None:
    """Close each of ``streams`` (a child's pipes) that is not None, passing over an OSError
    (a pipe whose reader has gone: what is left unwritten is not wanted).

    >>> import io
    >>> pipe = io.BytesIO()
    >>> close_streams(pipe, None); pipe.closed
    True
    """
    for stream in streams:
        if stream is not None:
            try:
                stream.close()
            except OSError:
                pass


def _exit_fd(proc: subprocess.Popen) -> int | None:
    """A pidfd of ``proc`` (readable once it has exited), or None where Linux has none."""
    try:
        return os.pidfd_open(proc.pid)
    except (AttributeError, OSError):  # pragma: no cover - Linux < 5.3
        return None


def _communicate(proc: subprocess.Popen, data: bytes | None, deadline: float) -> tuple[bytes, bytes]:
    """Write ``data`` to the run's stdin and collect its stdout and stderr until its supervisor
    exits (TimeoutError past ``deadline``); then read what the pipes still hold, for at most
    :data:`DRAIN` seconds -- a process that keeps a pipe open cannot hold the run."""
    assert proc.stdout is not None and proc.stderr is not None
    out, err = bytearray(), bytearray()
    sinks = {proc.stdout.fileno(): out, proc.stderr.fileno(): err}
    sel = selectors.DefaultSelector()
    for fd in sinks:
        sel.register(fd, selectors.EVENT_READ)
    view = memoryview(data or b"")
    wfd = -1
    if proc.stdin is not None:
        if view:
            wfd = proc.stdin.fileno()
            os.set_blocking(wfd, False)
            sel.register(wfd, selectors.EVENT_WRITE)
        else:
            proc.stdin.close()
    exit_fd = _exit_fd(proc)
    if exit_fd is not None:
        sel.register(exit_fd, selectors.EVENT_READ)
    reading = set(sinks)

    def read(fd: int) -> None:
        chunk = os.read(fd, 1 << 16)
        if not chunk:
            reading.discard(fd)
            sel.unregister(fd)
            return
        sink = sinks[fd]
        sink += chunk
        if sink is err and len(err) > 2 * STDERR_KEEP:
            del err[STDERR_KEEP : len(err) - STDERR_KEEP]

    try:
        ended = False
        while not ended:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError
            for key, _ in sel.select(left if exit_fd is not None else min(left, 0.05)):
                if key.fd == exit_fd:
                    ended = True
                elif key.fd == wfd:
                    try:
                        view = view[os.write(wfd, view[: 1 << 16]) :]
                    except BlockingIOError:
                        continue
                    except OSError:  # the program closed its stdin: the rest is not wanted
                        view = view[:0]
                    if not view:
                        sel.unregister(wfd)
                        wfd = -1
                        proc.stdin.close()  # type: ignore[union-attr]
                else:
                    read(key.fd)
            if exit_fd is None and proc.poll() is not None:  # pragma: no cover - Linux < 5.3
                ended = True
        proc.wait()
        end = time.monotonic() + DRAIN
        while reading and (left := end - time.monotonic()) > 0:
            ready = select.select(sorted(reading), [], [], left)[0]
            if not ready:
                break
            for fd in ready:
                read(fd)
    finally:
        sel.close()
        if exit_fd is not None:
            os.close(exit_fd)
        close_streams(proc.stdin, proc.stdout, proc.stderr)
    return bytes(out), bytes(err)


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
    """Run ``cmd`` under its supervisor and the limits; every process of the run is killed when
    ``cmd`` exits, on timeout and on interrupt.

    Returns the CompletedProcess (stdout/stderr bytes, ``returncode`` that of ``cmd``: negative
    when a signal killed it).  A timeout raises GraderUnavailable with one line; a run killed
    by the memory limit is seen as a failed allocation (the caller reads ``returncode`` and
    ``stderr``: see :func:`memory_failure`).
    """
    timeout = TIMEOUT if timeout is None else timeout
    memory = MEMORY if memory is None else memory
    proc = _supervised(
        cmd,
        memory=memory,
        backstop=timeout + BACKSTOP,
        stdin=subprocess.PIPE if input is not None else subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=env,
    )
    try:
        out, err = _communicate(proc, input, time.monotonic() + timeout)
    except TimeoutError:
        kill_group(proc)
        raise GraderUnavailable(
            f"{label} did not finish within {timeout:g} s (the time limit of user code; "
            "raise it with --timeout SECONDS): killed"
        ) from None
    except BaseException:
        kill_group(proc)
        raise
    return subprocess.CompletedProcess(list(cmd), proc.returncode, out, err)


class Worker:
    """A child process that runs jobs one after the other under the limits of user code.

    Started on the first :meth:`request` with ``cmd`` (under a supervisor and the limits, as
    :func:`run_limited`: it dies with this process; the current environment), it reads
    length-prefixed job frames on stdin and answers each with a status and a payload (the
    protocol of ``_gpu_child``: ``JOB_HEADER``, ``ANSWER_HEADER``).
    The time limit is per job: a job that has not answered within it is killed with every
    process of the child's run, as is the child when the parent is interrupted while it
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
        self._exit_fd: int | None = None
        self._lock = threading.Lock()

    def _start(self, memory: int, env: dict[str, str]) -> subprocess.Popen:
        self._stderr = tempfile.TemporaryFile()
        self.proc = _supervised(
            self.cmd,
            memory=memory,
            backstop=0,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=self._stderr,
            env=env,
        )
        self._exit_fd = _exit_fd(self.proc)
        self.memory, self.env = memory, env
        return self.proc

    def stop(self) -> None:
        """End the child (and every process of its run) if it runs."""
        if self.proc is not None:
            close_streams(self.proc.stdin, self.proc.stdout)
            kill_group(self.proc)
            self.proc = None
        if self._exit_fd is not None:
            os.close(self._exit_fd)
            self._exit_fd = None
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
                    head = _read_until(proc, ANSWER_HEADER.size, deadline, self._exit_fd)
                    status, n = ANSWER_HEADER.unpack(head)
                    data = _read_until(proc, n, deadline, self._exit_fd)
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


def _read_until(proc: subprocess.Popen, n: int, deadline: float, exit_fd: int | None = None) -> bytes:
    """n bytes from the child's stdout before ``deadline`` (TimeoutError), or EOFError when it
    closes first or when the run has ended (``exit_fd``, a pidfd of its supervisor, readable)
    and nothing more comes within :data:`DRAIN` seconds."""
    fd = proc.stdout.fileno()  # type: ignore[union-attr]
    watched = [fd] if exit_fd is None else [fd, exit_fd]
    chunks, got = [], 0
    while got < n:
        left = deadline - time.monotonic()
        ready = select.select(watched, [], [], left)[0] if left > 0 else []
        if not ready:
            raise TimeoutError
        if fd not in ready and not select.select([fd], [], [], DRAIN)[0]:
            raise EOFError
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
