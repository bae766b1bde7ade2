"""Albedo: the closed forms against the shipped reference tables, and the Eq. 14 fit's error.

The reference tables (``data/albedo_<model>.csv``) were computed by numerical integration
of ``evaluate``, never from a closed form (their headers give method, resolution and the
held-out interpolation error); ``directional_albedo`` / ``average_albedo`` are the closed
forms (Eq. 8-9, 12-15, 20).  The Eq. 14 fit of E_F is compared with the FON table.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ...result import Result
from .._plot import pyplot
from ..model import QUICK_MODELS, WHITE, CheckTable, Context, Figure, SectionResult, Table
from ._common import label_panels, roughness_max, save_panels

TITLE = "Albedo: closed forms against the reference tables"

#: The section's checks: its rows of the static registry ``data/report_checks.tsv``.
CHECKS = CheckTable.declared("albedo")

#: Closed form vs table: the tables' interpolation error is < 3e-6 (stated in each file).
TABLE_TOL = 1e-5
#: The paper: the Eq. 14 fit "has fractional error of less than 0.1% over all directions".
FIT_TOL = 1e-3
#: The colours of the table comparison.
COLOURS = (WHITE, [0.8, 0.5, 0.2], [0.05, 0.3, 0.9])


def _fit_error(ctx, n_mu, n_r):
    """(mu, r, exact table E_F, Eq. 14 fit) on a grid."""
    import openpbr_diffuse as od

    from ...models.fon import E_F_approx

    mu = np.linspace(0.0, 1.0, n_mu)
    r = np.linspace(0.0, 1.0, n_r)
    exact = np.stack([od.reference_albedo("fon", mu, rr, 1.0)[:, 0] for rr in r])
    fit = np.array([[E_F_approx(float(m), float(rr)) for m in mu] for rr in r])
    return mu, r, exact, fit


#: Values stated in the EON paper [Portsmouth2025] and checked by independent quadrature:
#: (label, model, kind, mu, roughness, value, decimals).
STATED = (
    ("E_F(mu = 1, r = 1)", "fon", "E", 1.0, 1.0, 0.776522, 6),
    ("E_F(mu = 0.7, r = 1)", "fon", "E", 0.7, 1.0, 0.817888, 6),
    ("E_F(mu = 0.3, r = 0.5)", "fon", "E", 0.3, 0.5, 0.954690, 6),
    ("<E_F>(r = 0.5)", "fon", "avg", None, 0.5, 0.905890, 6),
    ("<E_F>(r = 1)", "fon", "avg", None, 1.0, 0.832811, 6),
    ("E_QON(mu = 0.5, sigma = pi/4)", "qon", "E", 0.5, 0.25 * math.pi, 0.791338, 6),
    ("<E_QON>(sigma = pi/4)", "qon", "avg", None, 0.25 * math.pi, 0.758285, 6),
    ("full ON E(mu = 0.05, sigma = 0.5), rho = 1", "full_on", "E", 0.05, 0.5, 1.0047, 4),
)


_STATED_REFERENCE = "EON paper values (Portsmouth et al. 2025), checked by independent quadrature"


def _stated(ctx, res):
    """The library's quadrature of ``evaluate`` against the stated values."""
    import openpbr_diffuse as od

    from ...albedo.quadrature import hemisphere_albedo, hemisphere_average_albedo

    rows = []
    for label, m, kind, mu, rough, value, dec in STATED:
        if ctx.quick and not CHECKS.spec(f"stated value {label}").quick:
            continue
        ctx.progress(f"stated value {label}")

        def brdf(wi, wo, m=m, rough=rough):
            return od.evaluate(m, wi, wo, rough, WHITE)[..., 0]

        q = float(hemisphere_albedo(brdf, mu, 12) if kind == "E" else hemisphere_average_albedo(brdf, 8, n_mu=8))
        tol = 0.5 * 10.0**-dec + 1e-9
        rows.append([label, value, q, q - value])
        res.checks.append(
            CHECKS.check(
                f"stated value {label}",
                q,
                tol,
                "==",
                expected=value,
                reference=_STATED_REFERENCE,
                detail="quadrature of evaluate; tolerance: half a unit of the last stated digit",
            )
        )
    res.tables.append(
        Table(
            "Stated values against quadrature of evaluate (rho = 1)",
            ["quantity", "stated", "quadrature", "difference"],
            rows,
        )
    )


def _table_errors(ctx: Context, m: str, info: Any) -> tuple[float, float, int]:
    """Largest |closed form - table| of model ``m``: directional, average; how many roughness values."""
    import openpbr_diffuse as od

    mu = np.linspace(0.01, 1.0, 12 if ctx.quick else 40)
    rough = np.linspace(0.0, 1.0, 4 if ctx.quick else 9) * roughness_max(info)
    worst = 0.0
    worst_avg = 0.0
    for rho in COLOURS:
        for rr in rough:
            E = od.directional_albedo(m, mu, rr, rho)
            R = od.reference_albedo(m, mu, rr, rho)
            worst = max(worst, float(np.abs(E - R).max()))
        Ea = od.average_albedo(m, rough, rho)
        Ra = od.reference_average_albedo(m, rough, rho)
        worst_avg = max(worst_avg, float(np.abs(Ea - Ra).max()))
    return worst, worst_avg, len(rough)


