"""`check FILE` streams: the same grade streamed as in one piece, memory independent of the
file's length (peak RSS of a child process on a 10^6-row file), and every malformed input
one line naming the row and the column."""

import json
import math
import os
import subprocess
import sys

import _hand_impl as hand
import numpy as np
import pytest

from openpbr_diffuse.cli.main import main
from openpbr_diffuse.conformance.grade import grade, grade_chunks
from openpbr_diffuse.conformance.vectors import (
    COLUMNS,
    default_vectors,
    iter_results,
    read_results,
    write_vectors,
)

V = default_vectors()
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _fields(g):
    d = g.to_dict()
    d.pop("rms_error")  # summed in another order: equal to rounding
    return d


@pytest.mark.parametrize(
    "switches", [dict(), dict(ms_scale="rho"), dict(scale=math.pi), dict(c1=0.3), dict(mu_floor=0.02)]
)
def test_streamed_grade_equals_one_piece(tmp_path, switches):
    out = hand.answer(V, np.float64, **switches)
    out[17, 1] = math.nan
    path = tmp_path / "r.csv"
    write_vectors(V, path, out=out)
    whole = grade(V, out)
    streamed = grade_chunks(iter_results(path, chunk_rows=97))
    assert _fields(streamed) == _fields(whole)
    assert streamed.rms_error == pytest.approx(whole.rms_error, rel=1e-12) or math.isinf(whole.rms_error)
    # and against the reference directly: the hand implementation itself conforms
    if not switches:
        assert whole.n_failed_rows == 1 and whole.n_nan == 1


def test_own_rows_are_graded_from_their_inputs(tmp_path):
    """Rows with ids of the submitter's own: the reference is evaluated at their inputs."""
    out = hand.answer(V, np.float64)
    own = V.subset(np.arange(len(V)))
    own.id = np.array([f"mine-{k}" for k in range(len(V))])
    path = tmp_path / "own.csv"
    write_vectors(own, path, out=out)
    g = grade_chunks(iter_results(path, chunk_rows=500))
    assert g.passed and g.n_rows == len(V)
    bad = hand.answer(V, np.float64, ms_scale="rho")
    write_vectors(own, path, out=bad)
    g = grade_chunks(iter_results(path, chunk_rows=500))
    assert not g.passed and g.diagnosis == "rho_ms_extra_rho"


def _write_big(path, n_rows):
    """n_rows of the submitter's own rows (the default set repeated with new ids), CSV."""
    ref = hand.answer(V, np.float64)
    tmp = path.with_suffix(".one.csv")
    write_vectors(V, tmp, out=ref.astype(np.float32).astype(np.float64))
    lines = [ln for ln in tmp.read_text().splitlines() if not ln.startswith("#")]
    head, body = lines[0], [ln.split(",", 1)[1] for ln in lines[1:]]
    with open(path, "w") as fh:
        fh.write(head + "\n")
        k = 0
        while k < n_rows:
            m = min(len(body), n_rows - k)
            fh.write("".join(f"r{k + j},{body[j]}\n" for j in range(m)))
            k += m


_CHILD = """
import sys, json
from openpbr_diffuse.conformance.grade import grade_chunks
from openpbr_diffuse.conformance.vectors import iter_results
grade_chunks(iter_results(sys.argv[2]))  # warm-up: imports and numba compilation (or cache loads)
with open("/proc/self/clear_refs", "w") as f:  # Linux: reset the peak RSS (VmHWM) after the warm-up
    f.write("5")
g = grade_chunks(iter_results(sys.argv[1]))
hwm = next(int(ln.split()[1]) for ln in open("/proc/self/status") if ln.startswith("VmHWM:"))
print(json.dumps({"passed": g.passed, "n": g.n_rows, "rss_mb": hwm / 1024}))
"""


def _peak(path, warm):
    env = dict(os.environ, PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))
    r = subprocess.run(
        [sys.executable, "-c", _CHILD, str(path), str(warm)], capture_output=True, text=True, env=env, timeout=900
    )
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


