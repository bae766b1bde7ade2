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


# --- previous reports: only what their marker lists, inside them, never through a link ---


def _report(out: Path, text: str = "old") -> Path:
    """A report of this tool at ``out``, made with the library's own staging and publishing."""
    stage = output.staging_dir(out)
    (stage / "index.html").write_text(text)
    (stage / "report.json").write_text("{}")
    (stage / "images").mkdir()
    (stage / "images" / "a.png").write_bytes(b"png")
    output.publish(stage, out)
    return out


def _listing(folder: Path) -> list[str]:
    return sorted(str(p) for p in folder.rglob("*"))


def _refused_and_untouched(out: Path, watched: Path) -> None:
    """``check_target`` and ``publish`` refuse ``out`` in one line; nothing under ``watched`` changes."""
    before = _listing(watched)
    with pytest.raises(UnsafeOutputError) as exc:
        output.check_target(out)
    assert "\n" not in str(exc.value)
    stage = output.staging_dir(out)
    (stage / "index.html").write_text("new")
    with pytest.raises(UnsafeOutputError):
        output.publish(stage, out)
    assert _listing(watched) == before
    assert _no_leftovers(out.parent)


@pytest.mark.parametrize(
    "entry",
    [
        "../victim.txt",
        "ABSOLUTE",
        "images/../../victim.txt",
        "./index.html",
        "images//a.png",
        "images\\a.png",
        "images/a.png\x00",
        "",
        7,
    ],
)
def test_marker_listing_anything_but_a_path_inside_is_refused(tmp_path, entry):
    victim = tmp_path / "victim.txt"
    victim.write_text("keep")
    out = _report(tmp_path / "rep")
    doc = json.loads((out / MARKER).read_text())
    doc["entries"].append(str(victim) if entry == "ABSOLUTE" else entry)
    (out / MARKER).write_text(json.dumps(doc))
    _refused_and_untouched(out, tmp_path)
    assert victim.read_text() == "keep"


@pytest.mark.parametrize("link", ["images_folder", "listed_file"])
def test_link_inside_a_previous_report_is_refused(tmp_path, link):
    """A report never holds a link: a sub-folder or a listed file replaced by one makes the
    folder not a report, and nothing is removed through the link."""
    photos = tmp_path / "photos"
    photos.mkdir()
    (photos / "a.png").write_bytes(b"holiday")
    out = _report(tmp_path / "rep")
    if link == "images_folder":
        for p in (out / "images").iterdir():
            p.unlink()
        (out / "images").rmdir()
        (out / "images").symlink_to("../photos")
    else:
        (out / "report.json").unlink()
        (out / "report.json").symlink_to(photos / "a.png")
    _refused_and_untouched(out, tmp_path)
    assert (photos / "a.png").read_bytes() == b"holiday"


@pytest.mark.parametrize("swap", ["exchange", "rename"])
def test_file_appearing_in_the_old_report_during_its_removal_stays(tmp_path, monkeypatch, capsys, swap):
    """A file written into the swapped-out report after the checks stays, with its folder;
    the new report is in place, publish returns normally and discarding the staging name
    afterwards (what the runner does on an error) removes nothing."""
    out = _report(tmp_path / "rep")
    capsys.readouterr()
    real_exchange = output._exchange

    def exchange_then_write(a, b):
        done = real_exchange(a, b)
        if not list(tmp_path.rglob("late.txt")):
            (a / "images" / "late.txt").write_text("mine")
        return done

    def write_then_remove(folder, entries):
        (folder / "images" / "late.txt").write_text("mine")
        return real_remove(folder, entries)

    real_remove = getattr(output, "_remove_listed", None)

    if swap == "exchange":
        monkeypatch.setattr(output, "_exchange", exchange_then_write)
    else:
        monkeypatch.setattr(output, "_exchange", lambda a, b: False)
        monkeypatch.setattr(output, "_remove_listed", write_then_remove)
    stage = output.staging_dir(out)
    (stage / "index.html").write_text("new")
    output.publish(stage, out)
    output.discard(stage)
    assert (out / "index.html").read_text() == "new"
    (late,) = tmp_path.rglob("late.txt")
    assert late.read_text() == "mine" and late.parent.parent != out
    kept = late.parent.parent
    assert sorted(p.relative_to(kept).as_posix() for p in kept.rglob("*")) == ["images", "images/late.txt"]
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "late.txt" in err[0] and "Traceback" not in err[0]
    monkeypatch.undo()
    _report(out, "newer")  # the kept folder is no leftover of this tool: the next run leaves it
    assert late.read_text() == "mine"


def test_discard_removes_only_a_staging_folder_this_process_owns(tmp_path):
    mine = tmp_path / ".rep.tmp-abcdefgh"
    mine.mkdir()
    (mine / "notes.txt").write_text("x")
    output.discard(mine)
    assert (mine / "notes.txt").read_text() == "x"
    stage = output.staging_dir(tmp_path / "rep")
    output.discard(stage)
    assert not stage.exists()


# --- leftovers of killed runs ---

