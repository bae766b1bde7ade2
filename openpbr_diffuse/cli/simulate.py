"""``openpbr-diffuse simulate``: Monte Carlo albedo of a rough Lambertian microsurface.

    openpbr-diffuse simulate --geometry vcavity --roughness 0.5 --mu 0.2 0.5 1 --rho 0.8 0.5 0.2
    openpbr-diffuse simulate --geometry smith-ggx --roughness 0.8 --average --json
    openpbr-diffuse simulate --geometry vcavity --roughness 0.5 --mu 0.5 --scheduler tcp://host:8786

Prints, per mu, the directional albedo in total and per bounce order (1, 2, >= 3) with
standard errors (``--json``: a ``rows`` list with mu, albedo, albedo_by_order, stderr).
"""

from __future__ import annotations

import argparse
import json
import math
import sys

import numpy as np

from ..simulation.api import GEOMETRIES, simulate_albedo, simulate_average_albedo
from . import simulate_layered
from ._options import add_command, add_number, add_numbers

#: The command's line in ``openpbr-diffuse --help``.
HELP = "Monte Carlo albedo of a V-cavity / Smith Lambertian microsurface"


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = add_command(subparsers, "simulate", HELP, run, doc=__doc__)
    p.add_argument(
        "--geometry",
        choices=list(GEOMETRIES),
        help="vcavity (Oren-Nayar V-grooves) or a Smith microsurface (Heitz et al. 2016)",
    )
    add_number(
        p,
        "--roughness",
        metavar="S",
        help="sigma in radians [0, pi/2] for vcavity; alpha [0, 2] for smith-*; EON r with --layered",
    )
    add_numbers(p, "--mu", metavar="MU", help="cosine(s) of the incident angle in [1e-100, 1]")
    p.add_argument("--average", action="store_true", help="average albedo <E> instead of E(mu)")
    add_numbers(p, "--rho", metavar="RHO", default=[1.0], help="microfacet albedo per channel in [0, 1] (default 1)")
    p.add_argument(
        "--paths", type=_count, default=1_000_000, metavar="N", help="paths per mu (default 10^6; 1e6 accepted)"
    )
    p.add_argument("--seed", type=int, default=0, metavar="K", help="seed (default 0)")
    p.add_argument("--workers", type=int, default=None, metavar="W", help="local threads (default: all cores)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="run the chunks on this Dask distributed scheduler")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.add_argument(
        "--no-progress", action="store_true", help="no progress bar (off anyway when stderr is not a terminal)"
    )
    p.add_argument(
        "--yes",
        action="store_true",
        help=f"run even above the work budget of {WORK_BUDGET_PATHS:.0e} paths in total "
        "(paths x number of mu; about 25 min on 2 cores)",
    )
    simulate_layered.add_arguments(p)
    return p


#: Paths in total (paths x queries) run without ``--yes``.
WORK_BUDGET_PATHS = 10**9
#: Rough throughput of the path tracer on 2 cores (paths per second), for the estimate.
PATHS_PER_S = 7e5


def _count(text):
    """An integer count, also written as 1e6."""
    import argparse

    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value.is_integer()):
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {text!r}")
    return int(value)


def _usage(message):
    from .main import UsageError

    return UsageError(f"simulate: {message}")


def run(args: argparse.Namespace) -> int:
    total = args.paths * (1 if args.average or not args.mu else len(args.mu))
    if total > WORK_BUDGET_PATHS and not args.yes:
        raise _usage(
            f"{total:.3g} paths in total exceed the work budget of {WORK_BUDGET_PATHS:.0e} "
            f"(about {total / PATHS_PER_S / 3600:.3g} h here); pass --yes to run anyway"
        )
    if args.layered:
        return simulate_layered.run(args)
    if args.geometry is None or args.roughness is None:
        raise _usage("--geometry and --roughness are required (or --layered)")
    if args.average and args.mu:
        raise _usage("--average takes no --mu")
    if not args.average and not args.mu:
        raise _usage("--mu is required (or --average)")
    rho = np.array(args.rho, dtype=np.float64)
    kw = dict(
        rho=rho,
        paths=args.paths,
        seed=args.seed,
        workers=args.workers,
        scheduler=args.scheduler,
        progress=not args.no_progress and sys.stderr.isatty(),
    )
    try:
        if args.average:
            est = simulate_average_albedo(args.geometry, args.roughness, **kw)
        else:
            est = simulate_albedo(args.geometry, args.roughness, np.array(args.mu, dtype=np.float64), **kw)
    except ImportError as exc:  # dask missing: a usage problem, one line
        raise _usage(str(exc)) from None
    if args.json:
        print(json.dumps(est.to_dict()))
        return 0
    name = GEOMETRIES[args.geometry][0]
    C = rho.size
    chan = [""] if C == 1 else [f"[{k}]" for k in range(C)]
    print(
        f"# {args.geometry}, {name} = {args.roughness:g}, rho = ({', '.join(f'{r:g}' for r in rho)}), "
        f"{args.paths} paths per row, seed {args.seed}; values +- one standard error"
    )
    cols = ["mu"]
    for c in chan:
        cols += ["E" + c, "E1" + c, "E2" + c, "E3+" + c]
    cols += ["bounces"]
    widths = [max(21, len(c)) for c in cols]
    widths[0] = 8
    print("  ".join(c.rjust(w) for c, w in zip(cols, widths)))
    for i in range(est.albedo.shape[0]):
        cells = ["average" if est.mu is None else f"{est.mu[i]:.6f}"]
        for k in range(C):
            cells.append(f"{est.albedo[i, k]:.6f} +- {est.stderr[i, k]:.1e}")
            for o in range(3):
                cells.append(f"{est.albedo_by_order[i, o, k]:.6f} +- {est.stderr_by_order[i, o, k]:.1e}")
        cells.append(f"{est.bounces[i]:.3f}")
        print("  ".join(c.rjust(w) for c, w in zip(cells, widths)))
    return 0


__all__ = ["add_parser", "run"]
