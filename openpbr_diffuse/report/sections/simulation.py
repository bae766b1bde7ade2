"""Report section "simulation": the lobe models against a simulated Lambertian microsurface.

Reads the shipped tables of ``tools/make_simulation_tables.py`` (``data/simulation_*.csv``,
and the figures it draws from them with ``plot_all``) and re-runs a small live simulation to show that they are reproduced: the shipped numbers
are Monte Carlo estimates with standard errors, and a fresh estimate with another seed must
agree with them within its error.
"""

from __future__ import annotations

import os
import time
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ...result import Result
from .._plot import pyplot
from ..model import CheckTable, Context, Figure, SectionResult, Table, grey
from ._common import copy_figure, within_errors

TITLE = "Physical ground truth: simulated rough Lambertian microsurfaces"

#: The section's checks: its rows of the static registry ``data/report_checks.tsv``.
CHECKS = CheckTable.declared("simulation")

KEY = "simulation"
GEOMETRY_LABEL = {
    "vcavity": "V-cavities (Oren-Nayar), sigma",
    "smith-beckmann": "Smith Beckmann, alpha",
    "smith-ggx": "Smith GGX, alpha",
}
FIGURES = ("albedo_error", "colorshift", "brdf_slices")
MODEL_STYLE = {"full_on": "C0", "qon": "C1", "qon_fujii": "C2", "fon": "C3", "eon": "C4", "eon_approx": "C5"}


def _tables(directory=None):
    """The shipped simulation tables by name: (header, columns)."""
    from ...simulation import grading as gr

    return {name: gr.load(name, directory) for name in gr.TABLES}


def _grading_rows(g, fit="albedo"):
    """The grading table's rows (as dicts) of one fit (albedo or BRDF)."""
    n = len(g["model"])
    return [{k: g[k][i] for k in g} for i in range(n) if g["fit"][i] == fit]


def fit_power_law(x: ArrayLike, y: ArrayLike) -> tuple[float, float] | None:
    """r = (x / x0)^p by least squares in log space over 0 < r < 0.98; returns (x0, p) or None."""
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    ok = (y > 0.005) & (y < 0.98)
    if ok.sum() < 2:
        return None
    p, c = np.polyfit(np.log(x[ok]), np.log(y[ok]), 1)
    return float(np.exp(-c / p)), float(p)


def _plot_albedo_error(plt: Any, t: dict) -> Any:
    """Albedo error, BRDF error and fitted roughness against the simulated roughness."""
    g = t["grading"][1]
    rows, brows = _grading_rows(g), _grading_rows(g, "brdf")
    fig, axes = plt.subplots(3, 3, figsize=(13, 10), constrained_layout=True)
    for j, geom in enumerate(GEOMETRY_LABEL):
        for model, color in MODEL_STYLE.items():
            rr = [r for r in rows if r["geometry"] == geom and r["model"] == model]
            bb = [r for r in brows if r["geometry"] == geom and r["model"] == model]
            x = [r["roughness"] for r in rr]
            axes[0, j].plot(x, [r["albedo_rms"] for r in rr], "o-", color=color, label=model, ms=3)
            axes[1, j].plot(x, [r["brdf_rel_rms"] for r in bb], "o-", color=color, label=model, ms=3)
            axes[2, j].plot(x, [r["model_roughness"] for r in rr], "o-", color=color, label=model, ms=3)
            axes[2, j].plot(x, [r["model_roughness"] for r in bb], "x--", color=color, ms=4)
        axes[0, j].set_title(GEOMETRY_LABEL[geom])
        axes[0, j].set_ylabel("RMS albedo error, albedo fit")
        axes[1, j].set_ylabel("RMS relative BRDF error, BRDF fit")
        axes[2, j].set_ylabel("fitted roughness (o: albedo fit, x: BRDF fit)")
        axes[2, j].set_xlabel("simulated roughness")
    axes[0, 0].legend(fontsize=8)
    return fig


