"""``openpbr-diffuse report``: the conformance report (HTML + JSON + images).

    openpbr-diffuse report                      # the bundled materials, into report/
    openpbr-diffuse report scene.usda looks.mtlx --out out/report --quick

Writes DIR/index.html (opens offline), DIR/report.json and DIR/images/, replacing an
existing report only when the new one is complete.  Exit status: 0 every check passes,
1 a check fails, 2 unusable input.
"""
import sys


def add_parser(subparsers):
    p = subparsers.add_parser("report", help="the conformance report: HTML + JSON + images",
                              description=__doc__.splitlines()[0].strip("`").replace("``", ""))
    p.add_argument("paths", nargs="*", metavar="PATHS",
                   help="USD / MaterialX files or folders (default: the bundled materials/)")
    p.add_argument("--out", default="report", metavar="DIR", help="output directory (default: report)")
    p.add_argument("--quick", action="store_true", help="smaller grids and sample counts (a few seconds)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(run=run)
    return p


def run(args):
    from ..report.runner import run_report

    result = run_report(args.paths, args.out, quick=args.quick,
                        progress=not args.no_progress and sys.stderr.isatty())
    doc = result.document
    for s in doc["sections"]:
        n_pass = sum(c["passed"] for c in s["checks"])
        print(f"  {s['key']:<16} {s['status']:<14} {n_pass}/{len(s['checks'])} checks  {s['elapsed_s']:.1f} s")
    failed = [c for c in doc["checks"] if not c["passed"]]
    for c in failed[:20]:
        print(f"  FAIL {c['section']}: {c['name']} (measured {c['measured']}, {c['comparison']} {c['threshold']})")
    print(f"{'PASS' if result.passed else 'FAIL'}: {doc['n_checks'] - doc['n_failed']}/{doc['n_checks']} checks; "
          f"report in {result.out_dir / 'index.html'} ({doc['elapsed_s']:.1f} s)")
    return result.exit_status


__all__ = ["add_parser", "run"]
