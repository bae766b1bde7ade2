"""The report section "approximations": builds from the shipped table, its live checks pass."""

import pytest

from openpbr_diffuse.report.model import Context, SectionResult
from openpbr_diffuse.report.runner import run_section
from openpbr_diffuse.report.sections import approximations


def test_section_builds_and_passes(tmp_path):
    # through the runner: the quick run's not-run rows come from the section's CHECKS table
    res = run_section("approximations", Context(image_dir=tmp_path, quick=True)).result
    assert isinstance(res, SectionResult) and res.key == "approximations"
    ran = [c for c in res.checks if c.status != "not run"]
    assert ran and all(c.passed for c in ran), [c.name for c in ran if not c.passed]
    # --quick: the live recomputations with the Gotanda and full Oren-Nayar models are the
    # full report's (test_section_plots runs them)
    assert {c.name.split(":")[0] for c in res.checks if c.status == "not run"} == {
        "gotanda_eq27_vs_e25",
        "gotanda_eq25_vs_fullon",
    }
    table = res.tables[0]
    assert len(table.rows) >= 25
    assert {"Gotanda Eq. 27 (DC scale)", "ZH fit E0(beta), Oren-Nayar (code form)"} <= {r[0] for r in table.rows}


@pytest.mark.slow
def test_section_plots(tmp_path):
    res = approximations.build(Context(image_dir=tmp_path))
    assert res.checks and all(c.passed for c in res.checks), [c.name for c in res.checks if not c.passed]
    assert len(res.figures) == 2
    for f in res.figures:
        assert (tmp_path / f.file).stat().st_size > 10_000 and f.file.startswith("approximations_")
