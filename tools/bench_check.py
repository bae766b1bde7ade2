"""Benchmark: `check FILE` on a large results file -- peak memory and CPU time of a streamed grade.

    python tools/bench_check.py [--rows 10000000] [--dir /tmp]

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
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

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


def cpu_name() -> str:
    try:
        for ln in Path("/proc/cpuinfo").read_text().splitlines():
            if ln.startswith("model name"):
                return ln.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=10_000_000)
    ap.add_argument("--dir", default=tempfile.gettempdir())
    a = ap.parse_args()
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
                    "cpu": cpu_name(),
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