def _plot_colorshift(plt: Any, t: dict) -> Any:
    """Multi-bounce colour and albedo nonlinearity, EON against the simulation."""
    _, cs = t["colorshift"]
    fig, axes = plt.subplots(2, 3, figsize=(13, 7), constrained_layout=True)
    for j, geom in enumerate(GEOMETRY_LABEL):
        rough = sorted({float(r) for gg, r in zip(cs["geometry"], cs["roughness"]) if gg == geom})
        for k, s in enumerate(rough[1::2]):
            sel = (cs["geometry"] == geom) & np.isclose(cs["roughness"], s)
            c = f"C{k}"
            lab = f"{s:g} (EON r = {cs['r_eon'][sel][0]:.2f})"
            axes[0, j].plot(cs["rho"][sel], cs["ms_sim"][sel], "-", color=c, label=f"sim {lab}")
            axes[0, j].plot(cs["rho"][sel], cs["ms_eon"][sel], "--", color=c)
            axes[1, j].plot(cs["rho"][sel], cs["ratio_sim"][sel], "-", color=c, label=f"sim {lab}")
            axes[1, j].plot(cs["rho"][sel], cs["ratio_eon"][sel], "--", color=c)
        axes[0, j].plot([0, 1], [0, 1], ":", color="gray", lw=0.8)
        axes[0, j].set_title(GEOMETRY_LABEL[geom])
        axes[0, j].set_ylabel("E_ms(rho) / E_ms(1) (dashed: EON rho_ms)")
        axes[1, j].set_ylabel("<E>(rho) / rho (dashed: EON)")
        axes[1, j].set_xlabel("microfacet albedo rho")
        axes[0, j].legend(fontsize=7)
    return fig


def _plot_brdf_slices(plt: Any, t: dict) -> Any:
    """BRDF slices at one roughness per geometry, theta_i = 60 deg, rho = 0.8."""
    from ...models import evaluate
    from ...simulation import grading as gr

    _, b = t["brdf"]
    brows = _grading_rows(t["grading"][1], "brdf")
    fig, axes = plt.subplots(1, 3, figsize=(13, 4), constrained_layout=True)
    for j, geom in enumerate(GEOMETRY_LABEL):
        target = {"vcavity": 0.4, "smith-beckmann": 0.5, "smith-ggx": 0.3}[geom]
        sel = (
            (b["geometry"] == geom)
            & np.isclose(b["roughness"], target)
            & np.isclose(b["theta_i"], 60.0)
            & np.isclose(b["rho"], gr.BRDF_RHO)
        )
        to = b["theta_o"][sel]
        axes[j].errorbar(to, b["f"][sel], yerr=b["f_se"][sel], fmt="ko", ms=3, label="simulation")
        axes[j].plot(to, b["f1"][sel], "k:", label="simulation, 1 bounce")
        wi, wo = gr.slice_directions(np.radians(np.full(200, 60.0)), np.radians(np.linspace(-89, 89, 200)))
        for r in brows:
            if r["geometry"] == geom and np.isclose(r["roughness"], target):
                f = evaluate(r["model"], wi, wo, r["model_roughness"], grey(gr.BRDF_RHO))[:, 0]  # RGB: one driver
                axes[j].plot(
                    np.linspace(-89, 89, 200),
                    f,
                    color=MODEL_STYLE[r["model"]],
                    label=f"{r['model']} ({r['model_roughness']:.2f})",
                )
        axes[j].set_title(f"{GEOMETRY_LABEL[geom]} = {target:g}; theta_i 60, rho {gr.BRDF_RHO:g}", fontsize=8)
        axes[j].set_xlabel("theta_o (deg; < 0: towards the light)")
        axes[j].set_ylabel("f (1/sr)")
        axes[j].legend(fontsize=7)
    return fig


#: How each figure of :data:`FIGURES` is drawn from the tables.
_PLOTS = {"albedo_error": _plot_albedo_error, "colorshift": _plot_colorshift, "brdf_slices": _plot_brdf_slices}


