"""``openpbr-diffuse template``: write a starting file for another implementation.

    openpbr-diffuse template glsl [--out FILE] [--force]   # the documented GLSL signatures
    openpbr-diffuse template cpp  [--out FILE] [--force]   # the same in C++ with GLM
    openpbr-diffuse template csv  [--out FILE] [--force]   # the vectors with empty out_* columns

The code templates hold a clearly marked Lambertian placeholder (they compile and run as
they are).  An existing file is never overwritten without ``--force``.
"""

from __future__ import annotations

import argparse

from ._options import add_command, add_output

_DEFAULT = {"glsl": "diffuse.glsl", "cpp": "diffuse.cpp", "csv": "vectors.csv"}


#: The command's line in ``openpbr-diffuse --help``.
HELP = "write a starting GLSL, C++ or CSV file to grade with check"


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = add_command(subparsers, "template", HELP, run, doc=__doc__)
    p.add_argument("kind", choices=sorted(_DEFAULT), help="glsl, cpp or csv")
    add_output(p, "output file (default diffuse.glsl / diffuse.cpp / vectors.csv)", required=False)
    return p


def run(args: argparse.Namespace) -> int:
    from ..conformance.templates import write_template

    path = args.out or _DEFAULT[args.kind]
    path = write_template(args.kind, path, force=args.force)  # refusals: one line, exit 2
    if args.kind == "csv":
        print(f"wrote {path}: fill out_r, out_g, out_b of the rows you grade, then: openpbr-diffuse check {path}")
    else:
        print(
            f"wrote {path} (a Lambertian placeholder): replace the bodies, then: "
            f"openpbr-diffuse check --{args.kind} {path} --function f --albedo-function albedo"
        )
    return 0


__all__ = ["add_parser", "run"]