def _table_checks(ctx: Context, m: str, info: Any) -> tuple[list[Result], list[Any]]:
    """Model ``m``'s closed forms against its reference table: the two checks and the table row."""
    from ...albedo.tables import load_table, table_path

    table = load_table(m)
    worst, worst_avg, n_rough = _table_errors(ctx, m, info)
    ref = f"data/{table_path(m).name} (quadrature of evaluate; interpolation error {table.interpolation_error:.1e})"
    checks = [
        CHECKS.check(
            f"{m}: directional albedo, closed form vs table",
            worst,
            TABLE_TOL,
            "<=",
            reference=ref,
            detail=f"mu in [0.01, 1], {n_rough} roughness values, 3 colours",
        ),
        CHECKS.check(f"{m}: average albedo, closed form vs table", worst_avg, TABLE_TOL, "<=", reference=ref),
    ]
    return checks, [m, worst, worst_avg, float(table.interpolation_error)]


def _closed_forms(ctx: Context, res: SectionResult) -> None:
    """Every closed-form model against its reference table: checks and the summary table."""
    from ...models.registry import INFO

    rows = []
    for m, info in INFO.items():
        if not info.closed_form_albedo:
            continue
        if ctx.quick and m not in QUICK_MODELS:  # listed as not run (the full report runs them)
            continue
        ctx.progress(f"albedo {m}")
        checks, row = _table_checks(ctx, m, info)
        res.checks += checks
        rows.append(row)
    res.tables.append(
        Table(
            "Largest |closed form - reference table| (rho = 1, (0.8, 0.5, 0.2), (0.05, 0.3, 0.9))",
            ["model", "directional albedo", "average albedo", "table interpolation error"],
            rows,
        )
    )


def _fit(ctx: Context, res: SectionResult) -> None:
    """The Eq. 14 fit of E_F against the FON table: its check, note and figure (Fig. 6)."""
    ctx.progress("Eq. 14 fit")
    mu_g, r_g, exact, fit = _fit_error(ctx, 101 if ctx.quick else 401, 11 if ctx.quick else 21)
    err = fit - exact
    frac = np.abs(err) / exact
    k = np.unravel_index(np.argmax(np.abs(err)), err.shape)
    res.checks.append(
        CHECKS.check(
            "Eq. 14 fit of E_F: max fractional error",
            float(frac.max()),
            FIT_TOL,
            "<=",
            reference="data/albedo_fon.csv; paper: < 0.1 % over all directions",
            detail=f"max |error| {abs(err[k]):.3e} at r = {r_g[k[0]]:.3g}, mu = {mu_g[k[1]]:.3g}",
        )
    )
    res.notes.append(
        f"The Eq. 14 fit's largest error against the exact E_F (reference table): "
        f"{abs(err[k]):.3e} at r = {r_g[k[0]]:.3g}, mu = {mu_g[k[1]]:.3g}; at mu = 0 it reaches "
        f"E_F = {fit[-1, 0]:.6f} at r = 1 (exact: 1)."
    )
    res.figures.append(_fit_figure(ctx, mu_g, r_g, exact, fit))


def _fit_figure(ctx: Context, mu_g: np.ndarray, r_g: np.ndarray, exact: np.ndarray, fit: np.ndarray) -> Figure:
    """Fig. 6: E_F and the Eq. 14 fit (left), the fit's fractional error (right)."""
    err = fit - exact
    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.2))
    for i in range(0, len(r_g), max(1, len(r_g) // 5)):
        axes[0].plot(mu_g, exact[i], label=f"r = {r_g[i]:.2f}")
        axes[0].plot(mu_g, fit[i], "k:", lw=0.8)
        axes[1].plot(mu_g, 100.0 * err[i] / exact[i], label=f"r = {r_g[i]:.2f}")
    axes[0].set_title("E_F(mu): exact (table, solid) and Eq. 14 fit (dotted)")
    axes[1].set_title("Eq. 14 fit: fractional error (%) (EON paper Fig. 6 right)")
    label_panels(axes, "mu = cos theta_o (unitless)", 7)
    return Figure(save_panels(fig, ctx, "albedo_fit.png"), "FON albedo E_F and the Eq. 14 fit (Fig. 6)")


def build(ctx: Context) -> SectionResult:
    """Closed forms against the tables, the stated values, the Eq. 14 fit."""
    res = SectionResult("albedo", TITLE)
    _closed_forms(ctx, res)
    _stated(ctx, res)
    _fit(ctx, res)
    return res
