"""``check … --watch``: a grade after every save, what changed, Ctrl-C, no process left behind."""

from __future__ import annotations

import doctest
import hashlib
import os
import queue
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from openpbr_diffuse.cli import _watch
from openpbr_diffuse.cli.main import main

ROOT = Path(__file__).resolve().parent.parent
SUBJECTS = Path(__file__).resolve().parent / "subjects"
needs_gxx = pytest.mark.skipif(
    shutil.which("g++") is None or not Path("/usr/include/glm/glm.hpp").is_file(),
    reason="g++ and libglm-dev needed: apt-get install g++ libglm-dev",
)
#: seconds allowed for one grade to show up (start-up, a g++ compile and the grade take ~3 s)
BOUND = 60.0


def _roughness_squared(text: str) -> str:
    """The BRDF function of the subject with its roughness squared before use (its albedo kept)."""
    wrong = text.replace("float r = roughness;", "float r = roughness * roughness;", 1)
    assert wrong != text
    return wrong


def _descendants(pid: int) -> set[int]:
    """Every live process below ``pid`` (by parent pid, read from /proc)."""
    children: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:
            continue
        ppid = int(stat.rsplit(")", 1)[1].split()[1])
        children.setdefault(ppid, []).append(int(entry.name))
    found, todo = set(), [pid]
    while todo:
        for c in children.get(todo.pop(), []):
            if c not in found:
                found.add(c)
                todo.append(c)
    return found


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def _leftovers(below: set[int], tool: int, tmp_path: Path) -> list[int]:
    """Live processes that were below the tool, or that run a supervisor of its runs, or a
    file of the test's folder (the subject's compiled harness is cached there)."""
    left = [p for p in below if _alive(p)]
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit() or int(entry.name) == os.getpid():
            continue
        try:
            argv = (entry / "cmdline").read_bytes().split(b"\0")
        except OSError:
            continue
        ours = any(str(tmp_path).encode() in a for a in argv)
        supervisor = any(a.endswith(b"_supervisor.py") for a in argv) and str(tool).encode() in argv
        if (ours or supervisor) and _alive(int(entry.name)):
            left.append(int(entry.name))
    return left


class _Lines:
    """The lines a process writes on a stream, read by a thread, waited for with a deadline."""

    def __init__(self, stream) -> None:
        self.q: queue.Queue = queue.Queue()
        self.seen: list[str] = []
        threading.Thread(target=self._pump, args=(stream,), daemon=True).start()

    def _pump(self, stream) -> None:
        for line in stream:
            self.q.put(line.rstrip("\n"))
        self.q.put(None)

    def until(self, predicate, timeout: float = BOUND) -> list[str]:
        """Lines up to and including the first one for which ``predicate`` holds."""
        end = time.monotonic() + timeout
        got = []
        while True:
            try:
                line = self.q.get(timeout=max(0.0, end - time.monotonic()))
            except queue.Empty:
                raise AssertionError(f"not seen within {timeout:g} s; so far: {self.seen}") from None
            if line is None:
                raise AssertionError(f"the stream ended; so far: {self.seen}")
            self.seen.append(line)
            got.append(line)
            if predicate(line):
                return got


def _verdict(line: str) -> bool:
    return line.startswith("[") and "checks pass" in line


