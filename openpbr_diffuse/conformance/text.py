"""The text of a values grade, one presentation for ``check FILE`` and ``check --glsl/--cpp``:
the verdict (its tier), the errors, the diagnosis, which term, the region table and the worst rows.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Iterable
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .grade import Grade

#: The largest float: an error that a finite result makes larger than this is out of range
#: (``grade.OUT_OF_RANGE``), not an Inf.
_HUGE = sys.float_info.max


def _num(x: float) -> str:
    if x is None:
        return "-"
    if isinstance(x, float) and math.isnan(x):
        return "NaN"
    if isinstance(x, float) and math.isinf(x):
        return "Inf" if x > 0 else "-Inf"
    if isinstance(x, float) and x >= _HUGE:
        return "out of range (> 1.8e+308)"
    return f"{x:.6g}"


def _vec(v: Iterable[float] | None) -> str:
    return "-" if v is None else "(" + ", ".join(_num(x) for x in v) + ")"


def _error(w: dict) -> str:
    if w["status"] == "nan":
        return "NaN output"
    if w["status"] == "inf":
        return "Inf output"
    if w["normalised_error"] >= _HUGE:  # a finite result too far off for the ratio to be a float
        return f"error {w['abs_error']:.3g}, out of range in tolerances (> 1.8e+308x)"
    return f"error {w['normalised_error']:.3g}x tolerance"


_HEAD = {
    "conforms": "CONFORMS",
    "conforms with warnings": "CONFORMS WITH WARNINGS",
    "does not conform": "DOES NOT CONFORM",
}


def print_grade(g: Grade, path: str) -> None:
    """Print the :class:`.grade.Grade` ``g`` as text, headed by ``path`` (the file or the code's name).

    >>> from openpbr_diffuse.conformance.grade import grade
    >>> from openpbr_diffuse.conformance.vectors import default_vectors
    >>> from openpbr_diffuse.conformance.deviations import reference
    >>> v = default_vectors(["lambert"])
    >>> print_grade(grade(v, reference(v)), "mine.csv")  # doctest: +ELLIPSIS
    mine.csv: CONFORMS (153 rows of lambert, vectors version 4)
    ...
    """
    skipped = f"; {g.n_skipped} blank rows skipped" if g.n_skipped else ""
    print(
        f"{path}: {_HEAD.get(g.tier, 'CONFORMS' if g.passed else 'DOES NOT CONFORM')} "
        f"({g.n_rows} rows of {', '.join(g.models)}, vectors version {g.version}"
        f"{skipped})"
    )
    print(
        f"  max abs error {_num(g.max_abs_error)}, rms {_num(g.rms_error)}, max relative "
        f"{_num(g.max_rel_error)}; {g.n_failed_rows} rows outside the tolerance"
    )
    if g.n_nan or g.n_inf:
        print(f"  non-finite output: {g.n_nan} NaN values, {g.n_inf} Inf values")
    print(
        f"  tolerance: {g.tolerance['rule']} with relative {g.tolerance['relative']:g}, "
        f"absolute {g.tolerance['absolute']:g}"
    )
    if g.passed:
        return
    if g.diagnosis is not None:
        print(f"  diagnosis: {g.diagnosis} -- {g.diagnosis_detail}")
    else:
        print(f"  diagnosis: {g.diagnosis_detail}")
    if g.terms:
        print(f"  which term: {g.terms}")
    print("  by region (rows failed / rows, max error in tolerances):")
    for r in g.regions:
        m = r["max_normalised_error"]
        worst = "NaN/Inf output" if isinstance(m, float) and math.isinf(m) else _num(m)
        print(f"    {r['region']:<28} {r['n_failed']:>6} / {r['n']:<6} max {worst}")
    if g.worst:
        print("  worst rows:")
        for w in g.worst:
            if w["kind"] == "brdf":
                where = (
                    f"wi {_vec(w['wi'])} wo {_vec(w['wo'])} mu_i {_num(w['mu_i'])} mu_o {_num(w['mu_o'])} "
                    f"L.V {_num(w['ldotv'])}"
                )
            else:
                where = f"albedo at mu {_num(w['mu'])}"
            print(f"    {w['id']} [{w['model']}] {where} roughness {_num(w['roughness'])} rho {_vec(w['rho'])}")
            print(f"      got {_vec(w['got'])}, expected {_vec(w['expected'])}, {_error(w)}")


__all__ = ["print_grade"]
