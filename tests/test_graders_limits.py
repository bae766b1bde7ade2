"""User code (--cpp/--glsl) runs in a child process under a wall-time and memory limit."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import tempfile
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
    from openpbr_diffuse.graders import glsl

    try:
        glsl.gl_version()
    except GraderUnavailable as exc:
        pytest.skip(str(exc))
    return glsl


def _worker_pids() -> list[int]:
    """The GL children (not their supervisors, whose command line holds theirs)."""
    return [int(p.split(":")[0]) for p in _processes_with("_gpu_child.py") if " gl" in p and "_supervisor.py" not in p]


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


def test_each_limit_is_the_lower_of_the_asked_and_the_callers(tmp_path: Path) -> None:
    """Under a caller's soft RLIMIT_AS of 2 GiB and hard 3 GiB (below the 4 GiB asked), user
    code gets 2 GiB, soft and hard, and no core files; asking more raises nothing."""
    code = (
        "from openpbr_diffuse.graders import limits; "
        "r = limits.run_limited(['sh', '-c', 'ulimit -S -v; ulimit -H -v; ulimit -c'], label='limits'); "
        "print(r.returncode, r.stdout.decode().split(), r.stderr.decode())"
    )
    run = subprocess.run(
        ["prlimit", f"--as={2 * 2**30}:{3 * 2**30}", sys.executable, "-c", code],
        capture_output=True,
        text=True,
        env=dict(os.environ, PYTHONPATH=str(ROOT)),
        timeout=60,
        check=False,
    )
    assert run.returncode == 0, run.stderr
    assert run.stdout.split("]")[0] + "]" == f"0 ['{2 * 2**20}', '{2 * 2**20}', '0']"


def test_the_run_ends_as_its_program_did() -> None:
    assert limits.run_limited(["sh", "-c", "exit 3"], label="three").returncode == 3
    assert limits.run_limited(["sh", "-c", "kill -SEGV $$"], label="segv").returncode == -signal.SIGSEGV
    run = limits.run_limited(["sh", "-c", "echo out; echo err >&2"], label="echo")
    assert (run.returncode, run.stdout, run.stderr) == (0, b"out\n", b"err\n")


def test_a_program_that_cannot_start_is_one_line() -> None:
    run = limits.run_limited(["/nonexistent/program"], label="missing")
    assert run.returncode == 127
    assert run.stderr.decode().splitlines() == ["cannot run /nonexistent/program: No such file or directory"]


NOBODY_PYTHON = Path("/usr/bin/python3")


@pytest.mark.skipif(
    os.geteuid() != 0 or shutil.which("setpriv") is None or not NOBODY_PYTHON.is_file(),
    reason="needs root, setpriv (util-linux) and /usr/bin/python3 to run as the user nobody",
)
def test_a_non_root_run_cannot_fork_past_its_process_limit() -> None:
    """RLIMIT_NPROC = the user's threads + NPROC_EXTRA: a run of the user nobody forking 200
    sleepers gets at most NPROC_EXTRA of them, and none is left after the run."""
    program = (
        "import os, time\n"
        "pids = []\n"
        "for _ in range(200):\n"
        "    try:\n"
        "        pid = os.fork()\n"
        "    except OSError:\n"
        "        break\n"
        "    if pid == 0:\n"
        "        time.sleep(30)\n"
        "        os._exit(0)\n"
        "    pids.append(pid)\n"
        "print(*pids)\n"
    )
    # the supervisor (one stdlib-only file) copied where the user nobody can read it: a
    # checkout in a private folder (``mktemp -d`` is 0700) is not readable by other users
    with tempfile.TemporaryDirectory(dir="/tmp") as folder:
        os.chmod(folder, 0o755)
        supervisor = Path(folder) / limits.SUPERVISOR.name
        shutil.copyfile(limits.SUPERVISOR, supervisor)
        supervisor.chmod(0o644)
        supervised = [
            *(str(NOBODY_PYTHON), "-I", "-S", str(supervisor)),
            *(str(os.getpid()), "20", str(2**30), str(limits.NPROC_EXTRA)),
            *(str(NOBODY_PYTHON), "-c", program),
        ]
        run = subprocess.run(
            ["setpriv", "--reuid=65534", "--regid=65534", "--clear-groups", *supervised],
            capture_output=True,
            text=True,
            timeout=60,
            cwd="/",
            check=False,
        )
    assert run.returncode == 0, run.stderr
    pids = [int(p) for p in run.stdout.split()]
    assert 0 < len(pids) <= limits.NPROC_EXTRA
    assert [p for p in pids if Path(f"/proc/{p}").exists()] == []


def test_messages_name_a_lower_limit_in_force(monkeypatch: pytest.MonkeyPatch) -> None:
    """When the caller's own RLIMIT_AS is the lower limit, a failure for memory (or a GL
    context that cannot be made) names it and the floor, in one line."""
    import resource

    from openpbr_diffuse.graders import glsl

    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    mine = 2**40  # 1 TiB: far above what this process maps, below the 2 TiB asked
    if hard != resource.RLIM_INFINITY and hard < mine:
        pytest.skip("the hard RLIMIT_AS of the test process is below 1 TiB")
    monkeypatch.setattr(limits, "MEMORY", 2 * mine)
    resource.setrlimit(resource.RLIMIT_AS, (mine, hard))
    try:
        assert limits.memory_in_force() == mine
        text = limits.memory_failure("compiling x.cpp", "g++", 1)
        no_context = glsl._no_device("no OpenGL 4.3 context through EGL (eglInitialize failed)")
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))
    assert text == (
        f"compiling x.cpp: the memory limit in force (ulimit -v {mine // 1024} KiB) is too low for g++ "
        "(status 1); raise it (user code may use up to 2048 GiB), e.g. ulimit -v unlimited"
    )
    assert no_context.startswith("no OpenGL 4.3 context through EGL (eglInitialize failed); or the memory limit")
    assert f"ulimit -v {mine // 1024} KiB" in no_context and "\n" not in no_context
    assert limits.raise_hint(400 * 2**20, 2**32).startswith(f"raise it to at least {limits.MEMORY_FLOOR_KIB} KiB")


def test_a_worker_outlives_the_thread_that_started_it() -> None:
    """The parent-death signal of a worker's supervisor comes when the thread that started it
    ends: the worker goes on while its process lives."""
    import threading

    code = (
        "import struct, sys; i, o = sys.stdin.buffer, sys.stdout.buffer\n"
        "while True:\n"
        "    h = i.read(8)\n"
        "    if len(h) < 8: break\n"
        "    d = i.read(struct.unpack('<Q', h)[0])\n"
        "    o.write(struct.pack('<iQ', 0, len(d)) + d); o.flush()\n"
    )
    w = limits.Worker([sys.executable, "-c", code])
    try:
        answers: list[bytes] = []
        thread = threading.Thread(target=lambda: answers.append(w.request(b"one", label="echo").stdout))
        thread.start()
        thread.join(30)
        assert answers == [b"one"]
        pid = w.proc.pid
        time.sleep(0.6)  # past the supervisor's periodic check of its parent
        assert w.request(b"two", label="echo").stdout == b"two"
        assert w.proc.pid == pid
    finally:
        w.stop()
