"""Grading a user's sampler and pdf (``--sample-function S --pdf-function P``), GLSL and C++.

The samplers are written here, independently of the library's code: the EON sampler of
Portsmouth, Kutz and Hill (JCGT 2025) Section 3.1 -- the clipped LTC of Listing 3 (coefficients
of Listing 2) mixed one-sample with uniform hemisphere sampling (Listing 4) -- and
cosine-weighted hemisphere sampling with its exact pdf mu_i / pi (Eq. 21).  Two wrong ones:
the EON sampler whose pdf reports 10 % too much at grazing view (mu_o < 0.2), and cosine samples
reported with the uniform hemisphere pdf 1 / (2 pi).

The grading must accept both correct samplers (cosine as a valid sampler whose pdf is not
"eon"'s, with the variance warning at grazing view the paper's Fig. 10-12 predicts), reject the
two wrong ones with the diagnosis named, and count NaN / below-horizon samples.
"""

import json
from xml.etree import ElementTree as ET

import pytest
from _system import requires

from openpbr_diffuse.cli.main import main
from openpbr_diffuse.graders import generic
from openpbr_diffuse.graders.grading import (
    SAMPLER_MASS_TOL,
    grade_sampler,
    grade_subject,
)

# --- GLSL: written from the paper's Listings 2-4 -------------------------------------------------
GLSL = """
const float T_PI = 3.14159265358979;

// Listing 2: the LTC coefficients of (mu_o, r); M = [[a, 0, b], [0, c, 0], [d, 0, 1]]
void t_ltc(float mu, float r, out float a, out float b, out float c, out float d) {
    a = 1.0 + r * (0.303392 + (-0.518982 + 0.111709 * mu) * mu + (-0.276266 + 0.335918 * mu) * r);
    b = r * (-1.16407 + 1.15859 * mu + (0.150815 - 0.150105 * mu) * r) / (mu * mu * mu - 1.43545);
    c = 1.0 + (0.20013 + (-0.506373 + 0.261777 * mu) * mu) * r;
    d = r * (0.540852 + (-1.01625 + 0.475392 * mu) * mu) / (-1.0743 + mu * (0.0725628 + mu));
}
void t_frame(vec3 wo, out vec3 X, out vec3 Y) {
    float l = length(wo.xy);
    X = l > 1e-7 ? vec3(wo.xy / l, 0.0) : vec3(1.0, 0.0, 0.0);
    Y = vec3(-X.y, X.x, 0.0);
}
float t_Pu(float mu, float r) {
    return pow(r, 0.1) * (0.162925 + mu * (-0.372058 + (0.538233 - 0.290822 * mu) * mu));
}
// Listing 3: the clipped LTC's density of wi
float t_cltc_pdf(vec3 wo, vec3 wi, float r) {
    float a, b, c, d; t_ltc(wo.z, r, a, b, c, d);
    vec3 X, Y; t_frame(wo, X, Y);
    vec3 w = vec3(dot(wi, X), dot(wi, Y), wi.z);
    vec3 wh = vec3(c * (w.x - b * w.z), (a - b * d) * w.y, -c * (d * w.x - a * w.z));
    float det = c * (a - b * d);
    float s = 0.5 * (1.0 + 1.0 / sqrt(d * d + 1.0));
    float l2 = dot(wh, wh);
    return (det / l2) * (det / l2) * max(wh.z, 0.0) / (T_PI * s);
}
vec3 t_cltc_sample(vec3 wo, vec2 u, float r) {
    float a, b, c, d; t_ltc(wo.z, r, a, b, c, d);
    vec3 X, Y; t_frame(wo, X, Y);
    float R = sqrt(u.x), phi = 2.0 * T_PI * u.y;
    float x = R * cos(phi), y = R * sin(phi);
    float s = 0.5 * (1.0 + 1.0 / sqrt(d * d + 1.0));
    x = -mix(sqrt(max(0.0, 1.0 - y * y)), x, s);
    vec3 wh = vec3(x, y, sqrt(max(0.0, 1.0 - x * x - y * y)));
    vec3 w = vec3(a * wh.x + b * wh.z, c * wh.y, d * wh.x + wh.z);
    return normalize(w.x * X + w.y * Y + w.z * vec3(0.0, 0.0, 1.0));
}
// Listing 4: one-sample MIS of uniform and CLTC
vec3 eon_sample(vec3 wo, vec2 u, float r) {
    float Pu = t_Pu(wo.z, r);
    if (u.x < Pu) {
        float z = u.x / Pu, st = sqrt(max(0.0, 1.0 - z * z)), phi = 2.0 * T_PI * u.y;
        return vec3(st * cos(phi), st * sin(phi), z);
    }
    return t_cltc_sample(wo, vec2((u.x - Pu) / (1.0 - Pu), u.y), r);
}
float eon_pdf(vec3 wo, vec3 wi, float r) {
    float Pu = t_Pu(wo.z, r);
    return Pu / (2.0 * T_PI) + (1.0 - Pu) * t_cltc_pdf(wo, wi, r);
}
// wrong: 10 % too much density reported at grazing view
float eon_pdf_grazing_off(vec3 wo, vec3 wi, float r) {
    return eon_pdf(wo, wi, r) * (wo.z < 0.2 ? 1.1 : 1.0);
}
// Eq. 21: cosine-weighted hemisphere sampling
vec3 cos_sample(vec3 wo, vec2 u, float r) {
    float R = sqrt(u.x), phi = 2.0 * T_PI * u.y;
    return vec3(R * cos(phi), R * sin(phi), sqrt(max(0.0, 1.0 - u.x)));
}
float cos_pdf(vec3 wo, vec3 wi, float r) { return max(wi.z, 0.0) / T_PI; }
// wrong: the uniform hemisphere's pdf for cosine samples
float uniform_pdf(vec3 wo, vec3 wi, float r) { return wi.z >= 0.0 ? 1.0 / (2.0 * T_PI) : 0.0; }
// wrong: a NaN at u.x = 0 and a sample below the horizon at u.y = 0.5
vec3 cos_sample_nan(vec3 wo, vec2 u, float r) {
    if (u.x == 0.0) return vec3(uintBitsToFloat(0x7fc00000u));   // NaN
    vec3 w = cos_sample(wo, u, r);
    return u.y == 0.5 ? vec3(w.xy, -w.z) : w;
}
"""

