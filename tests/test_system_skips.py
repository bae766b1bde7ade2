"""A test that needs a missing system program skips with one line naming what to install, and
under OPENPBR_DIFFUSE_REQUIRE_SYSTEM (set by .ci/run) the same skip is a failure."""

import os
import subprocess
import sys
from pathlib import Path

import _system

TESTS = Path(__file__).resolve().parent

INNER = '''
import _system

_system.PROGRAMS["absent"] = ("the absent program", "apt-get install absent-package", lambda: False)


def test_needs_it_inside():
    _system.need("absent")


@_system.requires("absent")
def test_needs_it_by_marker():
    pass


def test_plain_skip_stays_a_skip():
    import pytest

    pytest.skip("not about a system program")
'''


def _run(tmp_path, require):
    (tmp_path / "test_inner.py").write_text(INNER)
    env = {k: v for k, v in os.environ.items() if k != _system.REQUIRE_ENV}
    env["PYTHONPATH"] = os.pathsep.join([str(TESTS), env.get("PYTHONPATH", "")])
    if require:
        env[_system.REQUIRE_ENV] = "1"
    return subprocess.run(
        [
            sys.executable,
            "-m",
            "pytest",
            "-p",
            "conftest",
            "-c",
            os.devnull,
            "-q",
            "-rs",
            "-p",
            "no:cacheprovider",
            str(tmp_path / "test_inner.py"),
        ],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env=env,
        timeout=120,
    )


def test_missing_program_skips_with_the_install_line(tmp_path):
    r = _run(tmp_path, require=False)
    assert r.returncode == 0, r.stdout + r.stderr
    lines = [ln for ln in r.stdout.splitlines() if ln.startswith("SKIPPED")]
    assert len(lines) == 3, r.stdout
    named = [ln for ln in lines if "the absent program is not installed (apt-get install absent-package)" in ln]
    assert len(named) == 2, r.stdout
    assert "3 skipped" in r.stdout


def test_missing_program_fails_when_required(tmp_path):
    r = _run(tmp_path, require=True)
    assert r.returncode == 1, r.stdout + r.stderr
    # the marker's skip happens in set-up, so pytest counts that failure as an error
    assert "1 failed, 1 skipped, 1 error" in r.stdout, r.stdout
    assert _system.REQUIRE_ENV in r.stdout


def test_every_program_has_an_install_line():
    for name, (what, install, probe) in _system.PROGRAMS.items():
        assert what and callable(probe), name
        assert install.startswith(("apt-get install", "npm install", "python3")), (name, install)
