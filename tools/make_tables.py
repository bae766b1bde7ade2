#!/usr/bin/env python
"""Regenerate the reference albedo tables shipped in ``openpbr_diffuse/data/``.

    python tools/make_tables.py                      # all models, ~5-10 min on 2 cores
    python tools/make_tables.py --models qon eon     # a subset
    python tools/make_tables.py --out /tmp/tables    # somewhere else
    python tools/make_tables.py --check              # recompute and compare with the shipped files

Each table is an independent numerical integration of the model's ``evaluate`` (see
``openpbr_diffuse.albedo.tables`` for the method and grid), followed by a held-out check of
the interpolation error at every cell centre, which is written into the file's header.
Progress goes to stderr.
"""

import argparse
import sys
import time

import numpy as np

from openpbr_diffuse.albedo import generate as tables
from openpbr_diffuse.models.registry import MODELS


class Progress:
    """A one-line text progress bar on stderr (no dependency)."""

    def __init__(self, label, stream=sys.stderr, width=30):
        self.label, self.stream, self.width = label, stream, width
        self.start = time.monotonic()

    def __call__(self, done, total):
        frac = done / total if total else 1.0
        bar = "#" * int(round(frac * self.width))
        elapsed = time.monotonic() - self.start
        eta = f"{elapsed / frac - elapsed:4.0f}s" if frac > 0 else "  --"
        self.stream.write(f"\r{self.label:<28} [{bar:<{self.width}}] {done}/{total} {elapsed:5.0f}s eta {eta}")
        self.stream.flush()

    def done(self, message):
        self.stream.write(f"\r{self.label:<28} {message}{' ' * 30}\n")
        self.stream.flush()


def generate(model, order=tables.ORDER, held_out=True):
    """Compute one table and its held-out interpolation error: (result, error, seconds)."""
    start = time.monotonic()
    bar = Progress(f"{model}: quadrature")
    res = tables.compute_table(model, n=order, progress=bar)
    for key in ("e_g", "e_h", "avg_g", "avg_h"):  # as shipped: the held-out check sees the rounding
        res[key] = np.round(res[key], tables.DECIMALS)
    bar.done(f"{res['err'].max():.1e} max quadrature error")
    if not held_out:
        return res, None, time.monotonic() - start
    bar = Progress(f"{model}: held-out check")
    bar(0, 1)
    directional, average, _ = tables.held_out_error(model, res, n=order)
    interp = max(directional, average)
    bar.done(f"{interp:.1e} max interpolation error")
    return res, interp, time.monotonic() - start


def compare(model, res):
    """Largest |recomputed - shipped| over every tabulated quantity, and the allowance."""
    shipped = tables.load_table(model)
    worst = 0.0
    for key in ("e_g", "e_h", "avg_g", "avg_h"):
        worst = max(worst, float(np.max(np.abs(getattr(shipped, key) - res[key]))))
    allowance = tables.ROUNDING + max(shipped.quadrature_error, float(res["err"].max()))
    return worst, allowance


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--models",
        nargs="+",
        default=list(MODELS),
        choices=MODELS,
        metavar="MODEL",
        help=f"models to generate (default all: {' '.join(MODELS)})",
    )
    parser.add_argument("--out", default=None, help="output directory (default: the package data directory)")
    parser.add_argument(
        "--order",
        type=int,
        default=tables.ORDER,
        help="Gauss-Legendre order per panel n (value at 2n, error estimate n vs 2n)",
    )
    parser.add_argument(
        "--check", action="store_true", help="recompute and compare with the shipped tables instead of writing"
    )
    args = parser.parse_args(argv)
    status = 0
    for model in args.models:
        res, interp, seconds = generate(model, args.order, held_out=not args.check)
        if args.check:
            worst, allowance = compare(model, res)
            ok = worst <= allowance
            status |= not ok
            print(
                f"{model}: max |recomputed - shipped| = {worst:.1e} (allowed {allowance:.1e}) "
                f"{'OK' if ok else 'MISMATCH'}"
            )
        else:
            path = tables.write_table(model, res, interp, args.out)
            print(f"{model}: wrote {path} ({seconds:.0f} s, interpolation error {interp:.1e})")
    return status


if __name__ == "__main__":
    sys.exit(main())