# --- C++ (GLM): the same equations, written again ------------------------------------------------
CPP = """
#include <cmath>
#include <glm/glm.hpp>

static const float T_PI = 3.14159265358979f;

struct TLtc { float a, b, c, d; };
static TLtc t_ltc(float mu, float r) {
    TLtc m;
    m.a = 1.0f + r * (0.303392f + (-0.518982f + 0.111709f * mu) * mu + (-0.276266f + 0.335918f * mu) * r);
    m.b = r * (-1.16407f + 1.15859f * mu + (0.150815f - 0.150105f * mu) * r) / (mu * mu * mu - 1.43545f);
    m.c = 1.0f + (0.20013f + (-0.506373f + 0.261777f * mu) * mu) * r;
    m.d = r * (0.540852f + (-1.01625f + 0.475392f * mu) * mu) / (-1.0743f + mu * (0.0725628f + mu));
    return m;
}
static void t_frame(glm::vec3 wo, glm::vec3& X, glm::vec3& Y) {
    const float l = std::sqrt(wo.x * wo.x + wo.y * wo.y);
    X = l > 1e-7f ? glm::vec3(wo.x / l, wo.y / l, 0.0f) : glm::vec3(1.0f, 0.0f, 0.0f);
    Y = glm::vec3(-X.y, X.x, 0.0f);
}
static float t_Pu(float mu, float r) {
    return std::pow(r, 0.1f) * (0.162925f + mu * (-0.372058f + (0.538233f - 0.290822f * mu) * mu));
}
static float t_cltc_pdf(glm::vec3 wo, glm::vec3 wi, float r) {
    const TLtc m = t_ltc(wo.z, r);
    glm::vec3 X, Y; t_frame(wo, X, Y);
    const glm::vec3 w(glm::dot(wi, X), glm::dot(wi, Y), wi.z);
    const glm::vec3 wh(m.c * (w.x - m.b * w.z), (m.a - m.b * m.d) * w.y, -m.c * (m.d * w.x - m.a * w.z));
    const float det = m.c * (m.a - m.b * m.d);
    const float s = 0.5f * (1.0f + 1.0f / std::sqrt(m.d * m.d + 1.0f));
    const float q = det / glm::dot(wh, wh);
    return q * q * std::fmax(wh.z, 0.0f) / (T_PI * s);
}
static glm::vec3 t_cltc_sample(glm::vec3 wo, glm::vec2 u, float r) {
    const TLtc m = t_ltc(wo.z, r);
    glm::vec3 X, Y; t_frame(wo, X, Y);
    const float R = std::sqrt(u.x), phi = 2.0f * T_PI * u.y;
    float x = R * std::cos(phi);
    const float y = R * std::sin(phi);
    const float s = 0.5f * (1.0f + 1.0f / std::sqrt(m.d * m.d + 1.0f));
    x = -((1.0f - s) * std::sqrt(std::fmax(0.0f, 1.0f - y * y)) + s * x);
    const glm::vec3 wh(x, y, std::sqrt(std::fmax(0.0f, 1.0f - x * x - y * y)));
    const glm::vec3 w(m.a * wh.x + m.b * wh.z, m.c * wh.y, m.d * wh.x + wh.z);
    return glm::normalize(w.x * X + w.y * Y + glm::vec3(0.0f, 0.0f, w.z));
}
glm::vec3 eon_sample(glm::vec3 wo, glm::vec2 u, float r) {
    const float Pu = t_Pu(wo.z, r);
    if (u.x < Pu) {
        const float z = u.x / Pu, st = std::sqrt(std::fmax(0.0f, 1.0f - z * z)), phi = 2.0f * T_PI * u.y;
        return glm::vec3(st * std::cos(phi), st * std::sin(phi), z);
    }
    return t_cltc_sample(wo, glm::vec2((u.x - Pu) / (1.0f - Pu), u.y), r);
}
float eon_pdf(glm::vec3 wo, glm::vec3 wi, float r) {
    const float Pu = t_Pu(wo.z, r);
    return Pu / (2.0f * T_PI) + (1.0f - Pu) * t_cltc_pdf(wo, wi, r);
}
float eon_pdf_grazing_off(glm::vec3 wo, glm::vec3 wi, float r) {
    return eon_pdf(wo, wi, r) * (wo.z < 0.2f ? 1.1f : 1.0f);
}
glm::vec3 cos_sample(glm::vec3 wo, glm::vec2 u, float r) {
    const float R = std::sqrt(u.x), phi = 2.0f * T_PI * u.y;
    return glm::vec3(R * std::cos(phi), R * std::sin(phi), std::sqrt(std::fmax(0.0f, 1.0f - u.x)));
}
float cos_pdf(glm::vec3 wo, glm::vec3 wi, float r) { return std::fmax(wi.z, 0.0f) / T_PI; }
float uniform_pdf(glm::vec3 wo, glm::vec3 wi, float r) { return wi.z >= 0.0f ? 1.0f / (2.0f * T_PI) : 0.0f; }
"""

