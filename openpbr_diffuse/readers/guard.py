"""Bounded memory for USD stages: a stage that could need more memory than a budget is opened
first in a child process under an address-space limit.

usd-core trusts the sizes and counts a file declares: a 2 kB corrupt crate file (``.usdc``,
or one inside a ``.usdz``) can make it allocate gigabytes before it reports the corruption,
and a few lines of text whose prims reference each other twice per level compose into 2^n
prims.  So before the reader opens a stage in its own process, :func:`check_stage` opens it
in a child (``_usd_child.py``) whose address space is limited (``RLIMIT_AS``) to what it
uses once usd-core is imported plus :data:`STAGE_BUDGET_MB`; the child opens the stage the
way the reader does (every layer, variants selected, the values of the shading prims read)
and reports whether it ran out of memory or crashed.  Only a stage that the child read
within the budget is then opened here, where it costs the same.

A text layer (``#usda``) of at most :data:`TEXT_DIRECT_BYTES` without any composition arc
(no ``references``, ``payload``, ``inherits``, ``specializes``, ``subLayers`` or value
``clips``) composes only itself, in memory proportional to its text, and is opened
directly (no child: most hand-written files).  The limit needs Linux (``/proc`` gives the
child's address space); elsewhere the child still isolates a crash but is not limited.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import tempfile
from typing import Any

#: Memory a stage may need (MB) beyond usd-core itself: opened first in a child under this
#: limit.  Real assets of up to 10 MB need well under 100 MB.
STAGE_BUDGET_MB = 512
#: Largest text layer without composition arcs opened without the child (bytes).
TEXT_DIRECT_BYTES = 1 << 20

_ARCS = re.compile(rb"references|payload|inherits|specializes|subLayers|clips|clipAssetPaths")
_CHILD = os.path.join(os.path.dirname(os.path.abspath(__file__)), "_usd_child.py")
_MARKERS = tuple(m.encode() for m in ("bad_alloc", "MemoryError", "Cannot allocate memory", "out of memory"))
_PASSED: dict[tuple, bool] = {}


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


def check_stage(path: str, variants: dict | None = None, time: float | None = None) -> None:
    """Raise ValueError (one line naming the file) if opening the stage needs more than
    :data:`STAGE_BUDGET_MB` of memory or crashes usd-core; return if it can be opened here.

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
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (_pxr_folder(), env.get("PYTHONPATH", "")) if p)
    env["PXR_WORK_THREAD_LIMIT"] = "1"  # one thread: no per-thread stacks and arenas in the limit
    env["MALLOC_ARENA_MAX"] = "2"
    cmd = [
        sys.executable,
        _CHILD,
        path,
        str(STAGE_BUDGET_MB << 20),
        json.dumps(variants or {}),
        json.dumps(time),
    ]
    with tempfile.TemporaryFile() as log:
        try:
            proc = subprocess.run(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=log, env=env)
        except OSError:  # no interpreter to start (an embedded Python): open here, unguarded
            return
        code = proc.returncode
        if code == 5:  # usd-core cannot be imported in a child: open here, unguarded
            return
        if code == 3 or _said_out_of_memory(log):  # also a warning: usd-core may go on without a layer
            raise ValueError(
                f"{path}: not read: usd-core needs more than {STAGE_BUDGET_MB} MB of memory to open it "
                f"(a corrupt or self-multiplying file; the readers' limit per stage)"
            )
        if code < 0:
            try:
                name = signal.Signals(-code).name
            except ValueError:
                name = f"signal {-code}"
            raise ValueError(
                f"{path}: not read: usd-core crashed opening it ({name} in a child process limited to "
                f"{STAGE_BUDGET_MB} MB: a corrupt file, or one that needs more memory)"
            )
        if code != 0:
            raise ValueError(f"{path}: not read: usd-core stopped opening it (exit status {code}, in a child process)")
    if len(_PASSED) > 256:
        _PASSED.clear()
    _PASSED[key] = True


__all__ = ["check_stage", "needs_child", "STAGE_BUDGET_MB", "TEXT_DIRECT_BYTES"]
