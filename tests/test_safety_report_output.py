"""``report --out``: nothing deleted that the tool did not write; atomic, concurrent-safe replace."""

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from openpbr_diffuse.report import output
from openpbr_diffuse.report.output import MARKER, UnsafeOutputError

ROOT = Path(__file__).resolve().parents[1]
MATERIAL = ROOT / "materials" / "chalk_white.mtlx"

#: A child process running ``run_report`` with one tiny fake section (a fraction of a second).
CHILD = textwrap.dedent("""
    import sys, time, types
    from openpbr_diffuse.report.model import SectionResult
    fake = types.ModuleType("openpbr_diffuse.report.sections.timings")
    fake.TITLE = "Fake"
    def build(ctx):
        time.sleep(float(sys.argv[3]))
        (ctx.image_dir / "x.txt").write_text("x" * 1000)
        return SectionResult("timings", "Fake")
    fake.build = build
    sys.modules[fake.__name__] = fake
    from openpbr_diffuse import _signals
    from openpbr_diffuse.report.runner import run_report
    _signals.install()
    print("started", flush=True)
    try:
        run_report([sys.argv[1]], sys.argv[2], progress=False, sections=["timings"])
    except KeyboardInterrupt as exc:
        sys.exit(128 + exc.signum)
    except ValueError as exc:
        print(exc, file=sys.stderr); sys.exit(2)
""")


def _fake_run(out, paths=(MATERIAL,)):
    return subprocess.run(
        [sys.executable, "-c", CHILD, str(paths[0]), str(out), "0"],
        check=False,
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )


def _is_complete_report(out: Path) -> bool:
    doc = json.loads((out / MARKER).read_text())
    return (
        (out / "report.json").is_file()
        and (out / "index.html").is_file()
        and set(doc["entries"]) == {p.relative_to(out).as_posix() for p in out.rglob("*")} - {MARKER}
    )


def _no_leftovers(parent: Path) -> bool:
    return not [p for p in parent.iterdir() if ".tmp-" in p.name or ".old-" in p.name]


def test_user_files_left_in_place_cli(tmp_path):
    d = tmp_path / "d"
    d.mkdir()
    (d / "thesis.tex").write_text("x")
    r = subprocess.run(
        [sys.executable, "-m", "openpbr_diffuse", "report", str(MATERIAL), "--out", str(d), "--quick", "--no-progress"],
        check=False,
        capture_output=True,
        text=True,
        timeout=300,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )
    assert r.returncode == 2, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and "thesis.tex" in r.stderr
    assert [p.name for p in d.iterdir()] == ["thesis.tex"] and (d / "thesis.tex").read_text() == "x"
    assert _no_leftovers(tmp_path)


@pytest.mark.parametrize("case", ["dot_next_to_input", "empty", "home", "input_parent", "file"])
def test_unsafe_targets_refused(tmp_path, monkeypatch, case):
    src = tmp_path / "proj"
    src.mkdir()
    inp = src / "m.mtlx"
    inp.write_text(MATERIAL.read_text())
    (src / "renderer.cpp").write_text("int main(){}")
    home = tmp_path / "home"
    (home / ".ssh").mkdir(parents=True)
    (home / ".bashrc").write_text("alias x=y")
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.chdir(src)
    out = {
        "dot_next_to_input": ".",
        "empty": "",
        "home": str(home),
        "input_parent": str(tmp_path),
        "file": str(src / "renderer.cpp"),
    }[case]
    before = sorted(str(p) for p in tmp_path.rglob("*"))
    with pytest.raises(UnsafeOutputError):
        output.check_target(out, [inp])
    r = _fake_run(out, [inp])
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert sorted(str(p) for p in tmp_path.rglob("*")) == before


def test_previous_report_replaced_and_mode_follows_umask(tmp_path):
    out = tmp_path / "rep"
    old = os.umask(0o027)
    try:
        assert _fake_run(out).returncode == 0
    finally:
        os.umask(old)
    assert _is_complete_report(out)
    assert (out.stat().st_mode & 0o777) == 0o750
    first = (out / "report.json").stat().st_mtime_ns
    r = _fake_run(out)
    assert r.returncode == 0, r.stderr
    assert _is_complete_report(out) and (out / "report.json").stat().st_mtime_ns != first
    assert _no_leftovers(tmp_path)


def test_empty_folder_used(tmp_path):
    out = tmp_path / "empty"
    out.mkdir()
    assert _fake_run(out).returncode == 0 and _is_complete_report(out)


def test_previous_report_plus_user_file_not_replaced(tmp_path):
    out = tmp_path / "rep"
    assert _fake_run(out).returncode == 0
    (out / "images" / "notes.txt").write_text("mine")
    listing = sorted(str(p) for p in out.rglob("*"))
    r = _fake_run(out)
    assert r.returncode == 2 and "notes.txt" in r.stderr
    assert sorted(str(p) for p in out.rglob("*")) == listing
    assert _no_leftovers(tmp_path)


def test_forged_marker_does_not_cover_other_files(tmp_path):
    out = tmp_path / "rep"
    out.mkdir()
    (out / MARKER).write_text("{}")
    (out / "data.csv").write_text("1")
    with pytest.raises(UnsafeOutputError):
        output.check_target(out)


def test_concurrent_runs_each_complete(tmp_path):
    out = tmp_path / "rep"
    assert _fake_run(out).returncode == 0
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    procs = [
        subprocess.Popen(
            [sys.executable, "-c", CHILD, str(MATERIAL), str(out), "0.2"],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=env,
        )
        for _ in range(4)
    ]
    results = [(p.wait(timeout=120), p.stderr.read()) for p in procs]
    for p in procs:
        p.stdout.close()
        p.stderr.close()
    for code, err in results:
        assert code == 0 or (code == 2 and len(err.strip().splitlines()) == 1), err
    assert _is_complete_report(out)
    assert _no_leftovers(tmp_path)