needs_cxx = requires("glm")


needs_gl = requires("gl")


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("samplers")
    (d / "samplers.glsl").write_text(GLSL)
    (d / "samplers.cpp").write_text(CPP)
    return d


def _subject(files, lang, sample, pdf):
    if lang == "glsl":
        return generic.glsl_subject(files / "samplers.glsl", sample_function=sample, pdf_function=pdf)
    return generic.cpp_subject(files / "samplers.cpp", sample_function=sample, pdf_function=pdf)


_graded = {}


def graded(files, lang, sample, pdf, claim=None):
    """Grade once per (language, functions, claim) in this module (GLSL runs cost ~1 s each)."""
    key = (lang, sample, pdf, claim)
    if key not in _graded:
        q_pdf, q_chi = grade_sampler(_subject(files, lang, sample, pdf), quick=True, claim=claim)
        _graded[key] = (q_pdf, q_chi)
    return _graded[key]


def _check(q, check_id):
    return next(c for c in q.checks if c["id"] == check_id)


def _assert_eon_accepted(q_pdf, q_chi):
    assert q_pdf.passed and q_chi.passed, (q_pdf.sentence, q_chi.sentence)
    ref = _check(q_pdf, "sampler_pdf.reference")
    assert ref["status"] == "pass" and ref["by_strategy"]["eon"] <= 2e-3
    assert ref["by_strategy"]["cosine"] > 0.1  # and it is not the cosine pdf
    assert _check(q_pdf, "sampler_pdf.normalisation")["measured"] < 1e-3
    # the reference sampler's variance, within Monte Carlo noise of the same estimator
    assert 0.8 < _check(q_chi, "sampler_chi2.variance")["measured"] < 1.25
    assert not q_chi.warnings


