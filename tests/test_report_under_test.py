"""The report grades the implementation under test first: GLSL written here from the paper's
equations (EON, Portsmouth-Kutz-Hill 2025, Eq. 10-20), a correct one and one that returns FON
where EON is claimed; the first screen (in headless Chromium), exit codes, JUnit, --select,
--list-checks and "not run" sections."""

import json
import sys
import types
from xml.etree import ElementTree as ET

import pytest
from _system import CHROMIUM, need, reason

from openpbr_diffuse.cli.main import main
from openpbr_diffuse.report import runner
from openpbr_diffuse.report.model import Check, SectionResult

# EON from the paper's equations (Eq. 10-20): FON single scattering, exact E_F (Eq. 12-13, with
# 1 - S^3 written without cancellation), <E_F> (Eq. 15), f_ms and rho_ms (Eq. 16-20).
EON_GLSL = """
const float PI_ = 3.14159265358979;
const float C1 = 0.5 - 2.0 / (3.0 * PI_);
const float C2 = 2.0 / 3.0 - 28.0 / (15.0 * PI_);
float mine_EF(float mu, float r) {
    float S = sqrt(max(1.0 - mu * mu, 0.0));
    float GF = S * (acos(clamp(mu, -1.0, 1.0)) - S * mu)
             + (2.0 / 3.0) * (S * mu * (1.0 + S + S * S) / (1.0 + S) - S);
    return (1.0 + r * GF / PI_) / (1.0 + C1 * r);
}
vec3 mine_fss(vec3 wi, vec3 wo, float r, vec3 rho) {
    float s = dot(wi, wo) - wi.z * wo.z;
    float st = s > 0.0 ? s / max(wi.z, wo.z) : s;
    return rho / PI_ / (1.0 + C1 * r) * (1.0 + r * st);
}
vec3 mine_rho_ms(float r, vec3 rho) {
    float avg = (1.0 + C2 * r) / (1.0 + C1 * r);
    return rho * rho * avg / (vec3(1.0) - rho * (1.0 - avg));
}
vec3 eon(vec3 wi, vec3 wo, float r, vec3 rho) {
    if (wi.z <= 0.0 || wo.z <= 0.0) return vec3(0.0);
    float avg = (1.0 + C2 * r) / (1.0 + C1 * r);
    float ms = max(1e-7, 1.0 - mine_EF(wo.z, r)) * max(1e-7, 1.0 - mine_EF(wi.z, r)) / max(1e-7, 1.0 - avg);
    return mine_fss(wi, wo, r, rho) + mine_rho_ms(r, rho) / PI_ * ms;
}
vec3 eon_albedo(float mu, float r, vec3 rho) {
    float E = mine_EF(mu, r);
    return rho * E + mine_rho_ms(r, rho) * (1.0 - E);
}
vec3 fon_not_eon(vec3 wi, vec3 wo, float r, vec3 rho) {
    if (wi.z <= 0.0 || wo.z <= 0.0) return vec3(0.0);
    return mine_fss(wi, wo, r, rho);
}
"""

FAST = ["--select", "implementations.reference*", "--no-progress"]


@pytest.fixture(scope="module")
def glsl(tmp_path_factory):
    path = tmp_path_factory.mktemp("code") / "mine.glsl"
    path.write_text(EON_GLSL)
    return path


@pytest.fixture(scope="module")
def wrong(glsl, tmp_path_factory):
    out = tmp_path_factory.mktemp("wrong") / "report"
    status = main(
        [
            "report",
            "--glsl",
            str(glsl),
            "--function",
            "fon_not_eon",
            "--out",
            str(out),
            "--junit",
            str(out.parent / "junit.xml"),
            *FAST,
        ]
    )
    return out, status


def _could_not_run(out):
    doc = json.loads((out / "report.json").read_text())
    return doc["implementation"]["status"] == "could not run"


def test_wrong_glsl_does_not_conform_and_is_named(wrong):
    out, status = wrong
    if _could_not_run(out):
        pytest.skip(reason("gl"))
    assert status == 1
    doc = json.loads((out / "report.json").read_text())
    ut = doc["implementation"]
    assert ut["status"] == "does not conform"
    assert ut["headline"].startswith("glsl:mine.glsl:fon_not_eon does not conform: no_energy_compensation_fon")
    brdf = next(v for v in ut["verdicts"] if v["quantity"] == "brdf")
    assert brdf["max_abs_error"] > 1e-3 and "wi (" in brdf["where"] and brdf["worst"]
    assert doc["schema"] == "openpbr-diffuse-report/2"
    assert [s["key"] for s in doc["sections"]] == ["implementations"]  # --select ran only that


