"""User code graded with ``check --cpp/--glsl`` cannot outlive the run, and its limits are never
above the caller's.

The C++ subject below wraps the conforming subject (tests/subjects/eon_conforming.cpp): the
graded function forks, once per harness process, CHILDREN processes that (SETSID) leave the
session, ignore SIGTERM and SIGHUP, keep the inherited stdout/stderr open and sleep 60 s;
with HANG the harness itself then sleeps 60 s.  Every process writes its pid to the file named
by $FORKING_PIDS before the harness goes on.
"""

from __future__ import annotations

import doctest
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SUBJECTS = ROOT / "tests" / "subjects"
needs_gxx = pytest.mark.skipif(
    shutil.which("g++") is None or not Path("/usr/include/glm/glm.hpp").is_file(),
    reason="g++ and libglm-dev needed: apt-get install g++ libglm-dev",
)

FORKING = r"""
#include "eon_conforming.cpp"
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <unistd.h>

static void note(const char* what) {
    FILE* out = std::fopen(std::getenv("FORKING_PIDS"), "a");
    std::fprintf(out, "%s %d\n", what, (int)getpid());
    std::fclose(out);
}

static void spawn_once() {
    static bool done = false;
    if (done) return;
    done = true;
    note("harness");
    int ready[2];
    if (pipe(ready) != 0) return;
    for (int k = 0; k < CHILDREN; ++k) {
        pid_t pid = fork();
        if (pid < 0) break;
        if (pid == 0) {
            if (SETSID) setsid();
            std::signal(SIGTERM, SIG_IGN);
            std::signal(SIGHUP, SIG_IGN);
            note("child");
            (void)!write(ready[1], "x", 1);
            sleep(60);
            _exit(0);
        }
        char c;
        (void)!read(ready[0], &c, 1);
    }
    if (HANG) sleep(60);
}

glm::vec3 f_forking(glm::vec3 wi, glm::vec3 wo, float r, glm::vec3 rho) {
    spawn_once();
    return f(wi, wo, r, rho);
}
"""


@pytest.fixture(scope="module")
def cache(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One harness cache for the module: a subject built with the same defines compiles once."""
    return tmp_path_factory.mktemp("harness-cache")


def _alive(pid: int) -> bool:
    """True while ``pid`` is a process that has not ended (a zombie has)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_bytes()
    except OSError:
        return False
    return stat[stat.rfind(b")") + 2 :].split()[0] != b"Z"


def _pids(path: Path) -> dict[int, str]:
    if not path.is_file():
        return {}
    return {int(pid): what for what, pid in (line.split() for line in path.read_text().splitlines() if line.strip())}


def _left_after(pids, seconds: float = 5.0) -> list[int]:
    """The ``pids`` still running ``seconds`` after now (polled)."""
    end = time.monotonic() + seconds
    while True:
        left = [p for p in pids if _alive(p)]
        if not left or time.monotonic() > end:
            return left
        time.sleep(0.05)


def _kill_left(pids) -> None:
    for p in pids:
        try:
            os.kill(p, signal.SIGKILL)
        except OSError:
            pass


def _cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "openpbr_diffuse", "check", *args]


def _env(cache: Path, pids: Path | None = None) -> dict[str, str]:
    env = dict(os.environ, PYTHONPATH=str(ROOT), OPENPBR_DIFFUSE_CACHE=str(cache))
    if pids is not None:
        env["FORKING_PIDS"] = str(pids)
    return env


def _forking_args(tmp_path: Path, children: int, setsid: int, hang: int, timeout: int = 20) -> list[str]:
    src = tmp_path / "forking.cpp"
    src.write_text(FORKING)
    return [
        "--cpp",
        str(src),
        "--include",
        str(SUBJECTS),
        "--function",
        "f_forking",
        "--albedo-function",
        "albedo",
        "--quick",
        "--timeout",
        str(timeout),
        "--define",
        f"CHILDREN={children}",
        "--define",
        f"SETSID={setsid}",
        "--define",
        f"HANG={hang}",
    ]


