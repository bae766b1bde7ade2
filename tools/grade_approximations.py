"""Grade published real-time approximations against exact quantities; write the table.

    python tools/grade_approximations.py [--quick] [--out PATH] [--check]

Writes ``openpbr_diffuse/data/approximation_errors.csv`` (a ``#`` provenance header, then one
row per approximation: what it approximates, the reference, domain, metric, max and RMS error
and where the max is) and prints the table.  ``--check`` recomputes and compares with the
shipped file instead of writing it.  Takes ~1-2 min (``--quick``: ~15 s, smaller grids).
"""

import argparse
import csv
import io
import math
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from openpbr_diffuse import __version__  # noqa: E402
from openpbr_diffuse.approximations import grading  # noqa: E402

DEFAULT_OUT = ROOT / "openpbr_diffuse" / "data" / "approximation_errors.csv"
FIELDS = [
    "id",
    "approximation",
    "equation",
    "approximates",
    "reference",
    "domain",
    "metric",
    "max_error",
    "rms_error",
    "at",
    "n",
    "note",
]


def header(quick, seconds):
    return (
        "\n".join(
            [
                "# title: openpbr-diffuse grading of published real-time approximations (Gotanda 2012; "
                "table-based energy compensation, Kulla-Conty as in patapom's 'Energy Compensation Pt. 2')",
                "# method: each approximation evaluated on a grid over its domain and compared with an exact "
                "quantity computed independently: od.evaluate of the exact lobe, Gauss-Legendre quadrature of "
                "od.evaluate (SH projections, white furnace, brute-force area-light integrals), the shipped "
                "reference albedo tables; max_error = max |error|, rms_error = root mean square over the grid nodes",
                f"# grids: {'quick' if quick else 'full'} (openpbr_diffuse.approximations.grading)",
                f"# library: openpbr-diffuse {__version__}; computed in {seconds:.0f} s",
                "# regenerate: python tools/grade_approximations.py",
            ]
        )
        + "\n"
    )


def to_csv(rows, quick, seconds):
    buf = io.StringIO()
    buf.write(header(quick, seconds))
    w = csv.DictWriter(buf, FIELDS, lineterminator="\n")
    w.writeheader()
    for r in rows:
        d = r.to_dict()
        d["max_error"] = f"{d['max_error']:.8e}"
        d["rms_error"] = f"{d['rms_error']:.8e}"
        w.writerow(d)
    return buf.getvalue()


def read_csv(path):
    lines = [ln for ln in Path(path).read_text().splitlines() if not ln.startswith("#")]
    return list(csv.DictReader(lines))


def print_table(rows):
    print(f"| {'approximation':58} | {'approximates':60} | max error | RMS error |")
    print(f"|{'-' * 60}|{'-' * 62}|-----------|-----------|")
    for r in rows:
        d = r if isinstance(r, dict) else r.to_dict()
        print(
            f"| {d['approximation'][:58]:58} | {d['approximates'][:60]:60} | "
            f"{float(d['max_error']):9.3g} | {float(d['rms_error']):9.3g} |"
        )


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="smaller grids (not for the shipped file)")
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    ap.add_argument("--check", action="store_true", help="compare with the shipped file, do not write")
    args = ap.parse_args(argv)
    t0 = time.time()
    rows = grading.grade_all(args.quick, progress=lambda m: print(f"  {m} ...", file=sys.stderr))
    seconds = time.time() - t0
    print_table(rows)
    if args.check:
        shipped = {r["id"]: r for r in read_csv(args.out)}
        bad = 0
        for r in rows:
            s = shipped.get(r.id)
            if s is None or not math.isclose(float(s["max_error"]), r.max_error, rel_tol=1e-3, abs_tol=1e-12):
                print(f"MISMATCH {r.id}: shipped {s and s['max_error']} now {r.max_error:.6e}")
                bad += 1
        print("check:", "ok" if not bad else f"{bad} mismatches")
        return 1 if bad else 0
    args.out.write_text(to_csv(rows, args.quick, seconds))
    print(f"wrote {args.out} ({seconds:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