def _assert_grazing_rejected(q_pdf, q_chi):
    assert not q_pdf.passed and q_pdf.diagnosis == "pdf_not_normalised"
    assert "pdf integrates to 1.1 at grazing mu_o" in q_pdf.sentence
    norm = _check(q_pdf, "sampler_pdf.normalisation")
    assert norm["status"] == "fail" and abs(norm["measured"] - 0.1) < 2e-3
    # the samples do not follow the reported pdf; rescaled to 1, they would
    assert not q_chi.passed and q_chi.diagnosis == "samples_do_not_follow_pdf"
    assert "chi² p = " in q_chi.sentence and "integrates to 1.1" in q_chi.sentence


def _assert_uniform_pdf_rejected(q_pdf, q_chi):
    assert q_pdf.passed  # 1 / (2 pi) is a normalised pdf ...
    assert not q_chi.passed and q_chi.diagnosis == "samples_do_not_follow_pdf"  # ... not theirs
    assert _check(q_chi, "sampler_chi2.chi2")["measured"] < 1e-12
    assert q_chi.sentence.startswith("samples do not follow the pdf (chi² p = ")


@needs_gl
def test_glsl_eon_sampler_from_the_paper_is_accepted_and_matches_eon(files):
    _assert_eon_accepted(*graded(files, "glsl", "eon_sample", "eon_pdf", claim="eon"))


@needs_gl
def test_glsl_pdf_10_percent_off_at_grazing_view_fails_the_report(files, tmp_path, capsys):
    """Through ``report``: the first line names it, the sub-checks carry their ids in the JSON, the
    HTML and the JUnit file, and the histograms are drawn."""
    out = tmp_path / "report"
    status = main(
        [
            "report",
            "--glsl",
            str(files / "samplers.glsl"),
            "--sample-function",
            "eon_sample",
            "--pdf-function",
            "eon_pdf_grazing_off",
            "--sampler-model",
            "eon",
            "--out",
            str(out),
            "--evidence",
            "none",
            "--no-progress",
            "--junit",
            str(tmp_path / "junit.xml"),
        ]
    )
    first = capsys.readouterr().out.splitlines()[0]
    assert status == 1
    assert first.startswith("glsl:samplers.glsl:eon_sample does not conform: pdf integrates to 1.1 at grazing mu_o")
    assert "cases off by more than 0.005, at mu_o 0.02 to 0.15)" in first  # exactly the mu_o < 0.2 ones
    doc = json.loads((out / "report.json").read_text())
    v = {x["id"]: x for x in doc["implementation"]["verdicts"]}
    pdf, chi = v["implementation.sampler_pdf"], v["implementation.sampler_chi2"]
    assert pdf["status"] == chi["status"] == "does not conform" and pdf["label"] == "pdf"
    checks = {c["id"]: c for c in pdf["checks"] + chi["checks"]}
    norm = checks["implementation.sampler_pdf.normalisation"]
    assert norm["status"] == "fail" and abs(norm["measured"] - 0.1) < 2e-3
    assert checks["implementation.sampler_pdf.reference"]["status"] == "fail"  # claimed eon
    assert checks["implementation.sampler_chi2.chi2"]["status"] == "fail"
    assert checks["implementation.sampler_chi2.valid"]["status"] == "pass"
    assert "integrates to 1.1" in chi["sentence"] and "p = " in chi["sentence"]
    # rescaled to 1 the pdf is right: the samples are EON's
    assert "against it rescaled to 1: p = " in chi["sentence"]
    html = (out / "index.html").read_text()
    assert 'data-id="implementation.sampler_pdf.normalisation"' in html
    for name in ("subject_sampler_cos.png", "subject_sampler_phi.png", "subject_sampler_residuals.png"):
        assert (out / "images" / name).stat().st_size > 1000 and f"images/{name}" in html
    root = ET.parse(tmp_path / "junit.xml").getroot()
    assert root.find(".//testcase[@name='implementation.sampler_pdf.normalisation']/failure") is not None
    assert root.find(".//testcase[@name='implementation.sampler_chi2.valid']/failure") is None


