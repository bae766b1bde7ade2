"""Supervisor of one run of user code: it owns the run's whole process tree.

The parent (:mod:`.limits`) runs this file as a script, with the standard library only::

    python -I -S _supervisor.py PARENT_PID BACKSTOP MEMORY NPROC_EXTRA CMD...

It makes itself a *child subreaper* (``prctl(PR_SET_CHILD_SUBREAPER)``: a process of the run
whose parent ends, even one that left the session with ``setsid``, becomes its child) and
asks for ``SIGUSR1`` when its parent dies (``PR_SET_PDEATHSIG``, checked against
``PARENT_PID`` right after, which closes the race of a parent that died first).  It then
starts ``CMD`` with the limits of user code: ``RLIMIT_AS`` = ``MEMORY`` bytes, ``RLIMIT_NPROC``
= the threads of the user now + ``NPROC_EXTRA``, no core files -- each the smaller of that and
the limit in force -- and ``PR_SET_PDEATHSIG(SIGKILL)``, so the program dies with it.  ``CMD``
gets the supervisor's standard streams; the supervisor keeps none of them open.

The run ends when the program exits, when the parent dies (the death signal, or a changed
``getppid()``, checked every 0.25 s), at ``SIGTERM``/``SIGINT``/``SIGHUP``, or ``BACKSTOP``
seconds after the start (0: none).  Every process of the run that is still there is then
killed with ``SIGKILL`` -- the descendants found through the ``/proc/*/stat`` parent links,
again and again until there are none, each signalled through a pidfd after checking its
parent once more -- and reaped.  The supervisor then exits as the program did: with its exit
status, or killed by its signal (without a core file); after a stop or the backstop, 128 + the
signal, or 124.
"""

from __future__ import annotations

import ctypes
import os
import resource
import signal
import sys
import time

PR_SET_PDEATHSIG = 1
PR_SET_DUMPABLE = 4
PR_SET_CHILD_SUBREAPER = 36
#: the signal the supervisor gets when its parent dies
PARENT_DIED = signal.SIGUSR1
#: signals that end the run
STOPS = (signal.SIGTERM, signal.SIGINT, signal.SIGHUP)
#: exit status after the backstop time
BACKSTOP_STATUS = 124
#: how long killing the tree may take (a process in uninterruptible sleep), seconds
KILL_PATIENCE = 10.0

_libc = ctypes.CDLL(None, use_errno=True)


def prctl(option: int, value: int) -> None:
    """``prctl(option, value, 0, 0, 0)``; OSError when it fails."""
    if _libc.prctl(option, ctypes.c_ulong(value), 0, 0, 0) != 0:
        err = ctypes.get_errno()
        raise OSError(err, f"prctl({option}): {os.strerror(err)}")


