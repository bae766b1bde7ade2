"""Report section "layered": the diffuse lobe under a dielectric layer, graded against physics.

Reads the shipped tables of ``tools/make_layered_tables.py`` (``data/layered_grading.csv``,
``data/layered_gotanda_absorption.csv`` and the figure ``data/layered_grading.png``) and
runs a small live check: the layered simulator against the exact closed form of a smooth
interface over a Lambertian base, and a fresh rough-interface estimate against the
shipped one.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ..model import QUICK_NOT_RUN, CheckTable, Context, Figure, SectionResult, Table
from ._common import copy_figure, within_errors

TITLE = "The diffuse lobe under a dielectric layer: layering rules against physics"

#: The section's checks: its rows of the static registry ``data/report_checks.tsv``.
CHECKS = CheckTable.declared("layered")

KEY = "layered"
HEADLINE_N, HEADLINE_RHO = 1.5, 0.8


_SMOOTH = "live simulation vs exact closed form (smooth n 1.5, coat_color 0.8, rho {rho}, mu 0.3)"
_SMOOTH_REF = "closed form with internal reflections (Saunderson 1942; Lekner & Dorf 1988)"
_GGX = "live GGX-interface simulation reproduces the shipped diffuse part (alpha 0.25, n 1.5, mu 0.4, rho 0.8)"
_FURNACE = "white furnace of the GGX-interface layer (rho 1, no absorption)"
_FURNACE_REF = "energy-conserving microsurface walk: every path leaves"


def _live(quick: bool, rows: list[dict]) -> list:
    """The live layered simulations against the closed form and the shipped table."""
    from ...simulation.layered import (
        LayeredSurface,
        simulate_layered_albedo,
        smooth_lambert_albedo,
    )

    paths = 20_000 if quick else 100_000
    checks = []
    t0 = time.monotonic()
    e = simulate_layered_albedo(
        LayeredSurface("smooth", 1.5, coat_color=0.8), [0.3], rho=[0.8, 1.0], paths=paths, seed=11
    )
    sec = time.monotonic() - t0
    for c, rho in enumerate((0.8, 1.0)):
        ref = float(smooth_lambert_albedo(1.5, rho, 0.3, -np.log(0.8)))
        z = abs(e.total[0, c] - ref) / e.total_stderr[0, c]
        detail = f"{e.total[0, c]:.5f} +- {e.total_stderr[0, c]:.1e} vs {ref:.5f} ({paths} paths, {sec:.1f} s)"
        checks.append(within_errors(CHECKS, _SMOOTH.format(rho=rho), z, 4.0, _SMOOTH_REF, detail))
    row = next(
        r
        for r in rows
        if r["interface_alpha"] == 0.25 and r["n"] == 1.5 and r["tau"] == 0.0 and r["mu"] == 0.4 and r["rho"] == 0.8
    )
    e = simulate_layered_albedo(LayeredSurface("ggx", 1.5, 0.25), [0.4], rho=[0.8, 1.0], paths=paths, seed=12)
    z = abs(e.diffuse[0, 0] - row["physics"]) / np.hypot(e.diffuse_stderr[0, 0], row["physics_se"])
    detail = f"{e.diffuse[0, 0]:.5f} +- {e.diffuse_stderr[0, 0]:.1e} vs {row['physics']:.5f} +- {row['physics_se']:.1e}"
    checks.append(within_errors(CHECKS, _GGX, z, 4.5, "data/layered_grading.csv", detail))
    checks.append(
        CHECKS.check(
            _FURNACE,
            measured=float(abs(e.total[0, 1] - 1.0)),
            threshold=1e-12,
            reference=_FURNACE_REF,
        )
    )
    return checks


def _headline(rows: list[dict]) -> tuple[list[dict], str]:
    """The smooth-interface rows at n 1.5, rho 0.8, no absorption, and the headline note on them."""
    sel = [
        r
        for r in rows
        if r["interface_alpha"] == 0.0 and r["n"] == HEADLINE_N and r["rho"] == HEADLINE_RHO and r["tau"] == 0.0
    ]
    graz = min(sel, key=lambda r: r["mu"])
    head = graz["openpbr"] / graz["physics"] - 1
    coat = graz["openpbr_coat"] / graz["physics"] - 1
    note = (
        f"Headline: OpenPBR's diffuse weight under its dielectric specular layer (albedo scaling, 1 - E_spec) is "
        f"{100 * head:+.0f} % off the physics at grazing (mu = {graz['mu']:g}) for n = {HEADLINE_N:g}, rho = "
        f"{HEADLINE_RHO:g}, smooth interface: the physics darkens the base by the light the interface reflects back "
        f"into it (internal reflection, r_i = 1 - (1 - r_e)/n^2), which albedo scaling omits.  OpenPBR's coat "
        f"darkening formula (1 - K)/(1 - rho K) captures it: the coat rule is {100 * coat:+.1f} % off there."
    )
    return sel, note


def _rule_tables(rows: list[dict]) -> list[Table]:
    """Each rule's error per interface, without and with absorption in the slab."""
    from ...approximations import layering_grading as lg

    tables = []
    for tau in (0.0, 0.1, 0.5):
        trows = []
        for a in sorted({r["interface_alpha"] for r in rows}):
            cells: list[Any] = [_interface(a)]
            for rule in lg.RULES:
                s = lg.error_summary(rows, rule, interface_alpha=a, tau=tau)
                cells.append(f"{100 * s['mean']:.1f} / {100 * s['max']:.0f}")
            trows.append(cells)
        tables.append(
            Table(
                caption=f"Relative error of the diffuse albedo E_d(mu), mean / max in %, over n 1.3-2, rho 0.2-1, "
                f"mu 0.1-1; slab optical depth tau = {tau:g}",
                columns=["interface", *lg.RULES],
                rows=trows,
            )
        )
    return tables


