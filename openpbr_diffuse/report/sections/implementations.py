"""Graded implementations: the test vectors, and the grader's self-test on the known deviations.

The reference rounded to float32 must pass; an implementation with each known deviation
(its prediction by :mod:`openpbr_diffuse.conformance.deviations`, rounded to float32 like a
shader's output) must fail and be diagnosed as that deviation.  Real implementations run by
their own code are graded in the next section ("graders").
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...result import Result
from ..model import CheckTable, Context, SectionResult, Table

TITLE = "Grader self-test: test vectors and known deviations"

#: The section's checks: its rows of the static registry ``data/report_checks.tsv``.
CHECKS = CheckTable.declared("implementations")


def _deviation(v: Any, name: str, dev: Any) -> tuple[Result, list[Any]]:
    """A float32 implementation with the known deviation ``name``: its check (fails, diagnosed) and table row."""
    from ...conformance.grade import grade

    pred = dev(v)
    known = np.isfinite(pred).all(axis=1)
    sub = v.subset(known)
    g = grade(sub, pred[known].astype(np.float32))
    ok = (not g.passed) and g.diagnosis == name
    detail = g.candidate_details.get(name, {})
    check = CHECKS.check(
        f"{name}: fails and is diagnosed",
        1.0 if ok else 0.0,
        0.0,
        "==",
        expected=1.0,
        reference=f"{dev.source}; predicted with the library's models ({dev.variants[0][0]})",
        detail=f"diagnosis {g.diagnosis}; {g.n_failed_rows} of {g.n_rows} rows outside the tolerance",
    )
    row = [
        name,
        dev.description,
        dev.source,
        g.n_failed_rows,
        g.n_rows,
        g.max_abs_error,
        g.max_normalised_error,
        g.diagnosis or "none",
        detail.get("explained_fraction", float("nan")),
    ]
    return check, row


def _deviations_table(rows: list[list[Any]]) -> Table:
    """The known deviations as graded float32 implementations."""
    from ...conformance.grade import ABS_TOL, REL_TOL

    return Table(
        f"Known deviations as float32 implementations, graded at |out - ref| <= {ABS_TOL:g} + {REL_TOL:g} |ref|",
        [
            "deviation",
            "what",
            "seen in",
            "rows failing",
            "rows",
            "max abs error",
            "max error / tolerance",
            "diagnosis",
            "failing values explained",
        ],
        rows,
    )


def build(ctx: Context) -> SectionResult:
    """The test vectors, the float32 reference's conformance and each known deviation's diagnosis."""
    from ...conformance.deviations import DEVIATIONS, reference
    from ...conformance.grade import TOLERANCE_REASON, grade
    from ...conformance.vectors import default_vectors

    v = default_vectors()
    ctx.progress("reference values")
    ref = reference(v)
    res = SectionResult("implementations", TITLE)
    res.notes.append(
        f"Test vectors version {v.version}: {len(v)} rows ({int((v.kind == 'brdf').sum())} BRDF, "
        f"{int((v.kind == 'albedo').sum())} albedo) over {', '.join(sorted(set(v.model)))}, including grazing "
        "(mu = 0.01, 0.001), backscatter, s = 0, L.V < 0, below-horizon directions, r = 0 and 1, mu = 0. "
        "Write them with `openpbr-diffuse vectors --out vectors.csv`, append out_r, out_g, out_b, and grade "
        "with `openpbr-diffuse check vectors.csv`."
    )
    res.notes.append(f"Tolerance: {TOLERANCE_REASON}")
    g32 = grade(v, ref.astype(np.float32))
    res.checks.append(
        CHECKS.check(
            "reference rounded to float32 conforms",
            g32.max_normalised_error,
            1.0,
            "<=",
            reference="openpbr_diffuse.conformance.deviations.reference (float64 evaluate / directional_albedo)",
            unit="x tolerance",
            detail=f"max abs error {g32.max_abs_error:.2e} over {g32.n_rows} rows",
        )
    )
    rows = []
    for name, dev in DEVIATIONS.items():
        ctx.progress(f"deviation {name}")
        check, row = _deviation(v, name, dev)
        res.checks.append(check)
        rows.append(row)
    res.tables.append(_deviations_table(rows))
    return res
