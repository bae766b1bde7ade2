"""`report --out`: nothing is deleted that the tool did not write; replacement is atomic.

Every case ends with the user's files byte-for-byte as they were, one line on stderr and exit
2, or with a complete report in place; never with a hidden temporary folder left behind.
"""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from openpbr_diffuse.report import output, runner

ROOT = Path(__file__).resolve().parents[1]
MATERIAL = ROOT / "materials" / "chalk_white.mtlx"


def _snapshot(folder: Path) -> dict:
    return {str(p.relative_to(folder)): (p.read_bytes() if p.is_file() else None) for p in sorted(folder.rglob("*"))}


def _cli(*argv, cwd, env=None, timeout=120):
    return subprocess.run([sys.executable, "-m", "openpbr_diffuse", "report", *argv, "--no-progress"], cwd=cwd,
                          capture_output=True, text=True, env=env, timeout=timeout)


def _env(**extra):
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    env.update(extra)
    return env


def _report(out, **kw):
    return runner.run_report(None, out, quick=True, progress=False, sections=(), **kw)


def _no_temp_left(parent: Path):
    assert not [p.name for p in parent.iterdir() if ".tmp-" in p.name or ".old-" in p.name]


def test_folder_with_user_files_is_refused_and_untouched(tmp_path):
    d = tmp_path / "d"
    d.mkdir()
    (d / "thesis.tex").write_text("chapter 1")
    (d / "sub").mkdir()
    (d / "sub" / "data.csv").write_text("1,2")
    before = _snapshot(d)
    with pytest.raises(ValueError, match="did not write"):
        _report(d)
    assert _snapshot(d) == before
    _no_temp_left(tmp_path)


@pytest.mark.parametrize("out", [".", "", "..", "~"])
def test_cwd_empty_parent_and_home_are_refused(tmp_path, out):
    work = tmp_path / "home" / "project"
    work.mkdir(parents=True)
    (work / "renderer.cpp").write_text("int main() {}")
    (work / "m.mtlx").write_bytes(MATERIAL.read_bytes())
    (tmp_path / "home" / ".bashrc").write_text("export X=1")
    before = _snapshot(tmp_path)
    p = _cli("m.mtlx", "--out", out, "--select", "materials", cwd=work, env=_env(HOME=str(tmp_path / "home")))
    assert p.returncode == 2, p.stderr
    assert len(p.stderr.strip().splitlines()) == 1 and "Traceback" not in p.stderr
    assert _snapshot(tmp_path) == before


def test_ancestor_of_the_inputs_is_refused(tmp_path):
    src = tmp_path / "scenes"
    src.mkdir()
    (src / "m.mtlx").write_bytes(MATERIAL.read_bytes())
    before = _snapshot(tmp_path)
    p = _cli(str(src / "m.mtlx"), "--out", str(src), "--select", "materials", cwd=tmp_path, env=_env())
    assert p.returncode == 2 and "did not write" in p.stderr
    assert _snapshot(tmp_path) == before


def test_a_file_is_refused(tmp_path):
    f = tmp_path / "report"
    f.write_text("not a folder")
    with pytest.raises(ValueError, match="not a folder"):
        _report(f)
    assert f.read_text() == "not a folder"


def test_empty_folder_and_previous_report_are_used(tmp_path):
    out = tmp_path / "r"
    out.mkdir()
    _report(out)
    assert (out / output.MARKER).is_file() and (out / "index.html").is_file()
    first = json.loads((out / "report.json").read_text())["generated"]
    time.sleep(1.1)
    _report(out)  # a previous report of this tool: replaced
    assert json.loads((out / "report.json").read_text())["generated"] != first
    _no_temp_left(tmp_path)


def test_previous_report_with_a_user_file_is_not_replaced(tmp_path):
    out = tmp_path / "r"
    _report(out)
    (out / "images" / "my_notes.txt").write_text("keep me")
    before = _snapshot(out)
    with pytest.raises(ValueError, match="my_notes.txt"):
        _report(out)
    assert _snapshot(out) == before


