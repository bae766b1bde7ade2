"""``check … --watch``: grade again on every save of the file, and say what changed.

    openpbr-diffuse check --glsl FILE --function f --albedo-function albedo --watch
    openpbr-diffuse check --cpp FILE --function f --watch
    openpbr-diffuse check results.csv --watch

One process keeps everything warm between grades: the GL child that runs GLSL (a
:class:`~openpbr_diffuse.graders.limits.Worker`), the reference values, the vectors and the
property checks' references.  C++ is compiled again after each save (the harness cache is
keyed by the source's hash), the rest is reused.

The file is polled every :data:`POLL` seconds (modification time, size and, for files up to
:data:`HASH_LIMIT` bytes, a SHA-256 of the content); a change is graded once the file has
stayed the same for :data:`SETTLE` seconds, so a save written in pieces is graded once, whole.
A save that leaves the content as it was is not graded again.  A file that does not compile
prints its one-line error and the watch goes on; a deleted file is waited for.  Only FILE is
watched (not the files it includes).  Ctrl-C ends the watch as it ends every command:
``openpbr-diffuse: interrupted``, exit status 130.
"""

from __future__ import annotations

import argparse
import hashlib
import math
import os
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

#: seconds between two looks at the file
POLL = 0.2
#: seconds a changed file must stay the same before it is graded
SETTLE = 0.2
#: files up to this size are hashed at every poll; larger ones only when their time or size moved
HASH_LIMIT = 16 << 20
#: failing checks listed under a verdict
MAX_FAILING = 6

#: a file's state: (mtime_ns, size, sha256 or None), or None when it does not exist
State = tuple


def file_state(path: str | os.PathLike[str], previous: State | None = None) -> State | None:
    """``(mtime_ns, size, sha256)`` of ``path``, or None when it is not a readable file.

    A file larger than :data:`HASH_LIMIT` is hashed only when its time or size differs from
    ``previous`` (its hash is carried over otherwise).

    Example
    -------
    >>> import pathlib, tempfile
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "f.glsl"
    >>> file_state(p) is None
    True
    >>> _ = p.write_text("vec3 f() { return vec3(0); }")
    >>> s = file_state(p)
    >>> import hashlib
    >>> s[1], s[2] == hashlib.sha256(p.read_bytes()).hexdigest()
    (28, True)
    """
    try:
        st = os.stat(path)
        if not os.path.isfile(path):
            return None
        if st.st_size > HASH_LIMIT and previous is not None and previous[:2] == (st.st_mtime_ns, st.st_size):
            return previous
        h = hashlib.sha256()
        with open(path, "rb") as fh:
            for chunk in iter(lambda: fh.read(1 << 20), b""):
                h.update(chunk)
    except OSError:
        return None
    return (st.st_mtime_ns, st.st_size, h.hexdigest())


def wait_for_change(
    path: str | os.PathLike[str],
    graded: State | None,
    *,
    poll: float = POLL,
    settle: float = SETTLE,
    on_missing: Callable[[], None] = lambda: None,
    sleep: Callable[[float], None] = time.sleep,
) -> State:
    """Block until ``path`` holds content other than ``graded``'s and has stayed the same for
    ``settle`` seconds; returns its new state.  ``on_missing`` is called once each time the
    file disappears (it is then waited for).

    Example
    -------
    >>> import pathlib, tempfile
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "f.glsl"
    >>> _ = p.write_text("a")
    >>> old = file_state(p)
    >>> def save(seconds):          # the "editor" saves once while the watch sleeps
    ...     if p.read_text() == "a":
    ...         _ = p.write_text("b")
    >>> wait_for_change(p, old, sleep=save)[1:] == file_state(p)[1:]
    True
    """
    missing = False
    state = file_state(path)
    while True:
        if state is None:
            if not missing:
                missing = True
                on_missing()
        elif graded is None or state[1:] != graded[1:]:
            sleep(settle)
            again = file_state(path, state)
            if again == state:
                return state
            state = again
            continue
        else:
            missing = False  # back, unchanged (e.g. a rename over it with the same content)
        sleep(poll)
        state = file_state(path, state)


@dataclass
class Snapshot:
    """One grade, as the watch compares it: the tier, each check's status and (for the
    values) the max error and diagnosis, and the one-line details of the failing checks."""

    tier: str
    items: dict = field(default_factory=dict)
    failing: list = field(default_factory=list)
    n_checks: int = 0


def _status_word(item_id: str, status: str) -> str:
    if item_id == "values" or item_id.startswith("values."):
        return {"pass": "conforms", "warn": "conforms with warnings", "fail": "does not conform"}.get(status, status)
    return status