def _stat(pid: int) -> tuple[bytes, int] | None:
    """(state, parent pid) of ``pid`` from /proc, or None when it is gone."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            data = f.read()
    except OSError:
        return None
    fields = data[data.rfind(b")") + 2 :].split()  # the name may hold spaces and ')'
    return fields[0], int(fields[1])


def descendants(root: int) -> list[int]:
    """Every process below ``root``, from the parent links in /proc/*/stat.

    >>> import subprocess
    >>> child = subprocess.Popen(["sleep", "5"])
    >>> child.pid in descendants(os.getpid())
    True
    >>> child.kill(); child.wait()
    -9
    """
    children: dict[int, list[int]] = {}
    for name in os.listdir("/proc"):
        if name.isdigit():
            st = _stat(int(name))
            if st is not None:
                children.setdefault(st[1], []).append(int(name))
    found, stack = [], [root]
    while stack:
        for child in children.get(stack.pop(), ()):
            found.append(child)
            stack.append(child)
    return found


def _kill(pid: int, tree: set[int]) -> None:
    """SIGKILL ``pid`` if its parent is still in ``tree`` (the pid was not reused meanwhile)."""
    try:
        fd = os.pidfd_open(pid)
    except OSError:
        return
    try:
        st = _stat(pid)
        if st is not None and st[1] in tree:
            signal.pidfd_send_signal(fd, signal.SIGKILL)
    except OSError:
        pass
    finally:
        os.close(fd)


def reap(program: int, status: int | None) -> int | None:
    """Reap every finished child; returns the program's wait status once it is reaped."""
    while True:
        try:
            pid, st = os.waitpid(-1, os.WNOHANG)
        except ChildProcessError:
            return status
        if pid == 0:
            return status
        if pid == program:
            status = st


def kill_tree(program: int, status: int | None) -> int | None:
    """SIGKILL and reap every descendant until none is left; returns the program's status."""
    me = os.getpid()
    give_up = time.monotonic() + KILL_PATIENCE
    while True:
        status = reap(program, status)
        below = descendants(me)
        if not below or time.monotonic() > give_up:
            return status
        tree = {me, *below}
        for pid in below:
            _kill(pid, tree)
        time.sleep(0.001)


def user_threads(uid: int) -> int:
    """How many threads the real user ``uid`` runs now (what RLIMIT_NPROC counts).

    >>> import threading
    >>> user_threads(os.getuid()) >= threading.active_count()
    True
    """
    n = 0
    for name in os.listdir("/proc"):
        if not name.isdigit():
            continue
        try:
            with open(f"/proc/{name}/status") as f:
                real, threads = -1, 1
                for line in f:
                    if line.startswith("Uid:"):
                        real = int(line.split()[1])
                    elif line.startswith("Threads:"):
                        threads = int(line.split()[1])
        except (OSError, ValueError, IndexError):
            continue
        if real == uid:
            n += threads
    return n


def lower_limit(which: int, value: int) -> None:
    """Set soft and hard ``which`` to ``value``, or to the soft limit in force when lower."""
    soft, hard = resource.getrlimit(which)
    for current in (soft, hard):
        if current != resource.RLIM_INFINITY:
            value = min(value, current)
    resource.setrlimit(which, (value, value))


def _start(cmd: list[str], memory: int, nproc: int) -> int:
    me = os.getpid()
    pid = os.fork()
    if pid:
        return pid
    try:  # the child: default signal handling, the limits, then the program
        signal.pthread_sigmask(signal.SIG_SETMASK, [])
        for sig in (signal.SIGPIPE, signal.SIGXFSZ):
            signal.signal(sig, signal.SIG_DFL)
        prctl(PR_SET_PDEATHSIG, signal.SIGKILL)
        if os.getppid() != me:
            os._exit(125)
        lower_limit(resource.RLIMIT_CORE, 0)
        lower_limit(resource.RLIMIT_AS, memory)
        lower_limit(resource.RLIMIT_NPROC, nproc)
        os.execvp(cmd[0], cmd)
    except BaseException as exc:  # noqa: BLE001 - anything: one line on stderr, status 127
        try:
            why = exc.strerror if isinstance(exc, OSError) and exc.strerror else exc
            os.write(2, f"cannot run {cmd[0]}: {why}\n".encode())
        finally:
            os._exit(127)
    return 0  # pragma: no cover - execvp does not return


def main(argv: list[str]) -> int:
    parent, backstop, memory, extra = int(argv[1]), float(argv[2]), int(argv[3]), int(argv[4])
    cmd = argv[5:]
    waited = {signal.SIGCHLD, PARENT_DIED, *STOPS}
    signal.pthread_sigmask(signal.SIG_BLOCK, waited)
    prctl(PR_SET_CHILD_SUBREAPER, 1)
    prctl(PR_SET_PDEATHSIG, PARENT_DIED)
    if os.getppid() != parent:
        return 125
    program = _start(cmd, memory, user_threads(os.getuid()) + extra)
    null = os.open(os.devnull, os.O_RDWR)
    for fd in (0, 1, 2):  # the program holds the streams; EOF comes when the run is over
        os.dup2(null, fd)
    os.close(null)
    deadline = time.monotonic() + backstop if backstop > 0 else None
    status: int | None = None
    code = None
    while status is None and code is None:
        wait = 0.25 if deadline is None else max(0.0, min(0.25, deadline - time.monotonic()))
        info = signal.sigtimedwait(waited, wait)
        if info is not None and info.si_signo in STOPS:
            code = 128 + info.si_signo
        elif os.getppid() != parent:
            code = 128 + signal.SIGKILL
        elif deadline is not None and time.monotonic() >= deadline:
            code = BACKSTOP_STATUS
        status = reap(program, status)
    status = kill_tree(program, status)
    if code is not None or status is None:
        return BACKSTOP_STATUS if code is None else code
    if os.WIFSIGNALED(status):  # end as the program did, without a core file of our own
        sig = os.WTERMSIG(status)
        prctl(PR_SET_DUMPABLE, 0)
        if sig != signal.SIGKILL:
            signal.signal(sig, signal.SIG_DFL)
        signal.pthread_sigmask(signal.SIG_UNBLOCK, [sig])
        os.kill(os.getpid(), sig)
        return 128 + sig
    return os.waitstatus_to_exitcode(status)


if __name__ == "__main__":
    sys.exit(main(sys.argv))
