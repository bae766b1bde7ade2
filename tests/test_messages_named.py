"""Every message of unusable input names its file (and row, line, column where there is
one), in one line, without Python-internal advice; NumPy's floating-point warnings never
reach the user of a command, and a finite result too large for the error ratio is called
out of range, not NaN/Inf.

The convention is ``docs/guide/command-line.md``: one line ``openpbr-diffuse COMMAND:
error: ...`` on stderr, exit status 2, no traceback; OS errors read "reason: path".
"""

import argparse
import doctest
import errno
import json
import math
import os
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from openpbr_diffuse import _csv, _textfiles
from openpbr_diffuse.cli import main as cli_main
from openpbr_diffuse.cli.main import main
from openpbr_diffuse.conformance.grade import OUT_OF_RANGE, grade
from openpbr_diffuse.conformance.vectors import COLUMNS, OUT_COLUMNS, read_results, write_vectors

ROOT = Path(__file__).resolve().parents[1]
HEADER = ",".join(COLUMNS + OUT_COLUMNS)
NOT_FOR_USERS = ("Traceback", "set_int_max_str_digits", "RuntimeWarning", "sys.", "codec can't")


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def one_line_error(code, err, *fragments, status=2):
    """The command failed with ``status`` and one stderr line holding every fragment."""
    assert code == status, err
    assert err.count("\n") == 1 and err.endswith("\n"), err
    assert err.startswith("openpbr-diffuse ") and ": error: " in err, err
    for bad in NOT_FOR_USERS:
        assert bad not in err, err
    for f in fragments:
        assert f in err, (f, err)


def cli(*argv, **kw):
    """The command in a child process (warnings are printed there as a user sees them)."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    env.pop("PYTHONWARNINGS", None)
    kw.setdefault("stdout", subprocess.PIPE)
    return subprocess.run(
        [sys.executable, "-m", "openpbr_diffuse", *map(str, argv)],
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        timeout=120,
        **kw,
    )


def own_albedo_row(rid="my-1", rho=("0.5", "0.5", "0.5"), out=("0.5", "0.5", "0.5"), mu="0.5"):
    """A row of the submitter's own: Lambert albedo at ``mu`` (E = rho), as CSV text."""
    return f"{rid},albedo,lambert,,,,,,,{mu},,{','.join(rho)},{','.join(out)}"


# ---------------------------------------------------------------- files that are not text


@pytest.mark.parametrize(
    "name, data",
    [
        ("random.csv", bytes(np.random.default_rng(7).integers(0, 256, 4000, dtype=np.uint8))),
        ("picture.png", b"\x89PNG\r\n\x1a\n" + bytes(64)),
        ("results.json", b'{"rows": [{"id": "caf\xe9"}]}'),
    ],
)
def test_a_binary_file_is_named_with_its_first_bad_byte(capsys, tmp_path, name, data):
    path = tmp_path / name
    path.write_bytes(data)
    # the first offending byte, found by decoding the whole file at once (the command reads
    # it in blocks)
    with pytest.raises(UnicodeDecodeError) as info:
        data.decode("utf-8")
    first = info.value.start
    line = data[:first].count(b"\n") + 1
    code, _, err = run(capsys, "check", path)
    one_line_error(code, err, name, "not a UTF-8 text file", f"0x{data[first]:02x}", f"offset {first}, line {line})")


def test_the_bad_byte_is_placed_across_the_reading_blocks(tmp_path):
    # a two-byte character straddles the 64 KiB block boundary; the bad byte is further on
    block = 1 << 16
    head = b"id,kind\n" + b"a" * (block - 10) + b"\n"  # ends one byte before the boundary
    data = head + "é".encode() + b"\n" * 3 + b"xx\xfe\n"
    assert len(head) == block - 1
    path = tmp_path / "big.csv"
    path.write_bytes(data)
    bad = data.index(b"\xfe")
    assert _textfiles.utf8_problem(path) == f"not a UTF-8 text file (byte 0xfe at offset {bad}, line 6)"
    # a character cut off by the end of the file
    path.write_bytes(b"id\n" + "é".encode()[:1])
    assert _textfiles.utf8_problem(path) == "not a UTF-8 text file (a truncated character at offset 3, line 2)"


def test_a_shipped_style_table_that_is_not_text_is_named(tmp_path):
    path = tmp_path / "table.csv"
    data = b"# source: x\nmu,E\n0.5,\xff\n"
    path.write_bytes(data)
    bad = data.index(b"\xff")  # 21
    at = rf"offset {bad}, line 3"
    with pytest.raises(ValueError, match=rf"table\.csv: not a UTF-8 text file \(byte 0xff at {at}\)"):
        _csv.read_headed_csv(path)
    path.write_text("# only: comments\n")
    with pytest.raises(ValueError, match=r"table\.csv: no column row"):
        _csv.read_headed_csv(path)