def _label(item_id: str) -> str:
    return item_id[len("values.") :] if item_id.startswith("values.") else item_id


def _num(x: float | None) -> str:
    return "-" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{x:.2g}"


def snapshot(checks: list[dict], values: dict[str, tuple[float, str | None]], tier: str) -> Snapshot:
    """A :class:`Snapshot` of graded ``checks`` (id, status, detail; after --expect-fail),
    ``values`` {check id: (max abs error, diagnosis)} and the run's ``tier``.

    Example
    -------
    >>> s = snapshot([{"id": "values.brdf", "status": "fail", "detail": "3 rows"}],
    ...              {"values.brdf": (0.031, "roughness_squared")}, "does not conform")
    >>> s.items["brdf"], s.failing
    ({'status': 'does not conform', 'max error': 0.031, 'diagnosis': 'roughness_squared'}, ['brdf: 3 rows'])
    """
    snap = Snapshot(tier, n_checks=len(checks))
    for c in checks:
        item: dict = {"status": _status_word(c["id"], c["status"])}
        if c["id"] in values:
            item["max error"], item["diagnosis"] = values[c["id"]]
        snap.items[_label(c["id"])] = item
        if c["status"] == "fail":
            snap.failing.append(f"{_label(c['id'])}: {c.get('detail', '')}".rstrip(": "))
    return snap


def describe(item: dict) -> str:
    """One item of a snapshot in words.

    >>> describe({"status": "conforms", "max error": 2.4e-05, "diagnosis": None})
    'conforms; max error 2.4e-05; diagnosis none'
    """
    parts = [item["status"]]
    if "max error" in item:
        parts.append(f"max error {_num(item['max error'])}")
        parts.append(f"diagnosis {item['diagnosis'] or 'none'}")
    return "; ".join(parts)


def changes(old: Snapshot, new: Snapshot) -> list[str]:
    """What changed from one grade to the next, one line per check that changed.

    Example
    -------
    >>> a = Snapshot("does not conform", {"brdf": {"status": "does not conform", "max error": 0.031,
    ...                                            "diagnosis": "roughness_squared"},
    ...                                   "property.energy": {"status": "pass"}})
    >>> b = Snapshot("conforms", {"brdf": {"status": "conforms", "max error": 2.4e-05, "diagnosis": None},
    ...                           "property.energy": {"status": "pass"}})
    >>> changes(a, b)
    ['brdf: does not conform -> conforms; max error 0.031 -> 2.4e-05; diagnosis roughness_squared -> none']
    >>> changes(b, b)
    []
    """
    lines = []
    for name, item in new.items.items():
        before = old.items.get(name)
        if before is None:
            lines.append(f"{name}: (new) {describe(item)}")
            continue
        parts = []
        if before["status"] != item["status"]:
            parts.append(f"{before['status']} -> {item['status']}")
        if "max error" in item and "max error" in before:
            a, b = before["max error"], item["max error"]
            if _num(a) != _num(b):
                parts.append(f"max error {_num(a)} -> {_num(b)}")
            if before["diagnosis"] != item["diagnosis"]:
                parts.append(f"diagnosis {before['diagnosis'] or 'none'} -> {item['diagnosis'] or 'none'}")
        if parts:
            lines.append(f"{name}: " + "; ".join(parts))
    lines += [f"{name}: no longer checked" for name in old.items if name not in new.items]
    return lines


def _grade_code(args: argparse.Namespace) -> tuple[list[dict], dict]:
    """Grade --glsl / --cpp once: its checks and {check id: (max error, diagnosis)}."""
    from ..graders import cli as graders_cli
    from ..graders.errors import GraderUnavailable
    from ..graders.grading import grade_subject

    try:
        subject = graders_cli.subject_from_args(args)
        assert subject is not None
        result = grade_subject(
            subject, quick=args.quick, sampler_model=getattr(args, "sampler_model", None), precision=args.precision
        )
    except GraderUnavailable as exc:
        names = [getattr(args, k, None) for k in ("function", "albedo_function", "sample_function", "pdf_function")]
        missing = graders_cli._missing_function(str(exc), args.glsl or args.cpp, names)
        if missing is None:
            raise
        raise GraderUnavailable(missing) from None
    values = {
        f"values.{q.quantity.replace(' ', '_')}": (float(q.max_abs_error), q.diagnosis)
        for q in result.quantities
        if q.values is not None
    }
    return graders_cli.checks_of(result), values


