"""Bounded memory for USD stages: a stage that could need more memory than a budget is opened
first in a child process under an address-space limit.

usd-core trusts the sizes and counts a file declares: a 2 kB corrupt crate file (``.usdc``,
or one inside a ``.usdz``) can make it allocate gigabytes before it reports the corruption,
and a few lines of text whose prims reference each other twice per level compose into 2^n
prims.  So before the reader opens a stage in its own process, :func:`check_stage` opens it
in a child (``_usd_child.py``) whose address space is limited (``RLIMIT_AS``): a fresh
process limited to its size once usd-core is imported plus :data:`STAGE_BUDGET_MB` spends
part of that on loading usd-core's plugins, and each stage gets what remains.  The child opens
the stage the way the reader does (every layer, variants selected, the values of the shading
prims read) and reports whether it ran out of memory or crashed.  Only a stage that the child
read within the budget is then opened here, where it costs the same.

The child is started once per process (:data:`CHECKER`, on the first stage that needs it:
one Python start, one import of usd-core and its plugins, about 0.3 s) and checks stage
after stage, each with the same room; a child that dies on a stage -- out of memory,
crashed, killed -- is that stage's failure, and the next stage gets a fresh child.  So does a
stage that takes longer than :data:`STAGE_TIMEOUT` seconds (the child is killed).  The child
is also replaced after :data:`CHILD_FILES` stages, when its address space has grown more than
:data:`CHILD_GROWTH_MB` past its size once the plugins were loaded (what a stage may use is
counted from the size it starts at, so this bounds the child at that much more than a fresh
one), after a stage it could not read within the budget, and when usd-core still holds a
layer read from a file after a stage (the next stage must read its layers from disk).  It dies
with this process (``PR_SET_PDEATHSIG``) and ends when its pipe closes.

A text layer (``#usda``) of at most :data:`TEXT_DIRECT_BYTES` without any composition arc
(no ``references``, ``payload``, ``inherits``, ``specializes``, ``subLayers`` or value
``clips``) composes only itself, in memory proportional to its text, and is opened
directly (no child: most hand-written files).  The limit needs Linux (``/proc`` gives the
child's address space); elsewhere the child still isolates a crash but is not limited.
"""

from __future__ import annotations

import atexit
import concurrent.futures
import json
import os
import re
import select
import signal
import subprocess
import sys
import tempfile
import threading
import time as _time
from typing import Any

#: Memory a stage may need (MB) beyond usd-core itself: opened first in a child under this
#: limit.  Real assets of up to 10 MB need well under 100 MB.
STAGE_BUDGET_MB = 512
#: Largest text layer without composition arcs opened without the child (bytes).
TEXT_DIRECT_BYTES = 1 << 20
#: Seconds the child may take over one stage before it is killed and the stage refused.
STAGE_TIMEOUT = 120.0
#: Stages one child checks before a fresh one takes over.
CHILD_FILES = 200
#: Growth of the child's address space (MB), past its size once usd-core has loaded its plugins,
#: at which a fresh child takes over.
CHILD_GROWTH_MB = 64

_ARCS = re.compile(rb"references|payload|inherits|specializes|subLayers|clips|clipAssetPaths")
_CHILD = os.path.join(os.path.dirname(os.path.abspath(__file__)), "_usd_child.py")
_MARKERS = tuple(m.encode() for m in ("bad_alloc", "MemoryError", "Cannot allocate memory", "out of memory"))
_PASSED: dict[tuple, bool] = {}
_OUT_OF_MEMORY = 3  # the child's exit statuses (``_usd_child``)
_NO_USD = 5


def needs_child(path: str) -> bool:
    """Whether a USD file is opened in the child first (see the module docstring).

    Examples
    --------
    >>> import os, tempfile
    >>> d = tempfile.mkdtemp()
    >>> plain = os.path.join(d, "a.usda")
    >>> _ = open(plain, "w").write('#usda 1.0\\ndef Material "M" {}\\n')
    >>> arcs = os.path.join(d, "b.usda")
    >>> _ = open(arcs, "w").write('#usda 1.0\\ndef "A" (references = @a.usda@) {}\\n')
    >>> needs_child(plain), needs_child(arcs)
    (False, True)
    """
    with open(path, "rb") as f:
        head = f.read(6)
        if head != b"#usda " or os.fstat(f.fileno()).st_size > TEXT_DIRECT_BYTES:
            return True
        return _ARCS.search(head + f.read()) is not None


def _pxr_folder() -> str:
    """The folder usd-core's ``pxr`` package is imported from here (for the child to find it)."""
    import pxr

    return os.path.dirname(os.path.dirname(os.path.abspath(pxr.__file__)))


