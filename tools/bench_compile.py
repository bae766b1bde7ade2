"""Compile-time profile of one CLI command: numba's compile events, self time per function.

    python tools/bench_compile.py eval materials/clay_rough.mtlx
    TOP=60 python tools/bench_compile.py report --quick --no-progress --out /tmp/r

Runs the command in this process with an empty numba cache (a new ``NUMBA_CACHE_DIR``
unless one is set) and prints, per compiled function, its compile time without that of
the functions it compiles in turn ("self"), with them ("tot"), and its number of
specialisations ("xN"), most expensive first.  ``SIGS=PATTERN`` also prints the argument
types of each specialisation of the functions whose name contains PATTERN (why a function
compiles more than once).
"""

import collections
import os
import sys
import tempfile
import threading
import time


def main(argv: list) -> int:
    """Run ``openpbr-diffuse *argv`` and print its compile profile to stderr.

    Example
    -------
    >>> main(["--version"]) in (0, None)   # doctest: +SKIP
    True
    """
    os.environ.setdefault("NUMBA_CACHE_DIR", tempfile.mkdtemp(prefix="numba-profile-"))
    from numba.core import event

    sigs = os.environ.get("SIGS", "")
    signatures = collections.defaultdict(list)
    stack = collections.defaultdict(list)
    self_s, total_s, count = collections.Counter(), collections.Counter(), collections.Counter()

    class Listener(event.Listener):
        def on_start(self, e):
            stack[threading.get_ident()].append([time.perf_counter(), 0.0])

        def on_end(self, e):
            s = stack[threading.get_ident()]
            t0, child = s.pop()
            d = time.perf_counter() - t0
            f = getattr(e.data["dispatcher"], "py_func", None)
            key = f"{f.__module__.split('.')[-1]}.{f.__qualname__}" if f else str(e.data["dispatcher"])
            self_s[key] += d - child
            total_s[key] += d
            count[key] += 1
            if sigs and sigs in key:
                signatures[key].append(e.data.get("args"))
            if s:
                s[-1][1] += d

    event.register("numba:compile", Listener())
    from openpbr_diffuse.cli.main import main as cli

    t, w = time.process_time(), time.perf_counter()
    try:
        rc = cli(argv)
    except SystemExit as x:
        rc = x.code
    print(
        f"exit {rc}: CPU {time.process_time() - t:.1f} s, wall {time.perf_counter() - w:.1f} s; compiling "
        f"{sum(self_s.values()):.1f} s, {sum(count.values())} specialisations of {len(count)} functions",
        file=sys.stderr,
    )
    for k, v in self_s.most_common(int(os.environ.get("TOP", "30"))):
        print(f"{v:7.2f} self {total_s[k]:7.2f} tot  x{count[k]:<3d} {k}", file=sys.stderr)
    for k, args in signatures.items():
        print(f"{k}:", file=sys.stderr)
        for a in args:
            print(f"    {a}", file=sys.stderr)
    return rc or 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
