"""Benchmark: `check --image` on a 1024^2 EXR of a chart scene -- wall and CPU seconds, warm.

    python tools/bench_chart.py [--resolution 1024] [--runs 3]

Builds scene_01 of the distant-light chart at the resolution asked, writes its expected
image with 1 % per-pixel Gaussian noise (seeded) as a float EXR in a temporary folder, then
runs ``openpbr-diffuse check --image FILE --chart chart.json --json`` in a child process
``runs + 1`` times (the first warms the numba cache and the OS file cache) and reports the
best warm wall time and that run's CPU time (user + sys of the child).  Target: under 5 s.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TARGET_S = 5.0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--resolution", type=int, default=1024)
    ap.add_argument("--runs", type=int, default=3)
    a = ap.parse_args()
    sys.path.insert(0, str(ROOT))
    import numpy as np

    from openpbr_diffuse.chart.expected import expected_image
    from openpbr_diffuse.chart.image import write_image
    from openpbr_diffuse.chart.layout import build_scene

    with tempfile.TemporaryDirectory() as d:
        scene = build_scene(35.0, "distant", a.resolution, 1)
        chart = Path(d, "chart.json")
        chart.write_text(json.dumps(scene))
        img = expected_image(scene)
        img = img * (1.0 + 0.01 * np.random.default_rng(1).standard_normal(img.shape)).astype(np.float32)
        exr = Path(d, "render.exr")
        write_image(exr, img)
        cmd = [sys.executable, "-m", "openpbr_diffuse", "check", "--image", str(exr), "--chart", str(chart), "--json"]
        best = None
        for k in range(a.runs + 1):
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            t = time.perf_counter()
            run = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, check=False)
            wall = time.perf_counter() - t
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
            if run.returncode not in (0, 1):
                print(run.stderr, file=sys.stderr)
                return 2
            if k and (best is None or wall < best[0]):
                best = (wall, cpu, json.loads(run.stdout)["passed"])
    wall, cpu, passed = best
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f}")
    print(
        f"check --image {a.resolution}x{a.resolution} EXR: wall {wall:.2f} s, CPU {cpu:.2f} s "
        f"(best of {a.runs} warm runs; verdict {'conforms' if passed else 'does not conform'}); "
        f"target {TARGET_S:g} s: {'met' if wall < TARGET_S else 'NOT met'}"
    )
    return 0 if wall < TARGET_S else 1


if __name__ == "__main__":
    sys.exit(main())
