"""Every output file a command writes follows one rule (``docs/guide/safety.md``, "Output files").

``report --junit``, ``render --out``, ``colorshift --image``, ``albedo --export``,
``vectors --out`` and ``template --out``: an existing file is replaced only with ``--force``
(and then only a regular file), never an input of the run, never through a symbolic link,
the folder must exist, all checked before any work; the data goes to a temporary sibling
that takes the name only once complete, and no temporary file is left behind.

The library rule (``openpbr_diffuse._outfile``) is checked against the file system itself
(``os.lstat``, inode numbers, file contents), the commands by running them in-process on
cheap inputs, with the expensive step replaced by a tripwire where a refusal must come first.
"""

from __future__ import annotations

import doctest
import errno
import os
import shutil
import stat
from pathlib import Path

import pytest

from openpbr_diffuse import _outfile, _signals
from openpbr_diffuse._outfile import (
    OutputExistsError,
    OutputFileError,
    check_output_file,
    output_file,
    write_output_file,
)
from openpbr_diffuse.cli.main import main

ROOT = Path(__file__).resolve().parents[1]
CLAY = ROOT / "materials" / "clay_rough.mtlx"
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def one_line(err):
    return err.count("\n") == 1 and err.endswith("\n")


def listing(folder):
    """Every entry of ``folder``, hidden ones included (a temporary file would show here)."""
    return sorted(p.name for p in Path(folder).iterdir())


def tripwire(*_, **__):
    raise AssertionError("the work started although the output file was refused")


# ----------------------------------------------------------------------------- the library rule


def test_module_examples_run():
    result = doctest.testmod(_outfile, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0


def test_new_file_is_written_with_the_umask_mode(tmp_path):
    old = os.umask(0o027)
    try:
        path = write_output_file(tmp_path / "a.txt", "hello\n", option="--out")
    finally:
        os.umask(old)
    assert path == tmp_path / "a.txt" and path.read_text() == "hello\n"
    assert stat.S_IMODE(os.lstat(path).st_mode) == 0o640  # 0o666 & ~0o027, like open(..., "w")
    assert listing(tmp_path) == ["a.txt"]


def test_existing_file_needs_force_and_is_replaced_not_written_in_place(tmp_path):
    path = tmp_path / "a.txt"
    path.write_text("mine\n")
    other = tmp_path / "hard-link"
    os.link(path, other)
    with pytest.raises(OutputExistsError) as info:
        write_output_file(path, "new\n", option="--junit")
    assert str(info.value) == f"--junit {path} exists: not overwritten (use --force to replace it)"
    assert isinstance(info.value, FileExistsError) and isinstance(info.value, ValueError)
    assert path.read_text() == "mine\n"
    write_output_file(path, "new\n", option="--junit", force=True)
    assert path.read_text() == "new\n"
    # a rename, not a write into the old file: its other name still holds the old text
    assert other.read_text() == "mine\n"
    assert listing(tmp_path) == ["a.txt", "hard-link"]


@pytest.mark.parametrize("dangling", [False, True])
def test_symbolic_link_is_never_written_through_even_with_force(tmp_path, dangling):
    victim = tmp_path / "victim.txt"
    if not dangling:
        victim.write_text("precious\n")
    link = tmp_path / "out.png"
    link.symlink_to(victim)
    for force in (False, True):
        with pytest.raises(OutputFileError, match="is a symbolic link; not written through"):
            write_output_file(link, "x", option="--out", force=force)
    assert link.is_symlink() and os.readlink(link) == str(victim)
    assert victim.exists() != dangling and (dangling or victim.read_text() == "precious\n")
    assert sorted(listing(tmp_path)) == sorted(["out.png"] + ([] if dangling else ["victim.txt"]))


def test_folder_and_fifo_are_never_replaced(tmp_path):
    folder = tmp_path / "d.xml"
    folder.mkdir()
    fifo = tmp_path / "f.xml"
    os.mkfifo(fifo)
    with pytest.raises(OutputFileError, match="is a folder; name a file"):
        check_output_file(folder, option="--junit", force=True)
    with pytest.raises(OutputFileError, match="is a FIFO; name a file"):
        check_output_file(fifo, option="--junit", force=True)
    with pytest.raises(OutputFileError, match="names a folder"):
        check_output_file(f"{tmp_path}/new/", option="--junit")
    with pytest.raises(OutputFileError, match="is empty"):
        check_output_file("", option="--junit")
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode) and folder.is_dir()