@needs_gxx
def test_a_save_is_graded_again_with_what_changed_and_ctrl_c_leaves_nothing(tmp_path: Path) -> None:
    src = tmp_path / "eon.cpp"
    good = (SUBJECTS / "eon_conforming.cpp").read_text()
    src.write_text(good)
    env = dict(os.environ, PYTHONPATH=str(ROOT), OPENPBR_DIFFUSE_CACHE=str(tmp_path / "cache"))
    cmd = [sys.executable, "-m", "openpbr_diffuse", "check", "--cpp", str(src)]
    tool = subprocess.Popen(
        [*cmd, "--function", "f", "--albedo-function", "albedo", "--watch"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    out, err = _Lines(tool.stdout), _Lines(tool.stderr)
    below: set[int] = set()
    try:
        first = out.until(_verdict)
        assert ": conforms (" in first[-1]
        out.until(lambda line: "watching" in line)

        start = time.monotonic()
        src.write_text(_roughness_squared(good))
        second = out.until(_verdict)
        assert time.monotonic() - start < BOUND
        assert ": does not conform (" in second[-1]
        block = out.until(lambda line: line.startswith("  failing: brdf"))
        assert any(
            line.startswith("  changed: brdf: conforms -> does not conform; max error 2.4e-05 -> ")
            and line.endswith("diagnosis none -> roughness_squared")
            for line in block
        ), block

        # a save that does not compile: one line on stderr, and the watch goes on
        src.write_text(good + "\nnot C++ {\n")
        line = err.until(lambda line: "error:" in line)[-1]
        assert "does not compile" in line and "Traceback" not in line
        # deleted, then back: graded again, the change measured against the last grade
        src.unlink()
        out.until(lambda line: "is gone: waiting for it to come back" in line)
        time.sleep(0.5)
        src.write_text(good)
        back = out.until(_verdict)
        assert ": conforms (" in back[-1]
        assert "  changed: brdf: does not conform -> conforms; max error " in "\n".join(
            out.until(lambda ln: "brdf" in ln)
        )

        below = _descendants(tool.pid)
        tool.send_signal(signal.SIGINT)
        assert tool.wait(timeout=15) == 130
        assert "openpbr-diffuse: interrupted" in err.until(lambda line: "interrupted" in line)[-1]
        assert not any("Traceback" in line for line in err.seen)
        end = time.monotonic() + 5
        while (left := _leftovers(below, tool.pid, tmp_path)) and time.monotonic() < end:
            time.sleep(0.05)
        assert left == []
    finally:
        if tool.poll() is None:
            tool.kill()
            tool.wait()
        for p in below:
            if _alive(p):
                os.kill(p, signal.SIGKILL)


def test_a_save_in_pieces_is_graded_once_whole(tmp_path: Path) -> None:
    """The file changes at every look for a while (an editor writing in pieces): the state
    returned is that of the final content, once it has stayed the same."""
    p = tmp_path / "f.glsl"
    p.write_bytes(b"old")
    old = _watch.file_state(p)
    pieces = [b"vec3 f(", b"vec3 f(vec3 wi", b"vec3 f(vec3 wi) { return wi; }"]
    looks = []

    def sleep(seconds: float) -> None:  # the editor writes one piece between two looks
        looks.append(seconds)
        if pieces:
            p.write_bytes(pieces.pop(0))

    state = _watch.wait_for_change(p, old, sleep=sleep)
    assert state[2] == hashlib.sha256(b"vec3 f(vec3 wi) { return wi; }").hexdigest()
    assert not pieces and len(looks) >= 4


def test_a_touch_without_a_change_is_not_graded_and_a_missing_file_is_waited_for(tmp_path: Path) -> None:
    p = tmp_path / "f.glsl"
    p.write_bytes(b"same")
    graded = _watch.file_state(p)
    events = []

    def sleep(seconds: float) -> None:
        events.append("look")
        if len(events) == 2:
            os.utime(p, ns=(1, 1))  # the time moves, the content does not
        elif len(events) == 4:
            p.unlink()
        elif len(events) == 7:
            p.write_bytes(b"new")

    state = _watch.wait_for_change(p, graded, sleep=sleep, on_missing=lambda: events.append("gone"))
    assert state[2] == hashlib.sha256(b"new").hexdigest()
    assert events.count("gone") == 1


@pytest.mark.parametrize(
    ("extra", "words"),
    [
        (["--json"], "not with --json"),
        (["--implementation", "threejs"], "--watch is for FILE"),
    ],
)
def test_options_a_save_cannot_fix_are_one_line_and_exit_2(tmp_path: Path, capsys, extra, words) -> None:
    src = tmp_path / "results.csv"
    src.write_text("x\n")
    argv = ["check", str(src), "--watch", *extra] if "--implementation" not in extra else ["check", "--watch", *extra]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0]


def test_a_file_missing_at_the_start_is_exit_2(tmp_path: Path, capsys) -> None:
    assert main(["check", "--cpp", str(tmp_path / "nope.cpp"), "--function", "f", "--watch"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "nope.cpp does not exist" in err[0]


def test_a_results_file_is_graded_and_its_change_reported(tmp_path: Path, capsys) -> None:
    """``check FILE --watch`` (two grades, in-process): the second names the values' change."""
    import numpy as np

    from openpbr_diffuse.conformance.deviations import reference
    from openpbr_diffuse.conformance.vectors import default_vectors, write_vectors

    v = default_vectors(["lambert"])
    path = tmp_path / "results.csv"
    write_vectors(v, path, out=reference(v))
    saves = iter([lambda: write_vectors(v, path, out=reference(v) * 1.5)])

    real = _watch.wait_for_change

    def wait(p, graded, **kw):
        if graded is not None:
            next(saves)()
        return real(p, graded, **{**kw, "poll": 0.01, "settle": 0.01})

    args = _parse(["check", str(path), "--watch"])
    orig, _watch.wait_for_change = _watch.wait_for_change, wait
    try:
        assert _watch.run(args, max_grades=2) == 1
    finally:
        _watch.wait_for_change = orig
    text = capsys.readouterr().out
    assert "results.csv: conforms (" in text and "results.csv: does not conform (" in text
    assert "changed: values: conforms -> does not conform; max error 0 -> " in text
    assert np.isfinite(reference(v)).all()


def _parse(argv):
    from openpbr_diffuse.cli.main import _parse as parse
    from openpbr_diffuse.cli.main import build_parser

    return parse(build_parser(), argv)


def test_watch_examples() -> None:
    result = doctest.testmod(_watch, optionflags=doctest.ELLIPSIS)
    assert result.failed == 0 and result.attempted >= 6
