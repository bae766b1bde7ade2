"""``openpbr-diffuse vectors``: write the conformance test vectors for another implementation.

    openpbr-diffuse vectors --out vectors.csv      # CSV (JSON when the name ends in .json)

Fill ``out_r, out_g, out_b`` of the rows to grade (the BRDF value without the cosine factor,
or the directional albedo; rows left blank are skipped) and grade the file with
``openpbr-diffuse check FILE``.  An existing file is not replaced without ``--force``.
"""

from __future__ import annotations

import argparse

from .._outfile import check_output_file, output_file
from ..conformance.vectors import ALL_VECTOR_MODELS, COLUMNS, OUT_COLUMNS, default_vectors, write_vectors
from ._options import add_command, add_output

#: The command's line in ``openpbr-diffuse --help``.
HELP = "write the conformance test vectors (CSV or JSON)"


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = add_command(subparsers, "vectors", HELP, run, doc=__doc__)
    add_output(p, "output file (.csv, or .json)")
    p.add_argument(
        "--model", choices=ALL_VECTOR_MODELS, help="only the rows of this model (qon_fujii: not in the default set)"
    )
    return p


def run(args: argparse.Namespace) -> int:
    check_output_file(args.out, option="--out", force=args.force)  # before any work
    path = args.out
    v = default_vectors(None if args.model is None else (args.model,))
    with output_file(args.out, option="--out", force=args.force) as tmp:
        write_vectors(v, tmp, blank_out=True)
    print(
        f"wrote {len(v)} vectors (version {v.version}) to {path}; columns {', '.join(COLUMNS)}; "
        f"fill {', '.join(OUT_COLUMNS)} (blank rows are skipped) and run: openpbr-diffuse check {path}"
    )
    return 0


__all__ = ["add_parser", "run"]
