"""The report's checks are declared once, in each section's ``CHECKS`` table: stable ids, a
``--list-checks`` that builds no section, and a ``--quick`` not-run list derived from the table."""

from __future__ import annotations

import importlib
import resource
import subprocess
import sys
from pathlib import Path

import pytest

from openpbr_diffuse.report.model import QUICK_NOT_RUN, CheckTable, Context
from openpbr_diffuse.report.runner import declared_checks, run_section
from openpbr_diffuse.report.sections import SECTIONS

#: The ids as ``openpbr-diffuse report --list-checks`` printed them before the tables existed
#: (derived then from each check's name), plus the implementation's properties: a user's
#: --select patterns and expected-failure lists name them, so they must not change.
COMMITTED = Path(__file__).parent / "data" / "check_ids.txt"


def _table(key):
    return importlib.import_module(f"openpbr_diffuse.report.sections.{key}").CHECKS


def test_ids_match_the_committed_list():
    ids = [i for i, _ in declared_checks()]
    assert ids == COMMITTED.read_text().split(), "check ids changed: update tests/data/check_ids.txt knowingly"


@pytest.mark.parametrize("key", SECTIONS)
def test_every_section_declares_its_checks(key):
    table = _table(key)
    assert isinstance(table, CheckTable) and table.section == key
    titles = [s.title for s in table.specs]
    assert len(set(titles)) == len(titles)  # a title names one check


def test_a_table_refuses_duplicate_or_foreign_ids():
    with pytest.raises(ValueError, match="unique"):
        CheckTable("a", [("a.x", "x"), ("a.x", "y")])
    with pytest.raises(ValueError, match="start with"):
        CheckTable("a", [("b.x", "x")])
    with pytest.raises(KeyError, match="not declared"):
        CheckTable("a", [("a.x", "x")]).check("an undeclared check", 0.0, 1.0)


def test_list_checks_builds_no_section_and_is_fast():
    """--list-checks reads the tables: well under 2 CPU s (building the sections took ~17)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    out = subprocess.run(
        [sys.executable, "-m", "openpbr_diffuse.cli.main", "report", "--list-checks"],
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
    ).stdout
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    assert [line.split("\t")[0] for line in out.splitlines()] == COMMITTED.read_text().split()
    assert cpu < 2.0, f"{cpu:.2f} CPU s"


def test_a_full_run_of_a_section_makes_exactly_its_declared_ids(tmp_path):
    """implementations (the grader's self-test, a few seconds) built in full."""
    run = run_section("implementations", Context(tmp_path, quick=False), ["implementations"])
    assert run.status == "pass", run.error
    assert [c.id for c in run.result.checks] == list(_table("implementations").ids)


@pytest.mark.parametrize("key", ["layered", "simulation"])
def test_quick_lists_the_tables_not_quick_checks_as_not_run(key, tmp_path):
    """The not-run rows of --quick come from the table (quick=False), in declared order."""
    run = run_section(key, Context(tmp_path, quick=True))
    table = _table(key)
    assert [c.id for c in run.result.checks] == list(table.ids)
    not_run = {c.id for c in run.result.checks if c.status == "not run"}
    assert not_run == {s.id for s in table.specs if not s.quick}
    assert all(c.not_run == QUICK_NOT_RUN for c in run.result.checks if c.id in not_run)


def test_quick_marks_in_list_checks_and_select():
    rows = dict(declared_checks(["layered", "albedo"], ["albedo.stated*"], quick=True))
    assert "layered.white_furnace_of_the_ggx_interface_layer_rho_1_no_absorption" not in rows
    assert rows["albedo.stated_value_e_f_r_1"].endswith("(not run in --quick)")
    assert not rows["albedo.stated_value_e_f_mu_1_r_1"].endswith("(not run in --quick)")
    with pytest.raises(ValueError, match="no section or check id matches"):
        declared_checks(None, ["nothing_like_this"])
