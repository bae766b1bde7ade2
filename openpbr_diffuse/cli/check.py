"""``openpbr-diffuse check``: grade another implementation's results on the test vectors.

    openpbr-diffuse check results.csv [--model eon] [--json]

Exit status: 0 conforms, 1 does not conform, 2 unusable file (missing columns, non-numeric
values, rows that do not match the vectors).
"""
import importlib.util
import json

from ..conformance.vectors import VECTOR_MODELS


def _hook():
    """Grading by running an implementation's own code (issue 12), when that module exists."""
    if importlib.util.find_spec("openpbr_diffuse.graders") is None:
        return None
    if importlib.util.find_spec("openpbr_diffuse.graders.cli") is None:
        return None
    return importlib.import_module("openpbr_diffuse.graders.cli")


def add_parser(subparsers):
    p = subparsers.add_parser("check", help="grade an implementation's results on the test vectors",
                              description=__doc__.splitlines()[0].strip("`").replace("``", ""))
    p.add_argument("file", metavar="FILE", nargs="?",
                   help="the vectors file with out_r, out_g, out_b appended (CSV or JSON)")
    p.add_argument("--model", choices=VECTOR_MODELS, help="grade only the rows of this model")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    # HOOK (issue 12): --implementation / --glsl / --cpp options are added here by
    # openpbr_diffuse.graders.cli.add_arguments(parser); its run(args) takes over when it
    # returns an int (None: grade FILE as below).
    hook = _hook()
    if hook is not None:
        hook.add_arguments(p)
    p.set_defaults(run=run)
    return p


def _print_text(g, path):
    print(f"{path}: {'CONFORMS' if g.passed else 'DOES NOT CONFORM'} "
          f"({g.n_rows} rows of {', '.join(g.models)}, vectors version {g.version})")
    print(f"  max abs error {g.max_abs_error:.3g}, rms {g.rms_error:.3g}, max relative {g.max_rel_error:.3g}; "
          f"{g.n_failed_rows} rows outside the tolerance")
    print(f"  tolerance: {g.tolerance['rule']} with relative {g.tolerance['relative']:g}, "
          f"absolute {g.tolerance['absolute']:g}")
    if g.worst and not g.passed:
        print("  worst rows:")
        for w in g.worst:
            got = ", ".join(f"{x:.6g}" for x in w["got"])
            exp = ", ".join(f"{x:.6g}" for x in w["expected"])
            print(f"    {w['id']}: got ({got}), expected ({exp}), error {w['normalised_error']:.3g}x tolerance")
    if not g.passed:
        print(f"  diagnosis: {g.diagnosis or 'none'} -- {g.diagnosis_detail}")


def run(args):
    hook = _hook()
    if hook is not None:
        status = hook.run(args)
        if status is not None:
            return status
    from ..conformance.grade import grade
    from ..conformance.vectors import read_results
    from .main import UsageError

    if args.file is None:
        raise UsageError("check: FILE is required")
    vectors, out = read_results(args.file)
    g = grade(vectors, out, model=args.model)
    if args.json:
        d = g.to_dict()
        d["file"] = str(args.file)
        print(json.dumps(d))
    else:
        _print_text(g, args.file)
    return 0 if g.passed else 1


__all__ = ["add_parser", "run"]
