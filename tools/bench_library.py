"""Benchmark of ``report`` and ``eval --jsonl`` over material libraries: cold and warm cache,
serial and parallel.

    python tools/bench_library.py                      # the corpus and 10,000 synthetic files
    python tools/bench_library.py --only corpus [--corpus DIR] [--numba-cold]
    python tools/bench_library.py --only synthetic --n 10000 [--jobs 2]

Each run is the command line in a subprocess (``python -m openpbr_diffuse ...``), timed by wall
clock and by the CPU time of the command and of its worker processes; memory is sampled every
0.1 s from /proc: the peak of the sum of the proportional set sizes of the command and its
workers (shared pages counted once), and the largest resident set of one process.  The
libraries:

- **corpus**: the shared real-world corpus (``../shared/corpus/realworld``: MaterialX's test
  suite and examples, usd-wg/assets, kwokcb/materialxusd; 393 files, 1502 materials), when
  present; ``report --quick`` (every section) and ``report --quick --select materials``;
- **synthetic**: ``--n`` variants of the bundled materials with other colours and
  roughnesses (``openpbr_diffuse.library.synthetic``) written into a temporary folder (not
  timed); ``report --quick --select materials`` and ``eval --jsonl``.

"cold" runs start from an empty cache folder (``--cache-dir``), "warm" ones reuse the cache of
the run before them (nothing changed).  An untimed ``report --quick`` first fills numba's cache
(every run but the ``--numba-cold`` one loads compiled kernels).  ``--numba-cold`` also points ``NUMBA_CACHE_DIR`` at an
empty folder for the first corpus run: every kernel is compiled as after a fresh install.
Prints a Markdown table (with the date, the CPU model and the load average) for
docs/benchmarks/library.md.
"""

from __future__ import annotations

import argparse
import datetime
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))  # tools/_machine.py
from _machine import cpu_model

ROOT = Path(__file__).resolve().parents[1]
CORPUS = Path(os.environ.get("OPENPBR_DIFFUSE_SHARED") or ROOT.parent / "shared") / "corpus" / "realworld"


def _tree_memory_kb(root: int) -> tuple[int, int]:
    """(sum of the proportional set sizes, largest resident set) in kB of ``root`` and its
    descendants, from /proc (the PSS counts a page shared by n processes as 1/n in each)."""
    parents: dict[int, int] = {}
    for d in os.listdir("/proc"):
        if d.isdigit():
            try:
                stat = Path(f"/proc/{d}/stat").read_text()
            except OSError:
                continue
            parents[int(d)] = int(stat.rsplit(")", 1)[1].split()[1])
    tree, changed = {root}, True
    while changed:
        changed = False
        for pid, ppid in parents.items():
            if ppid in tree and pid not in tree:
                tree.add(pid)
                changed = True
    pss = largest = 0
    for pid in tree:
        try:
            for line in Path(f"/proc/{pid}/smaps_rollup").read_text().splitlines():
                if line.startswith("Pss:"):
                    pss += int(line.split()[1])
                elif line.startswith("Rss:"):
                    largest = max(largest, int(line.split()[1]))
        except OSError:
            continue
    return pss, largest


