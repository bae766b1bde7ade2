"""The report writes the lobe explorer beside index.html, lists it in its manifest and links it;
with a GLSL implementation under test the explorer shows that function beside the reference
and |theirs - reference|, computed in headless Chromium (SwiftShader WebGL2).  The references:
the library's ``evaluate`` of EON (the wrong implementation's error is compared with it), and the
file tests/subjects/eon_conforming.glsl, written from the paper's equations."""

import json
from pathlib import Path

import numpy as np
import pytest
from _browser import opened_page
from test_explore import FLAGS

import openpbr_diffuse as od
from openpbr_diffuse.cli.main import main
from openpbr_diffuse.export.explorer import explorer_html
from openpbr_diffuse.report.explore import explorer_subject

SUBJECTS = Path(__file__).parent / "subjects"
#: a comment that would end the page's script and run one of its own, were the GLSL embedded raw
HOSTILE = "// </script><script>window.pwned = 1;</script><!-- <script> </SCRIPT > & &lt;\n"
#: one cheap section of the evidence (as tests/test_report_under_test.py runs it)
CHEAP = ["--select", "implementations.reference*", "--no-progress"]
SETTINGS = {"r": 0.7, "rho_r": 0.9, "rho_g": 0.5, "rho_b": 0.1, "theta_o": 50, "theta_i": 60, "phi": 120}


def _report(tmp_path, name, code, function="f"):
    src = tmp_path / name
    src.write_text(code)
    out = tmp_path / f"report-{src.stem}"
    main(["report", "--glsl", str(src), "--function", function, "--out", str(out), *CHEAP])
    return out


def _open(page_path):
    """What the explorer shows after the sliders are set: the subject's state, its f and the
    reference's on one sphere, the shown maximum, and the page's errors."""
    with opened_page(page_path, flags=FLAGS) as (page, errors):
        page.evaluate("v => window.explorer.set(v)", SETTINGS)
        got = page.evaluate("window.explorer.readSubject()")
        got["shown"] = page.evaluate("document.getElementById('diff-max').textContent")
        got["error"] = page.evaluate("document.getElementById('subject-error').textContent")
        got["pwned"] = page.evaluate("window.pwned === undefined ? null : window.pwned")
        got["size"] = page.evaluate("window.explorer.size")
    got["errors"] = errors
    return got


def test_report_writes_lists_and_links_the_explorer(tmp_path):
    out = tmp_path / "report"
    main(["report", "--out", str(out), "--select", "implementations.reference*", "--no-progress"])
    page = (out / "explore.html").read_text()
    assert page == explorer_html()  # no implementation under test: the reference only
    assert "explore.html" in json.loads((out / ".openpbr-diffuse-report").read_text())["entries"]
    doc = json.loads((out / "report.json").read_text())
    assert doc["explorer"] == {"file": "explore.html", "subject": None, "function": None, "message": ""}
    assert '<a href="explore.html">' in (out / "index.html").read_text()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report"]  # nothing written beside it


def test_the_implementation_is_embedded_escaped(tmp_path):
    code = HOSTILE + (SUBJECTS / "eon_conforming.glsl").read_text()
    page = explorer_html(code, "f", 'mine".glsl')
    block = page[page.index('<script id="subject-glsl"') :]
    block = block[: block.index("</script>")]
    assert "<" not in block[1:]  # nothing in it can end or open a script
    assert "&lt;/script&gt;&lt;script&gt;window.pwned" in block and 'data-name="mine&quot;.glsl"' in block
    assert page.count("<script") == 3 and page.count("</script>") == 3  # the reference, theirs, the page's code
    with pytest.raises(ValueError, match="function"):
        explorer_html(code, "f(); x", "mine.glsl")


def test_a_missing_include_is_named_in_the_page(tmp_path):
    src = tmp_path / "mine.glsl"
    src.write_text('#include "nowhere.glsl"\n')
    s = explorer_subject(src, "f")
    assert s.code is None and "nowhere.glsl" in s.message
    assert "nowhere.glsl" in explorer_html(s.code, s.function, s.name, s.message)