def _grade_forking(tmp_path: Path, cache: Path, children: int, setsid: int, timeout: int = 20):
    pids = tmp_path / "pids"
    start = time.monotonic()
    run = subprocess.run(
        _cli(*_forking_args(tmp_path, children, setsid, 0, timeout)),
        capture_output=True,
        text=True,
        env=_env(cache, pids),
        timeout=120,
        check=False,
    )
    return run, time.monotonic() - start, _pids(pids)


@needs_gxx
def test_a_setsid_child_that_ignores_sigterm_is_gone_after_the_run(tmp_path: Path, cache: Path) -> None:
    run, _, pids = _grade_forking(tmp_path, cache, children=1, setsid=1)
    try:
        assert run.returncode == 0, run.stderr
        assert "child" in pids.values()
        assert _left_after(pids) == []
    finally:
        _kill_left(pids)


@needs_gxx
def test_a_child_holding_the_output_pipes_does_not_hold_the_run(tmp_path: Path, cache: Path) -> None:
    """The run is over when the harness exits, not when its pipes close: a child that keeps
    stdout/stderr open (in the harness's session) neither turns it into a timeout nor delays it."""
    run, elapsed, pids = _grade_forking(tmp_path, cache, children=1, setsid=0, timeout=15)
    try:
        assert run.returncode == 0, run.stderr
        assert "did not finish" not in run.stderr
        assert elapsed < 15
        assert "child" in pids.values() and _left_after(pids) == []
    finally:
        _kill_left(pids)


@needs_gxx
def test_a_fork_bomb_leaves_nothing_and_ends_in_time(tmp_path: Path, cache: Path) -> None:
    """200 children leaving the session: the run ends normally within its time limit and none
    is left (as root, RLIMIT_NPROC does not apply: the supervisor's kill is the bound)."""
    run, elapsed, pids = _grade_forking(tmp_path, cache, children=200, setsid=1, timeout=20)
    try:
        assert run.returncode == 0, run.stderr
        assert elapsed < 20
        children = [p for p, what in pids.items() if what == "child"]
        # 200 per run of the harness (the values' run, the properties' run)
        assert (len(children) > 0 and len(children) % 200 == 0) or os.geteuid() != 0
        assert children and _left_after(pids) == []
    finally:
        _kill_left(pids)


@needs_gxx
def test_sigkill_of_the_tool_ends_its_user_code(tmp_path: Path, cache: Path) -> None:
    """kill -9 of openpbr-diffuse while the harness runs (and its setsid child sleeps): no
    process of the run is left 5 s later."""
    pids_file = tmp_path / "pids"
    log = tmp_path / "log"
    with log.open("w") as out:
        tool = subprocess.Popen(
            _cli(*_forking_args(tmp_path, 1, 1, 1, timeout=50)),
            stdout=out,
            stderr=out,
            env=_env(cache, pids_file),
        )
    pids: dict[int, str] = {}
    try:
        end = time.monotonic() + 90
        while "child" not in (pids := _pids(pids_file)).values():
            assert tool.poll() is None, log.read_text()
            assert time.monotonic() < end, "the harness did not start"
            time.sleep(0.05)
        tool.send_signal(signal.SIGKILL)
        tool.wait(timeout=10)
        assert sorted(pids.values()) == ["child", "harness"]
        assert _left_after(pids) == []
    finally:
        _kill_left(pids)
        if tool.poll() is None:
            tool.kill()
            tool.wait()