def _grade_file(args: argparse.Namespace) -> tuple[list[dict], dict]:
    """Grade a results FILE once (as ``check FILE``)."""
    from ..conformance.grade import grade_chunks
    from ..conformance.tiers import check_from_grade
    from ..conformance.vectors import iter_results

    g = grade_chunks(iter_results(args.file), model=args.model, precision=args.precision)
    checks = [check_from_grade("values", g)]
    checks += [c for c in g.properties if c["status"] != "skip"]
    return checks, {"values": (float(g.max_abs_error), g.diagnosis)}


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip() or type(exc).__name__
    return text.splitlines()[0]


def _preflight(args: argparse.Namespace) -> None:
    """What a save cannot fix is reported before the watch (exit 2): conflicting options,
    a missing compiler or GL driver, a FILE that is not there."""
    if args.json:
        raise ValueError("check: --watch prints text for a person; not with --json")
    if getattr(args, "implementation", None) or args.image is not None or args.chart is not None:
        raise ValueError("check: --watch is for FILE, --glsl or --cpp (a file you edit)")
    if args.glsl or args.cpp:
        from ..graders import cpp, glsl, limits
        from ..graders.generic import _names

        if args.file is not None or (args.glsl and args.cpp):
            raise ValueError("check: give one of FILE, --implementation, --glsl, --cpp")
        _names(args.function, args.albedo_function, args.sample_function, args.pdf_function)
        limits.parse_defines(args.define)
        if args.glsl:
            glsl.gl_version()  # GraderUnavailable (exit 2) without a GL 4.3 context
        else:
            cpp.compiler()
    elif args.file is None:
        raise ValueError("check: --watch needs FILE, --glsl FILE or --cpp FILE")
    path = str(args.glsl or args.cpp or args.file)
    if not Path(path).is_file():
        raise ValueError(f"check: {path} does not exist or is not a file")


def run(args: argparse.Namespace, *, max_grades: int | None = None) -> int:
    """Grade FILE, then again after every save, until interrupted (KeyboardInterrupt, which
    the command line turns into exit status 130) or ``max_grades`` grades; returns the exit
    status of the last grade (0 conforms, 1 does not conform, 2 it could not be graded)."""
    from ..conformance.tiers import EXIT, apply_expected, tier_of
    from ..graders import cli as graders_cli
    from ..graders.errors import GraderUnavailable

    _preflight(args)
    path: str = args.glsl or args.cpp or args.file
    name = Path(path).name
    expected = graders_cli.prepare(args, [path])
    grade = _grade_code if (args.glsl or args.cpp) else _grade_file
    if args.glsl or args.cpp:
        graders_cli._exit_on_sigterm()

    def say(text: str, stream: Any = None) -> None:
        print(text, file=stream or sys.stdout, flush=True)

    last: Snapshot | None = None
    graded: State | None = None
    status, n = 2, 0
    while max_grades is None or n < max_grades:
        graded = wait_for_change(path, graded, on_missing=lambda: say(f"{name} is gone: waiting for it to come back"))
        n += 1
        stamp = time.strftime("%H:%M:%S")
        start = time.monotonic()
        try:
            checks, values = grade(args)
        except (GraderUnavailable, ValueError, OSError) as exc:
            status = 2
            say(f"[{stamp}] {name}: error: {_one_line(exc)}", sys.stderr)
            if n == 1:
                say(f"  watching {path} for changes (Ctrl-C to stop)")
            continue
        checks, _notes = apply_expected(checks, expected, str(args.expect_fail or "FILE"))
        tier = tier_of(checks)
        status = EXIT[tier]
        snap = snapshot(checks, values, tier)
        n_pass = sum(c["status"] != "fail" for c in checks)
        lines = [
            f"[{stamp}] {name}: {tier} ({n_pass} of {len(checks)} checks pass; "
            f"graded in {time.monotonic() - start:.1f} s)"
        ]
        if last is None:
            lines += [f"  {k}: {describe(v)}" for k, v in snap.items.items() if "max error" in v]
        else:
            lines += [f"  changed: {c}" for c in changes(last, snap)] or ["  no change since the last grade"]
        lines += [f"  failing: {f}" for f in snap.failing[:MAX_FAILING]]
        if len(snap.failing) > MAX_FAILING:
            lines.append(f"  ... and {len(snap.failing) - MAX_FAILING} more failing checks")
        say("\n".join(lines))
        if n == 1:
            say(f"  watching {path} for changes (Ctrl-C to stop)")
        last = snap
    return status


__all__ = ["changes", "describe", "file_state", "run", "snapshot", "wait_for_change"]