def plot_all(
    table_dir: str | os.PathLike[str], image_dir: str | os.PathLike[str], prefix: str = "simulation"
) -> list[Path]:
    """Figures from the shipped tables; returns the written paths."""
    plt = pyplot()
    t = _tables(table_dir)
    paths = []
    plt.rcParams.update({"font.size": 8})
    for name in FIGURES:
        fig = _PLOTS[name](plt, t)
        p = Path(image_dir) / f"{prefix}_{name}.png"
        fig.savefig(p, dpi=90)
        plt.close(fig)
        paths.append(p)
    return paths


def _live_row(albedo_cols):
    """The shipped table's row the live check reproduces (V-cavity, sigma 0.4, rho 0.8, mu ~ 0.5)."""
    sel = (
        (albedo_cols["geometry"] == "vcavity")
        & np.isclose(albedo_cols["roughness"], 0.4)
        & (albedo_cols["kind"] == "directional")
        & np.isclose(albedo_cols["rho"], 0.8)
    )
    k = np.flatnonzero(sel)
    return k[np.argmin(np.abs(albedo_cols["mu"][k] - 0.5))]


def _live_name(col, mu):
    """The title of the live check of column ``col``."""
    return f"live V-cavity simulation reproduces the shipped {col} (sigma 0.4, mu {mu:.3f}, rho 0.8)"


_FURNACE = "simulator white furnace: V-cavity albedo at rho = 1"


def _live_check(albedo_cols, quick):
    """A fresh simulation (another seed) against the shipped table."""
    from ...simulation import simulate_albedo

    paths = 20_000 if quick else 100_000
    k = _live_row(albedo_cols)
    mu = float(albedo_cols["mu"][k])
    start = time.monotonic()
    est = simulate_albedo("vcavity", 0.4, [mu], rho=[0.8, 1.0], paths=paths, seed=7)
    seconds = time.monotonic() - start
    out = {}
    for col, idx in (("E", None), ("E1", 0), ("E2", 1)):
        v = est.albedo[0, 0] if idx is None else est.albedo_by_order[0, idx, 0]
        s = est.stderr[0, 0] if idx is None else est.stderr_by_order[0, idx, 0]
        out[col] = (v, s, albedo_cols[col][k], albedo_cols[col + "_se"][k])
    return mu, paths, seconds, out, est


def _live_checks(ctx: Context, alb: dict) -> list[Result]:
    """The live simulation against the shipped table, and the simulator's white furnace."""
    from ...simulation import grading as gr

    ctx.progress("simulation: live check")
    mu, paths, seconds, live, est = _live_check(alb, ctx.quick)
    checks = []
    for col, (v, s, ref, ref_se) in live.items():
        z = abs(v - ref) / np.hypot(s, ref_se)
        detail = (
            f"live {v:.5f} +- {s:.1e} ({paths} paths, seed 7, {seconds:.1f} s) vs shipped {ref:.5f} +- {ref_se:.1e}"
        )
        checks.append(within_errors(CHECKS, _live_name(col, mu), z, 4.5, gr.TABLES["albedo"], detail))
    checks.append(
        CHECKS.check(
            _FURNACE,
            measured=float(abs(est.albedo[0, 1] - 1.0)),
            threshold=1e-12,
            reference="every path leaves an open cavity",
        )
    )
    return checks


def _eon_checks(rows: list[dict]) -> list[Result]:
    """EON against the microsurfaces where its roughness range reaches them (fitted r < 1)."""
    from ...simulation import grading as gr

    checks = []
    for geom in GEOMETRY_LABEL:
        rr = [r for r in rows if r["model"] == "eon" and r["geometry"] == geom and r["model_roughness"] < 0.99]
        if rr:
            worst = max(rr, key=lambda r: r["albedo_rms"])
            checks.append(
                CHECKS.check(
                    f"EON albedo vs {geom} within EON's roughness range (fitted r < 1)",
                    measured=float(worst["albedo_rms"]),
                    threshold=0.02,
                    reference=gr.TABLES["grading"],
                    detail=f"worst at roughness {worst['roughness']:g} (r = {worst['model_roughness']:.3f}); "
                    "threshold: the documented agreement, not a physical law",
                )
            )
    return checks