def test_an_input_is_never_written_even_with_force(tmp_path):
    mine = tmp_path / "mine.mtlx"
    mine.write_text("<materialx/>")
    os.link(mine, tmp_path / "alias.mtlx")
    (tmp_path / "via").symlink_to(tmp_path, target_is_directory=True)
    for name in (mine, tmp_path / "alias.mtlx", tmp_path / "via" / "mine.mtlx"):
        with pytest.raises(OutputFileError) as info:
            write_output_file(name, "x", option="--junit", force=True, inputs=[mine])
        assert str(info.value) == f"--junit {name} is an input of this run; choose another file"
    # below an input folder: the files the run reads from it (by suffix) are inputs too
    with pytest.raises(OutputFileError, match="is an input"):
        check_output_file(mine, option="--junit", force=True, inputs=[tmp_path], input_suffixes=(".mtlx",))
    other = tmp_path / "junit.xml"
    other.write_text("old")
    check_output_file(other, option="--junit", force=True, inputs=[tmp_path], input_suffixes=(".mtlx",))
    assert mine.read_text() == "<materialx/>"


def test_the_folder_must_exist_and_be_a_folder(tmp_path):
    with pytest.raises(OutputFileError) as info:
        check_output_file(tmp_path / "no" / "x.xml", option="--junit")
    assert str(info.value) == f"--junit {tmp_path / 'no' / 'x.xml'}: the folder {tmp_path / 'no'} does not exist"
    (tmp_path / "file").write_text("x")
    with pytest.raises(OutputFileError, match="is not a folder"):
        check_output_file(tmp_path / "file" / "x.xml", option="--junit")
    assert listing(tmp_path) == ["file"]


def test_the_temporary_file_is_a_hidden_sibling_keeping_the_suffix(tmp_path):
    with output_file(tmp_path / "x.png", option="--out") as tmp:
        assert tmp.parent == tmp_path and tmp.name.startswith(".x.png.") and tmp.name.endswith(".tmp.png")
        assert stat.S_ISREG(os.lstat(tmp).st_mode) and stat.S_IMODE(os.lstat(tmp).st_mode) == 0o600
        tmp.write_bytes(b"data")
        assert not (tmp_path / "x.png").exists()  # nothing poses as complete before the end
    assert listing(tmp_path) == ["x.png"] and (tmp_path / "x.png").read_bytes() == b"data"


def test_an_error_while_writing_leaves_no_file_and_the_old_one_intact(tmp_path):
    with pytest.raises(RuntimeError), output_file(tmp_path / "new.xml", option="--junit") as tmp:
        tmp.write_text("half")
        raise RuntimeError("the writer failed")
    assert listing(tmp_path) == []
    old = tmp_path / "old.xml"
    old.write_text("complete\n")
    with pytest.raises(RuntimeError), output_file(old, option="--junit", force=True) as tmp:
        tmp.write_text("half")
        raise RuntimeError("the writer failed")
    assert listing(tmp_path) == ["old.xml"] and old.read_text() == "complete\n"


def test_a_file_created_meanwhile_is_not_clobbered_without_force(tmp_path):
    path = tmp_path / "j.xml"
    with pytest.raises(OutputExistsError), output_file(path, option="--junit") as tmp:
        tmp.write_text("ours")
        path.write_text("someone else's")
    assert path.read_text() == "someone else's" and listing(tmp_path) == ["j.xml"]


def test_a_link_placed_at_the_name_meanwhile_is_not_written_through(tmp_path):
    victim = tmp_path / "victim"
    victim.write_text("precious")
    path = tmp_path / "j.xml"
    with pytest.raises(OutputFileError, match="symbolic link"), output_file(path, option="--junit", force=True) as t:
        t.write_text("ours")
        path.symlink_to(victim)
    assert victim.read_text() == "precious" and path.is_symlink()
    assert listing(tmp_path) == ["j.xml", "victim"]