def _said_out_of_memory(log: Any) -> bool:
    log.seek(0)
    tail = b""
    while True:
        chunk = log.read(1 << 16)
        if not chunk:
            return False
        if any(m in tail + chunk for m in _MARKERS):
            return True
        tail = chunk[-64:]


class StageChecker:
    """The child process that opens stages under the memory limit, one after the other.

    Started on the first :meth:`check` (``cmd``: the command of the child, by default
    ``_usd_child.py``), it gets one job per stage on its stdin and answers on its stdout (the
    protocol of ``_usd_child``); its stderr is a log of the current stage.  Thread-safe: the
    jobs of several threads wait for each other.

    Examples
    --------
    >>> from openpbr_diffuse.readers import BUNDLED_MATERIALS
    >>> checker = StageChecker()
    >>> checker.check(str(BUNDLED_MATERIALS / "paint_variants.usda"))
    ('ok', 0)
    >>> checker.stop()
    """

    def __init__(self, cmd: list[str] | None = None) -> None:
        self.cmd = cmd
        self.proc: subprocess.Popen | None = None
        self.log: Any = None
        self.env: dict[str, str] | None = None
        self.owner = 0
        self.files = 0
        self._lock = threading.Lock()

    def _start(self) -> subprocess.Popen:
        env = dict(os.environ)
        self.env = dict(env)
        env["PYTHONPATH"] = os.pathsep.join(p for p in (_pxr_folder(), env.get("PYTHONPATH", "")) if p)
        env["PXR_WORK_THREAD_LIMIT"] = "1"  # one thread: no per-thread stacks and arenas in the limit
        env["MALLOC_ARENA_MAX"] = "2"
        cmd = self.cmd or [sys.executable, _CHILD]
        self.log = tempfile.TemporaryFile()
        self.owner, self.files = os.getpid(), 0
        self.proc = _spawn(
            [*cmd, str(os.getpid())], stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=self.log, env=env
        )
        return self.proc

    def forget(self) -> None:
        """Drop the child without ending it (in a forked copy of this process: it is the parent's)."""
        if self.proc is not None:
            for stream in (self.proc.stdin, self.proc.stdout):
                try:
                    stream.close()  # type: ignore[union-attr]
                except OSError:
                    pass
            self.proc = None
        if self.log is not None:
            self.log.close()
            self.log = None

    def stop(self, kill: bool = False) -> None:
        """End the child, if one runs: close its stdin (it exits) or, with ``kill``, SIGKILL it."""
        proc = self.proc
        if proc is None or self.owner != os.getpid():
            self.forget()
            return
        try:
            proc.stdin.close()  # type: ignore[union-attr]
        except OSError:
            pass
        if not kill:
            try:
                proc.wait(timeout=1.0)
            except subprocess.TimeoutExpired:
                kill = True
        if kill and proc.poll() is None:
            proc.kill()
        proc.wait()
        self.forget()

    def _answer(self, deadline: float) -> bytes:
        """What the child wrote up to the end of its answer line, or until its stdout closed."""
        fd = self.proc.stdout.fileno()  # type: ignore[union-attr]
        got = b""
        while not got.endswith(b"\n"):
            left = deadline - _time.monotonic()
            if left <= 0 or not select.select([fd], [], [], left)[0]:
                raise TimeoutError
            chunk = os.read(fd, 1 << 16)
            if not chunk:
                break
            got += chunk
        return got

    def check(
        self,
        path: str,
        variants: dict | None = None,
        time: float | None = None,
        *,
        budget_mb: int | None = None,
        timeout: float | None = None,
    ) -> tuple[str, int]:
        """Open the stage ``path`` in the child; return ``(outcome, code)``: ``("ok", 0)``,
        ``("memory", status)`` (out of memory), ``("died", exit status)`` (negative: the
        signal), ``("timeout", 0)`` or ``("unguarded", status)`` (no child can run usd-core
        here: the caller opens the stage itself)."""
        job = {
            "path": os.path.abspath(path),
            "budget": (STAGE_BUDGET_MB if budget_mb is None else budget_mb) << 20,
            "variants": variants or {},
            "time": time,
        }
        line = json.dumps(job).encode() + b"\n"
        with self._lock:
            for attempt in range(2):
                if self.owner != os.getpid():
                    self.forget()
                if self.proc is None or self.proc.poll() is not None or self.env != dict(os.environ):
                    self.stop()
                    try:
                        self._start()
                    except OSError:  # no interpreter to start (an embedded Python): open here, unguarded
                        self.forget()
                        return "unguarded", 0
                deadline = _time.monotonic() + (STAGE_TIMEOUT if timeout is None else timeout)
                self.log.seek(0)
                self.log.truncate()
                try:
                    try:
                        self.proc.stdin.write(line)  # type: ignore[union-attr]
                        self.proc.stdin.flush()  # type: ignore[union-attr]
                    except OSError:  # the child had ended before this stage
                        got = b""
                    else:
                        got = self._answer(deadline)
                    if got.startswith(b"+") and got.endswith(b"\n"):
                        return self._done(json.loads(got[1:]))
                    code = self.proc.wait(timeout=max(0.1, deadline - _time.monotonic()))  # type: ignore[union-attr]
                except (TimeoutError, subprocess.TimeoutExpired):
                    self.stop(kill=True)
                    return "timeout", 0
                except BaseException:  # interrupted: the child's half-done stage must not answer the next
                    self.stop(kill=True)
                    raise
                said_oom = _said_out_of_memory(self.log)
                self.stop(kill=True)
                if not got.startswith(b"+"):  # it ended before it took the stage
                    if code == _NO_USD:
                        return "unguarded", code
                    if attempt == 0:
                        continue
                if code == _OUT_OF_MEMORY or said_oom:
                    return "memory", code
                return "died", code
        raise AssertionError("unreachable")  # pragma: no cover

    def _done(self, answer: dict) -> tuple[str, int]:
        self.files += 1
        said_oom = answer["status"] != 0 or _said_out_of_memory(self.log)
        if (
            said_oom
            or answer["layers"]
            or self.files >= CHILD_FILES
            or answer["vm"] > answer["warm"] + (CHILD_GROWTH_MB << 20)
        ):
            self.stop()
        return ("memory", answer["status"]) if said_oom else ("ok", 0)