def _error_table(geom: str, rough: list[float], label: str, rows: list[dict], key: str) -> Table:
    """One geometry's error ``key`` at the fitted roughness, roughness ``rough`` x model."""
    from ...simulation import grading as gr

    table_rows = []
    for sv in rough:
        cells: list[Any] = [float(sv)]
        for model in gr.GRADED_MODELS:
            r = next(r for r in rows if r["geometry"] == geom and r["model"] == model and r["roughness"] == sv)
            cells.append(f"{r[key]:.4f} ({r['model_roughness']:.3f})")
        table_rows.append(cells)
    return Table(
        caption=f"{GEOMETRY_LABEL[geom]}: {label} (fitted roughness in brackets)",
        columns=[GEOMETRY_LABEL[geom].split(", ")[-1]] + list(gr.GRADED_MODELS),
        rows=table_rows,
    )


def _error_tables(rows: list[dict], brows: list[dict]) -> list[Table]:
    """Per geometry: albedo RMS at the albedo fit, BRDF error at the BRDF fit."""
    from ...simulation import grading as gr

    albedo = "RMS error of the directional albedo (rho = 0.2, 0.5, 0.8; 10 mu) at the roughness fitted to it"
    brdf = (
        f"RMS relative error of the in-plane BRDF slices (rho = {gr.BRDF_RHO:g}, theta_i = "
        "30/60/80 deg, 18 theta_o) at the roughness fitted to them"
    )
    tables = []
    for geom in GEOMETRY_LABEL:
        rough = sorted({r["roughness"] for r in rows if r["geometry"] == geom})
        for label, rr, key in ((albedo, rows, "albedo_rms"), (brdf, brows, "brdf_rel_rms")):
            tables.append(_error_table(geom, rough, label, rr, key))
    return tables


def _fit_table(rows: list[dict], brows: list[dict]) -> Table:
    """The sigma <-> r correspondence: fitted r per simulated surface and a power law through it."""
    fit_rows = []
    for geom in GEOMETRY_LABEL:
        name = GEOMETRY_LABEL[geom].split(", ")[-1]
        for model in ("eon", "fon"):
            for fit, rr_all in (("albedo", rows), ("brdf", brows)):
                rr = [r for r in rr_all if r["geometry"] == geom and r["model"] == model]
                law = fit_power_law([r["roughness"] for r in rr], [r["model_roughness"] for r in rr])
                sat = [r["roughness"] for r in rr if r["model_roughness"] >= 0.99]
                fit_rows.append(
                    [
                        geom,
                        model,
                        fit,
                        ", ".join(f"{r['roughness']:g}->{r['model_roughness']:.3f}" for r in rr),
                        "" if law is None else f"r = ({name}/{law[0]:.3f})^{law[1]:.2f}",
                        f">= {min(sat):g}" if sat else "none",
                    ]
                )
    return Table(
        caption="Best-fitting r for each simulated surface (fitted to the albedo or to the BRDF "
        "slices) and a power law through the unsaturated points",
        columns=["geometry", "model", "fit", "simulated -> fitted r", "power-law fit", "saturates (r = 1) from"],
        rows=fit_rows,
    )


#: The colour-shift table's columns: (header, column of the shipped table, decimals; None: as is).
_COLORSHIFT_COLUMNS = (
    ("geometry", "geometry", None),
    ("roughness", "roughness", None),
    ("EON r", "r_eon", 3),
    ("rho", "rho", None),
    ("ms sim", "ms_sim", 4),
    ("ms EON", "ms_eon", 4),
    ("<E> sim", "E_sim", 4),
    ("<E> EON", "E_eon", 4),
    ("ms fraction sim", "ms_fraction_sim", 4),
    ("ms fraction EON", "ms_fraction_eon", 4),
)