@needs_gl
def test_glsl_cosine_samples_with_the_uniform_pdf_are_rejected(files):
    _assert_uniform_pdf_rejected(*graded(files, "glsl", "cos_sample", "uniform_pdf"))


@pytest.mark.slow
@needs_gl
def test_glsl_nan_and_below_horizon_samples_are_counted_and_named(files):
    _, q_chi = graded(files, "glsl", "cos_sample_nan", "cos_pdf")
    valid = _check(q_chi, "sampler_chi2.valid")
    counts = valid["counts"]
    # corners u.x = 0 (3 per case) give NaN; u.y = 0.5 (2 more corners + random u of that value,
    # which float32 rounding makes rare) give z < 0: 6 cases
    assert counts["nan"] == 3 * 6 and counts["below_horizon"] >= 2 * 6
    assert not q_chi.passed and q_chi.diagnosis == "samples_not_finite"
    assert "NaN/Inf" in q_chi.sentence and "below the horizon" in q_chi.sentence and "u = (0," in q_chi.sentence


@needs_cxx
def test_cpp_pdf_10_percent_off_at_grazing_view_is_rejected(files):
    _assert_grazing_rejected(*graded(files, "cpp", "eon_sample", "eon_pdf_grazing_off"))


@needs_cxx
def test_cpp_cosine_sampler_is_valid_with_a_pdf_other_than_eon(files):
    q_pdf, q_chi = graded(files, "cpp", "cos_sample", "cos_pdf", claim=None)
    assert q_pdf.passed and q_chi.passed
    ref = _check(q_pdf, "sampler_pdf.reference")
    assert ref["status"] == "info" and ref["by_strategy"]["cosine"] < 1e-5 and ref["by_strategy"]["eon"] > 0.1
    assert "matches the reference 'cosine' strategy's pdf (not the 'eon' one" in q_pdf.sentence
    # EON paper Fig. 10-12: cosine sampling is much noisier than EON's at grazing view, r = 1
    var = _check(q_chi, "sampler_chi2.variance")
    assert var["status"] == "warn" and var["measured"] > 10
    assert "warning: the variance of f mu_i / pdf is" in q_chi.sentence
    # claimed to be EON sampling, the same sampler fails the pdf comparison
    q_pdf2, _ = grade_sampler(_subject(files, "cpp", "cos_sample", "cos_pdf"), quick=True, claim="eon")
    assert not q_pdf2.passed and q_pdf2.diagnosis == "pdf_differs_from_eon"
    assert "(it matches 'cosine')" in q_pdf2.sentence


