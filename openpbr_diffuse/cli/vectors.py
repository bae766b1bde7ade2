"""``openpbr-diffuse vectors``: write the conformance test vectors for another implementation.

    openpbr-diffuse vectors --out vectors.csv      # CSV (JSON when the name ends in .json)

Append ``out_r, out_g, out_b`` to every row (the BRDF value without the cosine factor, or
the directional albedo) and grade the file with ``openpbr-diffuse check FILE``.
"""
from ..conformance.vectors import COLUMNS, OUT_COLUMNS, default_vectors, write_vectors


def add_parser(subparsers):
    p = subparsers.add_parser("vectors", help="write the conformance test vectors (CSV or JSON)",
                              description=__doc__.splitlines()[0].strip("`").replace("``", ""))
    p.add_argument("--out", required=True, metavar="FILE", help="output file (.csv, or .json)")
    p.set_defaults(run=run)
    return p


def run(args):
    v = default_vectors()
    path = write_vectors(v, args.out)
    print(f"wrote {len(v)} vectors (version {v.version}) to {path}; columns {', '.join(COLUMNS)}; "
          f"append {', '.join(OUT_COLUMNS)} and run: openpbr-diffuse check {path}")
    return 0


__all__ = ["add_parser", "run"]
