"""Child process of :mod:`openpbr_diffuse.readers.guard`: open USD stages under a memory limit.

Run by path (``python _usd_child.py PARENT_PID``), importing nothing of the package.  It asks
to be killed when the thread that started it ends (``PR_SET_PDEATHSIG``, checked against
``PARENT_PID`` right after), imports usd-core once, reads a small stage held in memory (so
usd-core loads its plugins now: :func:`warm_up`), then serves jobs until its stdin closes.
A job is one JSON line ``{"path", "budget", "variants", "time"}``; for each the child

1. writes ``+`` (the job was received: a child that dies before it had not started the job),
2. limits its address space (``RLIMIT_AS``) to what it uses now plus what a fresh process
   limited to its size after the import plus ``budget`` bytes has left once the plugins are
   loaded (so every job gets the same room, whatever the jobs before it left behind),
3. does what the reader does that can allocate: opens the stage (every layer, reference and
   payload), selects the variants in the session layer and reads every attribute value of
   the shading prims (crate files read values lazily),
4. lifts the limit again and answers one JSON line ``{"status", "base", "warm", "vm", "rss",
   "layers"}``: status 0 done (whether usd-core accepted the file or not) or 3 out of memory
   (``MemoryError``, or usd-core's ``std::bad_alloc`` turned into an error); its address space
   after the import, after the warm-up and after the job, its resident memory after the job
   (bytes); and how many layers read from files usd-core still holds.

Exit status 5 at the start: usd-core cannot be imported here (the reader then opens the stage
itself).  What usd-core prints goes to stderr, the parent's log of the current job; the
answers go to a private copy of stdout.
"""

from __future__ import annotations

import ctypes
import gc
import json
import os
import signal
import sys
from typing import BinaryIO

try:
    import resource
except ImportError:  # not a Unix system
    resource = None  # type: ignore[assignment]

OUT_OF_MEMORY = 3
NO_USD = 5
MARKERS = ("bad_alloc", "MemoryError", "Cannot allocate memory", "out of memory")
PR_SET_PDEATHSIG = 1
WARM_UP = '#usda 1.0\ndef Material "M"\n{\n    def Shader "S"\n    {\n        uniform token info:id = "UsdPreviewSurface"\n    }\n}\n'


def _status_bytes(field: str) -> int:
    """A ``/proc/self/status`` size field (``VmSize``, ``VmRSS``) in bytes; 0 where unknown."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith(field + ":"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


def _die_with(parent: int) -> None:
    """SIGKILL when the thread that started this process ends (Linux); exit if it already has."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(PR_SET_PDEATHSIG, ctypes.c_ulong(signal.SIGKILL), 0, 0, 0)
    except (OSError, AttributeError):  # not Linux: the child still ends when its stdin closes
        pass
    if os.getppid() != parent:
        os._exit(0)


def _set_soft(value: int | None) -> None:
    """Set the soft address-space limit to ``value`` bytes (None: none), at most the hard one."""
    if resource is None:  # no resource limits on this system: the child still isolates a crash
        return
    _, hard = resource.getrlimit(resource.RLIMIT_AS)
    soft = resource.RLIM_INFINITY if value is None else value
    if hard != resource.RLIM_INFINITY and (soft == resource.RLIM_INFINITY or soft > hard):
        soft = hard
    resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


def _variants(stage, variants):
    pending = dict(variants)
    for _ in range(len(pending) + 2):
        progressed = False
        for prim in stage.TraverseAll():
            vsets = prim.GetVariantSets()
            for name in vsets.GetNames():
                if name in pending:
                    vs = vsets.GetVariantSet(name)
                    if pending[name] in vs.GetVariantNames() and vs.GetVariantSelection() != pending[name]:
                        vs.SetVariantSelection(pending[name])
                        progressed = True
        if not progressed:
            break