def test_correct_glsl_conforms(glsl, tmp_path, capsys):
    out = tmp_path / "report"
    status = main(
        [
            "report",
            "--glsl",
            str(glsl),
            "--function",
            "eon",
            "--albedo-function",
            "eon_albedo",
            "--out",
            str(out),
            *FAST,
        ]
    )
    if _could_not_run(out):
        pytest.skip(reason("gl"))
    doc = json.loads((out / "report.json").read_text())
    verdicts = doc["implementation"]["verdicts"]
    assert [(v["quantity"], v["status"]) for v in verdicts] == [
        ("brdf", "conforms"),
        ("albedo", "conforms"),
        ("properties", "conforms"),
    ], verdicts
    assert status == 0
    # the last line of the output is the implementation's verdict, not the evidence's count
    last = capsys.readouterr().out.splitlines()[-1]
    assert last.startswith("CONFORMS: ") and "properties" in last, last
    assert doc["implementation"]["tier"] == "conforms" == doc["implementation"]["status"]
    assert doc["implementation"]["figures"] and all(
        (out / f["file"]).is_file() for f in doc["implementation"]["figures"]
    )


FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
]


def test_first_screen_in_chromium_says_does_not_conform(wrong):
    from playwright import sync_api

    need("chromium")
    out, _ = wrong
    if _could_not_run(out):
        pytest.skip(reason("gl"))
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=FLAGS)
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 800})
            errors = []
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto((out / "index.html").resolve().as_uri(), wait_until="load")
            first = page.inner_text("body")[:400]
            box = page.eval_on_selector("#headline", "e => e.getBoundingClientRect().bottom")
            text = page.inner_text("#headline")
        finally:
            browser.close()
    assert errors == []
    assert box < 800  # on the first screen
    assert "does not conform: no_energy_compensation_fon" in text and text in first


def test_junit_has_one_testcase_per_check(wrong):
    out, _ = wrong
    doc = json.loads((out / "report.json").read_text())
    root = ET.parse(out.parent / "junit.xml").getroot()
    cases = root.findall(".//testcase")
    names = [c.get("name") for c in cases]
    verdicts = doc["implementation"]["verdicts"]
    ids = (
        [c["id"] for c in doc["checks"]]
        + [v["id"] for v in verdicts]
        + [c["id"] for v in verdicts for c in v["checks"]]
    )
    assert sorted(names) == sorted(ids) and len(set(names)) == len(names)
    if not _could_not_run(out):
        assert root.find(".//testcase[@name='implementation.brdf']/failure") is not None


def test_no_implementation_says_so_and_select_filters(tmp_path, capsys):
    out = tmp_path / "r"
    status = main(
        ["report", "--out", str(out), "--select", "implementations.no_energy_compensation_fon*", "--no-progress"]
    )
    assert status == 0
    first = capsys.readouterr().out.splitlines()[0]
    assert first.startswith("No implementation under test: this report shows the reference's own evidence.")
    doc = json.loads((out / "report.json").read_text())
    assert [c["id"] for c in doc["checks"]] == ["implementations.no_energy_compensation_fon_fails_and_is_diagnosed"]
    assert doc["implementation"] is None and "No implementation under test" in (out / "index.html").read_text()


def _fake_section(monkeypatch, key, build):
    mod = types.ModuleType(f"openpbr_diffuse.report.sections.{key}")
    mod.TITLE = key
    mod.build = build
    monkeypatch.setitem(sys.modules, mod.__name__, mod)


def test_a_section_that_ran_nothing_is_not_run(tmp_path, monkeypatch):
    _fake_section(monkeypatch, "simulation", lambda ctx: SectionResult("simulation", "s"))
    _fake_section(
        monkeypatch,
        "colorshift",
        lambda ctx: SectionResult(
            "colorshift", "c", checks=[Check("renders", 0.0, 1.0, reference="x", not_run="bpy absent")]
        ),
    )
    run = runner.run_report(None, tmp_path / "r", quick=True, progress=False, sections=["simulation", "colorshift"])
    doc = run.document
    assert [s["status"] for s in doc["sections"]] == ["not run", "not run"]
    assert doc["sections"][1]["not_run"] == "bpy absent" and doc["checks"][0]["status"] == "not run"
    html = (tmp_path / "r" / "index.html").read_text()
    assert "Not run: bpy absent" in html and "0 / 0" not in html
    assert run.exit_status == 0