@pytest.mark.parametrize("module", [_textfiles, _csv], ids=lambda m: m.__name__)
def test_the_private_helpers_examples_run(module):
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0


# ---------------------------------------------------------------- rows and lines


def test_an_own_row_with_rho_1e308_names_its_line_and_column(capsys, tmp_path):
    # two comment lines, the header, a good row whose quoted id spans two lines, then the bad row
    text = "\n".join(
        [
            "# openpbr-diffuse conformance vectors, version 2",
            "# a note",
            HEADER,
            own_albedo_row(rid='"my\n1"'),
            own_albedo_row(rid="my-2", rho=("1e308", "0.5", "0.5")),
        ]
    )
    path = tmp_path / "mine.csv"
    path.write_text(text + "\n")
    bad_line = text.split("\n").index(own_albedo_row(rid="my-2", rho=("1e308", "0.5", "0.5"))) + 1
    assert bad_line == 6
    code, _, err = run(capsys, "check", path)
    one_line_error(code, err, "mine.csv", "row 2", f"line {bad_line}", "my-2", "rho_r", "1e+308", "[0, 1]")


@pytest.mark.parametrize("value", ["-0.25", "1.5"])
def test_an_own_row_with_rho_outside_0_1_is_refused_before_grading(tmp_path, value):
    path = tmp_path / "mine.csv"
    path.write_text(HEADER + "\n" + own_albedo_row(rho=("0.5", value, "0.5")) + "\n")
    with pytest.raises(ValueError, match=r"mine\.csv: row 1 \(line 2, id 'my-1'\): column rho_g must be in \[0, 1\]"):
        read_results(path)


def test_a_row_with_too_few_cells_names_its_line(capsys, tmp_path):
    path = tmp_path / "short.csv"
    path.write_text("# note\n\n" + HEADER + "\n" + own_albedo_row() + "\n" + "my-2,albedo\n")
    code, _, err = run(capsys, "check", path)
    one_line_error(code, err, "short.csv", "data row 2 (line 5)", "2 cells")


# ---------------------------------------------------------------- JSON numbers


def _json_row(**cells):
    row = {c: None for c in COLUMNS}
    row.update(id="my-1", kind="albedo", model="lambert", mu=0.5, rho_r=0.5, rho_g=0.5, rho_b=0.5)
    row.update(out_r=0.5, out_g=0.5, out_b=0.5)
    row.update(cells)
    return row


@pytest.mark.parametrize("digits", [401, 5001])
@pytest.mark.parametrize("field", ["rho_g", "out_b", "mu"])
def test_a_huge_json_integer_names_the_file_and_field(capsys, tmp_path, field, digits):
    path = tmp_path / "r.json"
    text = json.dumps({"rows": [_json_row(), _json_row(id="my-2", **{field: "HUGE"})]})
    path.write_text(text.replace('"HUGE"', "1" + "0" * (digits - 1)))
    code, _, err = run(capsys, "check", path)
    one_line_error(code, err, "r.json", "row 2", "my-2", f"column {field}", "too large for a float", f"{digits} digits")


def test_a_huge_json_integer_as_an_id_is_no_crash(capsys, tmp_path):
    path = tmp_path / "r.json"
    text = json.dumps({"rows": [_json_row(kind="HUGE")]})
    path.write_text(text.replace('"HUGE"', "9" * 5000))
    code, _, err = run(capsys, "check", path)
    one_line_error(code, err, "r.json", "row 1", "column kind", "5000-digit integer")


def test_a_json_input_that_overflows_to_inf_is_refused(capsys, tmp_path):
    path = tmp_path / "r.json"
    path.write_text(json.dumps({"rows": [_json_row(rho_b="X")]}).replace('"X"', "1e400"))
    code, _, err = run(capsys, "check", path)
    one_line_error(code, err, "r.json", "row 1", "column rho_b", "not a finite number")


# ---------------------------------------------------------------- huge but finite results


def test_huge_finite_results_are_out_of_range_and_print_no_warning(tmp_path):
    path = tmp_path / "huge.csv"
    path.write_text(HEADER + "\n" + own_albedo_row(out=("1e308", "-1e308", "0.5")) + "\n")
    r = cli("check", path)
    assert r.returncode == 1, r.stderr
    assert r.stderr == ""  # no RuntimeWarning, nothing at all
    assert "NaN/Inf" not in r.stdout and "non-finite" not in r.stdout
    assert "max out of range (> 1.8e+308)" in r.stdout and "error 1e+308, out of range" in r.stdout
    # rms over the three values |1e308 - 0.5|, |-1e308 - 0.5|, 0 (E = rho = 0.5): 1e308 sqrt(2/3)
    assert f"rms {1e308 * math.sqrt(2.0 / 3.0):.6g}," in r.stdout


