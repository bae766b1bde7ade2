#!/usr/bin/env python
"""The sampling-quality curves of the EON paper's Fig. 10-12, as a table and a PNG plot.

For each roughness r, view angle theta_o and sampling strategy, draw N directions wi with
``openpbr_diffuse.sampling.sample`` and report the throughput weight
w = f_EON(wi, wo; rho = 1) mu_i / pdf (0 for samples below the horizon, where f = 0):

- variance Var[w] (Fig. 10 left, Fig. 12 left): the estimator's noise per sample;
- maximum weight max w (Fig. 10 middle, Fig. 12 right): firefly risk;
- mean weight E[w] (Fig. 10 right): 1 for an unbiased strategy (EON passes the white
  furnace), < 1 for "ltc" and "cltc", which miss a lune of directions.

Method: Monte Carlo, N samples per point from numpy's default Generator seeded with
--seed + the point's index (reproducible); the standard error of the mean is
sqrt(Var/N), printed in the CSV.

Writes <out>.png and <out>.csv (with a '#' provenance header) and prints the tables.

Usage:  python tools/variance_curves.py [--samples 200000] [--roughness 0.25 0.5 1]
                                        [--theta 0 30 60 ...] [--seed 1] [--out out/variance_curves.png]
"""

import argparse
import datetime
import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

import openpbr_diffuse as od  # noqa: E402
from openpbr_diffuse.sampling import STRATEGIES  # noqa: E402
from openpbr_diffuse.sampling.quality import weight_stats  # noqa: E402  (the computation lives in the library)

#: theta_o in degrees: dense towards grazing, where the strategies differ (88.854 deg is
#: mu_o = 0.02, 89.427 deg is mu_o = 0.01).
THETA_DEFAULT = (0, 15, 30, 45, 60, 70, 75, 80, 84, 86, 87, 88, 88.854, 89.427)
ROUGHNESS_DEFAULT = (0.25, 0.5, 1.0)
QUANTITIES = ("variance", "max_weight", "mean_weight")


def compute(roughness, thetas, strategies, n, seed):
    """Rows (r, theta_o, mu_o, strategy, variance, max, mean, stderr)."""
    rows = []
    k = 0
    for r in roughness:
        for th in thetas:
            mu = math.cos(math.radians(th))
            for s in strategies:
                rows.append((r, th, mu, s) + weight_stats(s, mu, r, n, seed + k))
                k += 1
    return rows


def format_tables(rows, strategies):
    """One table per (roughness, quantity): rows theta_o, columns strategies."""
    lines = []
    index = {(r, th, s): vals for r, th, _, s, *vals in rows}
    for r in sorted({row[0] for row in rows}):
        thetas = sorted({row[1] for row in rows if row[0] == r})
        for q, name in enumerate(QUANTITIES):
            lines.append(f"\n{name} of the throughput weight, EON rho = 1, r = {r:g}")
            lines.append(f"{'theta_o':>8} {'mu_o':>7} " + " ".join(f"{s:>11}" for s in strategies))
            for th in thetas:
                vals = " ".join(f"{index[(r, th, s)][q]:11.5g}" for s in strategies)
                lines.append(f"{th:8.3f} {math.cos(math.radians(th)):7.4f} {vals}")
    return "\n".join(lines)


def provenance(args):
    return [
        "EON throughput-weight statistics (paper Fig. 10-12): w = f_EON(rho=1) mu_i / pdf",
        f"method: Monte Carlo, {args.samples} samples per point, "
        f"numpy default_rng(seed + point index), seed {args.seed}",
        "error estimate: stderr_mean = sqrt(variance / samples) per row; max_weight is a sample maximum",
        f"openpbr-diffuse {od.__version__}; "
        f"generated {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M UTC}",
        "regenerate: python tools/variance_curves.py " + " ".join(args.argv),
    ]


def write_csv(path, rows, args):
    with open(path, "w") as fh:
        for line in provenance(args):
            fh.write(f"# {line}\n")
        fh.write("roughness,theta_o_deg,mu_o,strategy,variance,max_weight,mean_weight,stderr_mean\n")
        for r, th, mu, s, var, mx, mean, se in rows:
            fh.write(f"{r:g},{th:g},{mu:.8g},{s},{var:.8g},{mx:.8g},{mean:.8g},{se:.3g}\n")


def plot(path, rows, strategies, args):
    import matplotlib  # lazily: only the plot needs it

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rs = sorted({row[0] for row in rows})
    fig, axes = plt.subplots(len(rs), 3, figsize=(15, 3.6 * len(rs)), squeeze=False)
    styles = {
        "cosine": ("tab:red", "-"),
        "uniform": ("black", ":"),
        "ltc": ("tab:blue", "-"),
        "ltc_nonneg": ("tab:blue", ":"),
        "cltc": ("tab:green", "--"),
        "eon": ("tab:green", "-"),
    }
    for i, r in enumerate(rs):
        for s in strategies:
            pts = sorted((row[1], row[4], row[5], row[6]) for row in rows if row[0] == r and row[3] == s)
            th = [p[0] for p in pts]
            color, ls = styles.get(s, (None, "-"))
            label = "CLTC + uniform (MIS)" if s == "eon" else s
            for j in range(3):
                axes[i, j].plot(th, [p[j + 1] for p in pts], color=color, ls=ls, label=label)
        for j, name in enumerate(("variance", "maximum weight", "mean weight")):
            ax = axes[i, j]
            ax.set_title(f"{name}, r = {r:g}")
            ax.set_xlabel("theta_o (degrees)")
            if j < 2:
                ax.set_yscale("log")
            ax.grid(True, alpha=0.3)
        axes[i, 0].legend(fontsize=8)
    fig.suptitle(
        "EON throughput weight f mu_i / pdf at rho = 1 by sampling strategy "
        f"({args.samples} samples per point, seed {args.seed}, openpbr-diffuse {od.__version__})",
        fontsize=10,
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None):
    argv = list(sys.argv[1:] if argv is None else argv)
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--samples", type=int, default=200_000, help="samples per point (default 200000)")
    ap.add_argument("--roughness", type=float, nargs="+", default=list(ROUGHNESS_DEFAULT))
    ap.add_argument("--theta", type=float, nargs="+", default=list(THETA_DEFAULT), help="theta_o in degrees")
    ap.add_argument("--strategies", nargs="+", default=list(STRATEGIES), choices=STRATEGIES)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument(
        "--out",
        default=os.path.join("out", "variance_curves.png"),
        help="PNG path; the CSV goes next to it (default out/variance_curves.png)",
    )
    args = ap.parse_args(argv)
    args.argv = argv
    if args.samples < 2:
        ap.error("--samples must be at least 2")
    if any(not 0.0 <= t < 90.0 for t in args.theta):
        ap.error("--theta values must lie in [0, 90) degrees")
    if any(not 0.0 <= r <= 1.0 for r in args.roughness):
        ap.error("--roughness values must lie in [0, 1]")
    rows = compute(args.roughness, args.theta, args.strategies, args.samples, args.seed)
    print("\n".join("# " + line for line in provenance(args)))
    print(format_tables(rows, args.strategies))
    png = args.out if args.out.lower().endswith(".png") else args.out + ".png"
    os.makedirs(os.path.dirname(os.path.abspath(png)), exist_ok=True)
    csv = png[:-4] + ".csv"
    write_csv(csv, rows, args)
    plot(png, rows, args.strategies, args)
    print(f"\nwrote {png} and {csv}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