def test_a_worker_child_dies_with_the_tool(tmp_path: Path) -> None:
    """A persistent worker child (what runs GLSL and WGSL jobs) busy in a job is ended when the
    process that started it is killed with SIGKILL."""
    pid_file = tmp_path / "worker-pid"
    job = (
        "import os, sys, time; sys.stdin.buffer.read(8 + 3); "
        f"open({str(pid_file)!r}, 'w').write(str(os.getpid())); time.sleep(60)"
    )
    tool_code = (
        "import sys; from openpbr_diffuse.graders import limits; "
        f"limits.Worker([sys.executable, '-c', {job!r}]).request(b'job', label='job', timeout=60)"
    )
    tool = subprocess.Popen([sys.executable, "-c", tool_code], env=dict(os.environ, PYTHONPATH=str(ROOT)))
    pid = 0
    try:
        end = time.monotonic() + 60
        while not (pid_file.is_file() and pid_file.read_text()):
            assert tool.poll() is None
            assert time.monotonic() < end, "the worker did not start"
            time.sleep(0.05)
        pid = int(pid_file.read_text())
        assert _alive(pid)
        tool.send_signal(signal.SIGKILL)
        tool.wait(timeout=10)
        assert _left_after([pid]) == []
    finally:
        _kill_left([pid] if pid else [])
        if tool.poll() is None:
            tool.kill()
            tool.wait()


def _gl_installed() -> bool:
    try:
        import moderngl  # noqa: F401
    except ImportError:
        return False
    return any(Path(d, "libEGL.so.1").exists() for d in ("/usr/lib/x86_64-linux-gnu", "/usr/lib64", "/usr/lib"))


@pytest.mark.parametrize("kib", [4000000, "floor"])
@pytest.mark.parametrize("language", ["cpp", "glsl"])
def test_a_caller_memory_limit_below_4_gib_still_grades(language: str, kib, tmp_path: Path) -> None:
    """Under ``ulimit -v`` (soft and hard) of 4000000 KiB, and of the floor the docs state, a
    correct file grades with exit status 0."""
    from openpbr_diffuse.graders import limits

    if language == "cpp" and (shutil.which("g++") is None or not Path("/usr/include/glm/glm.hpp").is_file()):
        pytest.skip("g++ and libglm-dev needed: apt-get install g++ libglm-dev")
    if language == "glsl" and not _gl_installed():
        pytest.skip("EGL and llvmpipe needed: apt-get install libegl1 libgl1-mesa-dri (and pip install moderngl)")
    kib = limits.MEMORY_FLOOR_KIB if kib == "floor" else kib
    subject = SUBJECTS / f"eon_conforming.{language}"
    command = " ".join(
        [
            f"ulimit -v {kib};",
            f"exec {sys.executable} -m openpbr_diffuse check --{language} {subject}",
            "--function f --albedo-function albedo --quick",
        ]
    )
    run = subprocess.run(
        ["bash", "-c", command],
        capture_output=True,
        text=True,
        env=_env(tmp_path / "cache"),
        timeout=120,
        check=False,
    )
    assert run.returncode == 0, run.stderr
    assert "conforms" in run.stdout


@needs_gxx
def test_too_low_a_caller_memory_limit_is_one_clean_line(tmp_path: Path) -> None:
    """g++ running out under the caller's own ``ulimit -v`` (below the 4 GiB of user code):
    one line naming that limit, exit status 2, no traceback."""
    src = tmp_path / "zero.cpp"
    src.write_text('#include "/dev/zero"\n')
    command = f"ulimit -v 1000000; exec {sys.executable} -m openpbr_diffuse check --cpp {src} --function f"
    run = subprocess.run(
        ["bash", "-c", command], capture_output=True, text=True, env=_env(tmp_path / "cache"), timeout=120, check=False
    )
    assert run.returncode == 2
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1, run.stderr
    assert "the memory limit in force (ulimit -v 1000000 KiB) is too low for g++" in lines[0]
    assert "Traceback" not in run.stderr and "not allowed" not in run.stderr


def test_supervisor_examples() -> None:
    from openpbr_diffuse.graders import _supervisor

    result = doctest.testmod(_supervisor)
    assert result.failed == 0 and result.attempted >= 4