@needs_cxx
def test_check_cli_grades_a_cpp_sampler_with_stable_ids(files, capsys):
    status = main(
        [
            "check",
            "--cpp",
            str(files / "samplers.cpp"),
            "--sample-function",
            "cos_sample",
            "--pdf-function",
            "uniform_pdf",
            "--quick",
            "--json",
        ]
    )
    doc = json.loads(capsys.readouterr().out)
    assert status == 1 and not doc["passed"]
    q = {x["quantity"]: x for x in doc["quantities"]}
    assert [c["id"] for c in q["sampler pdf"]["checks"]] == ["sampler_pdf.normalisation", "sampler_pdf.reference"]
    assert [c["id"] for c in q["sampler chi2"]["checks"]] == [
        "sampler_chi2.chi2",
        "sampler_chi2.valid",
        "sampler_chi2.variance",
    ]
    assert q["sampler chi2"]["diagnosis"] == "samples_do_not_follow_pdf" and "plot" not in q["sampler chi2"]
    status = main(
        [
            "check",
            "--cpp",
            str(files / "samplers.cpp"),
            "--sample-function",
            "cos_sample",
            "--pdf-function",
            "cos_pdf",
            "--quick",
        ]
    )
    out = capsys.readouterr().out
    assert status == 0 and "[warn] sampler_chi2.variance" in out and "[pass] sampler_pdf.normalisation" in out


def test_sampler_options_go_together_and_name_the_option(files, capsys):
    with pytest.raises(ValueError, match="--sample-function and --pdf-function go together"):
        generic.glsl_subject(files / "samplers.glsl", sample_function="eon_sample")
    with pytest.raises(ValueError, match="--pdf-function: 'x y'"):
        generic.cpp_subject(files / "samplers.cpp", sample_function="eon_sample", pdf_function="x y")
    assert main(["check", "--sample-function", "eon_sample", "--pdf-function", "eon_pdf"]) == 2
    assert "needs --implementation, --glsl or --cpp" in capsys.readouterr().err
    assert (
        main(
            [
                "check",
                "--cpp",
                str(files / "samplers.cpp"),
                "--sample-function",
                "s",
                "--pdf-function",
                "p",
                "--sampler-model",
                "nope",
            ]
        )
        == 2
    )


def test_normalisation_tolerance_separates_float32_from_a_10_percent_error():
    assert 1e-4 < SAMPLER_MASS_TOL < 0.1 / 10


# --- the rest of the matrix: slow (llvmpipe runs and g++ compiles) -------------------------------


@pytest.mark.slow
@needs_cxx
def test_cpp_eon_sampler_from_the_paper_is_accepted(files):
    _assert_eon_accepted(*graded(files, "cpp", "eon_sample", "eon_pdf", claim="eon"))


@pytest.mark.slow
@needs_cxx
def test_cpp_cosine_samples_with_the_uniform_pdf_are_rejected(files):
    _assert_uniform_pdf_rejected(*graded(files, "cpp", "cos_sample", "uniform_pdf"))


@pytest.mark.slow
@needs_gl
def test_glsl_cosine_sampler_is_valid_and_full_sample_counts_agree(files):
    q_pdf, q_chi = grade_sampler(_subject(files, "glsl", "cos_sample", "cos_pdf"), quick=False)
    from openpbr_diffuse.graders.grading import SAMPLER_SAMPLES

    assert q_pdf.passed and q_chi.passed and q_chi.n == 6 * (SAMPLER_SAMPLES + 9)
    q_pdf, q_chi = grade_sampler(_subject(files, "glsl", "eon_sample", "eon_pdf_grazing_off"), quick=False)
    assert not q_pdf.passed and not q_chi.passed


@pytest.mark.slow
@needs_gl
def test_glsl_sampler_with_its_brdf_through_grade_subject(files, tmp_path):
    """The variance uses the subject's own f when --function is given (here the reference's
    EON written in GLSL in test_report_under_test)."""
    from test_report_under_test import EON_GLSL

    path = tmp_path / "both.glsl"
    path.write_text(EON_GLSL + GLSL)
    subject = generic.glsl_subject(path, "eon", sample_function="eon_sample", pdf_function="eon_pdf")
    result = grade_subject(subject, quick=True, quantities=("brdf", "sampler"), sampler_model="eon")
    assert result.passed, [(q.quantity, q.sentence or q.detail) for q in result.quantities]
    var = next(c for q in result.quantities for c in q.checks if c["id"] == "sampler_chi2.variance")
    assert "their f" in var["detail"] and 0.8 < var["measured"] < 1.25
