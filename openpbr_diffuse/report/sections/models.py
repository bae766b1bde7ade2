"""Model properties: white furnace, reciprocity, the Lambert limit, energy conservation.

Every albedo here is a numerical integral of ``evaluate`` (the library's panel
Gauss-Legendre rule, :func:`openpbr_diffuse.albedo.quadrature.hemisphere_albedo`), not a
closed form; reciprocity and the Lambert limit compare ``evaluate`` with itself under
swapped arguments and with rho/pi.  Plots re-make the EON paper's Fig. 2 (BRDF slices in
the plane of incidence, all models on one plot) and Fig. 5 (albedo curves).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ...result import Result
from .._plot import pyplot
from ..model import (
    QUICK_MODELS,
    WHITE,
    CheckTable,
    Context,
    Figure,
    SectionResult,
    Table,
    grey,
    in_quick,
)
from ._common import random_directions, roughness_max, save_panels

TITLE = "Model properties"

#: The section's checks: its rows of the static registry ``data/report_checks.tsv``.
CHECKS = CheckTable.declared("models")

RECIPROCITY = "evaluate with the arguments swapped"
LAMBERT_LIMIT = "rho / pi"
QUAD = "Gauss-Legendre quadrature of evaluate over the hemisphere (panels at the Oren-Nayar kinks)"


def _slices(ctx, models):
    """Fig. 2: f in the plane of incidence at rho = 0.8, 50 % roughness, several theta_o."""
    import openpbr_diffuse as od

    from ...models.registry import INFO

    plt = pyplot()
    thetas_o = (0.0, 30.0, 60.0, 80.0)
    fig, axes = plt.subplots(1, len(thetas_o), figsize=(16, 4.2), sharey=False)
    x = np.linspace(-89.5, 89.5, 90 if ctx.quick else 359)
    for ax, to in zip(axes, thetas_o):
        t = np.radians(to)
        wo = np.array([math.sin(t), 0.0, math.cos(t)])
        ti = np.radians(x)
        wi = np.stack([np.sin(ti), np.zeros_like(ti), np.cos(ti)], axis=-1)  # ti < 0: forward side
        for m in models:
            info = INFO[m]
            rough = 0.5 * roughness_max(info)
            f = od.evaluate(m, wi, wo, rough, grey(0.8))[:, 0]
            # EON wide underneath, eon_approx dotted on top: the two nearly coincide, both stay visible
            style = {"eon": dict(lw=3.0, zorder=3), "eon_approx": dict(lw=1.4, ls=":", color="k", zorder=4)}.get(
                m, dict(lw=1.2, ls="--" if m.startswith("qon_") or m == "gotanda" else "-")
            )
            ax.plot(x, f, label=m + (" (dotted, over eon)" if m == "eon_approx" else ""), **style)
        ax.set_title(f"theta_o = {to:g} deg")
        ax.set_xlabel("theta_i (deg); < 0 forward, > 0 back")
        ax.grid(True, alpha=0.3)
    axes[0].set_ylabel("f (1/sr; no cosine), rho = 0.8")
    axes[-1].legend(fontsize=7)
    fig.suptitle("BRDF slices (EON paper Fig. 2): rho = 0.8, 50 % roughness (r = 0.5; sigma = pi/4)", fontsize=10)
    return save_panels(fig, ctx, "models_slices.png")


def _albedo_curves(ctx):
    """Fig. 5: directional albedo against theta_o at rho = 1 for QON, FON, full ON (EON at
    rho = 0.8: at rho = 1 it is 1 everywhere)."""
    import openpbr_diffuse as od

    from ...models.registry import INFO

    plt = pyplot()
    models = in_quick(ctx, ("qon", "fon", "eon", "full_on"), QUICK_MODELS)
    fig, axes = plt.subplots(1, len(models), figsize=(16, 4), sharey=True)
    th = np.linspace(0.0, 89.9, 60 if ctx.quick else 180)
    mu = np.cos(np.radians(th))
    for ax, m in zip(axes, models):
        info = INFO[m]
        for frac in (0.25, 0.5, 0.75, 1.0):
            rough = frac * roughness_max(info)
            rho = grey(0.8) if m == "eon" else WHITE  # at rho = 1 EON is flat at 1 (white furnace)
            E = od.directional_albedo(m, mu, rough, rho)[:, 0]
            ax.plot(th, E, label=f"{info.roughness_name} = {rough:.3g}")
        ax.set_title(f"{m}: E(theta_o), rho = {0.8 if m == 'eon' else 1}")
        ax.set_xlabel("theta_o (deg)")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    axes[0].set_ylabel("directional albedo (unitless)")
    fig.suptitle("Albedo curves (EON paper Fig. 5): closed forms (full ON: reference tables)", fontsize=10)
    return save_panels(fig, ctx, "models_albedo.png")


def _symmetry_checks(m: str, wi: np.ndarray, wo: np.ndarray, r: np.ndarray, rho: np.ndarray) -> list[Result]:
    """Reciprocity and the Lambert limit of model ``m`` on the random pairs."""
    import openpbr_diffuse as od

    n = len(wi)
    f = od.evaluate(m, wi, wo, r, rho)
    g = od.evaluate(m, wo, wi, r, rho)
    recip = float(np.abs(f - g).max() / np.abs(f).max())
    lam = od.evaluate(m, wi, wo, 0.0, rho)
    with np.errstate(invalid="ignore", divide="ignore"):
        rel = np.where(rho > 0, np.abs(lam * math.pi / np.where(rho > 0, rho, 1.0) - 1.0), 0.0)
    return [
        CHECKS.check(
            f"{m}: reciprocity f(wi, wo) = f(wo, wi)",
            recip,
            1e-12,
            "<=",
            reference=RECIPROCITY,
            detail=f"max |difference| / max f over {n} random pairs, roughness, rho",
        ),
        CHECKS.check(
            f"{m}: Lambert limit at roughness 0",
            float(rel.max()),
            1e-6,
            "<=",
            reference=LAMBERT_LIMIT,
            detail="max |pi f / rho - 1| (EON: the 1e-7 guards of Listing 1)",
        ),
    ]


def _furnace_roughness(ctx: Context, m: str, info: Any) -> list[float]:
    """The roughness values of model ``m`` whose albedo at rho = 1 is integrated."""
    rmax = roughness_max(info)
    if m == "lambert":
        return [0.0]
    if info.roughness_name == "sigma":  # QON-like models peak above 1 near sigma ~ 0.2-0.3
        return [0.2, 0.5 * rmax, rmax] if ctx.quick else [0.1, 0.2, 0.3, 0.25 * rmax, 0.5 * rmax, rmax]
    return [0.25 * rmax, 0.5 * rmax, rmax]


def _energy_checks(m: str, info: Any, E: np.ndarray, mus: np.ndarray) -> list[Result]:
    """The energy checks of model ``m`` on its albedo grid ``E`` (roughness x mu) at rho = 1."""
    limits = []  # (title, measured, threshold, detail), all "<=" against the quadrature
    if info.energy_conserving:
        title, detail = f"{m}: energy conservation, max albedo at rho = 1", f"{E.size} (mu, roughness) points"
        limits.append((title, float(E.max()), 1.0 + 1e-6, detail))
    if m == "eon":
        detail = f"mu in {mus.min():g}..{mus.max():g}, r = 0.25, 0.5, 1"
        limits.append(("eon: white furnace |E - 1| at rho = 1", float(np.abs(E - 1.0).max()), 1e-6, detail))
    if m == "eon_approx":
        detail = "documented finding: at most 1.5e-4 (mu ~ 0.13, r = 1)"
        limits.append(("eon_approx: albedo overshoot above 1 (Eq. 14 fit in f_ms)", float(E.max() - 1.0), 2e-4, detail))
    return [CHECKS.check(title, v, limit, "<=", reference=QUAD, detail=d) for title, v, limit, d in limits]


def _furnace(ctx: Context, m: str, info: Any, mus: np.ndarray) -> tuple[list[Any], list[Result]]:
    """Model ``m``'s albedo at rho = 1 by quadrature: its table row and its energy checks."""
    import openpbr_diffuse as od

    from ...albedo.quadrature import hemisphere_albedo

    order = 5 if ctx.quick else 6
    roughs = _furnace_roughness(ctx, m, info)
    E = np.array(
        [hemisphere_albedo(lambda a, b, rr=rr: od.evaluate(m, a, b, rr, WHITE)[..., 0], mus, order) for rr in roughs]
    )
    k = np.unravel_index(np.argmax(E), E.shape)
    row = [
        m,
        info.roughness_name,
        float(E.min()),
        float(E.max()),
        float(mus[k[1]]),
        float(roughs[k[0]]),
        "yes" if info.energy_conserving else "no",
    ]
    return row, _energy_checks(m, info, E, mus)


