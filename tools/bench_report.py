"""Benchmark ``openpbr-diffuse report --glsl FILE --function f`` (warm: after one untimed run).

    python tools/bench_report.py [--runs 3] [--quick] [--breakdown]

The subjects are the conforming EON functions of tests/subjects/ (eon_conforming.glsl and
eon_conforming.cpp, written from the paper's equations).  Each variant is run once to warm the
caches (numba, the C++ harness cache), then timed ``--runs`` times as subprocesses: wall seconds
and CPU seconds (user + sys of the child and its children: the GL child processes, g++).
``--breakdown`` also times, in this process, the parts of ``report --glsl FILE --function f
--albedo-function albedo``: grading the subject, drawing its pictures (each call of the subject
is one GL child process), the evidence sections.  Prints one line per run, the CPU model and the
load average; the numbers go into docs/benchmarks/report.md.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))  # tools/_machine.py
from _machine import cpu_model

ROOT = Path(__file__).resolve().parents[1]
SUBJECTS = ROOT / "tests" / "subjects"


def run_once(args: list[str]) -> tuple[float, float, int]:
    """(wall s, CPU s of the child, exit status) of one report run."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "openpbr_diffuse", "report", *args],
        check=False,
        cwd=ROOT,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, proc.returncode


def sampler_variants(tmp: Path) -> dict[str, list[str]]:
    """The report with a sampler graded: the conforming EON subject (tests/subjects/) plus the EON
    sampler and pdf of tests/test_graders_sampler.py (Listings 2-4, written there)."""
    sys.path.insert(0, str(ROOT / "tests"))
    from test_graders_sampler import GLSL as SAMPLER_GLSL

    path = Path(tmp) / "mine_sampler.glsl"
    path.write_text((SUBJECTS / "eon_conforming.glsl").read_text() + SAMPLER_GLSL)
    return {
        "report --glsl FILE --function f --sample-function eon_sample --pdf-function eon_pdf --sampler-model eon": [
            "--glsl",
            str(path),
            "--function",
            "f",
            "--sample-function",
            "eon_sample",
            "--pdf-function",
            "eon_pdf",
            "--sampler-model",
            "eon",
        ]
    }


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark; 0 when every run exited 0."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="time report --quick and report (no implementation) too")
    ap.add_argument("--breakdown", action="store_true", help="time the parts of report --glsl in this process")
    opts = ap.parse_args(argv)

    with tempfile.TemporaryDirectory() as tmp:
        glsl, cpp = str(SUBJECTS / "eon_conforming.glsl"), str(SUBJECTS / "eon_conforming.cpp")
        both = ["--function", "f", "--albedo-function", "albedo"]
        variants = {
            "report --glsl FILE --function f": ["--glsl", glsl, "--function", "f"],
            "report --glsl FILE --function f --albedo-function albedo": ["--glsl", glsl, *both],
            "report --quick --glsl FILE --function f --albedo-function albedo": ["--quick", "--glsl", glsl, *both],
            "report --cpp FILE --function f --albedo-function albedo": ["--cpp", cpp, *both],
        }
        variants.update(sampler_variants(Path(tmp)))
        if opts.quick:
            variants["report --quick"] = ["--quick"]
            variants["report"] = []
        print(f"CPU: {cpu_model()}, {os.cpu_count()} logical cores; load average {os.getloadavg()[0]:.1f}")
        if opts.breakdown:
            breakdown(glsl, Path(tmp))
        ok = True
        for label, extra in variants.items():
            args = [*extra, "--out", str(Path(tmp) / "r"), "--no-progress"]
            run_once(args)  # warm
            for i in range(opts.runs):
                wall, cpu, rc = run_once(args)
                ok &= rc == 0
                print(f"{label}: run {i + 1}: {wall:.1f} s wall, {cpu:.1f} s CPU, exit {rc}")
        print(f"load average at the end {os.getloadavg()[0]:.1f}")
    return 0 if ok else 1


def _cpu() -> float:
    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def breakdown(glsl: str, tmp: Path) -> None:
    """Time the parts of ``report --glsl FILE --function f --albedo-function albedo`` in this process."""
    sys.path.insert(0, str(ROOT))
    from openpbr_diffuse.graders import glsl as gl
    from openpbr_diffuse.graders.generic import glsl_subject
    from openpbr_diffuse.report import runner
    from openpbr_diffuse.report.subject import figures, grade_subject_under_test

    runs = []
    run = gl.Kernel.run

    def counted(self, *args, **kwargs):
        runs.append(1)
        return run(self, *args, **kwargs)

    gl.Kernel.run = counted
    try:
        subject = glsl_subject(glsl, "f", "albedo")
        parts = {}
        for label, work in (
            ("grade the subject", lambda: grade_subject_under_test(subject)),
            ("its pictures", lambda: figures(subject, parts["grade the subject"][2], tmp, quick=False)),
            (
                "evidence sections",
                lambda: runner.run_report(
                    [], tmp / "r", quick=False, progress=False, sections=["implementations", "approximations"]
                ),
            ),
        ):
            n, t0, c0 = len(runs), time.perf_counter(), _cpu()
            value = work()
            parts[label] = (time.perf_counter() - t0, _cpu() - c0, value, len(runs) - n)
            wall, cpu, _, n_gl = parts[label]
            print(f"breakdown: {label}: {wall:.1f} s wall, {cpu:.1f} s CPU, {n_gl} GL child runs")
    finally:
        gl.Kernel.run = run


if __name__ == "__main__":
    raise SystemExit(main())
