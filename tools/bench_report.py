"""Benchmark ``openpbr-diffuse report --glsl FILE --function f`` (warm: after one untimed run).

    python tools/bench_report.py [--runs 3]

Writes a conforming EON GLSL function (the one of tests/test_report_under_test.py) to a
temporary folder, runs the report on it once to warm the caches (numba, the shader compiler),
then times ``--runs`` runs as subprocesses: wall seconds and CPU seconds (user + sys of the
child).  Prints one line per run and the CPU model; the numbers go into docs/benchmarks/report.md.
"""
from __future__ import annotations

import argparse
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def cpu_model() -> str:
    """The CPU's model name (Linux /proc/cpuinfo), or the platform's processor string."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def run_once(args: list[str]) -> tuple[float, float, int]:
    """(wall s, CPU s of the child, exit status) of one report run."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "openpbr_diffuse", "report", *args], check=False, cwd=ROOT,
                          stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                          env={**os.environ, "PYTHONPATH": str(ROOT)})
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, proc.returncode


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark; 0 when every run exited 0."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="time report --quick too")
    opts = ap.parse_args(argv)
    sys.path.insert(0, str(ROOT / "tests"))
    from test_report_under_test import EON_GLSL

    with tempfile.TemporaryDirectory() as tmp:
        glsl = Path(tmp) / "mine.glsl"
        glsl.write_text(EON_GLSL)
        variants = {"report --glsl FILE --function eon": ["--glsl", str(glsl), "--function", "eon"]}
        variants["report --glsl FILE --function eon --albedo-function eon_albedo"] = [
            "--glsl", str(glsl), "--function", "eon", "--albedo-function", "eon_albedo"]
        if opts.quick:
            variants["report --quick"] = ["--quick"]
            variants["report"] = []
        print(f"CPU: {cpu_model()}, {os.cpu_count()} logical cores; load average {os.getloadavg()[0]:.1f}")
        ok = True
        for label, extra in variants.items():
            args = [*extra, "--out", str(Path(tmp) / "r"), "--no-progress"]
            run_once(args)  # warm
            for i in range(opts.runs):
                wall, cpu, rc = run_once(args)
                ok &= rc == 0
                print(f"{label}: run {i + 1}: {wall:.1f} s wall, {cpu:.1f} s CPU, exit {rc}")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
