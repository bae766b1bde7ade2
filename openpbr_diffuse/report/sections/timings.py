"""Timings on this machine in the form of the EON paper's Table 1.

Each entry is the best of several timed batch calls through the public API (input checks
included), in nanoseconds per row: ``evaluate(model)``; ``sample("cosine")`` followed by
``evaluate`` in the sampled direction; ``sample("eon")`` (CLTC + uniform MIS) followed by
``evaluate``.  Inputs as in the paper: random directions, roughness and albedo; float64 (the
paper's glm code is float32), so that the timings run the drivers the other sections have
already compiled instead of compiling float32 variants of them (a cold report compiled ten
for this table alone).
The paper's numbers are scalar C++/glm calls on one thread of an AMD 3970X; these are
vectorised batch calls on numba's thread count -- a different measurement, shown side by
side for the shape of the table (relative costs), not as a pass/fail comparison.
"""

from __future__ import annotations

import math
import time
from typing import Any, NamedTuple

import numpy as np

from .._plot import pyplot
from ..model import QUICK_MODELS, CheckTable, Context, Figure, SectionResult, Table, in_quick
from ._common import random_directions, save_panels

TITLE = "Timings (the paper's Table 1 on this machine)"

#: The section's checks: its rows of the static registry ``data/report_checks.tsv``.
CHECKS = CheckTable.declared("timings")

#: EON paper Table 1 (ns): eval, cosine sample, CLTC sample (None: not given).
PAPER = {
    "lambert": (1.4, 67.2, None),
    "fon": (6.3, 67.2, None),
    "qon": (6.3, 67.4, None),
    "full_on": (141.7, 211.218, None),
    "eon_approx": (20.8, 105.8, 217.0),
    "eon": (108.7, 193.5, 297.0),
}
LABELS = {
    "lambert": "Lambert",
    "fon": "FON",
    "qon": "QON",
    "full_on": "fullON",
    "eon_approx": "EON (approx)",
    "eon": "EON (exact)",
}


def _best(fn, reps):
    """The best of ``reps`` timed calls of ``fn`` after a warm-up call, in seconds."""
    fn()  # warm-up (compilation or cache load)
    best = math.inf
    for _ in range(reps):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


class _Inputs(NamedTuple):
    """The random inputs of the timed calls, as in the paper: directions, roughness, albedo."""

    wi: np.ndarray
    wo: np.ndarray
    rho: np.ndarray
    r01: np.ndarray
    u: np.ndarray


def _inputs(n: int) -> _Inputs:
    """``n`` rows of random inputs (float64: the dtype every other section uses, no extra compilation)."""
    rng = np.random.default_rng(1)
    dt = np.float64
    wi, wo = random_directions(rng, n).astype(dt), random_directions(rng, n).astype(dt)
    rho = rng.uniform(0.0, 1.0, (n, 3)).astype(dt)
    r01 = rng.uniform(0.0, 1.0, n).astype(dt)
    u = rng.uniform(0.0, 1.0, (n, 2)).astype(dt)
    u = np.minimum(u, dt(0.99999994))
    return _Inputs(wi, wo, rho, r01, u)


def _time_model(m: str, x: _Inputs, reps: int) -> tuple[float, float, float | None]:
    """ns per row of model ``m``: evaluate; cosine sample + evaluate; CLTC sample + evaluate (None: not in the paper)."""
    import openpbr_diffuse as od

    n = len(x.wi)

    def sampled(strategy: str) -> Any:
        w, _ = od.sample(strategy, x.wo, x.r01, x.u)
        return od.evaluate(m, w, x.wo, x.r01, x.rho)

    t_eval = _best(lambda: od.evaluate(m, x.wi, x.wo, x.r01, x.rho), reps) / n * 1e9
    t_cos = _best(lambda: sampled("cosine"), reps) / n * 1e9
    t_cltc = None if PAPER[m][2] is None else _best(lambda: sampled("eon"), reps) / n * 1e9
    return t_eval, t_cos, t_cltc


def _figure(ctx: Context, rows: list[list[Any]]) -> Figure:
    """The evaluation times here and in the paper, per BRDF (log scale)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(10, 3.8))
    x = np.arange(len(rows))
    ax.bar(x - 0.2, [r[1] for r in rows], 0.4, label="eval, here (ns/row)")
    ax.bar(x + 0.2, [r[2] for r in rows], 0.4, label="eval, paper (ns/call)")
    ax.set_xticks(x, [r[0] for r in rows])
    ax.set_yscale("log")
    ax.grid(True, axis="y", alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("BRDF evaluation time: this machine vs EON paper Table 1")
    return Figure(save_panels(fig, ctx, "timings_table1.png"), "Evaluation time per BRDF (log scale)")


def _table(n: int, reps: int, rows: list[list[Any]]) -> Table:
    """Table 1: the times here beside the paper's."""
    import numba

    return Table(
        f"ns per row, float64, batches of {n}, best of {reps}, {numba.get_num_threads()} numba thread(s); "
        "paper: ns per scalar call, C++/glm, one thread of an AMD 3970X",
        [
            "BRDF",
            "eval (here)",
            "eval (paper)",
            "cosine sample (here)",
            "cosine sample (paper)",
            "CLTC sample (here)",
            "CLTC sample (paper)",
        ],
        rows,
    )


def build(ctx: Context) -> SectionResult:
    """Table 1 on this machine, its check, note and figure."""
    res = SectionResult("timings", TITLE)
    n = 20_000 if ctx.quick else 200_000
    reps = 2 if ctx.quick else 4
    x = _inputs(n)
    rows, measured = [], []
    for m in in_quick(ctx, tuple(PAPER), QUICK_MODELS):  # --quick: full ON's row in the full report
        p_eval, p_cos, p_cltc = PAPER[m]
        ctx.progress(f"timing {m}")
        t_eval, t_cos, t_cltc = _time_model(m, x, reps)
        measured += [t for t in (t_eval, t_cos, t_cltc) if t is not None]
        rows.append(
            [
                LABELS[m],
                t_eval,
                p_eval,
                t_cos,
                p_cos,
                t_cltc if t_cltc is not None else "—",
                p_cltc if p_cltc is not None else "—",
            ]
        )
    res.tables.append(_table(n, reps, rows))
    ok = sum(1 for t in measured if math.isfinite(t) and t > 0)
    res.checks.append(
        CHECKS.check(
            "every Table 1 entry measured",
            float(ok),
            0.0,
            "==",
            expected=float(len(measured)),
            reference="EON paper Table 1 (the entries it lists)",
        )
    )
    res.notes.append(
        "The paper times scalar calls of the GLSL listings ported to C++; here the library's "
        "vectorised, compiled batch calls are timed per row. Compare the ratios between rows "
        "(e.g. exact vs approximate EON, CLTC vs cosine sampling), not the absolute numbers. "
        "tools/bench.py compares against a scalar C port of the listings on this machine."
    )
    res.figures.append(_figure(ctx, rows))
    return res
