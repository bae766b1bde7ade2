"""Running user-supplied programs (their compiler, their compiled code) under limits.

``check --cpp`` and ``report --cpp`` compile and run the given code with the user's rights;
this module bounds what that can cost: each program runs in a session (process group) of its
own, with a wall-time limit (:data:`DEFAULT_TIMEOUT`, ``--timeout``) and an address-space
limit (:data:`DEFAULT_MEMORY`), and its whole group is killed on timeout or when the
grading process is interrupted (Ctrl-C, SIGTERM), so nothing is left spinning.

Examples
--------
>>> run_limited(["true"]).returncode
0
>>> try:
...     run_limited(["sleep", "5"], timeout=0.2, what="sleep")
... except GraderTimeout as e:
...     print(e)
sleep did not finish within 0.2 s (see --timeout)
"""
from __future__ import annotations

import os
import re
import resource
import signal
import subprocess

from .errors import GraderUnavailable

#: Seconds a compile or a run of user code may take (``--timeout``).
DEFAULT_TIMEOUT = 60.0
#: Bytes of address space a compile or a run may map (4 GiB).
DEFAULT_MEMORY = 4 << 30

_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")


class GraderTimeout(GraderUnavailable):
    """User code (or its compiler) ran past its time limit and was killed."""


def check_identifier(name: str, option: str) -> str:
    """``name`` when it is a C/GLSL identifier, else ``ValueError`` naming ``option``."""
    if not isinstance(name, str) or not _IDENTIFIER.match(name):
        raise ValueError(f"{option}: {name!r} is not a function name (letters, digits and _, not starting "
                         f"with a digit)")
    return name


def check_define(value: str) -> tuple[str, str]:
    """``NAME=VALUE`` (or ``NAME``) split and checked: NAME an identifier, VALUE one plain line."""
    name, _, val = str(value).partition("=")
    if not _IDENTIFIER.match(name):
        raise ValueError(f"--define: {value!r} is not NAME or NAME=VALUE (NAME an identifier)")
    if any(c in val for c in "\n\r\\#") or any(ord(c) < 32 for c in val):
        raise ValueError(f"--define: the value of {name} may not hold newlines, '#', backslashes or "
                         f"control characters")
    return name, val or "1"


def _limits(memory: int):
    def apply():
        resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
        resource.setrlimit(resource.RLIMIT_CORE, (0, 0))
    return apply


def _kill_group(p: subprocess.Popen) -> None:
    try:
        os.killpg(p.pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass
    p.wait()


def run_limited(cmd: list[str], *, input: bytes | None = None, timeout: float | None = None,
                memory: int | None = None, what: str | None = None) -> subprocess.CompletedProcess:
    """Run ``cmd`` in its own process group under a time and memory limit; bytes in and out.

    Raises
    ------
    GraderTimeout
        The program did not finish within ``timeout`` seconds (its group is killed).
    """
    timeout = DEFAULT_TIMEOUT if timeout is None else float(timeout)
    if not timeout > 0:
        raise ValueError(f"--timeout must be > 0 seconds; got {timeout}")
    p = subprocess.Popen(cmd, stdin=subprocess.PIPE if input is not None else subprocess.DEVNULL,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True,
                         preexec_fn=_limits(DEFAULT_MEMORY if memory is None else int(memory)))
    try:
        out, err = p.communicate(input, timeout=timeout)
    except subprocess.TimeoutExpired:
        _kill_group(p)
        raise GraderTimeout(f"{what or cmd[0]} did not finish within {timeout:g} s (see --timeout)") from None
    except BaseException:
        _kill_group(p)
        raise
    if p.returncode is not None:  # the program ended; anything it left in its group goes too
        try:
            os.killpg(p.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
    return subprocess.CompletedProcess(cmd, p.returncode, out, err)


__all__ = ["DEFAULT_TIMEOUT", "DEFAULT_MEMORY", "GraderTimeout", "run_limited", "check_identifier", "check_define"]
