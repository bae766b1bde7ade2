"""Benchmark of the layered-surface simulator: time to a directional albedo with standard
error 1e-4, and the report section's warm build time.

Usage: python tools/bench_layered.py [--target 1e-4] [--workers 2]
Prints wall-clock and process CPU seconds (the machine may be shared: CPU seconds are the
steadier number).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))  # tools/_machine.py

from _machine import cpu_model

from openpbr_diffuse.simulation.layered import (
    CHUNK_PATHS,
    LayeredSurface,
    simulate_layered_albedo,
)

CONFIGS = {
    "smooth n 1.5, Lambert rho 0.8, mu 0.5": (LayeredSurface("smooth", 1.5), 0.8),
    "GGX alpha 0.25 n 1.5, coat_color 0.8, EON r 0.5 rho 0.8, mu 0.5": (
        LayeredSurface("ggx", 1.5, 0.25, coat_color=0.8, base="eon", roughness=0.5),
        0.8,
    ),
}


def to_target(surface: LayeredSurface, rho: float, target: float, workers: int) -> dict:
    simulate_layered_albedo(surface, [0.5], rho=rho, paths=CHUNK_PATHS, seed=99, workers=1)  # compile
    pilot = simulate_layered_albedo(surface, [0.5], rho=rho, paths=4 * CHUNK_PATHS, seed=98, workers=workers)
    n = math.ceil(4 * CHUNK_PATHS * (pilot.total_stderr[0, 0] / target) ** 2 * 1.05)
    t0, c0 = time.perf_counter(), time.process_time()
    e = simulate_layered_albedo(surface, [0.5], rho=rho, paths=n, seed=1, workers=workers)
    return {
        "paths": n,
        "wall": time.perf_counter() - t0,
        "cpu": time.process_time() - c0,
        "E": float(e.total[0, 0]),
        "se": float(e.total_stderr[0, 0]),
    }


def report_section() -> float:
    from openpbr_diffuse.report.model import Context
    from openpbr_diffuse.report.sections import layered

    with tempfile.TemporaryDirectory() as d:
        layered.build(Context(image_dir=Path(d)))  # warm-up (compiles, loads tables)
        t0 = time.perf_counter()
        layered.build(Context(image_dir=Path(d)))
        return time.perf_counter() - t0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--target", type=float, default=1e-4)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args(argv)
    print(
        f"# {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}; {cpu_model()}; {os.cpu_count()} cores; "
        f"workers {args.workers}; target standard error {args.target:g}"
    )
    for name, (s, rho) in CONFIGS.items():
        r = to_target(s, rho, args.target, args.workers)
        print(
            f"{name}: {r['paths']} paths, E = {r['E']:.5f} +- {r['se']:.1e}, wall {r['wall']:.2f} s, "
            f"CPU {r['cpu']:.2f} s"
        )
    print(f"report section 'layered' (warm, full): {report_section():.2f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
