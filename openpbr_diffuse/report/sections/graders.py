"""Report section ``graders``: real implementations graded by running their own code.

One table row per implementation x quantity (BRDF, albedo, sampler pdf, sampler chi-square,
surface weight x albedo, surface probability) with the max and RMS error, the tolerance, the
verdict and the diagnosis, plus what was run (versions, source hashes).  A third party's
verdict is a finding, not a failure of this report: the section adds no pass/fail checks for
them; an implementation that cannot run here (no GL driver, compiler, bpy, sources) is listed
as a warning naming the missing piece.

Which implementations run: every registered one, whose code comes with an installed package --
``materialx-glsl`` always, the others unless quick; ``cycles`` only when asked
(``ctx.extra["cycles"] = True`` or ``$OPENPBR_DIFFUSE_REPORT_CYCLES=1``: its renders take about
80 s).  ``ctx.quick``: MaterialX only.  Code that no package installs (a checkout, the user's
own) is graded as the implementation under test (``report --glsl/--cpp``), not here.
"""

from __future__ import annotations

import math
import os
from typing import Any

from ..model import CheckTable, Context, SectionResult, Table

TITLE = "Third-party implementations, graded by running their own code (findings)"
#: The section holds findings, not checks (a third party's verdict is not a failed check).
CHECKS = CheckTable.declared("graders")
KEY = "graders"


def _plan(ctx):
    """[(name, source)] in registry order (source None: the installed package's code)."""
    from ...graders import IMPLEMENTATIONS

    plan = [("materialx-glsl", None)]
    if ctx.quick:
        return plan
    for name, impl in IMPLEMENTATIONS.items():
        if name not in ("materialx-glsl", "cycles") and not impl.needs_source:
            plan.append((name, None))
    if ctx.extra.get("cycles") or os.environ.get("OPENPBR_DIFFUSE_REPORT_CYCLES") == "1":
        plan.append(("cycles", None))
    return plan


def _fmt(x):
    """A number to 3 significant digits (kept numeric for report.json); '—' where undefined."""
    if x is None or not math.isfinite(x):
        return "—" if x is None or math.isnan(x) else "inf"
    return float(f"{x:.3g}")


def _version(v: dict) -> str:
    """What was run, in words: MaterialX / Blender version and source hash."""
    parts = []
    for key in ("materialx", "blender"):
        if v.get(key):
            parts.append(f"{'MaterialX' if key == 'materialx' else 'Blender'} {v[key]}")
    if v.get("sha256"):
        parts.append(f"sha256 {v['sha256'][:12]}")
    return ", ".join(parts) or "—"


def _table_rows(name: str, g: Any) -> list[list[Any]]:
    """The table rows of implementation ``name``'s grade ``g``: one per quantity."""
    return [
        [
            name,
            _version(g.version),
            q.quantity,
            _fmt(q.max_abs_error),
            _fmt(q.rms_error),
            q.tolerance,
            "pass" if q.passed else "FAIL",
            q.diagnosis or "—",
        ]
        for q in g.quantities
    ]


def _summary(name: str, g: Any) -> dict[str, Any]:
    """The listed summary of implementation ``name``'s grade ``g``: its verdicts, version and notes."""
    items = [
        f"{q.quantity}: {'conforms' if q.passed else 'FINDING: does not conform'}"
        + (f" ({q.diagnosis})" if q.diagnosis and not q.passed else "")
        + f", max abs error {_fmt(q.max_abs_error)}"
        for q in g.quantities
    ]
    items.append("version: " + ("; ".join(f"{k} = {v}" for k, v in g.version.items() if v) or "—"))
    items += list(g.notes)
    return {"title": name, "items": items}


#: The caption of the graded implementations' table.
CAPTION = (
    "Implementations run on this machine and graded against the reference (conformance.grade on "
    "the default vectors for BRDF and albedo; sampler: reported pdf against the reference "
    "strategies and chi-square of its samples against its own pdf; surface: diffuse weight x "
    "albedo and selection probability against OpenPBRSurface)"
)


def build(ctx: Context) -> SectionResult:
    """Every planned implementation graded: the table of its quantities, its summary, the findings."""
    from ...graders import grade_implementation
    from ...graders.errors import GraderUnavailable

    result = SectionResult(key=KEY, title=TITLE)
    rows, run = [], []
    for name, source in _plan(ctx):
        ctx.progress(f"grading {name}")
        try:
            g = grade_implementation(name, source, quick=True)
        except GraderUnavailable as exc:
            result.warnings.append(f"{name}: not graded: {exc}")
            continue
        run.append(g.to_dict())
        rows += _table_rows(name, g)
        result.lists.append(_summary(name, g))
    columns = [
        "implementation",
        "version",
        "quantity",
        "max abs error",
        "RMS error",
        "tolerance",
        "verdict",
        "diagnosis",
    ]
    result.tables.append(Table(caption=CAPTION, columns=columns, rows=rows))
    ctx.extra.setdefault("graders", run)
    result.findings = sum(r[6] == "FAIL" for r in rows)
    if not rows:
        result.not_run = "no implementation could run here: " + ("; ".join(result.warnings) or "none planned")
    result.notes.append(
        "Code no package installs (a checkout of another renderer, your own) is graded as the "
        "implementation under test: report --glsl FILE --function F, or --cpp FILE."
    )
    return result
