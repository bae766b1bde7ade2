"""Tiers of ``check`` (conforms / conforms with warnings / does not conform) in text, JSON and
JUnit, ``--expect-fail`` and ``--precision half``; one presentation for ``check FILE`` and
``check --cpp`` (the same region table for the same values); "no function NAME(...) in FILE".

The implementations are written here or in tests/_hand_eon.py (NumPy from the spec); the
float16 rounding is NumPy's own ``float16``.
"""

import json
import re
import xml.etree.ElementTree as ET

import _hand_eon as he
import numpy as np
import pytest
from _subject_mutants import write_mutant
from _system import requires

from openpbr_diffuse.cli.main import main
from openpbr_diffuse.conformance.grade import grade
from openpbr_diffuse.conformance.terms import which_term
from openpbr_diffuse.conformance.vectors import default_vectors, write_vectors

V = default_vectors(["eon"])


def _eq14(v):
    """EON with the Eq. 14 fit of E_F in f_ms and the albedo (Listing 1, exact = false)."""
    g1, g2, g3, g4 = 0.0571085289, 0.491881867, -0.332181442, 0.0714429953
    orig = he.e_f

    def fit(mu, r, guarded=True, digits=None):
        m = 1.0 - np.asarray(mu, float)
        return (1.0 + r * m * (g1 + m * (g2 + m * (g3 + m * g4)))) / (1.0 + he.C1 * r)

    he.e_f = fit
    try:
        out = he.eon(v)
    finally:
        he.e_f = orig
    # f_ss keeps the exact form (only f_ms uses E_F): the fit enters f_ms and the albedo only
    return out


def run(capsys, *args):
    status = main(["check", *args])
    cap = capsys.readouterr()
    return status, cap.out, cap.err


def write(tmp_path, name, out, v=V):
    p = tmp_path / name
    write_vectors(v, p, out=out)
    return p


def test_grade_tiers_half_precision():
    h = he.eon(V).astype(np.float16).astype(np.float64)
    g = grade(V, h)
    assert not g.passed and g.tier == "does not conform"
    g = grade(V, h, precision="half")
    assert not g.passed and g.tier == "conforms with warnings"
    assert g.warnings[0].startswith("half precision declared")
    # 2 ulp of float16 is beyond the warning
    two = he.eon(V) + 2.2 * np.maximum(np.abs(he.eon(V)), 1e-3) * 2.0**-10
    assert grade(V, two, precision="half").tier == "does not conform"
    assert grade(V, he.eon(V), precision="half").tier == "conforms"
    with pytest.raises(ValueError, match="precision"):
        grade(V, h, precision="quarter")


def test_grade_tier_eq14_fit_is_a_warning():
    g = grade(V, _eq14(V))
    assert g.diagnosis == "eq14_fit_for_exact"
    assert g.tier == "conforms with warnings"
    assert "Eq. 14 fit" in g.warnings[0]
    # a real bug stays "does not conform"
    assert grade(V, he.eon(V, drop_mu_i=True)).tier == "does not conform"


def test_check_text_json_junit_per_tier(tmp_path, capsys):
    good = write(tmp_path, "good.csv", he.eon(V))
    warn = write(tmp_path, "eq14.csv", _eq14(V))
    bad = write(tmp_path, "bad.csv", he.eon(V, extra_rho_ms=True))
    for path, tier, code in ((good, "conforms", 0), (warn, "conforms with warnings", 0), (bad, "does not conform", 1)):
        status, out, err = run(capsys, str(path))
        assert status == code and err == ""
        assert out.rstrip().splitlines()[-1] == f"  result: {tier}"
        status, out, _ = run(capsys, str(path), "--json")
        d = json.loads(out)
        assert status == code and d["tier"] == tier
        assert [c["id"] for c in d["checks"]][0] == "values"
        junit = tmp_path / f"{path.stem}.xml"
        status, _, _ = run(capsys, str(path), "--junit", str(junit))
        root = ET.parse(junit).getroot()
        cases = {c.get("name"): c for c in root.iter("testcase")}
        values = cases["values"]
        if tier == "conforms":
            assert values.find("failure") is None and values.find("system-out") is None
        elif tier == "conforms with warnings":
            assert values.find("failure") is None
            assert values.find("properties/property").get("value") == "warn"
            assert "Eq. 14" in values.find("system-out").text
        else:
            assert values.find("failure") is not None
        assert root.find("testsuite/properties/property").get("value") == tier
    # the JUnit file is never overwritten without --force
    status, _, err = run(capsys, str(good), "--junit", str(tmp_path / "good.xml"))
    assert status == 2 and "exists" in err and len(err.strip().splitlines()) == 1


def test_check_names_the_term(tmp_path, capsys):
    ss = he.eon(V, with_ms=False)
    out = ss + 1.18 * (he.eon(V) - ss)
    status, text, _ = run(capsys, str(write(tmp_path, "ms.csv", out)))
    assert status == 1
    line = next(x for x in text.splitlines() if x.startswith("  which term: "))
    assert "the error is in the multiple-scattering term" in line and "f_ms is 1.18x off" in line
    d = json.loads(run(capsys, str(tmp_path / "ms.csv"), "--json")[1])
    assert d["terms"] == line[len("  which term: ") :]