def test_grading_huge_values_raises_no_warning_and_tells_them_from_inf(tmp_path):
    path = tmp_path / "huge.csv"
    rows = [own_albedo_row(rid=f"my-{k}", out=o) for k, o in enumerate([("1e308",) * 3, ("inf", "0.5", "0.5")])]
    path.write_text(HEADER + "\n" + "\n".join(rows) + "\n")
    v, out = read_results(path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # any NumPy RuntimeWarning would raise here
        g_huge = grade(v.subset(slice(0, 1)), out[:1])
        g_inf = grade(v.subset(slice(1, 2)), out[1:])
    assert g_huge.max_normalised_error == OUT_OF_RANGE and g_huge.n_inf == 0
    assert g_huge.worst[0]["status"] == "fail" and math.isfinite(g_huge.rms_error)
    assert g_huge.rms_error == pytest.approx(1e308, rel=1e-12)
    assert math.isinf(g_inf.max_normalised_error) and g_inf.n_inf == 1 and g_inf.worst[0]["status"] == "inf"


def test_the_command_line_hides_runtime_warnings_the_library_still_issues(capsys, monkeypatch):
    from openpbr_diffuse.cli import check

    def overflowing(args):
        np.float64(1e308) * np.float64(10.0)  # RuntimeWarning: overflow encountered
        return 0

    monkeypatch.setattr(check, "run", overflowing)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        assert main(["check", "x.csv"]) == 0
        assert not seen
        overflowing(None)  # outside a command the warning is issued
        assert [w.category for w in seen] == [RuntimeWarning]
    assert capsys.readouterr().err == ""


# ---------------------------------------------------------------- OS errors name the file


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="no /dev/full on this system")
def test_a_full_standard_output_is_named(tmp_path):
    with open("/dev/full", "w") as full:
        r = cli("vectors", "--out", tmp_path / "v.csv", stdout=full)
    assert r.returncode == 2
    assert r.stderr == "openpbr-diffuse vectors: error: No space left on device: standard output\n"


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="no /dev/full on this system")
def test_write_vectors_names_a_full_device():
    from openpbr_diffuse.conformance.vectors import default_vectors

    with pytest.raises(OSError) as info:
        write_vectors(default_vectors(), "/dev/full")
    assert info.value.errno == errno.ENOSPC and info.value.filename == "/dev/full"


def _file_size_limit():
    import resource
    import signal

    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails with EFBIG
    resource.setrlimit(resource.RLIMIT_FSIZE, (200, 200))


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX resource limits")
@pytest.mark.parametrize("argv", [["vectors", "--out", "v.csv"], ["template", "glsl"]])
def test_a_failed_write_names_the_output_file(tmp_path, argv):
    # a real failed write, the one a full disk gives: the OS names no file
    r = cli(*argv, cwd=tmp_path, preexec_fn=_file_size_limit)
    name = argv[2] if argv[0] == "vectors" else "diffuse.glsl"
    assert r.returncode == 2
    assert r.stderr == f"openpbr-diffuse {argv[0]}: error: File too large: {name}\n"
    assert list(tmp_path.iterdir()) == []  # and nothing is left behind


def test_an_unnamed_write_error_names_the_output_option():
    exc = OSError(errno.ENOSPC, "No space left on device")
    assert cli_main._message(exc, argparse.Namespace(out="report")) == "No space left on device (while writing report)"
    assert cli_main._message(exc, argparse.Namespace()) == "No space left on device"
    named = OSError(errno.EACCES, "Permission denied", "x.csv")
    assert cli_main._message(named, argparse.Namespace(out="y")) == "Permission denied: x.csv"


# ---------------------------------------------------------------- arguments and commands


@pytest.mark.parametrize("value", [42, None, b"clay.mtlx", ["clay.mtlx"]])
def test_load_materials_names_its_path_argument(value):
    from openpbr_diffuse.readers import load_materials

    with pytest.raises(TypeError, match=rf"^path must be a str or os\.PathLike .* got {type(value).__name__}$"):
        load_materials(value)


def test_report_on_a_missing_file_names_it_once(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # relative names: the message holds no folder name
    code, _, err = run(capsys, "report", "nosuch.mtlx", "--out", "r")
    one_line_error(code, err, "nosuch.mtlx", "no such file")
    assert err.count("report") == 1, err  # "openpbr-diffuse report: error: ...", not "report: ... report"
    assert list(tmp_path.iterdir()) == []


def test_a_message_does_not_repeat_the_command(capsys):
    code, _, err = run(capsys, "check")
    one_line_error(code, err, "FILE is required")
    assert err.startswith("openpbr-diffuse check: error: FILE") and err.count("check") == 1
