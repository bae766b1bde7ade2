"""`check --cpp/--glsl` run the user's code under limits, and refuse what is not a name.

An infinite loop ends within its timeout plus a few seconds with one line and exit 2, leaving
no process behind; a source that makes the compiler read forever (``#include "/dev/zero"``)
hits the same limits; function names and ``--define`` values cannot inject code.
"""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
needs_gxx = pytest.mark.skipif(shutil.which("g++") is None, reason="g++ is installed by .ci/run")

LOOP = """
#include <glm/glm.hpp>
glm::vec3 looping(glm::vec3 wi, glm::vec3 wo, float roughness, glm::vec3 rho) {
    volatile float x = 0.0f;
    for (;;) { x += 1.0f; }
    return rho;
}
"""


def _check(*argv, cache, timeout=120):
    env = dict(os.environ, PYTHONPATH=str(ROOT), OPENPBR_DIFFUSE_CACHE=str(cache))
    t0 = time.monotonic()
    p = subprocess.run([sys.executable, "-m", "openpbr_diffuse", "check", *argv], capture_output=True, text=True,
                       env=env, timeout=timeout)
    return p, time.monotonic() - t0


def _processes_mentioning(text: str) -> list[str]:
    found = []
    for pid in os.listdir("/proc"):
        if not pid.isdigit() or int(pid) == os.getpid():
            continue
        try:
            cmd = Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        if text in cmd:
            found.append(f"{pid}: {cmd}")
    return found


@needs_gxx
def test_infinite_loop_is_killed_at_the_timeout(tmp_path):
    src = tmp_path / "loop.cpp"
    src.write_text(LOOP)
    p, took = _check("--cpp", str(src), "--function", "looping", "--timeout", "3", "--quick", cache=tmp_path / "cache")
    assert p.returncode == 2, p.stderr
    assert "did not finish within 3 s" in p.stderr and len(p.stderr.strip().splitlines()) == 1
    assert took < 3 * 2 + 5 + 20  # compile (own limit) + run + start-up; never unbounded
    time.sleep(0.5)
    assert _processes_mentioning(str(tmp_path / "cache")) == []


@needs_gxx
def test_compiler_reading_forever_is_bounded(tmp_path):
    src = tmp_path / "zero.cpp"
    src.write_text('#include "/dev/zero"\n')
    p, took = _check("--cpp", str(src), "--function", "f", "--timeout", "5", "--quick", cache=tmp_path / "cache")
    assert p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert "Traceback" not in p.stderr
    assert took < 5 + 30
    assert _processes_mentioning(str(src)) == []


@pytest.mark.parametrize("name", ["lambda x: x", "[](auto...){return 1;}", "f; system(\"id\")", "9f", ""])
def test_function_names_must_be_identifiers(tmp_path, name):
    src = tmp_path / "x.cpp"
    src.write_text(LOOP)
    p, _ = _check("--cpp", str(src), "--function", name, cache=tmp_path / "cache")
    assert p.returncode == 2 and ("--function" in p.stderr or "needs" in p.stderr), p.stderr
    assert not (tmp_path / "cache").exists()  # refused before anything was compiled


@pytest.mark.parametrize("define", ["X=1\n#include </etc/passwd>", "X=\\\nint y;", "1X=2", "X=#pragma"])
def test_defines_cannot_inject_directives(tmp_path, define):
    src = tmp_path / "x.glsl"
    src.write_text("vec3 f(vec3 wi, vec3 wo, float r, vec3 rho) { return rho; }\n")
    p, _ = _check("--glsl", str(src), "--function", "f", "--define", define, cache=tmp_path / "cache")
    assert p.returncode == 2 and "--define" in p.stderr, p.stderr


def test_help_says_the_code_is_run():
    p = subprocess.run([sys.executable, "-m", "openpbr_diffuse", "check", "--help"], capture_output=True,
                       text=True, env=dict(os.environ, PYTHONPATH=str(ROOT)))
    assert "run the given code with your user's rights" in " ".join(p.stdout.split())