@pytest.mark.parametrize("n_big", [pytest.param(1_000_000, marks=pytest.mark.slow), 150_000])
def test_memory_is_independent_of_the_file_length(tmp_path, n_big):
    small, big = tmp_path / "small.csv", tmp_path / "big.csv"
    _write_big(small, 10_000)
    _write_big(big, n_big)
    warm = tmp_path / "warm.csv"
    _write_big(warm, 100)
    a, b = _peak(small, warm), _peak(big, warm)
    assert a["passed"] and b["passed"] and b["n"] == n_big
    assert b["rss_mb"] < 500
    # many times the rows (and the 50 000-row chunks and diagnosis sample filled): the same memory
    assert b["rss_mb"] - a["rss_mb"] < 120, (a, b)


def _csv_with(tmp_path, edit):
    path = tmp_path / "r.csv"
    write_vectors(V, path, out=hand.answer(V, np.float64))
    lines = path.read_text().splitlines()
    body = [ln for ln in lines if not ln.startswith("#")]
    path.write_text("\n".join(edit(body)) + "\n")
    return path


def _cell(body, row, col, value):
    head = body[0].split(",")
    cells = body[row].split(",")
    cells[head.index(col)] = value
    body = list(body)
    body[row] = ",".join(cells)
    return body


CSV_CASES = {
    "unbalanced_quote": (lambda b: b[:5] + ['"' + b[5]] + b[6:], ["row 5", "CSV"]),
    "underscore": (lambda b: _cell(b, 9, "out_g", "1_000"), ["row 9", "out_g"]),
    "non_numeric": (lambda b: _cell(b, 4, "roughness", "rough"), ["row 4", "roughness"]),
    "nan_input": (lambda b: _cell(b, 4, "wi_x", "nan"), ["row 4", "wi_x"]),
    "duplicated_column": (lambda b: [b[0] + ",out_r"] + [ln + ",1" for ln in b[1:]], ["duplicated", "out_r"]),
    "short_row": (lambda b: b[:3] + [b[3].rsplit(",", 1)[0]] + b[4:], ["row 3", "cells"]),
    "long_row": (lambda b: b[:3] + [b[3] + ",7"] + b[4:], ["row 3", "cells"]),
    "partial_blank_out": (lambda b: _cell(b, 6, "out_b", ""), ["row 6", "out_b"]),
    "own_row_not_unit": (
        lambda b: b + ["mine-1,brdf,eon,0.5,0,0.5,0,0,1,,0.5,0.5,0.5,0.5,0.1,0.1,0.1"],
        ["mine-1", "wi_x"],
    ),
}


@pytest.mark.parametrize("case", sorted(CSV_CASES))
def test_malformed_csv_gives_one_line(tmp_path, capsys, case):
    edit, fragments = CSV_CASES[case]
    path = _csv_with(tmp_path, edit)
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert all(f in err for f in fragments), err
    with pytest.raises(ValueError):
        read_results(path)


def _json_doc():
    path_rows = []
    ref = hand.answer(V, np.float64)
    cols = V.columns()
    for i in range(len(V)):
        row = {
            c: (
                str(cols[c][i])
                if c in ("id", "kind", "model")
                else (None if math.isnan(float(cols[c][i])) else float(cols[c][i]))
            )
            for c in COLUMNS
        }
        row["out"] = [float(x) for x in ref[i]]
        path_rows.append(row)
    return {"columns": list(COLUMNS), "rows": path_rows}


@pytest.mark.parametrize("case", ["huge_integer", "deep_nesting", "not_a_number", "string_number_underscore"])
def test_malformed_json_gives_one_line(tmp_path, capsys, case):
    doc = _json_doc()
    text = None
    if case == "huge_integer":
        text = json.dumps(doc).replace('"out": [', '"out": [1' + "0" * 400 + ", ", 1).replace(", ", ", ", 1)
        # the first row's out list now has 4 items: put the huge one in place of a value instead
        doc["rows"][3]["out"][0] = 0.123456
        text = json.dumps(doc).replace("0.123456", "1" + "0" * 400, 1)
    elif case == "deep_nesting":
        text = json.dumps(doc)[:-1] + ', "x": ' + "[" * 100000 + "]" * 100000 + "}"
    elif case == "not_a_number":
        doc["rows"][2]["out"][1] = {"a": 1}
    elif case == "string_number_underscore":
        doc["rows"][2]["out"][1] = "1_0"
    path = tmp_path / "r.json"
    path.write_text(text if text is not None else json.dumps(doc))
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    if case != "deep_nesting":
        assert "row" in err and "out" in err, err