def test_a_temporary_file_swapped_for_a_link_is_refused(tmp_path):
    victim = tmp_path / "victim"
    victim.write_text("precious")
    with pytest.raises(OutputFileError, match="replaced while written"), output_file(tmp_path / "j.xml") as tmp:
        tmp.unlink()
        tmp.symlink_to(victim)
    assert victim.read_text() == "precious" and listing(tmp_path) == ["victim"]


def test_a_signal_received_meanwhile_publishes_nothing(tmp_path, monkeypatch):
    monkeypatch.setattr(_signals, "_received", [])
    with pytest.raises(_signals.Terminated), output_file(tmp_path / "j.xml") as tmp:
        tmp.write_text("complete")
        _signals._received.append(15)  # what the handler records when the exception was swallowed
    assert listing(tmp_path) == []


def test_a_signal_while_the_temporary_file_is_made_leaves_no_file(tmp_path, monkeypatch):
    import signal
    import tempfile

    real = tempfile.mkstemp

    def mkstemp_then_signal(*args, **kwargs):
        made = real(*args, **kwargs)
        _signals._handler(signal.SIGINT, None)  # as if Ctrl-C arrived right after the file was made
        return made

    monkeypatch.setattr(_signals, "_received", [])
    monkeypatch.setattr(tempfile, "mkstemp", mkstemp_then_signal)
    with pytest.raises(_signals.Terminated), output_file(tmp_path / "j.xml") as tmp:
        tmp.write_text("never reached")
    assert listing(tmp_path) == []