def _read(stage, variants, time):
    from pxr import Usd, UsdShade

    if stage is None:
        return
    if variants:
        stage.SetEditTarget(Usd.EditTarget(stage.GetSessionLayer()))
        _variants(stage, variants)
    tc = Usd.TimeCode(time) if time is not None else Usd.TimeCode.Default()
    for prim in stage.TraverseAll():
        if not (prim.IsA(UsdShade.Shader) or prim.IsA(UsdShade.Material) or prim.IsA(UsdShade.NodeGraph)):
            continue
        for attr in prim.GetAttributes():
            attr.Get(tc)
            if attr.GetNumTimeSamples() > 0:
                attr.Get(Usd.TimeCode(attr.GetTimeSamples()[0]))


def warm_up() -> None:
    """Read a stage held in memory: usd-core loads its plugins and schemas, once per process
    (hundreds of MB of address space), before the first limit is set."""
    from pxr import Sdf, Usd

    layer = Sdf.Layer.CreateAnonymous(".usda")
    layer.ImportFromString(WARM_UP)
    _read(Usd.Stage.Open(layer), {}, None)
    gc.collect()


def run_job(job: dict, allowance: int, start: int | None) -> int:
    """Read one stage with ``allowance`` bytes of address space beyond what this process uses
    now (never above ``start``, the limit it started with, None for none, which is restored
    afterwards); its status, 0 or :data:`OUT_OF_MEMORY`."""
    from pxr import Usd

    if allowance <= 0:  # a fresh process would run out of memory loading usd-core's plugins
        return OUT_OF_MEMORY
    vm = _status_bytes("VmSize")
    if vm:
        want = vm + max(allowance, 0)
        _set_soft(want if start is None else min(want, start))
    try:
        _read(Usd.Stage.Open(job["path"], Usd.Stage.LoadAll), job.get("variants") or {}, job.get("time"))
    except MemoryError:
        return OUT_OF_MEMORY
    except BaseException as exc:  # noqa: BLE001 -- usd-core refused the file: the reader says why
        try:
            text = str(exc)
        except Exception:  # noqa: BLE001 -- a message that is not UTF-8
            text = ""
        if any(m in text for m in MARKERS):
            return OUT_OF_MEMORY
    finally:
        gc.collect()  # the stage (held by a traceback, say) and its layers go before the limit is lifted
        _set_soft(start)
    return 0


def serve(jobs: BinaryIO, answers: BinaryIO) -> int:
    """Answer the jobs of ``jobs`` (binary lines) on ``answers`` until ``jobs`` closes.

    A fresh process that opens a stage under ``VmSize after the import + budget`` spends part
    of the budget on loading usd-core's plugins; each job here gets what remains of it after
    :func:`warm_up` (the same for every job), on top of what the process uses when it starts.
    """
    from pxr import Sdf

    start = None
    if resource is not None:
        soft = resource.getrlimit(resource.RLIMIT_AS)[0]
        start = None if soft == resource.RLIM_INFINITY else soft
    base = _status_bytes("VmSize")
    try:
        warm_up()
    except BaseException:  # noqa: BLE001 -- then each job pays for the plugins, as in a fresh process
        pass
    warm = _status_bytes("VmSize")
    for line in iter(jobs.readline, b""):
        answers.write(b"+")
        answers.flush()
        job = json.loads(line)
        status = run_job(job, base + int(job["budget"]) - warm, start)
        sys.stderr.flush()
        answer = {
            "status": status,
            "base": base,
            "warm": warm,
            "vm": _status_bytes("VmSize"),
            "rss": _status_bytes("VmRSS"),
            "layers": sum(not layer.anonymous for layer in Sdf.Layer.GetLoadedLayers()),
        }
        answers.write(json.dumps(answer).encode() + b"\n")
        answers.flush()
    return 0


def main(argv: list[str]) -> int:
    _die_with(int(argv[1]))
    try:
        from pxr import Usd, UsdShade  # noqa: F401 -- imported before any limit is set
    except (ImportError, MemoryError, OSError):  # the reader then opens the stage itself, as without a child
        return NO_USD
    answers = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)  # what usd-core prints on stdout goes to the job's log too
    return serve(sys.stdin.buffer, answers)


if __name__ == "__main__":
    code = main(sys.argv)
    sys.stdout.flush()
    os._exit(code)  # no interpreter teardown
