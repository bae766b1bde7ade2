"""``openpbr-diffuse check``: grade another implementation's results on the test vectors.

    openpbr-diffuse check results.csv [--model eon] [--json]
    openpbr-diffuse check results.csv --watch     (also with --glsl FILE / --cpp FILE)
    openpbr-diffuse check --wgsl FILE --function NAME [--albedo-function NAME]

Rows whose out_r, out_g, out_b are blank are skipped (and counted). Exit status: 0 conforms,
1 does not conform, 2 unusable file (missing columns, non-numeric values, rows that do not
match the vectors).
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from ..conformance.vectors import ALL_VECTOR_MODELS
from ..graders import cli as graders_cli
from . import _check_image
from ._options import add_command

if TYPE_CHECKING:
    from ..conformance.grade import Grade


#: The command's line in ``openpbr-diffuse --help``.
HELP = "grade an implementation's results on the test vectors"


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = add_command(subparsers, "check", HELP, run, doc=__doc__)
    p.add_argument(
        "file", metavar="FILE", nargs="?", help="the vectors file with out_r, out_g, out_b filled in (CSV or JSON)"
    )
    p.add_argument("--model", choices=ALL_VECTOR_MODELS, help="grade only the rows of this model")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.add_argument(
        "--watch",
        action="store_true",
        help="grade again on every save of FILE (or the --glsl/--cpp file) and print what changed; Ctrl-C ends",
    )
    from ..renderers import RENDERERS

    graders_cli.add_arguments(p, renderers=list(RENDERERS))  # --implementation / --glsl / --cpp / --wgsl
    graders_cli.add_tier_arguments(p)  # --precision / --expect-fail
    _check_image.add_arguments(p)  # --image / --chart: a rendered conformance chart
    return p


def _print_text(g: Grade, path: str) -> None:
    from ..conformance.text import print_grade

    print_grade(g, path)


def run(args: argparse.Namespace) -> int:
    if getattr(args, "watch", False):
        from . import _watch

        return _watch.run(args)
    if args.image is not None or args.chart is not None:
        return _check_image.run(args, _print_text)
    if _check_image.is_renderer(getattr(args, "implementation", None)):
        return _check_image.run_renderer(args, _print_text)
    status = graders_cli.run(args)
    if status is not None:
        return status
    from ..conformance.grade import grade_chunks
    from ..conformance.vectors import iter_results

    if args.file is None:  # ValueError, not main.UsageError: the same exit 2 under `python -m`
        raise ValueError("FILE is required (the vectors file with out_r, out_g, out_b filled in)")
    expected = graders_cli.prepare(args, [args.file])
    # streamed: memory bounded by a chunk
    g = grade_chunks(iter_results(args.file), model=args.model, precision=args.precision)
    d = None
    if args.json:
        d = g.to_dict()
        d["file"] = str(args.file)
    checks = [_values_check(g)] + [c for c in g.properties if c["status"] != "skip"]
    return graders_cli.finish(args, str(args.file), checks, expected, d, lambda: _print_text(g, args.file))


def _values_check(g: Grade) -> dict:
    from ..conformance.tiers import check_from_grade

    return check_from_grade("values", g)


__all__ = ["add_parser", "run"]
