"""The report on the implementation under test, end to end: ``report --quick --glsl FILE
--function f`` (and ``--cpp``) on the conforming EON subjects of tests/subjects/ and on mutants
of them (tests/_subject_mutants.py).  A wrong function puts "does not conform: <diagnosis>" on
the first screen, seen in headless Chromium, and exits 1; the conforming one conforms and exits 0.
"""

import json

import _subject_mutants as sm
import pytest
from _browser import first_screen
from _system import requires

from openpbr_diffuse.cli.main import main
from openpbr_diffuse.conformance.grade import NOT_EXPLAINED

needs_gl = requires("gl")
needs_cxx = requires("glm")
#: the implementation's verdicts only (no evidence section): the quick cases that need no page
ONLY_IMPLEMENTATION = ["--select", "implementation.*"]


def report(capsys, out, *args):
    """(exit status, first stdout line, report.json) of ``report --quick ... --out out``."""
    capsys.readouterr()
    status = main(["report", "--quick", *args, "--out", str(out), "--no-progress"])
    first = capsys.readouterr().out.splitlines()[0]
    return status, first, json.loads((out / "report.json").read_text())


@pytest.fixture(scope="module")
def wrong_glsl(tmp_path_factory):
    """The report on the GLSL mutant that forgot 1/pi, with the library's quick evidence after it."""
    folder = tmp_path_factory.mktemp("wrong_glsl")
    path = sm.write_mutant("pi_forgotten", "glsl", folder)
    out = folder / "report"
    status = main(["report", "--quick", "--glsl", str(path), "--function", "f", "--out", str(out), "--no-progress"])
    return out, status, json.loads((out / "report.json").read_text())


@needs_gl
def test_wrong_glsl_exits_1_and_is_named(wrong_glsl):
    _, status, doc = wrong_glsl
    ut = doc["implementation"]
    assert status == 1 and ut["status"] == "does not conform"
    assert ut["headline"].startswith("glsl:pi_forgotten.glsl:f does not conform: constant_factor")
    brdf = next(v for v in ut["verdicts"] if v["quantity"] == "brdf")
    assert brdf["diagnosis"] == "constant_factor" and brdf["n_failed"] > 300
    assert brdf["worst"] and "wi (" in brdf["where"]
    assert doc["sections"] and all(s["status"] != "fail" for s in doc["sections"])  # the library's own evidence


@needs_gl
def test_wrong_glsl_first_screen_in_chromium(wrong_glsl):
    out, _, _ = wrong_glsl
    page = first_screen(out / "index.html")
    assert page["errors"] == [] and page["failed"] == []
    assert "does not conform: constant_factor" in page["text"]
    assert page["bottom"] <= page["height"]  # on the first screen
    assert page["body"].lstrip().startswith(page["text"].strip()[:40]) or page["text"] in page["body"][:600]
    assert page["images"] and all(done and width > 0 for _, done, width in page["images"])


@needs_gl
def test_conforming_glsl_exits_0_and_says_so(tmp_path, capsys):
    status, first, doc = report(
        capsys,
        tmp_path / "r",
        "--glsl",
        str(sm.GLSL_FILE),
        "--function",
        "f",
        "--albedo-function",
        "albedo",
        *ONLY_IMPLEMENTATION,
    )
    ut = doc["implementation"]
    assert status == 0 and ut["status"] == "conforms", ut["verdicts"]
    assert [v["status"] for v in ut["verdicts"]] == ["conforms", "conforms", "conforms"]  # brdf, albedo, properties
    assert first.startswith("glsl:eon_conforming.glsl:f conforms")
    page = first_screen(tmp_path / "r" / "index.html")
    assert page["errors"] == [] and "conforms" in page["text"] and "does not conform" not in page["text"]
    assert page["bottom"] <= page["height"]


@needs_cxx
@pytest.mark.parametrize("name,diagnosis", [("ms_missing_inv_pi", "ms_missing_inv_pi"), ("sin_mu_i", None)])
def test_wrong_cpp_exits_1_and_is_named(name, diagnosis, tmp_path, capsys):
    path = sm.write_mutant(name, "cpp", tmp_path)
    status, first, doc = report(
        capsys,
        tmp_path / "r",
        "--cpp",
        str(path),
        "--function",
        "f",
        "--albedo-function",
        "albedo",
        *ONLY_IMPLEMENTATION,
    )
    ut = doc["implementation"]
    assert status == 1 and ut["status"] == "does not conform"
    verdicts = {v["quantity"]: v for v in ut["verdicts"]}
    assert verdicts["brdf"]["diagnosis"] == diagnosis and verdicts["albedo"]["status"] == "conforms"
    said = diagnosis or NOT_EXPLAINED
    assert first.startswith(f"cpp:{name}.cpp:f does not conform: {said}")
    assert ut["headline"] == first
    if diagnosis is None:
        html = (tmp_path / "r" / "index.html").read_text()
        assert "closest" not in html.lower() and "closest" not in json.dumps(ut).lower()


@needs_cxx
def test_conforming_cpp_exits_0(tmp_path, capsys):
    status, first, doc = report(
        capsys,
        tmp_path / "r",
        "--cpp",
        str(sm.CPP_FILE),
        "--function",
        "f",
        "--albedo-function",
        "albedo",
        *ONLY_IMPLEMENTATION,
    )
    assert status == 0 and doc["implementation"]["status"] == "conforms"
    assert first == "cpp:eon_conforming.cpp:f conforms (BRDF, albedo, properties)"