#: Makes a staging folder with some of a report in it, prints its path, then is killed
#: (argv[2] == "kill") or waits for its stdin to close.
MAKE_STAGE = textwrap.dedent("""
    import os, signal, sys
    from openpbr_diffuse.report.output import staging_dir
    t = staging_dir(sys.argv[1])
    (t / "report.json").write_text("{}")
    (t / "images").mkdir()
    (t / "images" / "a.png").write_bytes(b"png")
    print(t, flush=True)
    if sys.argv[2] == "kill":
        os.kill(os.getpid(), signal.SIGKILL)
    sys.stdin.read()
""")


def _stage_in_child(out: Path, mode: str) -> tuple[Path, subprocess.Popen]:
    p = subprocess.Popen(
        [sys.executable, "-c", MAKE_STAGE, str(out), mode],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )
    line = p.stdout.readline().strip()
    if mode == "kill":
        assert p.wait(timeout=60) == -9
        p.stdin.close()
        p.stdout.close()
    return Path(line), p


def test_leftovers_of_killed_runs_removed_by_the_next_publish(tmp_path):
    out = tmp_path / "rep"
    dead, _ = _stage_in_child(out, "kill")
    dead_with_mine, _ = _stage_in_child(out, "kill")
    (dead_with_mine / "mine.txt").write_text("x")
    live, child = _stage_in_child(out, "wait")
    other_host, _ = _stage_in_child(out, "kill")
    stamp = json.loads((other_host / output.STAMP).read_text())
    (other_host / output.STAMP).write_text(json.dumps({**stamp, "host": stamp["host"] + "-elsewhere"}))
    swapped_out = _report(tmp_path / "x").rename(tmp_path / ".rep.old-abcd1234")  # killed after a swap
    backup = _report(tmp_path / "y").rename(tmp_path / ".rep.old-backup")  # not a name the tool gives
    foreign = tmp_path / ".rep.tmp-zzzz9999"
    foreign.mkdir()
    (foreign / "report.json").write_text("mine")
    kept = {p: _listing(p) for p in (live, other_host, backup, foreign)}
    try:
        _report(out, "new")
        assert (out / "index.html").read_text() == "new"
        assert not dead.exists() and not swapped_out.exists()
        assert [p.name for p in dead_with_mine.iterdir()] == ["mine.txt"]
        assert {p: _listing(p) for p in kept} == kept
    finally:
        child.stdin.close()
        child.stdout.close()
        child.wait(timeout=60)


def test_marker_outside_path_refused_by_a_run(tmp_path):
    """The run (``run_report``, as ``openpbr-diffuse report`` calls it) on a report whose
    marker lists ``../victim.txt``: one line, exit status 2, the victim and report intact."""
    out = tmp_path / "rep"
    victim = tmp_path / "victim.txt"
    victim.write_text("keep")
    assert _fake_run(out).returncode == 0
    doc = json.loads((out / MARKER).read_text())
    (out / MARKER).write_text(json.dumps({**doc, "entries": [*doc["entries"], "../victim.txt"]}))
    listing = _listing(tmp_path)
    r = _fake_run(out)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1 and "victim.txt" in r.stderr, r.stderr
    assert _listing(tmp_path) == listing and victim.read_text() == "keep"


# --- a termination signal while the report is put in place ---


@pytest.fixture
def signals_installed():
    import signal

    from openpbr_diffuse import _signals

    saved = {s: signal.getsignal(s) for s in _signals.SIGNALS}
    _signals.install()
    try:
        yield _signals
    finally:
        for s, h in saved.items():
            signal.signal(s, h)
        _signals._received.clear()


def test_signal_before_the_swap_keeps_the_old_report(tmp_path, monkeypatch, signals_installed):
    """A signal held during the checks under the lock stops the run before the swap: the
    old report stays, the staging folder goes, the run ends with ``Terminated``."""
    import signal

    out = _report(tmp_path / "rep", "old")
    real = output.check_target

    def check_then_signal(*args, **kwargs):
        os.kill(os.getpid(), signal.SIGTERM)
        return real(*args, **kwargs)

    monkeypatch.setattr(output, "check_target", check_then_signal)
    stage = output.staging_dir(out)
    (stage / "index.html").write_text("new")
    with pytest.raises(signals_installed.Terminated):
        output.publish(stage, out)
    assert (out / "index.html").read_text() == "old"
    assert _no_leftovers(tmp_path)


def test_signal_after_the_swap_ends_with_the_new_report(tmp_path, monkeypatch, signals_installed):
    """A signal that arrives while the swapped-out report is removed: the new report is in
    place, so publishing ends normally (not as an interrupted run) and leaves nothing."""
    import signal

    out = _report(tmp_path / "rep", "old")
    real = output._remove_listed

    def signal_then_remove(folder, entries):
        os.kill(os.getpid(), signal.SIGTERM)
        return real(folder, entries)

    monkeypatch.setattr(output, "_remove_listed", signal_then_remove)
    stage = output.staging_dir(out)
    (stage / "index.html").write_text("new")
    output.publish(stage, out)
    assert (out / "index.html").read_text() == "new"
    assert _no_leftovers(tmp_path)