def _colorshift_table(cs: dict) -> Table:
    """EON's multiple-scattering colour against the simulation at rho = 0.2, 0.5, 0.8."""

    def cell(col: str, digits: int | None, i: int) -> Any:
        if col == "geometry":
            return str(cs[col][i])
        return float(cs[col][i]) if digits is None else round(float(cs[col][i]), digits)

    cs_rows = [
        [cell(col, digits, i) for _, col, digits in _COLORSHIFT_COLUMNS]
        for i in range(len(cs["rho"]))
        if np.isclose(cs["rho"][i], [0.2, 0.5, 0.8]).any()
    ]
    return Table(
        caption="EON's multiple-scattering colour against the simulation (average albedo): ms = E_>=2(rho)/E_>=2(1) "
        "(EON: rho_ms, Eq. 18); E = <E>(rho); ms fraction = share of multiple scattering at rho = 1",
        columns=[header for header, _, _ in _COLORSHIFT_COLUMNS],
        rows=cs_rows,
    )


#: The captions of :data:`FIGURES`.
_CAPTIONS = {
    "albedo_error": "RMS albedo error (top) and best-fitting model roughness (bottom) against the simulated roughness",
    "colorshift": "Colour of multiply scattered light (top) and albedo nonlinearity <E>/rho (bottom): "
    "simulation (solid) vs EON at its fitted r (dashed)",
    "brdf_slices": "In-plane BRDF slices: simulation (points, +- 1 standard error) vs the models at "
    "the roughness fitted to the slices",
}


def _figures(ctx: Context) -> list[Figure]:
    """The shipped figures, copied (re-plotted from the shipped tables only if one is missing)."""
    from ...simulation.grading import DATA

    ctx.progress("simulation: figures")
    # the figures are drawn from the shipped tables by the same tool that writes them
    # (plot_all); copying them keeps the section fast, re-plotting only if one is missing
    shipped = [DATA / f"{KEY}_{name}.png" for name in FIGURES]
    if all(p.is_file() for p in shipped):
        figures = [copy_figure(p, ctx) for p in shipped]
    else:
        figures = plot_all(DATA, ctx.image_dir)
    return [Figure(file=p.name, caption=_CAPTIONS[p.stem.replace("simulation_", "")]) for p in figures]


def build(ctx: Context) -> SectionResult:
    """The live checks, EON against the microsurfaces, the grading tables and figures."""
    res = SectionResult(key=KEY, title=TITLE)
    t = _tables()
    alb_header, alb = t["albedo"]
    rows = _grading_rows(t["grading"][1])
    if ctx.quick:  # the live simulation compiles the simulator's kernels: the full report runs it
        res.notes.append(
            "Quick run: the live simulation (a fresh V-cavity estimate against the shipped table, and the "
            "simulator's white furnace) was not run; `openpbr-diffuse report` runs it. The tables and figures "
            "below are the shipped simulation results."
        )
    else:
        res.checks += _live_checks(ctx, alb)
    res.checks += _eon_checks(rows)
    brows = _grading_rows(t["grading"][1], "brdf")
    res.tables += _error_tables(rows, brows)
    res.tables.append(_fit_table(rows, brows))
    res.tables.append(_colorshift_table(t["colorshift"][1]))
    res.figures += _figures(ctx)
    res.notes.append(
        "Simulated by openpbr_diffuse.simulation (Monte Carlo with every interreflection; V-cavities after Oren & "
        "Nayar 1994 with their Gaussian slope-area distribution, Smith random walk after Heitz et al. 2016). "
        f"Tables regenerate with `python tools/make_simulation_tables.py`; provenance: {alb_header.get('resolution', '')}"
    )
    return res


__all__ = ["TITLE", "build", "plot_all", "fit_power_law"]