def test_forged_marker_does_not_cover_unlisted_files(tmp_path):
    out = tmp_path / "r"
    out.mkdir()
    (out / output.MARKER).write_text(json.dumps({"tool": "openpbr-diffuse", "files": ["index.html"]}))
    (out / "index.html").write_text("x")
    (out / "precious.db").write_text("data")
    with pytest.raises(ValueError, match="precious.db"):
        _report(out)
    assert (out / "precious.db").read_text() == "data"


@pytest.mark.parametrize("umask", [0o022, 0o077, 0o002])
def test_permissions_follow_the_umask(tmp_path, umask):
    old = os.umask(umask)
    try:
        _report(tmp_path / "r")
    finally:
        os.umask(old)
    assert (tmp_path / "r").stat().st_mode & 0o777 == 0o777 & ~umask


_CONCURRENT = textwrap.dedent("""
    import sys
    from openpbr_diffuse.report import runner
    try:
        runner.run_report(None, sys.argv[1], quick=True, progress=False, sections=())
    except (ValueError, OSError) as e:
        print("error:", e, file=sys.stderr)
        sys.exit(2)
""")


def test_concurrent_runs_to_one_folder(tmp_path):
    out = tmp_path / "r"
    procs = [subprocess.Popen([sys.executable, "-c", _CONCURRENT, str(out)], env=_env(), stderr=subprocess.PIPE,
                              text=True) for _ in range(4)]
    results = [(p.wait(timeout=120), p.stderr.read()) for p in procs]
    for code, err in results:
        assert code == 0 or (code == 2 and err.startswith("error:")), err
    assert any(code == 0 for code, _ in results)
    assert sorted(p.name for p in out.iterdir()) == sorted([output.MARKER, "images", "index.html", "report.json"])
    json.loads((out / "report.json").read_text())
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r"]


_SLOW_RUN = textwrap.dedent("""
    import sys, time, types
    from openpbr_diffuse import _signals
    _signals.install()
    from openpbr_diffuse.report import runner, sections
    from openpbr_diffuse.report.model import SectionResult
    mod = types.ModuleType("openpbr_diffuse.report.sections.sleepy")
    mod.TITLE = "sleepy"
    def build(ctx):
        print("started", flush=True)
        time.sleep(float(sys.argv[2]))
        return SectionResult("sleepy", "sleepy")
    mod.build = build
    sys.modules[mod.__name__] = mod
    sections.SECTIONS = sections.SECTIONS + ("sleepy",)
    try:
        runner.run_report(None, sys.argv[1], quick=True, progress=False, sections=("sleepy",))
    except KeyboardInterrupt:
        sys.exit(130)
    except _signals.Terminated as e:
        sys.exit(128 + e.signum)
""")


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP])
@pytest.mark.parametrize("delay", [0.0, 0.5])
def test_signal_leaves_old_report_and_no_temp_folder(tmp_path, sig, delay):
    out = tmp_path / "r"
    _report(out)
    before = _snapshot(out)
    p = subprocess.Popen([sys.executable, "-c", _SLOW_RUN, str(out), "30"], env=_env(), stdout=subprocess.PIPE,
                         text=True)
    assert p.stdout.readline().strip() == "started"
    time.sleep(delay)
    p.send_signal(sig)
    code = p.wait(timeout=60)
    assert code == 128 + sig
    assert _snapshot(out) == before
    assert sorted(q.name for q in tmp_path.iterdir()) == ["r"]


def test_signal_during_start_up_is_honoured(tmp_path):
    out = tmp_path / "r"
    _report(out)
    before = _snapshot(out)
    p = subprocess.Popen([sys.executable, "-m", "openpbr_diffuse", "report", "--out", str(out), "--select",
                          "implementations", "--quick", "--no-progress"], env=_env(), cwd=tmp_path,
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    time.sleep(0.6)  # inside the imports
    p.send_signal(signal.SIGINT)
    code = p.wait(timeout=120)
    err = p.stderr.read()
    assert code == 130 and "Traceback" not in err, err
    assert _snapshot(out) == before
    assert sorted(q.name for q in tmp_path.iterdir()) == ["r"]