def test_which_term_single_scattering_and_branches():
    ss = he.eon(V, with_ms=False)
    ms = he.eon(V) - ss
    assert which_term(V, 1.02 * ss + ms).startswith("the error is in the single-scattering term: f_ss is 1.02x off")
    # s > 0 branch only: t = min instead of max changes nothing where s <= 0
    s = np.einsum("ij,ij->i", V.wi, V.wo) - V.wi[:, 2] * V.wo[:, 2]
    brdf = V.kind == "brdf"
    out = he.eon(V)
    sel = brdf & (s > 0) & (V.roughness > 0)
    out[sel] += 0.01 * ss[sel]
    assert "only the s > 0 branch fails" in which_term(V, out)
    # a factor of f_ms that follows a quantity
    assert "following 1/(1 - E_F(mu_i))" in which_term(V, he.eon(V, drop_mu_i=True))
    assert "following (rho)" in which_term(V, he.eon(V, extra_rho_ms=True))
    assert which_term(V, he.eon(V)) is None
    # L.V clamped: f_ms does not depend on the azimuth, so the s <= 0 rows blame f_ss
    text = which_term(V, he.eon(V, ldotv_clamp=True))
    assert text.startswith("the error is in the single-scattering term f_ss")
    assert "only the s <= 0 branch fails" in text


def test_check_precision_half(tmp_path, capsys):
    p = write(tmp_path, "half.csv", he.eon(V).astype(np.float16))
    assert run(capsys, str(p))[0] == 1
    status, out, _ = run(capsys, str(p), "--precision", "half")
    assert status == 0 and "CONFORMS WITH WARNINGS" in out.splitlines()[0]
    assert "half precision declared" in out


def test_expect_fail(tmp_path, capsys):
    bad = write(tmp_path, "bad.csv", he.eon(V, drop_mu_i=True))
    xf = tmp_path / "xfail.txt"
    xf.write_text(
        "# known failures\nvalues  # f_ms without its mu_i factor\nproperty.reciprocity\nproperty.lambert_at_zero\n"
    )
    status, out, _ = run(capsys, str(bad), "--expect-fail", str(xf))
    assert status == 0
    assert "[expected failure] values: expected failure" in out
    assert "[expected failure] property.reciprocity" in out
    assert out.rstrip().endswith("result: conforms")
    # a listed check that passes is reported
    xf.write_text(xf.read_text() + "property.horizon\n")
    status, out, _ = run(capsys, str(bad), "--expect-fail", str(xf))
    assert status == 0
    assert f"[unexpectedly passes] property.horizon: unexpectedly passes: remove it from {xf}" in out
    d = json.loads(run(capsys, str(bad), "--expect-fail", str(xf), "--json")[1])
    assert {c["id"]: c["status"] for c in d["checks"]}["property.horizon"] == "unexpectedly passes"
    # an unlisted failure still fails the run
    xf.write_text("property.reciprocity\n")
    assert run(capsys, str(bad), "--expect-fail", str(xf))[0] == 1
    # unusable list: exit 2, one line, before grading
    xf.write_bytes(b"\xff\xfe")
    status, out, err = run(capsys, str(bad), "--expect-fail", str(xf))
    assert status == 2 and out == "" and "--expect-fail" in err and len(err.strip().splitlines()) == 1
    status, _, err = run(capsys, str(bad), "--expect-fail", str(tmp_path / "missing.txt"))
    assert status == 2 and "--expect-fail" in err


def test_vector_file_reciprocity_from_swapped_rows(tmp_path, capsys):
    status, out, _ = run(capsys, str(write(tmp_path, "times_mu.csv", he.eon(V, drop_mu_i=True))), "--json")
    d = json.loads(out)
    rec = {c["id"]: c for c in d["checks"]}["property.reciprocity"]
    assert rec["status"] == "fail" and rec["detail"].startswith("not reciprocal: f(wi,wo)/f(wo,wi) up to ")
    assert "from the swapped pairs among the rows" in rec["detail"]


@requires("glm")
def test_missing_function_is_named(tmp_path, capsys):
    src = write_mutant("ms_extra_rho", "cpp", tmp_path)
    status, out, err = run(capsys, "--cpp", str(src), "--function", "eon_f", "--albedo-function", "albedo")
    assert status == 2 and out == ""
    assert err.strip().endswith(f"no function eon_f(...) in {src}")
    assert "does not compile" not in err
    # behind an #include the source cannot be searched: the compiler's "not declared" is translated
    (tmp_path / "lobe.h").write_text(src.read_text())
    top = tmp_path / "top.cpp"
    top.write_text('#include "lobe.h"\n')
    status, out, err = run(capsys, "--cpp", str(top), "--function", "eon_f", "--include", str(tmp_path))
    assert status == 2 and err.strip().endswith(f"no function eon_f(...) in {top}")
    assert run(capsys, "--cpp", str(top), "--function", "f", "--include", str(tmp_path))[0] == 1


