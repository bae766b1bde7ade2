"""Benchmark: `check FILE` on a large results file -- peak memory and CPU time of a streamed grade.

    python tools/bench_check.py [--rows 10000000] [--dir /tmp]
    python tools/bench_check.py --glsl [--saves 5]

With ``--glsl``: the CPU and wall seconds of a warm ``check --glsl`` of a correct file (run
twice, the second measured), and the re-grade time of ``check --glsl … --watch`` after a
save (wall seconds from the write to the new verdict line, which includes the watch's
0.2 s settle time, and the grade time it prints), alternating a correct and a wrong file.

Writes a CSV of ROWS rows (the default vector set repeated under new ids of the submitter's
own, with the reference values rounded to float32 as results), then runs
``openpbr-diffuse check FILE --json`` in a child process and reports its peak RSS
(``resource.getrusage(RUSAGE_CHILDREN).ru_maxrss``), CPU seconds and wall seconds.  The file
is removed afterwards.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))  # tools/_machine.py
from _machine import cpu_model

ROOT = Path(__file__).resolve().parent.parent


def write_file(path: Path, n_rows: int) -> None:
    """``n_rows`` rows of own ids built from the default vectors and their reference values."""
    sys.path.insert(0, str(ROOT))
    import numpy as np

    from openpbr_diffuse.conformance.deviations import reference
    from openpbr_diffuse.conformance.vectors import default_vectors, write_vectors

    v = default_vectors()
    one = path.with_suffix(".one.csv")
    write_vectors(v, one, out=reference(v).astype(np.float32).astype(np.float64))
    lines = [ln for ln in one.read_text().splitlines() if not ln.startswith("#")]
    one.unlink()
    head, body = lines[0], [ln.split(",", 1)[1] for ln in lines[1:]]
    with open(path, "w") as fh:
        fh.write(head + "\n")
        k = 0
        while k < n_rows:
            m = min(len(body), n_rows - k)
            fh.write("".join(f"r{k + j},{body[j]}\n" for j in range(m)))
            k += m


def _load() -> str:
    try:
        return " ".join(Path("/proc/loadavg").read_text().split()[:3])
    except OSError:
        return "unknown"


def bench_glsl(saves: int) -> int:
    """Warm ``check --glsl`` (CPU s) and the ``--watch`` re-grade after a save (s)."""
    import re
    import signal

    good = (ROOT / "tests" / "subjects" / "eon_conforming.glsl").read_text()
    wrong = good.replace("float r = roughness;", "float r = roughness * roughness;", 1)
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    with tempfile.TemporaryDirectory() as tmp:
        src = Path(tmp) / "eon.glsl"
        src.write_text(good)
        cmd = [sys.executable, "-m", "openpbr_diffuse", "check", "--glsl", str(src), "--function", "f"]
        cmd += ["--albedo-function", "albedo"]
        cpu = []
        for _ in range(2):
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            t = time.time()
            r = subprocess.run(cmd, capture_output=True, text=True, env=env)
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            used = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
            cpu.append((round(used, 2), round(time.time() - t, 2), r.returncode))
        tool = subprocess.Popen([*cmd, "--watch"], stdout=subprocess.PIPE, text=True, env=env)
        assert tool.stdout is not None
        waits, graded = [], []
        try:
            for k in range(saves + 1):
                if k:
                    t = time.monotonic()
                    # a comment makes each save new text: compiled afresh by the GL child
                    src.write_text((wrong if k % 2 else good) + f"\n// save {k}\n")
                while True:
                    line = tool.stdout.readline()
                    if not line:
                        raise RuntimeError("the watch ended")
                    m = re.search(r"graded in ([0-9.]+) s", line)
                    if m:
                        break
                if k:
                    waits.append(round(time.monotonic() - t, 2))
                    graded.append(float(m.group(1)))
        finally:
            tool.send_signal(signal.SIGINT)
            tool.wait(timeout=30)
    print(
        json.dumps(
            {
                "date": time.strftime("%Y-%m-%d"),
                "cpu": cpu_model(),
                "cores": os.cpu_count(),
                "load": _load(),
                "check_glsl_warm_cpu_s": cpu[1][0],
                "check_glsl_warm_wall_s": cpu[1][1],
                "check_glsl_exit": cpu[1][2],
                "watch_save_to_verdict_s": waits,
                "watch_graded_in_s": graded,
            }
        )
    )
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=10_000_000)
    ap.add_argument("--dir", default=tempfile.gettempdir())
    ap.add_argument("--glsl", action="store_true", help="time check --glsl and its --watch re-grade instead")
    ap.add_argument("--saves", type=int, default=6, help="with --glsl: saves timed")
    a = ap.parse_args()
    if a.glsl:
        return bench_glsl(a.saves)
    path = Path(a.dir) / f"bench_check_{os.getpid()}.csv"
    try:
        t = time.time()
        write_file(path, a.rows)
        print(f"wrote {a.rows} rows ({path.stat().st_size / 2**20:.0f} MB) in {time.time() - t:.1f} s")
        env = dict(os.environ, PYTHONPATH=str(ROOT))
        t = time.time()
        r = subprocess.run(
            [sys.executable, "-m", "openpbr_diffuse", "check", str(path), "--json"],
            capture_output=True,
            text=True,
            env=env,
        )
        wall = time.time() - t
        ru = resource.getrusage(resource.RUSAGE_CHILDREN)
        d = json.loads(r.stdout) if r.stdout.strip() else {}
        print(
            json.dumps(
                {
                    "date": time.strftime("%Y-%m-%d"),
                    "cpu": cpu_model(),
                    "cores": os.cpu_count(),
                    "rows": a.rows,
                    "exit": r.returncode,
                    "passed": d.get("passed"),
                    "n_rows": d.get("n_rows"),
                    "peak_rss_mb": round(ru.ru_maxrss / 1024, 1),
                    "cpu_s": round(ru.ru_utime + ru.ru_stime, 1),
                    "wall_s": round(wall, 1),
                }
            )
        )
        return 0 if r.returncode == 0 else 1
    finally:
        for p in (path, path.with_suffix(".one.csv")):
            if p.exists():
                p.unlink()


if __name__ == "__main__":
    raise SystemExit(main())
