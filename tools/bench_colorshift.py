#!/usr/bin/env python
"""Benchmark of the spectral colour-shift validation (issue 11).

    python tools/bench_colorshift.py            # table on stdout
    python tools/bench_colorshift.py --quick    # one repetition of each

Rows (``rows(quick) -> list[dict]`` with name, value, unit, target, ok):

- ``colour_shift`` of the 24 measured ColorChecker spectra x 16 roughness x 32 view angles x
  81 wavelengths (D65, lin_rec709): the first call in a fresh process after colour-science is
  imported (colorimetry set-up, ColorChecker alignment, numba cache load: the cold case) and the
  best of several warm calls; target 2 s each;
- the CLI's default run (``python -m openpbr_diffuse.cli.main colorshift``, a new process:
  Python start, ``import colour``, numba cache load, 24 x 5 x 3 rows printed); target 5 s,
  best and median wall time of several runs, and the child's CPU time (user + sys), which a
  machine shared with other jobs inflates much less than the wall time.
"""

import argparse
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TARGET_GRID_S = 2.0
TARGET_CLI_S = 5.0

_COLD = r"""
import time, numpy as np
from openpbr_diffuse.spectral.colorimetry import _colour
_colour()                      # import colour-science (as the package does it) before timing
t0, c0 = time.perf_counter(), time.process_time()
from openpbr_diffuse.spectral import checker, colorimetry, colour_shift
cm = colorimetry("D65", "lin_rec709")
res = colour_shift(checker(cm), np.linspace(0, 1, 16), np.linspace(1 / 32, 1, 32), cm)
assert res.albedo_spectral.shape == (24, 16, 32, 3) and cm.wavelengths.size == 81
print(time.perf_counter() - t0, time.process_time() - c0)
"""


def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    return env


def _run(code_or_args):
    """Run a Python child: (wall s, CPU s = user + sys of the child, stdout)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    out = subprocess.run([sys.executable] + code_or_args, capture_output=True, text=True, env=_env(), cwd=ROOT)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if out.returncode:
        raise RuntimeError(out.stderr.strip().splitlines()[-1] if out.stderr.strip() else "failed")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, out.stdout


def grid_warm(reps):
    import numpy as np

    from openpbr_diffuse.spectral import checker, colorimetry, colour_shift

    cm = colorimetry("D65", "lin_rec709")
    cs = checker(cm)
    r, mu = np.linspace(0, 1, 16), np.linspace(1 / 32, 1, 32)
    colour_shift(cs, r, mu, cm)  # warm-up (numba cache, colour's caches)
    best = float("inf")
    for _ in range(reps):
        t = time.perf_counter()
        colour_shift(cs, r, mu, cm)
        best = min(best, time.perf_counter() - t)
    return best


def rows(quick=False):
    reps = 1 if quick else 3
    colds = [[float(v) for v in _run(["-c", _COLD])[2].split()] for _ in range(1 if quick else 2)]
    cold, cold_cpu = min(c[0] for c in colds), min(c[1] for c in colds)
    warm = grid_warm(reps)
    runs = [_run(["-m", "openpbr_diffuse.cli.main", "colorshift"])[:2] for _ in range(reps)]
    cli = sorted(w for w, _ in runs)
    cpu = sorted(c for _, c in runs)
    out = [
        {
            "name": "colorshift 24x16x32x81, first call after import colour (cold)",
            "value": cold,
            "unit": "s",
            "target": TARGET_GRID_S,
        },
        {
            "name": "colorshift 24x16x32x81, cold, CPU time (process)",
            "value": cold_cpu,
            "unit": "s",
            "target": TARGET_GRID_S,
        },
        {"name": "colorshift 24x16x32x81, warm (best)", "value": warm, "unit": "s", "target": TARGET_GRID_S},
        {
            "name": "CLI 'colorshift' default run incl. import colour (best)",
            "value": cli[0],
            "unit": "s",
            "target": TARGET_CLI_S,
        },
        {
            "name": "CLI 'colorshift' default run incl. import colour (median)",
            "value": cli[len(cli) // 2],
            "unit": "s",
            "target": TARGET_CLI_S,
        },
        {
            "name": "CLI 'colorshift' default run, CPU time user+sys (best)",
            "value": cpu[0],
            "unit": "s",
            "target": TARGET_CLI_S,
        },
    ]
    for row in out:
        row["ok"] = row["value"] <= row["target"]
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args(argv)
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    for row in rows(args.quick):
        print(
            f"{row['name']:60} {row['value']:8.3f} {row['unit']}  target <= {row['target']:g} "
            f"{'ok' if row['ok'] else 'MISSED'}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
