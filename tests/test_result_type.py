"""One result type end to end: every grade is an ``openpbr_diffuse.result.Result`` and reaches
``report.json``, ``check --json`` and JUnit with the same fields (id, quantity, measured,
threshold, verdict, tier, finding, worst inputs).

The implementation graded here is tests/_hand_eon.py (NumPy written from the EON paper's
equations), right and with the extra rho on its multiple-scattering term (Cycles' deviation).
"""

import json
import math
import xml.etree.ElementTree as ET

import _hand_eon as he
import numpy as np
import pytest

from openpbr_diffuse.cli.main import main
from openpbr_diffuse.conformance.grade import Grade, grade
from openpbr_diffuse.conformance.tiers import check_from_grade
from openpbr_diffuse.conformance.vectors import default_vectors, write_vectors
from openpbr_diffuse.graders.grading import QuantityGrade, quantity_from_grade
from openpbr_diffuse.report.model import Check, CheckTable, registry
from openpbr_diffuse.report.subject import Verdict, verdict_from_quantity
from openpbr_diffuse.result import COMMON_KEYS, Result, junit_case, sub_check

V = default_vectors(["eon"])
CORE = set(COMMON_KEYS)


@pytest.mark.parametrize(
    ("measured", "threshold", "comparison", "expected", "verdict"),
    [
        (0.5, 1.0, "<=", None, "pass"),
        (1.5, 1.0, "<=", None, "fail"),
        (math.nan, 1.0, "<=", None, "fail"),  # NaN never passes
        (None, 1.0, "<=", None, "fail"),
        (0.9, 1.0, ">=", None, "fail"),
        (1.05, 0.1, "==", 1.0, "pass"),
        (1.2, 0.1, "==", 1.0, "fail"),
    ],
)
def test_verdict_follows_the_comparison(measured, threshold, comparison, expected, verdict):
    r = Result(id="t.x", quantity="x", measured=measured, threshold=threshold, comparison=comparison, expected=expected)
    assert r.verdict == verdict and r.passed is (verdict == "pass")
    assert r.effective_tier == ("conforms" if verdict == "pass" else "does not conform")


def test_not_run_neither_passes_nor_fails():
    r = Check("renders", 0.0, 1.0, not_run="bpy absent")
    assert (r.verdict, r.status, r.passed, r.effective_tier) == ("not run", "not run", False, "could not run")


def test_every_producer_makes_a_result():
    g = grade(V, he.eon(V, extra_rho_ms=True))
    table = CheckTable.declared("albedo")
    produced = {
        "grade": g,
        "section check": table.check(table.ids[0], 1e-5, 1e-4),
        "graded quantity": quantity_from_grade("brdf", g),
        "sampler quantity": QuantityGrade("sampler pdf", True, 1e-4, math.nan, "t", "r", measured=1e-4, threshold=5e-3),
        "verdict": Verdict("brdf", "does not conform", "white_tint"),
        "sub-check": sub_check("sampler_chi2.chi2", "warn", 0.02, 0.01),
    }
    for what, r in produced.items():
        assert isinstance(r, Result), what
        assert CORE <= set(r.to_dict()), what
    assert isinstance(g, Grade) and g.finding == "rho_ms_extra_rho" and g.measured > g.threshold == 1.0
    assert g.worst and all("wi" in row and "got" in row for row in g.worst)
    v = verdict_from_quantity(produced["graded quantity"])
    assert (v.id, v.status, v.finding) == ("implementation.brdf", "does not conform", "rho_ms_extra_rho")
    assert v.measured == pytest.approx(g.measured) and v.worst


def test_check_json_checks_are_results():
    c = check_from_grade("values.brdf", grade(V, he.eon(V, extra_rho_ms=True)))
    assert CORE <= set(c) and c["verdict"] == c["status"] == "fail" and c["finding"] == "rho_ms_extra_rho"
    ok = check_from_grade("values.brdf", grade(V, he.eon(V)))
    assert (ok["verdict"], ok["tier"], ok["finding"]) == ("pass", "conforms", None) and ok["measured"] <= 1.0


@pytest.mark.parametrize(
    ("status", "element"),
    [("fail", "failure"), ("not run", "skipped"), ("skip", "skipped"), ("could not run", "error"), ("pass", None)],
)
def test_one_junit_case_per_result(status, element):
    suite = ET.Element("testsuite")
    case = junit_case(suite, {"id": "a.b", "status": status, "detail": "why"}, "a")
    assert case.get("name") == "a.b"
    found = [e.tag for e in case if e.tag in ("failure", "skipped", "error")]
    assert found == ([element] if element else [])


def test_registry_rows_are_the_sections_tables():
    from openpbr_diffuse.report.sections import SECTIONS

    ids = [s.id for s in registry()]
    assert len(ids) == len(set(ids))
    assert ids == [i for key in SECTIONS for i in CheckTable.declared(key).ids]  # page order


def test_report_and_check_carry_the_same_fields(tmp_path, capsys):
    """A wrong implementation through ``report --vectors`` and ``check --json/--junit``."""
    path = tmp_path / "mine.csv"
    write_vectors(V, path, out=he.eon(V, extra_rho_ms=True))
    out, junit = tmp_path / "r", tmp_path / "r.xml"
    fast = ["--select", "implementations.reference*", "--no-progress"]
    assert main(["report", "--vectors", str(path), "--out", str(out), "--junit", str(junit), *fast]) == 1
    doc = json.loads((out / "report.json").read_text())
    verdicts = doc["implementation"]["verdicts"]
    assert doc["checks"] and all(CORE <= set(c) and c["kind"] == "check" for c in doc["checks"])
    assert verdicts and all(CORE <= set(v) and v["kind"] == "quantity" for v in verdicts)
    brdf = next(v for v in verdicts if v["id"] == "implementation.brdf")
    assert (brdf["verdict"], brdf["tier"], brdf["finding"]) == ("fail", "does not conform", "rho_ms_extra_rho")
    assert brdf["measured"] > brdf["threshold"] and brdf["worst"][0]["got"] != brdf["worst"][0]["expected"]
    names = {c.get("name") for c in ET.parse(junit).getroot().iter("testcase")}
    assert {c["id"] for c in doc["checks"]} | {v["id"] for v in verdicts} <= names
    capsys.readouterr()
    assert main(["check", str(path), "--json"]) == 1
    d = json.loads(capsys.readouterr().out)
    assert all(CORE <= set(c) for c in d["checks"])
    assert next(c for c in d["checks"] if c["id"].startswith("values"))["finding"] == "rho_ms_extra_rho"
    assert np.isfinite(d["max_normalised_error"])


def test_asdict_carries_the_derived_fields():
    """``dataclasses.asdict`` of a result holds its verdict, pass, status, finding and name
    beside the stored fields (callers that serialise with asdict see them)."""
    import dataclasses

    q = QuantityGrade("brdf", False, 0.1, 0.01, "t", "r", diagnosis="white_tint", measured=3.0, threshold=1.0)
    d = dataclasses.asdict(q)
    assert (d["passed"], d["verdict"], d["status"], d["finding"], d["name"]) == (
        False,
        "fail",
        "does not conform",
        "white_tint",
        "brdf",
    )
    assert dataclasses.asdict(Check("x", 0.5, 1.0))["passed"] is True
    warned = grade(V, he.eon(V, extra_rho_ms=True))
    warned.tier = "conforms with warnings"
    assert not warned.passed and warned.verdict == "warn"  # a warning tier is not a pass