def test_list_checks_prints_ids(capsys):
    assert main(["report", "--list-checks", "--select", "implementations", "--no-progress"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "implementations.reference_rounded_to_float32_conforms\treference rounded to float32 conforms" in lines
    assert any(line.startswith("implementation.brdf") for line in lines)


def test_vectors_file_is_graded_first(tmp_path):
    """A filled vectors file whose EON values are white-tinted (evaluated at rho = 1, times rho)."""
    from openpbr_diffuse.conformance.deviations import DEVIATIONS
    from openpbr_diffuse.conformance.vectors import default_vectors, write_vectors

    v = default_vectors()
    v = v.subset(v.model == "eon")
    path = write_vectors(v, tmp_path / "filled.csv", out=DEVIATIONS["white_tint"](v))
    out = tmp_path / "r"
    assert main(["report", "--vectors", str(path), "--out", str(out), *FAST]) == 1
    ut = json.loads((out / "report.json").read_text())["implementation"]
    assert ut["kind"] == "vectors" and ut["status"] == "does not conform"
    assert {v["quantity"]: v["diagnosis"] for v in ut["verdicts"]}["brdf"] == "white_tint"
    assert ut["verdict_line"].startswith(f"DOES NOT CONFORM: {path} (brdf: white_tint")


def test_last_line_is_the_implementations_verdict(tmp_path, capsys):
    """A CI log's tail reads as the implementation's result (exit status 1 unchanged)."""
    from openpbr_diffuse.conformance.deviations import DEVIATIONS
    from openpbr_diffuse.conformance.vectors import default_vectors, write_vectors

    v = default_vectors()
    v = v.subset(v.model == "eon")
    path = write_vectors(v, tmp_path / "mine.csv", out=DEVIATIONS["roughness_squared"](v))
    capsys.readouterr()
    assert main(["report", "--vectors", str(path), "--out", str(tmp_path / "r"), *FAST]) == 1
    lines = capsys.readouterr().out.splitlines()
    assert lines[-1].startswith(f"DOES NOT CONFORM: {path} (brdf: roughness_squared"), lines[-3:]
    assert any(line.startswith(("PASS: ", "FAIL: ", "NOT RUN: ")) for line in lines[:-1])


def test_conforms_with_warnings_is_its_own_tier(tmp_path, capsys):
    """The Eq. 14 fit where the exact albedo is claimed: a named, bounded deviation -> exit 0,
    "conforms with warnings" in the last line, the JSON and the JUnit XML."""
    from openpbr_diffuse.conformance.deviations import DEVIATIONS
    from openpbr_diffuse.conformance.vectors import default_vectors, write_vectors

    v = default_vectors()
    v = v.subset(v.model == "eon")
    path = write_vectors(v, tmp_path / "fit.csv", out=DEVIATIONS["eq14_fit_for_exact"](v))
    junit = tmp_path / "j.xml"
    capsys.readouterr()
    status = main(["report", "--vectors", str(path), "--out", str(tmp_path / "r"), "--junit", str(junit), *FAST])
    ut = json.loads((tmp_path / "r" / "report.json").read_text())["implementation"]
    assert ut["tier"] == "conforms with warnings", [(x["quantity"], x["status"]) for x in ut["verdicts"]]
    assert status == 0
    assert capsys.readouterr().out.splitlines()[-1].startswith(f"CONFORMS WITH WARNINGS: {path} (")
    xml = junit.read_text()
    assert 'name="tier" value="conforms with warnings"' in xml and "conforms with warnings:" in xml
    html = (tmp_path / "r" / "index.html").read_text()
    assert 'id="verdict-line" class="warntier"' in html


def test_code_that_does_not_compile_could_not_run(tmp_path, capsys):
    bad = tmp_path / "bad.glsl"
    bad.write_text("vec3 f(vec3 wi, vec3 wo, float r, vec3 rho) { return rho * undefined_thing; }\n")
    out = tmp_path / "r"
    status = main(["report", "--glsl", str(bad), "--function", "f", "--out", str(out), *FAST])
    assert status == 3
    first = capsys.readouterr().out.splitlines()[0]
    assert " could not run: " in first and "undefined_thing" in first
    assert (
        main(
            [
                "report",
                "--glsl",
                str(tmp_path / "missing.glsl"),
                "--function",
                "f",
                "--out",
                str(tmp_path / "r2"),
                *FAST,
            ]
        )
        == 2
    )
    assert not (tmp_path / "r2").exists()


def test_cpp_fon_for_eon_does_not_conform(tmp_path):
    need("glm")
    src = tmp_path / "mine.cpp"
    src.write_text("""
#include <cmath>
#include <glm/glm.hpp>
glm::vec3 fon(glm::vec3 wi, glm::vec3 wo, float r, glm::vec3 rho) {
    if (wi.z <= 0.f || wo.z <= 0.f) return glm::vec3(0.f);
    const float pi = 3.14159265358979f, c1 = 0.5f - 2.f / (3.f * pi);
    float s = glm::dot(wi, wo) - wi.z * wo.z;
    float st = s > 0.f ? s / std::max(wi.z, wo.z) : s;
    return rho / pi / (1.f + c1 * r) * (1.f + r * st);
}
""")
    out = tmp_path / "r"
    assert main(["report", "--cpp", str(src), "--function", "fon", "--out", str(out), *FAST]) == 1
    ut = json.loads((out / "report.json").read_text())["implementation"]
    assert ut["headline"].endswith(
        "does not conform: no_energy_compensation_fon: " + ut["verdicts"][0]["sentence"].split(": ", 1)[1]
    )
    assert ut["verdicts"][0]["diagnosis"] == "no_energy_compensation_fon"


def test_select_matching_nothing_is_unusable_input(tmp_path, capsys):
    assert main(["report", "--select", "no_such_section*", "--out", str(tmp_path / "r"), "--no-progress"]) == 2
    assert "no_such_section" in capsys.readouterr().err and not (tmp_path / "r").exists()