def _headline_table(sel: list[dict]) -> Table:
    """The physics and each rule's error on the headline rows, by mu."""
    from ...approximations import layering_grading as lg

    hrows = []
    for r in sorted(sel, key=lambda r: -r["mu"]):
        hrows.append([r["mu"], round(r["physics"], 4), *(f"{100 * (r[k] / r['physics'] - 1):+.1f}" for k in lg.RULES)])
    return Table(
        caption=f"Smooth interface, n {HEADLINE_N:g}, rho {HEADLINE_RHO:g}, no absorption: "
        "physics and each rule's error in %",
        columns=["mu", "physics E_d", *lg.RULES],
        rows=hrows,
    )


def _interface(alpha: float) -> str:
    """The name of an interface by its roughness."""
    return "smooth" if alpha == 0 else f"GGX alpha {alpha:g}"


def _eon_table() -> Table:
    """OpenPBR's rules over an EON base against the simulation."""
    from ..._csv import read_headed_csv
    from ...approximations import layering_grading as lg

    _, en, erows = read_headed_csv(lg.DATA / "layered_grading_eon.csv")
    ec = {k: i for i, k in enumerate(en)}
    etab = []
    for a in (0.0, 0.25):
        for r_eon in (0.5, 1.0):
            sel_e = [x for x in erows if float(x[ec["interface_alpha"]]) == a and float(x[ec["r"]]) == r_eon]
            cells: list[Any] = [_interface(a), r_eon]
            for rule in ("openpbr", "openpbr_coat"):
                err = np.array([float(x[ec[rule]]) / float(x[ec["physics"]]) - 1 for x in sel_e])
                cells.append(f"{100 * np.mean(np.abs(err)):.1f} / {100 * np.max(np.abs(err)):.0f}")
            etab.append(cells)
    return Table(
        caption="EON base (n 1.5, no absorption): relative error of E_d, mean / max in %, over "
        "rho 0.2-1 and mu 0.1-1 (data/layered_grading_eon.csv)",
        columns=["interface", "EON r", "openpbr", "openpbr_coat"],
        rows=etab,
    )


def _gotanda_table() -> Table:
    """Gotanda's absorption: Eq. 3 against Eq. 2, Eq. 9 against the integral of Eq. 2."""
    from ..._csv import read_headed_csv
    from ...approximations import layering_grading as lg

    _, names, grow = read_headed_csv(lg.DATA / "layered_gotanda_absorption.csv")
    col = {k: i for i, k in enumerate(names)}
    arows = []
    for tau in (0.01, 0.05, 0.1, 0.2):
        g = [r for r in grow if float(r[col["tau"]]) == tau and float(r[col["n"]]) == 1.5]
        d3 = max(abs(float(r[col["eq3_minus_eq2"]])) for r in g)
        d9 = max(abs(float(r[col["eq9_minus_exact"]])) for r in g)
        arows.append([tau, f"{d3:.4f}", f"{d9:.4f}"])
    return Table(
        caption="Gotanda 2012 absorption, n 1.5: largest |Eq. 3 - Eq. 2| over mu_l, mu_e in "
        "0.1-1, and |Eq. 9 - cosine-weighted Eq. 2| over mu_e (alpha' = alpha d = tau)",
        columns=["tau", "Eq. 3 - Eq. 2", "Eq. 9 - exact IBL"],
        rows=arows,
    )


def build(ctx: Context) -> SectionResult:
    """The live checks, the headline, the rules' error tables and the shipped figure."""
    from ...approximations import layering_grading as lg

    res = SectionResult(key=KEY, title=TITLE)
    header, rows = lg.load_table()
    if ctx.quick:  # every check of this section is live: the full report runs them
        res.not_run = QUICK_NOT_RUN
        res.notes.append(
            "Quick run: the live simulations (the layered simulator against the smooth interface's closed form "
            "and against the shipped GGX-interface table) were not run; `openpbr-diffuse report` runs them. "
            "The tables below are the shipped simulation results."
        )
    else:
        ctx.progress("layered: live check")
        res.checks.extend(_live(ctx.quick, rows))
    sel, headline = _headline(rows)
    res.notes.append(headline)
    res.tables += _rule_tables(rows)
    res.tables += [_headline_table(sel), _eon_table(), _gotanda_table()]
    shipped = lg.DATA / "layered_grading.png"
    if shipped.is_file():
        copy_figure(shipped, ctx)
        res.figures.append(
            Figure(
                file=shipped.name,
                caption="Relative error of each rule's diffuse albedo against "
                "the physics, n 1.5, rho 0.8, no absorption (left smooth, right GGX alpha 0.25)",
            )
        )
    res.notes.append(
        "Physics: exact closed form (smooth) or the position-free random walk of "
        "openpbr_diffuse.simulation.layered (GGX: Heitz et al. 2016 dielectric microsurface walk). "
        f"Tables regenerate with `{header.get('regenerate', '')}`; {header.get('resolution', '')}"
    )
    return res


__all__ = ["TITLE", "build"]