def _summary(res: SectionResult, rows: list[list[Any]]) -> None:
    """The white-furnace note and the table of the albedo at rho = 1."""
    gain = [r[0] for r in rows if r[3] > 1.0 + 1e-6]
    lose = [r[0] for r in rows if r[2] < 1.0 - 1e-3]
    res.notes.append(
        f"At rho = 1 (white furnace) these models exceed unit albedo somewhere on the grid (gain "
        f"energy): {', '.join(gain) or 'none'}; these lose more than 0.1 %: {', '.join(lose) or 'none'}. "
        "EON passes the white furnace; eon_approx overshoots by the Eq. 14 fit's error."
    )
    res.tables.append(
        Table(
            "Directional albedo at rho = 1 by quadrature of evaluate (sigma models: sigma = 0.1, 0.2, "
            "0.3, pi/8, pi/4, pi/2; r models: r = 0.25, 0.5, 1; mu from 0 to 1)",
            ["model", "roughness", "min E", "max E", "mu at max", "roughness at max", "energy conserving"],
            rows,
        )
    )


def _figures(ctx: Context, run: tuple) -> list[Figure]:
    """Fig. 2 (BRDF slices of the models ``run``) and Fig. 5 (albedo curves)."""
    slices = Figure(
        _slices(ctx, run),
        f"BRDF slices in the plane of incidence, {'the quick run' if ctx.quick else 'all'} models (EON "
        "paper Fig. 2): rho = 0.8, r = 0.5 for FON/EON, sigma = pi/4 for the sigma models",
    )
    curves = Figure(
        _albedo_curves(ctx),
        "Directional albedo curves (EON paper Fig. 5): rho = 1, EON at rho = 0.8"
        + (" (full ON: in the full report)" if ctx.quick else ""),
    )
    return [slices, curves]


def build(ctx: Context) -> SectionResult:
    """Reciprocity, Lambert limit and energy of every model, their table, Fig. 2 and Fig. 5."""
    from ...models.registry import INFO

    res = SectionResult("models", TITLE)
    rng = np.random.default_rng(2025)
    n = 500 if ctx.quick else 4000
    wi, wo = random_directions(rng, n), random_directions(rng, n)
    rho = rng.uniform(0.0, 1.0, (n, 3))
    mus = np.array([0.0, 0.3, 1.0] if ctx.quick else [0.0, 0.01, 0.05, 0.1, 0.2, 0.35, 0.5, 0.7, 0.85, 1.0])
    rows: list[list[Any]] = []
    run = in_quick(ctx, tuple(INFO), QUICK_MODELS)
    for m, info in INFO.items():
        if m not in run:  # --quick: the model's checks listed as not run (the full report runs them)
            continue
        ctx.progress(f"model {m}")
        res.checks += _symmetry_checks(m, wi, wo, rng.uniform(0.0, roughness_max(info), n), rho)
        row, energy = _furnace(ctx, m, info, mus)
        rows.append(row)
        res.checks += energy
    _summary(res, rows)
    ctx.progress("plots")
    res.figures += _figures(ctx, run)
    return res