def test_a_failing_write_names_the_output_not_the_temporary_file(tmp_path, monkeypatch):
    import tempfile

    def full_disk(*args, dir=None, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device", os.path.join(dir, ".j.xml.abc.tmp.xml"))

    monkeypatch.setattr(tempfile, "mkstemp", full_disk)
    with pytest.raises(OSError) as info, output_file(tmp_path / "j.xml", option="--junit"):
        pass
    assert info.value.errno == errno.ENOSPC and info.value.filename == str(tmp_path / "j.xml")
    assert listing(tmp_path) == []


def test_without_hard_links_the_name_is_still_never_clobbered(tmp_path, monkeypatch):
    def no_link(src, dst, **_):
        raise OSError(errno.EPERM, "Operation not permitted")

    monkeypatch.setattr(os, "link", no_link)
    path = write_output_file(tmp_path / "a.txt", "one", option="--out")
    assert path.read_text() == "one" and listing(tmp_path) == ["a.txt"]
    with pytest.raises(OutputExistsError), output_file(tmp_path / "b.txt") as tmp:
        tmp.write_text("ours")
        (tmp_path / "b.txt").write_text("theirs")
    assert (tmp_path / "b.txt").read_text() == "theirs" and listing(tmp_path) == ["a.txt", "b.txt"]


# ----------------------------------------------------------------------------- report --junit


def test_report_junit_naming_an_input_is_refused_before_any_work(tmp_path, capsys, monkeypatch):
    from openpbr_diffuse.cli import report as cli_report

    monkeypatch.chdir(tmp_path)
    shutil.copy(CLAY, "mine.mtlx")
    before = Path("mine.mtlx").read_bytes()
    monkeypatch.setattr(cli_report, "_under_test", tripwire)
    for force in ([], ["--force"]):
        code, out, err = run(capsys, "report", "--junit", "mine.mtlx", "--out", "rep", "mine.mtlx", *force)
        assert code == 2 and not out and one_line(err)
        assert "--junit mine.mtlx is an input of this run; choose another file" in err
    # in an input folder, a material file is an input too
    code, _, err = run(capsys, "report", "--junit", "mine.mtlx", "--out", "rep", ".", "--force")
    assert code == 2 and "is an input" in err
    assert Path("mine.mtlx").read_bytes() == before and listing(tmp_path) == ["mine.mtlx"]


def test_report_junit_in_a_missing_folder_is_refused_before_any_work(tmp_path, capsys, monkeypatch):
    from openpbr_diffuse.cli import report as cli_report

    monkeypatch.setattr(cli_report, "_under_test", tripwire)
    code, out, err = run(capsys, "report", "--junit", tmp_path / "no" / "j.xml", "--out", tmp_path / "rep")
    assert code == 2 and not out and one_line(err) and "does not exist" in err
    assert listing(tmp_path) == []


def test_report_junit_inside_the_report_folder_and_force_alone_are_refused(tmp_path, capsys, monkeypatch):
    from openpbr_diffuse.cli import report as cli_report

    monkeypatch.setattr(cli_report, "_under_test", tripwire)
    (tmp_path / "rep").mkdir()
    code, _, err = run(capsys, "report", "--junit", tmp_path / "rep" / "j.xml", "--out", tmp_path / "rep")
    assert code == 2 and one_line(err) and "inside the report folder" in err
    code, _, err = run(capsys, "report", "--force", "--out", tmp_path / "rep2")
    assert code == 2 and one_line(err) and "--force applies to --junit FILE only" in err
    assert listing(tmp_path) == ["rep"] and listing(tmp_path / "rep") == []


def test_report_junit_is_never_written_through_an_old_tmp_link(tmp_path, capsys):
    """A cheap report (no evidence sections): the XML lands at its name, a pre-existing
    ``.j.xml.tmp`` link is left alone, an existing file needs --force."""
    victim = tmp_path / "victim.txt"
    victim.write_text("precious\n")
    (tmp_path / ".j.xml.tmp").symlink_to(victim)
    junit = tmp_path / "j.xml"
    argv = ["report", "--evidence", "none", "--no-progress", "--junit", junit]
    code, _, _ = run(capsys, *argv, "--out", tmp_path / "r1")
    assert code == 0 and junit.read_text().startswith("<?xml")
    assert victim.read_text() == "precious\n" and (tmp_path / ".j.xml.tmp").is_symlink()
    assert listing(tmp_path) == [".j.xml.tmp", "j.xml", "r1", "victim.txt"]
    junit.write_text("mine\n")
    code, out, err = run(capsys, *argv, "--out", tmp_path / "r2")
    assert code == 2 and not out and one_line(err) and "use --force" in err
    assert junit.read_text() == "mine\n" and not (tmp_path / "r2").exists()  # refused before the report
    code, _, _ = run(capsys, *argv, "--out", tmp_path / "r2", "--force")
    assert code == 0 and junit.read_text().startswith("<?xml")
    assert listing(tmp_path) == [".j.xml.tmp", "j.xml", "r1", "r2", "victim.txt"]


# ----------------------------------------------------------------------------- render --out


def test_render_refuses_an_existing_image_before_any_work(tmp_path, capsys, monkeypatch):
    from openpbr_diffuse.cli import render as cli_render

    image = tmp_path / "existing.png"
    image.write_bytes(b"mine")
    monkeypatch.setattr(cli_render, "load", tripwire)
    code, out, err = run(capsys, "render", CLAY, "--out", image, "--size", "8")
    assert code == 2 and not out and one_line(err)
    assert f"--out {image} exists: not overwritten (use --force to replace it)" in err
    code, _, err = run(capsys, "render", CLAY, "--out", tmp_path / "no" / "x.png", "--size", "8")
    assert code == 2 and one_line(err) and "does not exist" in err
    assert image.read_bytes() == b"mine" and listing(tmp_path) == ["existing.png"]


def test_render_force_replaces_a_regular_file_never_a_link(tmp_path, capsys):
    image = tmp_path / "existing.png"
    image.write_bytes(b"mine")
    assert run(capsys, "render", CLAY, "--out", image, "--size", "8", "--force")[0] == 0
    assert image.read_bytes().startswith(PNG_MAGIC)
    victim = tmp_path / "victim.png"
    victim.write_bytes(b"precious")
    (tmp_path / "link.png").symlink_to(victim)
    code, _, err = run(capsys, "render", CLAY, "--out", tmp_path / "link.png", "--size", "8", "--force")
    assert code == 2 and one_line(err) and "is a symbolic link; not written through" in err
    assert victim.read_bytes() == b"precious"
    assert listing(tmp_path) == ["existing.png", "link.png", "victim.png"]


# ----------------------------------------------------------------------------- colorshift --image


def test_colorshift_image_rule(tmp_path, capsys, monkeypatch):
    from openpbr_diffuse.cli import colorshift as cli_colorshift

    image = tmp_path / "sw.png"
    image.write_bytes(b"mine")
    mine = tmp_path / "mine.mtlx"
    shutil.copy(CLAY, mine)
    with monkeypatch.context() as m:
        m.setattr(cli_colorshift, "colour_set", tripwire)
        code, _, err = run(capsys, "colorshift", "--image", image)
        assert code == 2 and one_line(err) and "--image" in err and "use --force" in err
        code, _, err = run(capsys, "colorshift", "--colors", mine, "--image", mine, "--force")
        assert code == 2 and one_line(err) and "is an input of this run" in err
        code, _, err = run(capsys, "colorshift", "--force")
        assert code == 2 and one_line(err) and "--force applies to --image" in err
    assert image.read_bytes() == b"mine" and mine.read_bytes() == CLAY.read_bytes()
    fast = ["colorshift", "--colors", "0.5,0.5,0.5", "--roughness", "1", "--mu", "1"]
    assert run(capsys, *fast, "--image", image, "--force")[0] == 0
    assert image.read_bytes().startswith(PNG_MAGIC)
    # a writer that fails (no format for the suffix) leaves no temporary file
    code, _, err = run(capsys, *fast, "--image", tmp_path / "sw.nosuchformat")
    assert code == 2 and one_line(err) and "sw.nosuchformat" in err and ".tmp" not in err
    assert listing(tmp_path) == ["mine.mtlx", "sw.png"]


# ----------------------------------------------------------------------------- albedo --export


def test_albedo_export_refuses_existing_files_before_any_work(tmp_path, capsys, monkeypatch):
    from openpbr_diffuse.albedo import export

    argv = ["albedo", "eon", "--export", tmp_path, "--size", "4", "--no-progress"]
    assert run(capsys, *argv)[0] == 0
    names = ["eon_albedo.exr", "eon_average_albedo.exr"]
    assert listing(tmp_path) == names
    before = {n: (tmp_path / n).read_bytes() for n in names}
    with monkeypatch.context() as m:
        m.setattr(export, "load_table", tripwire)
        code, out, err = run(capsys, *argv)
        assert code == 2 and not out and one_line(err) and "--export" in err and "use --force" in err
        code, _, err = run(capsys, "albedo", "eon", "--roughness", "1", "--mu", "0.5", "--force")
        assert code == 2 and one_line(err) and "--force only applies with --export" in err
    assert {n: (tmp_path / n).read_bytes() for n in names} == before
    (tmp_path / names[0]).write_bytes(b"mine")
    assert run(capsys, *argv, "--force")[0] == 0
    assert (tmp_path / names[0]).read_bytes() == before[names[0]]  # the same texture, written again
    assert listing(tmp_path) == names


def test_albedo_export_never_writes_through_a_link(tmp_path, capsys):
    victim = tmp_path / "victim"
    victim.write_bytes(b"precious")
    out = tmp_path / "luts"
    out.mkdir()
    (out / "eon_average_albedo.exr").symlink_to(victim)
    code, _, err = run(capsys, "albedo", "eon", "--export", out, "--size", "4", "--no-progress", "--force")
    assert code == 2 and one_line(err) and "symbolic link" in err
    assert victim.read_bytes() == b"precious" and listing(out) == ["eon_average_albedo.exr"]


# ----------------------------------------------------------------------------- vectors, template


@pytest.mark.parametrize(
    "argv", [["vectors", "--out"], ["template", "glsl", "--out"], ["template", "csv", "--out"]], ids=str
)
def test_vectors_and_template_follow_the_rule(tmp_path, capsys, argv):
    victim = tmp_path / "victim"
    victim.write_text("precious")
    link = tmp_path / "link.csv"
    link.symlink_to(victim)
    code, _, err = run(capsys, *argv, link, "--force")
    assert code == 2 and one_line(err) and "symbolic link" in err and victim.read_text() == "precious"
    code, _, err = run(capsys, *argv, tmp_path / "no" / "f.csv")
    assert code == 2 and one_line(err) and "does not exist" in err
    path = tmp_path / "f.csv"
    path.write_text("mine")
    code, _, err = run(capsys, *argv, path)
    assert code == 2 and one_line(err) and "use --force" in err and path.read_text() == "mine"
    assert run(capsys, *argv, path, "--force")[0] == 0 and path.read_text() != "mine"
    assert listing(tmp_path) == ["f.csv", "link.csv", "victim"]
