"""``openpbr-diffuse check``: grade another implementation's results on the test vectors.

    openpbr-diffuse check results.csv [--model eon] [--json]

Rows whose out_r, out_g, out_b are blank are skipped (and counted). Exit status: 0 conforms,
1 does not conform, 2 unusable file (missing columns, non-numeric values, rows that do not
match the vectors).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Iterable
from typing import TYPE_CHECKING

from ..conformance.vectors import ALL_VECTOR_MODELS
from ..graders import cli as graders_cli
from . import _check_image

if TYPE_CHECKING:
    from ..conformance.grade import Grade


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "check",
        help="grade an implementation's results on the test vectors",
        description=__doc__.splitlines()[0].strip("`").replace("``", ""),
    )
    p.add_argument(
        "file", metavar="FILE", nargs="?", help="the vectors file with out_r, out_g, out_b filled in (CSV or JSON)"
    )
    p.add_argument("--model", choices=ALL_VECTOR_MODELS, help="grade only the rows of this model")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    graders_cli.add_arguments(p)  # --implementation / --glsl / --cpp
    _check_image.add_arguments(p)  # --image / --chart: a rendered conformance chart
    p.set_defaults(run=run)
    return p


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


def _print_text(g: Grade, path: str) -> None:
    print(
        f"{path}: {'CONFORMS' if g.passed else 'DOES NOT CONFORM'} "
        f"({g.n_rows} rows of {', '.join(g.models)}, vectors version {g.version}"
        f"{f'; {g.n_skipped} blank rows skipped' if g.n_skipped else ''})"
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


def run(args: argparse.Namespace) -> int:
    if args.image is not None or args.chart is not None:
        return _check_image.run(args, _print_text)
    status = graders_cli.run(args)
    if status is not None:
        return status
    from ..conformance.grade import grade_chunks
    from ..conformance.vectors import iter_results

    if args.file is None:  # ValueError, not main.UsageError: the same exit 2 under `python -m`
        raise ValueError("FILE is required (the vectors file with out_r, out_g, out_b filled in)")
    g = grade_chunks(iter_results(args.file), model=args.model)  # streamed: memory bounded by a chunk
    if args.json:
        d = g.to_dict()
        d["file"] = str(args.file)
        print(json.dumps(d))
    else:
        _print_text(g, args.file)
    return 0 if g.passed else 1


__all__ = ["add_parser", "run"]