@requires("glm")
def test_same_region_table_for_check_file_and_check_cpp(tmp_path, capsys):
    """One wrong implementation (f_ms times rho once more) in C++: its BRDF values, written to a
    vectors file, give the same region table and worst rows through ``check FILE`` as through
    ``check --cpp`` on the code."""
    from openpbr_diffuse.graders.generic import cpp_subject

    src = write_mutant("ms_extra_rho", "cpp", tmp_path)
    status, code_out, _ = run(capsys, "--cpp", str(src), "--function", "f", "--albedo-function", "albedo")
    assert status == 1
    subject = cpp_subject(str(src), "f", "albedo", model="eon")
    rows = V.subset(V.kind == "brdf")
    values = subject.brdf(rows.wi, rows.wo, rows.roughness, rows.rho)
    status, file_out, _ = run(capsys, str(write(tmp_path, "brdf.csv", np.asarray(values, float), rows)))
    assert status == 1

    def section(text, start):
        lines = text.splitlines()
        k = next(i for i, x in enumerate(lines) if x.strip().startswith(start))
        out = []
        for x in lines[k + 1 :]:
            if not x.startswith("    "):
                break
            out.append(x.strip())
        return out

    file_table = section(file_out, "by region")
    code_table = section(code_out, "by region")  # the first values grade printed: the BRDF's
    assert file_table and file_table == code_table
    assert section(file_out, "worst rows") == section(code_out, "worst rows")
    # the properties of the code are checks of their own: f_ms x rho is not EON's dependence on rho
    status, out, _ = run(capsys, "--cpp", str(src), "--function", "f", "--albedo-function", "albedo", "--json")
    checks = {c["id"]: c for c in json.loads(out)["checks"]}
    assert checks["property.rho_dependence"]["status"] == "fail"
    assert "f_ms with an extra rho" in checks["property.rho_dependence"]["detail"]
    assert checks["property.reciprocity"]["status"] == "pass"


@pytest.mark.parametrize("kind", [pytest.param("cpp", marks=requires("glm"))])
def test_template_grade_it_comment_runs(kind, tmp_path, capsys):
    """The command in the template's "Grade it" comment, run as written (THIS_FILE replaced),
    grades the Lambertian placeholder: exit 1 (not EON), no usage error."""
    import shlex

    path = tmp_path / f"mine.{kind}"
    assert main(["template", kind, "--out", str(path)]) == 0
    capsys.readouterr()
    lines = path.read_text().splitlines()
    k = next(i for i, x in enumerate(lines) if x.startswith("// Grade it"))
    command = lines[k + 1].removeprefix("//").strip()
    assert not command.endswith("\\") and lines[k + 2].strip() == "//"  # one complete line
    argv = shlex.split(command.replace("THIS_FILE", shlex.quote(str(path))))
    assert argv[:2] == ["openpbr-diffuse", "check"]
    status = main(argv[1:] + ["--quick"])
    out = capsys.readouterr().out
    assert status == 1 and "values.brdf" in out and "sampler" in out
    assert not re.search(r"(?<![A-Za-z])nan(?![A-Za-z])", out)  # sampler rows: no "max nan rms nan"


def _python_sampler(pdf_factor):
    import openpbr_diffuse as od
    from openpbr_diffuse.graders.subject import Subject

    def pdf(wo, wi, r):
        return od.pdf("eon", wo, wi, r) * pdf_factor(wo, wi)

    return Subject("s", "eon", None, "", sample=lambda wo, r, u: od.sample("eon", wo, r, u), pdf=pdf)


def test_sampler_pdf_error_blamed_on_mu_i_or_mu_o():
    """A pdf 10 % high where the SAMPLED direction is grazing (wi.z < 0.2) is blamed on mu_i;
    one 10 % high at grazing VIEW (wo.z < 0.2) on mu_o."""
    from openpbr_diffuse.graders.grading import SAMPLER_SAMPLES, grade_sampler

    q_pdf, q_chi = grade_sampler(_python_sampler(lambda wo, wi: np.where(wi[:, 2] < 0.2, 1.1, 1.0)))
    assert not q_pdf.passed
    assert "where the sampled mu_i < 0.2 (at every mu_o)" in q_pdf.sentence
    assert "grazing mu_o" not in q_pdf.sentence
    q_pdf, _ = grade_sampler(_python_sampler(lambda wo, wi: np.where(wo[:, 2] < 0.2, 1.1, 1.0)))
    assert "at grazing mu_o" in q_pdf.sentence and "where mu_o <= 0.15" in q_pdf.sentence
    assert "sampled mu_i <" not in q_pdf.sentence
    # one sample count whatever `quick` says: check and report (which passes quick) agree
    n = {quick: grade_sampler(_python_sampler(lambda wo, wi: 1.0), quick=quick)[1].n for quick in (True, False)}
    assert n[True] == n[False] == 6 * (SAMPLER_SAMPLES + 9)
