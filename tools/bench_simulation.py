#!/usr/bin/env python
"""Benchmark of the microsurface simulator (issue 15).

    python tools/bench_simulation.py [--quick]

Rows (``rows(quick) -> list[dict]`` with name, value, unit, target, ok):

- bounce events per second (wall clock, and per CPU-second of the process, which does not
  depend on what else runs on the machine), V-cavity (sigma 0.5), Smith GGX and Beckmann
  (alpha 0.5), one thread and all cores (directional albedo, mu = 0.5, 3 channels);
- the same with next-event estimation towards 8 view directions (BRDF);
- seconds for a directional albedo to a standard error of 1e-4 (V-cavity sigma 0.5, mu 0.5,
  rho 0.8; the path count comes from a pilot run's per-path variance), target < 10 s;
- seconds of the report section ``simulation`` (shipped tables + live check + figures),
  target < 20 s.

Warm-up runs compile the kernels first (numba caches them on disk), so compile time is not
counted.
"""

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from openpbr_diffuse.simulation import simulate_albedo, simulate_brdf  # noqa: E402

CORES = os.cpu_count() or 1


def _bounce_rate(geometry, roughness, paths, workers, brdf=False):
    """(bounces per wall-clock second, bounces per CPU second of this process)."""
    if brdf:
        wo = np.stack(
            [
                np.sin(t) * np.array([1.0, 0.0, 0.0]) + np.cos(t) * np.array([0.0, 0.0, 1.0])
                for t in np.linspace(-1.3, 1.3, 8)
            ]
        )
        wi = np.broadcast_to([np.sqrt(0.75), 0.0, 0.5], wo.shape)
        simulate_brdf(geometry, roughness, wi, wo, rho=[0.8, 0.5, 0.2], paths=1000, workers=workers)
        start, cpu = time.perf_counter(), time.process_time()
        simulate_brdf(geometry, roughness, wi, wo, rho=[0.8, 0.5, 0.2], paths=paths, workers=workers)
        seconds, cpu = time.perf_counter() - start, time.process_time() - cpu
        est = simulate_albedo(geometry, roughness, [0.5], paths=paths // 4, workers=workers)
        return paths * est.bounces[0] / seconds, paths * est.bounces[0] / cpu
    simulate_albedo(geometry, roughness, [0.5], rho=[0.8, 0.5, 0.2], paths=1000, workers=workers)
    start, cpu = time.perf_counter(), time.process_time()
    est = simulate_albedo(geometry, roughness, [0.5], rho=[0.8, 0.5, 0.2], paths=paths, workers=workers)
    seconds, cpu = time.perf_counter() - start, time.process_time() - cpu
    return paths * est.bounces[0] / seconds, paths * est.bounces[0] / cpu


def _albedo_to_1e4():
    pilot = simulate_albedo("vcavity", 0.5, [0.5], rho=0.8, paths=100_000, seed=1)
    per_path = pilot.stderr[0, 0] * np.sqrt(pilot.paths)
    n = int(np.ceil((per_path / 1e-4) ** 2))
    start = time.perf_counter()
    est = simulate_albedo("vcavity", 0.5, [0.5], rho=0.8, paths=n, seed=2)
    return time.perf_counter() - start, n, float(est.stderr[0, 0]), float(est.albedo[0, 0])


def _report_section(quick):
    from openpbr_diffuse.report.model import Context
    from openpbr_diffuse.report.sections import simulation

    with tempfile.TemporaryDirectory() as tmp:
        simulation.build(Context(image_dir=Path(tmp), quick=quick))  # warm-up (imports, compilation)
        start = time.perf_counter()
        simulation.build(Context(image_dir=Path(tmp), quick=quick))
        return time.perf_counter() - start


def rows(quick=False):
    n = 200_000 if quick else 1_000_000
    out = []
    for geometry in ("vcavity", "smith-ggx", "smith-beckmann"):
        for workers in (1, CORES):
            rate, cpu_rate = _bounce_rate(geometry, 0.5, n, workers)
            out.append(
                {
                    "name": f"simulate {geometry} 0.5: bounces/s, {workers} thread(s)",
                    "value": rate,
                    "unit": "1/s",
                    "target": None,
                    "ok": True,
                }
            )
            out.append(
                {
                    "name": f"simulate {geometry} 0.5: bounces per CPU-second, {workers} thread(s)",
                    "value": cpu_rate,
                    "unit": "1/s",
                    "target": None,
                    "ok": True,
                }
            )
        rate, cpu_rate = _bounce_rate(geometry, 0.5, n // 4, CORES, brdf=True)
        out.append(
            {
                "name": f"simulate_brdf {geometry} 0.5, 8 wo: bounces/s, {CORES} thread(s)",
                "value": rate,
                "unit": "1/s",
                "target": None,
                "ok": True,
            }
        )
        out.append(
            {
                "name": f"simulate_brdf {geometry} 0.5, 8 wo: bounces per CPU-second",
                "value": cpu_rate,
                "unit": "1/s",
                "target": None,
                "ok": True,
            }
        )
    seconds, paths, se, E = _albedo_to_1e4()
    out.append(
        {
            "name": f"directional albedo to stderr 1e-4 (vcavity 0.5, mu 0.5, rho 0.8: {paths} paths, "
            f"E = {E:.5f} +- {se:.1e})",
            "value": seconds,
            "unit": "s",
            "target": 10.0,
            "ok": seconds < 10.0,
        }
    )
    seconds = _report_section(quick)
    out.append(
        {
            "name": f"report section 'simulation' ({'quick' if quick else 'default'})",
            "value": seconds,
            "unit": "s",
            "target": 20.0,
            "ok": seconds < 20.0,
        }
    )
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args(argv)
    for r in rows(args.quick):
        target = "" if r["target"] is None else f"  (target {r['target']:g} {r['unit']})"
        value = f"{r['value']:.3g}" if r["unit"] == "s" else f"{r['value'] / 1e6:.2f} M"
        print(f"{'ok ' if r['ok'] else 'BAD'} {r['name']}: {value} {r['unit']}{target}")


if __name__ == "__main__":
    main()