def _spawn(cmd: list[str], **kw: Any) -> subprocess.Popen:
    """Popen ``cmd`` from a thread that lives as long as this process: ``PR_SET_PDEATHSIG``
    fires when the *thread* that started the child ends, not the process."""
    global _SPAWNER
    if threading.current_thread() is threading.main_thread():
        return subprocess.Popen(cmd, **kw)
    with _SPAWNER_LOCK:
        if _SPAWNER is None:
            _SPAWNER = concurrent.futures.ThreadPoolExecutor(1, thread_name_prefix="usd-guard-spawn")
    return _SPAWNER.submit(lambda: subprocess.Popen(cmd, **kw)).result()


_SPAWNER: concurrent.futures.ThreadPoolExecutor | None = None
_SPAWNER_LOCK = threading.Lock()
#: the process's child (started on first use, stopped at exit, dropped in a forked copy)
CHECKER = StageChecker()
atexit.register(CHECKER.stop)
if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=CHECKER.forget)


def check_stage(path: str, variants: dict | None = None, time: float | None = None) -> None:
    """Raise ValueError (one line naming the file) if opening the stage needs more than
    :data:`STAGE_BUDGET_MB` of memory, crashes usd-core or takes more than
    :data:`STAGE_TIMEOUT` seconds (in :data:`CHECKER`'s child); return if it can be opened here.

    Examples
    --------
    >>> from openpbr_diffuse.readers import BUNDLED_MATERIALS
    >>> check_stage(str(BUNDLED_MATERIALS / "paint_variants.usda"))
    """
    path = os.fspath(path)
    if not needs_child(path):
        return
    st = os.stat(path)
    key = (os.path.abspath(path), st.st_size, st.st_mtime_ns, json.dumps(variants or {}, sort_keys=True), time)
    if key in _PASSED:
        return
    outcome, code = CHECKER.check(path, variants, time)
    if outcome == "unguarded":  # usd-core cannot run in a child here: open here, unguarded
        return
    if outcome == "memory":  # also a warning: usd-core may go on without a layer
        raise ValueError(
            f"{path}: not read: usd-core needs more than {STAGE_BUDGET_MB} MB of memory to open it "
            f"(a corrupt or self-multiplying file; the readers' limit per stage)"
        )
    if outcome == "timeout":
        raise ValueError(
            f"{path}: not read: usd-core did not finish opening it within {STAGE_TIMEOUT:g} s "
            f"(in a child process; the readers' limit per stage)"
        )
    if outcome == "died":
        if code < 0:
            try:
                name = signal.Signals(-code).name
            except ValueError:
                name = f"signal {-code}"
            raise ValueError(
                f"{path}: not read: usd-core crashed opening it ({name} in a child process limited to "
                f"{STAGE_BUDGET_MB} MB: a corrupt file, or one that needs more memory)"
            )
        raise ValueError(f"{path}: not read: usd-core stopped opening it (exit status {code}, in a child process)")
    if len(_PASSED) > 256:
        _PASSED.clear()
    _PASSED[key] = True


__all__ = [
    "check_stage",
    "needs_child",
    "StageChecker",
    "CHECKER",
    "STAGE_BUDGET_MB",
    "TEXT_DIRECT_BYTES",
    "STAGE_TIMEOUT",
    "CHILD_FILES",
    "CHILD_GROWTH_MB",
]
