"""User code (--cpp/--glsl) runs in a child process under a wall-time and memory limit."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from openpbr_diffuse.graders import limits
from openpbr_diffuse.graders.errors import GraderUnavailable

ROOT = Path(__file__).resolve().parents[1]
needs_gxx = pytest.mark.skipif(
    shutil.which("g++") is None or not Path("/usr/include/glm/glm.hpp").is_file(), reason="g++ and libglm-dev needed"
)


def _processes_with(marker: str) -> list[str]:
    found = []
    for pid in os.listdir("/proc"):
        if not pid.isdigit():
            continue
        try:
            cmd = Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        if marker in cmd:
            found.append(f"{pid}: {cmd}")
    return found


def _check(args: list[str], tmp_path: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(ROOT), OPENPBR_DIFFUSE_CACHE=str(tmp_path / "cache"))
    return subprocess.run(
        [sys.executable, "-m", "openpbr_diffuse", "check", *args],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
        check=False,
    )


@needs_gxx
def test_cpp_infinite_loop_is_killed_within_timeout(tmp_path: Path) -> None:
    src = tmp_path / "spin_subject.cpp"
    src.write_text(
        "#include <glm/glm.hpp>\n"
        "glm::vec3 f(glm::vec3 wi, glm::vec3 wo, float r, glm::vec3 rho) {\n"
        "  volatile int x = 0; while (true) { x = x + 1; } return rho; }\n"
    )
    start = time.monotonic()
    run = _check(["--cpp", str(src), "--function", "f", "--timeout", "3"], tmp_path)
    elapsed = time.monotonic() - start
    assert run.returncode == 2, run.stderr
    assert "did not finish within 3 s" in run.stderr
    assert len(run.stderr.strip().splitlines()) == 1
    assert elapsed < 3 + 60  # compile time included; the bound asked is timeout + 5 s on the run
    time.sleep(0.2)
    assert _processes_with(str(tmp_path / "cache")) == []


@needs_gxx
def test_compiler_including_dev_zero_hits_a_limit(tmp_path: Path) -> None:
    src = tmp_path / "zero.cpp"
    src.write_text('#include "/dev/zero"\n')
    run = _check(["--cpp", str(src), "--function", "f", "--timeout", "20"], tmp_path)
    assert run.returncode == 2
    assert len(run.stderr.strip().splitlines()) == 1
    assert "memory limit" in run.stderr or "did not finish" in run.stderr
    assert _processes_with("cc1plus") == [] or all(str(tmp_path) not in p for p in _processes_with("cc1plus"))


def test_timeout_kills_the_whole_process_group(tmp_path: Path) -> None:
    marker = tmp_path / "grandchild-marker"
    # the child starts a grandchild that would outlive it; both must go
    code = f"import subprocess, time; subprocess.Popen(['sh', '-c', 'sleep 300; echo {marker}']); time.sleep(300)"
    with pytest.raises(GraderUnavailable, match="did not finish within 3 s"):
        limits.run_limited([sys.executable, "-c", code], label="spinner", timeout=3)
    time.sleep(0.2)
    assert _processes_with(str(marker)) == []


def test_memory_limit_applies_in_the_child() -> None:
    run = limits.run_limited([sys.executable, "-c", "b = bytearray(2**31)"], label="hog", memory=2**30)
    assert run.returncode != 0
    assert limits.memory_message(run.stderr) or b"MemoryError" in run.stderr


def _gl_or_skip():
    pytest.importorskip("moderngl")
    from openpbr_diffuse.graders import glsl

    try:
        glsl.gl_version()
    except GraderUnavailable as exc:
        pytest.skip(str(exc))
    return glsl


def _worker_pids() -> list[int]:
    return [int(p.split(":")[0]) for p in _processes_with("_gpu_child.py") if " gl" in p]


def test_glsl_runs_in_a_killable_child(tmp_path: Path) -> None:
    """A run past the time limit is killed with its child's process group; the next run
    starts a new child."""
    import numpy as np

    glsl = _gl_or_skip()
    k = glsl.Kernel(code="float twice(float x) { return 2.0 * x; }", n_in=1, n_out=1, body="OUT(0) = twice(IN(0));")
    assert np.allclose(k.run(np.arange(5, dtype=np.float32)).ravel(), 2 * np.arange(5))
    old = limits.TIMEOUT
    limits.stop_workers()  # the next run starts a child, which takes longer than the limit
    try:
        limits.set_limits(timeout=0.05)
        with pytest.raises(GraderUnavailable, match="GLSL on llvmpipe.*did not finish within 0.05 s"):
            k.run(np.arange(5, dtype=np.float32), label="twice")
    finally:
        limits.set_limits(timeout=old)
    time.sleep(0.2)
    assert _processes_with("_gpu_child.py") == []
    assert np.allclose(k.run(np.arange(3, dtype=np.float32)).ravel(), 2 * np.arange(3))  # a new child


def test_glsl_runs_share_one_child_that_is_restarted_when_it_dies() -> None:
    """Runs one after the other go to one child (its GL context made once); a child that was
    killed between runs is reported by no run and replaced by a new one."""
    import signal

    import numpy as np

    glsl = _gl_or_skip()
    k = glsl.Kernel(code="float twice(float x) { return 2.0 * x; }", n_in=1, n_out=1, body="OUT(0) = twice(IN(0));")
    assert np.allclose(k.run(np.arange(4, dtype=np.float32)).ravel(), 2 * np.arange(4))
    first = _worker_pids()
    assert np.allclose(k.run(np.arange(6, dtype=np.float32)).ravel(), 2 * np.arange(6))
    assert len(first) == 1 and _worker_pids() == first
    os.kill(first[0], signal.SIGKILL)
    time.sleep(0.2)
    assert np.allclose(k.run(np.arange(2, dtype=np.float32)).ravel(), 2 * np.arange(2))
    again = _worker_pids()
    assert len(again) == 1 and again != first


def test_a_worker_that_dies_in_a_job_reports_it_and_the_memory_limit_applies() -> None:
    """A worker whose job exceeds the memory limit dies: the request returns its failure (as
    a run of its own would) and the next request starts a new child."""
    code = (
        "import struct, sys; i, o = sys.stdin.buffer, sys.stdout.buffer\n"
        "while True:\n"
        "    h = i.read(8)\n"
        "    if len(h) < 8: break\n"
        "    d = i.read(struct.unpack('<Q', h)[0])\n"
        "    if d == b'hog': b = bytearray(2**31)\n"
        "    o.write(struct.pack('<iQ', 0, len(d)) + d); o.flush()\n"
    )
    w = limits.Worker([sys.executable, "-c", code])
    try:
        assert w.request(b"one", label="echo", memory=2**30).stdout == b"one"
        pid = w.proc.pid
        run = w.request(b"hog", label="echo", memory=2**30)
        assert run.returncode != 0 and (limits.memory_message(run.stderr) or b"MemoryError" in run.stderr)
        assert w.request(b"two", label="echo", memory=2**30).stdout == b"two"
        assert w.proc.pid != pid
    finally:
        w.stop()


@pytest.mark.parametrize("name", ["lambda", "lambda x: x", "f(x)", "a b", "f;g", "", "1f", "main"])
def test_function_names_are_identifiers(name: str, tmp_path: Path) -> None:
    from openpbr_diffuse.graders.generic import cpp_subject

    src = tmp_path / "s.cpp"
    src.write_text("int x;\n")
    with pytest.raises(ValueError, match="--function"):
        cpp_subject(src, name)
    with pytest.raises(ValueError, match="--albedo-function"):
        cpp_subject(src, "ok_name", name)


@pytest.mark.parametrize("define", ["X=1\n#version 100", "X=1 \\\n", "X=#", "1X=2", "A B=1", "=3"])
def test_defines_are_validated(define: str) -> None:
    with pytest.raises(ValueError, match="--define"):
        limits.parse_defines([define])


def test_defines_accepted() -> None:
    assert limits.parse_defines(["FOO", "BAR=0.5", "M_PI=3.14159"]) == {"FOO": "1", "BAR": "0.5", "M_PI": "3.14159"}


def test_help_says_code_runs_with_users_rights(tmp_path: Path) -> None:
    run = _check(["--help"], tmp_path)
    text = " ".join(run.stdout.split()).lower()
    assert "run the given code with your user's rights" in text
    assert "--timeout" in text


def test_cycles_message_says_how_to_make_a_separate_python() -> None:
    from openpbr_diffuse.graders import cycles

    assert "python3.11 -m venv bpy-env" in cycles._INSTALL
    assert "bpy-env/bin/pip install bpy" in cycles._INSTALL
    assert "OPENPBR_DIFFUSE_BPY_PYTHON=$PWD/bpy-env/bin/python" in cycles._INSTALL