def _sphere_reference(size):
    """EON at the pixels of one sphere (the page's stated geometry), and which pixels to compare."""
    from test_explore import _frame

    ti, ph = np.radians(SETTINGS["theta_i"]), np.radians(SETTINGS["phi"])
    light = np.array([np.sin(ti) * np.cos(ph), np.sin(ti) * np.sin(ph), np.cos(ti)])
    rho = np.array([SETTINGS["rho_r"], SETTINGS["rho_g"], SETTINGS["rho_b"]])
    want, keep = np.zeros((size, size, 3)), np.zeros((size, size), bool)
    for py in range(0, size, 4):
        for px in range(0, size, 4):
            p = (np.array([px, py]) + 0.5) / size * 2 - 1
            if p @ p >= 0.98:
                continue
            n = np.array([p[0], p[1], np.sqrt(1 - p @ p)])
            F = _frame(n)
            wi, wo = (F @ light)[None], (F @ np.array([0.0, 0.0, 1.0]))[None]
            if abs(wi[0, 2]) < 1e-3:
                continue
            want[py, px] = od.evaluate("eon", wi / np.linalg.norm(wi), wo, SETTINGS["r"], rho)[0]
            keep[py, px] = True
    return want, keep


def test_correct_implementation_differs_by_float32_rounding_only(tmp_path):
    code = HOSTILE + (SUBJECTS / "eon_conforming.glsl").read_text()
    out = _report(tmp_path, "mine.glsl", code)
    doc = json.loads((out / "report.json").read_text())
    assert doc["explorer"]["subject"] == "mine.glsl" and doc["explorer"]["function"] == "f"
    got = _open(out / "explore.html")
    assert got["errors"] == [] and got["pwned"] is None and got["error"] == ""
    assert got["ok"] and got["name"] == "mine.glsl" and got["function"] == "f"
    assert 0 <= got["max"] < 1e-5 and float(got["shown"]) == pytest.approx(got["max"], rel=1e-3)
    size = got["size"]
    theirs = np.array(got["theirs"]).reshape(size, size, 4)[:, :, :3]
    want, keep = _sphere_reference(size)
    assert keep.sum() > 500
    assert np.all(np.abs(theirs[keep] - want[keep]) <= 5e-6 + 1e-4 * np.abs(want[keep]))


def test_wrong_implementation_shows_its_difference(tmp_path):
    code = (SUBJECTS / "eon_conforming.glsl").read_text()
    wrong = code.replace("float r = roughness;", "float r = roughness * roughness;", 1)
    assert wrong != code
    got = _open(_report(tmp_path, "squared.glsl", HOSTILE + wrong) / "explore.html")
    assert got["errors"] == [] and got["pwned"] is None and got["ok"]
    size = got["size"]
    theirs = np.array(got["theirs"]).reshape(size, size, 4)[:, :, :3]
    ref = np.array(got["ref"]).reshape(size, size, 4)[:, :, :3]
    want, keep = _sphere_reference(size)
    assert np.all(np.abs(ref[keep] - want[keep]) <= 5e-6 + 1e-4 * np.abs(want[keep]))  # the page's reference
    assert np.abs(theirs[keep] - want[keep]).max() > 1e-2  # theirs is off the library
    # the shown maximum is that of |theirs - reference| over the sphere's every pixel
    assert got["max"] == pytest.approx(np.abs(theirs - ref).max(), rel=1e-6)
    assert float(got["shown"]) == pytest.approx(got["max"], rel=1e-3)


def test_glsl_that_webgl_does_not_compile_is_a_one_line_message(tmp_path):
    # desktop GLSL converts the int 1 to float; GLSL ES 3.00 has no implicit conversion
    code = "vec3 f(vec3 wi, vec3 wo, float roughness, vec3 rho) { float k = 1; return rho * k / 3.14159265; }\n"
    got = _open(_report(tmp_path, "desktop.glsl", code) / "explore.html")
    assert not got["ok"] and got["errors"] == []
    assert got["error"].startswith("It does not compile in WebGL2") and "\n" not in got["error"]