def timed(argv: list[str], env: dict | None = None) -> dict:
    """Run ``python -m openpbr_diffuse ARGV``: wall s, CPU s (with its children), peak tree RSS."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.Popen(
        [sys.executable, "-m", "openpbr_diffuse", *argv],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, **(env or {})},
        cwd=ROOT,
    )
    peak = [0, 0]
    stop = threading.Event()

    def sample() -> None:
        while not stop.wait(0.1):
            pss, largest = _tree_memory_kb(proc.pid)
            peak[0], peak[1] = max(peak[0], pss), max(peak[1], largest)

    th = threading.Thread(target=sample, daemon=True)
    th.start()
    out, err = proc.communicate()
    stop.set()
    th.join()
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {
        "code": proc.returncode,
        "wall": wall,
        "cpu": cpu,
        "tree_mb": peak[0] / 1024,
        "max_mb": peak[1] / 1024,
        "tail": (out.strip().splitlines() or [""])[-1],
        "err": err.strip().splitlines()[-1:] if proc.returncode not in (0, 1) else [],
    }


def row(label: str, r: dict) -> str:
    return f"| {label} | {r['wall']:.1f} | {r['cpu']:.1f} | {r['tree_mb']:.0f} | {r['max_mb']:.0f} | {r['code']} |"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", choices=("corpus", "synthetic"), default=None)
    ap.add_argument("--corpus", type=Path, default=CORPUS)
    ap.add_argument("--n", type=int, default=10000, help="synthetic files (default 10000)")
    ap.add_argument("--jobs", type=int, default=2, help="worker processes of the parallel runs (default 2)")
    ap.add_argument("--numba-cold", action="store_true", help="compile every kernel in the first corpus run")
    args = ap.parse_args()
    rows = []
    start = datetime.datetime.now(datetime.timezone.utc)
    load0 = os.getloadavg()
    with tempfile.TemporaryDirectory(prefix="bench-library-") as tmp:
        tmp_path = Path(tmp)
        # untimed: fill numba's cache of this tree (every kernel a warm run loads)
        timed(["report", "--quick", "--no-cache", "--out", str(tmp_path / "prime")])
        shutil.rmtree(tmp_path / "prime", ignore_errors=True)

        def report(paths: list[str], name: str, label: str, *extra: str, env: dict | None = None) -> None:
            out = tmp_path / f"out-{len(rows)}"
            argv = ["report", *paths, "--quick", "--out", str(out), *extra]
            r = timed(argv, env)
            rows.append(row(label, r))
            print(rows[-1], r["err"], flush=True)
            shutil.rmtree(out, ignore_errors=True)

        if args.only in (None, "corpus") and args.corpus.is_dir():
            c = str(args.corpus)
            cache = str(tmp_path / "cache-corpus")
            j = ["--jobs", str(args.jobs)]
            env = {"NUMBA_CACHE_DIR": str(tmp_path / "numba")} if args.numba_cold else None
            cold = "cold (numba and library cache)" if args.numba_cold else "cold library cache"
            report(
                [c], "corpus", f"corpus `report --quick`, {cold}, --jobs {args.jobs}", *j, "--cache-dir", cache, env=env
            )
            report([c], "corpus", f"corpus `report --quick`, warm cache, --jobs {args.jobs}", *j, "--cache-dir", cache)
            sel = ["--select", "materials"]
            report([c], "corpus", "corpus `--select materials`, no cache, --jobs 1", *sel, "--jobs", "1", "--no-cache")
            report([c], "corpus", f"corpus `--select materials`, no cache, --jobs {args.jobs}", *sel, *j, "--no-cache")
            report(
                [c],
                "corpus",
                f"corpus `--select materials`, warm cache, --jobs {args.jobs}",
                *sel,
                *j,
                "--cache-dir",
                cache,
            )
        if args.only in (None, "synthetic"):
            from openpbr_diffuse.library.synthetic import write_variants

            lib = tmp_path / "synthetic"
            write_variants(lib, args.n)
            past = time.time() - 3600  # as an existing library: older than the run
            for p in [*lib.rglob("*"), lib]:
                os.utime(p, (past, past))
            s, cache = str(lib), str(tmp_path / "cache-synthetic")
            sel, j = ["--select", "materials"], ["--jobs", str(args.jobs)]
            n = f"{args.n} synthetic files"
            report([s], "synthetic", f"{n} `--select materials`, no cache, --jobs 1", *sel, "--jobs", "1", "--no-cache")
            report(
                [s],
                "synthetic",
                f"{n} `--select materials`, cold cache, --jobs {args.jobs}",
                *sel,
                *j,
                "--cache-dir",
                cache,
            )
            report(
                [s],
                "synthetic",
                f"{n} `--select materials`, warm cache, --jobs {args.jobs}",
                *sel,
                *j,
                "--cache-dir",
                cache,
            )
            for label, extra in (("cold", "cache-eval"), ("warm", "cache-eval")):
                out = tmp_path / f"eval-{label}.jsonl"
                r = timed(["eval", s, "--jsonl", str(out), *j, "--cache-dir", str(tmp_path / extra)])
                rows.append(row(f"{n} `eval --jsonl`, {label} cache, --jobs {args.jobs}", r))
                print(rows[-1], r["err"], flush=True)
    load1 = os.getloadavg()
    print()
    print(
        f"Measured {start:%Y-%m-%d %H:%M} UTC, {cpu_model()}, {os.cpu_count()} logical cores; "
        f"load average {load0[0]:.1f} at the start, {load1[0]:.1f} at the end."
    )
    print()
    print("| run | wall (s) | CPU (s) | peak memory, all processes (PSS, MB) | largest process (RSS, MB) | exit |")
    print("|---|---|---|---|---|---|")
    print("\n".join(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
