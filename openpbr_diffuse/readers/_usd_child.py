"""Child process of :mod:`openpbr_diffuse.readers.guard`: open a USD stage under a memory limit.

Run by path (``python _usd_child.py FILE BUDGET_BYTES VARIANTS_JSON TIME``), importing nothing
of the package: it imports usd-core, limits its own address space (``RLIMIT_AS``) to what it
uses after the import plus ``BUDGET_BYTES``, then does what the reader does that can
allocate: opens the stage (every layer, reference and payload), selects the variants in
the session layer and reads every attribute value of the shading prims (crate files read
values lazily).  Exit status: 0 done (whether usd-core accepted the file or not), 3 out of
memory (``MemoryError``, or usd-core's ``std::bad_alloc``, which it may turn into an error or
a warning), 5 usd-core cannot be imported here (the reader then opens the stage itself).
"""

from __future__ import annotations

import json
import os
import sys

OUT_OF_MEMORY = 3
NO_USD = 5
MARKERS = ("bad_alloc", "MemoryError", "Cannot allocate memory", "out of memory")


def _vm_bytes() -> int:
    """This process's address space now (Linux /proc; 0 where unknown)."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmSize:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


def _limit(budget: int) -> None:
    try:
        import resource
    except ImportError:  # no resource limits on this system: the child still isolates a crash
        return
    vm = _vm_bytes()
    if not vm:
        return
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    want = vm + budget
    if hard != resource.RLIM_INFINITY:
        want = min(want, hard)
    if soft == resource.RLIM_INFINITY or want < soft:
        resource.setrlimit(resource.RLIMIT_AS, (want, hard))


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


def _read(path, variants, time):
    from pxr import Usd, UsdShade

    stage = Usd.Stage.Open(path, Usd.Stage.LoadAll)
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


def main(argv: list[str]) -> int:
    path, budget, variants, time = argv[1], int(argv[2]), json.loads(argv[3]), json.loads(argv[4])
    try:
        from pxr import Usd, UsdShade  # noqa: F401 -- imported before the limit is set
    except (ImportError, MemoryError, OSError):  # the reader then opens the stage itself, as without a child
        return NO_USD
    _limit(budget)
    try:
        _read(path, variants, time)
    except MemoryError:
        return OUT_OF_MEMORY
    except BaseException as exc:  # noqa: BLE001 -- usd-core refused the file: the reader says why
        try:
            text = str(exc)
        except Exception:  # noqa: BLE001 -- a message that is not UTF-8
            text = ""
        if any(m in text for m in MARKERS):
            return OUT_OF_MEMORY
    return 0


if __name__ == "__main__":
    code = main(sys.argv)
    sys.stdout.flush()
    os._exit(code)  # no interpreter teardown: a half-read stage need not be freed
