"""Grading the lobe models against the simulated microsurfaces (the shipped tables).

Tables (``openpbr_diffuse/data/``, written by ``tools/make_simulation_tables.py``):

- ``simulation_albedo.csv``: directional albedo E(mu; rho) and average albedo <E>(rho) of
  each simulated surface, total and by bounce order, with standard errors;
- ``simulation_brdf.csv``: in-plane BRDF slices f(theta_i, theta_o; rho) with standard errors;
- ``simulation_grading.csv``: per model, geometry and simulated roughness, the fitted model
  roughness and the errors of the model's albedo, single-scattering albedo and BRDF slices;
- ``simulation_colorshift.csv``: EON's multiple-scattering colour against the simulation.

The fits: a model's roughness (sigma or r) is chosen per simulated surface either to minimise
the RMS of E_model(mu; rho) - E_sim(mu; rho) over the table's mu and ``FIT_RHO`` ("albedo";
at rho = 1 every energy-conserving model and both surfaces give 1, so the fit uses coloured
albedos), or the RMS relative error of the in-plane BRDF slices at ``BRDF_RHO`` ("brdf").
"""

from __future__ import annotations

import csv
import os
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._csv import read_headed_csv

DATA = Path(__file__).resolve().parents[1] / "data"
TABLES = {
    "albedo": "simulation_albedo.csv",
    "brdf": "simulation_brdf.csv",
    "grading": "simulation_grading.csv",
    "colorshift": "simulation_colorshift.csv",
}
#: the graded models (roughness: sigma for the first three, r for the others)
GRADED_MODELS = ("full_on", "qon", "qon_fujii", "fon", "eon", "eon_approx")
#: albedos used to fit the model roughness
FIT_RHO = (0.2, 0.5, 0.8)
#: albedo of the BRDF-slice comparison
BRDF_RHO = 0.8


def write_csv(
    path: str | os.PathLike[str], header: Mapping[str, object], columns: Sequence[str], rows: Iterable[Sequence[object]]
) -> Path:
    """CSV with a ``# key: value`` provenance header (as the reference albedo tables)."""
    path = Path(path)
    with path.open("w", newline="") as fh:
        for key, value in header.items():
            fh.write(f"# {key}: {value}\n")
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(columns)
        for row in rows:
            w.writerow([f"{v:.10g}" if isinstance(v, float) else v for v in row])
    return path


def read_csv(path: str | os.PathLike[str]) -> tuple[dict[str, str], dict[str, NDArray[Any]]]:
    """(header dict, {column: ndarray}) of a table written by ``write_csv``."""
    header, names, rows = read_headed_csv(path)
    cols = {}
    for k, name in enumerate(names):
        vals = [r[k] for r in rows]
        try:
            cols[name] = np.array([float(v) for v in vals])
        except ValueError:
            cols[name] = np.array(vals)
    return header, cols


def load(name: str, directory: str | os.PathLike[str] | None = None) -> tuple[dict[str, str], dict[str, NDArray[Any]]]:
    """One shipped table by key (``"albedo"``, ``"brdf"``, ``"grading"``, ``"colorshift"``)."""
    if name not in TABLES:
        raise ValueError(f"table must be one of {', '.join(TABLES)}, got {name!r}")
    return read_csv(Path(directory or DATA) / TABLES[name])


def _model_roughness_range(model):
    from ..models.registry import model_info

    info = model_info(model)
    return 0.0, float(info.roughness_max)


def model_albedo(model: str, mu: ArrayLike, roughness: float, rho: ArrayLike) -> NDArray[np.float64]:
    """E_model(mu; rho) for each mu (rows) and rho (columns)."""
    from ..models import directional_albedo

    return directional_albedo(model, np.asarray(mu, float), float(roughness), np.asarray(rho, float))


def fit_roughness(model: str, mu: ArrayLike, rho: ArrayLike, E_sim: NDArray[np.floating[Any]]) -> tuple[float, float]:
    """Model roughness minimising the RMS albedo error; returns (roughness, rms).

    A bounded scalar search (scipy) after a coarse scan (the objective can have two basins
    for the sigma models, whose albedo is not monotonic in sigma near grazing).
    """
    from scipy.optimize import minimize_scalar

    lo, hi = _model_roughness_range(model)
    rms = lambda s: float(np.sqrt(np.mean((model_albedo(model, mu, s, rho) - E_sim) ** 2)))
    grid = np.linspace(lo, hi, 41)
    vals = [rms(s) for s in grid]
    k = int(np.argmin(vals))
    a, b = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
    res = minimize_scalar(rms, bounds=(a, b), method="bounded", options={"xatol": 1e-5})
    return (float(res.x), float(res.fun)) if res.fun <= vals[k] else (float(grid[k]), float(vals[k]))


def _select(cols, **eq):
    m = np.ones(len(next(iter(cols.values()))), bool)
    for key, value in eq.items():
        col = cols[key]
        m &= (col == value) if col.dtype.kind in "US" else np.isclose(col, value)
    return m


def surfaces(albedo_cols: Mapping[str, NDArray[Any]]) -> list[tuple[str, float]]:
    """The simulated (geometry, roughness) pairs, in table order."""
    seen = []
    for g, r in zip(albedo_cols["geometry"], albedo_cols["roughness"]):
        if (g, float(r)) not in seen:
            seen.append((g, float(r)))
    return seen


def sim_albedo(
    albedo_cols: Mapping[str, NDArray[Any]],
    geometry: str,
    roughness: float,
    rho: Sequence[float] | NDArray[np.floating[Any]],
    column: str = "E",
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """(mu, E (n_mu, n_rho), stderr) of a simulated surface's directional albedo."""
    sel = _select(albedo_cols, geometry=geometry, roughness=roughness, kind="directional")
    mu = np.unique(albedo_cols["mu"][sel])
    E = np.empty((mu.size, len(rho)))
    se = np.empty_like(E)
    for j, r in enumerate(rho):
        for i, m in enumerate(mu):
            k = np.flatnonzero(sel & np.isclose(albedo_cols["mu"], m) & np.isclose(albedo_cols["rho"], r))[0]
            E[i, j] = albedo_cols[column][k]
            se[i, j] = albedo_cols[column + "_se"][k]
    return mu, E, se


def sim_average(
    albedo_cols: Mapping[str, NDArray[Any]], geometry: str, roughness: float, column: str = "E"
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """(rho, <E>(rho), stderr) of a simulated surface."""
    sel = _select(albedo_cols, geometry=geometry, roughness=roughness, kind="average")
    order = np.argsort(albedo_cols["rho"][sel])
    idx = np.flatnonzero(sel)[order]
    return albedo_cols["rho"][idx], albedo_cols[column][idx], albedo_cols[column + "_se"][idx]


def slice_directions(theta_i: ArrayLike, theta_o: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """In-plane directions: wi at azimuth 0, wo at signed angle theta_o (negative: the
    light's side, i.e. back-scattering; positive: forward)."""
    theta_i = np.asarray(theta_i, float)
    theta_o = np.asarray(theta_o, float)
    wi = np.stack([np.sin(theta_i), np.zeros_like(theta_i), np.cos(theta_i)], axis=-1)
    wo = np.stack([-np.sin(theta_o), np.zeros_like(theta_o), np.cos(np.abs(theta_o))], axis=-1)
    return wi, wo


def _slices(brdf_cols, geometry, roughness):
    sel = _select(brdf_cols, geometry=geometry, roughness=roughness)
    sel &= np.isclose(brdf_cols["rho"], BRDF_RHO)
    wi, wo = slice_directions(np.radians(brdf_cols["theta_i"][sel]), np.radians(brdf_cols["theta_o"][sel]))
    return wi, wo, brdf_cols["f"][sel]


def fit_roughness_brdf(
    model: str, wi: ArrayLike, wo: ArrayLike, f_sim: NDArray[np.floating[Any]]
) -> tuple[float, float]:
    """Model roughness minimising the RMS relative error of the BRDF slices at ``BRDF_RHO``."""
    from scipy.optimize import minimize_scalar

    from ..models import evaluate

    lo, hi = _model_roughness_range(model)
    rel = lambda s: float(np.sqrt(np.mean(((evaluate(model, wi, wo, s, [BRDF_RHO])[:, 0] - f_sim) / f_sim) ** 2)))
    grid = np.linspace(lo, hi, 41)
    vals = [rel(s) for s in grid]
    k = int(np.argmin(vals))
    res = minimize_scalar(
        rel, bounds=(grid[max(k - 1, 0)], grid[min(k + 1, 40)]), method="bounded", options={"xatol": 1e-5}
    )
    return (float(res.x), float(res.fun)) if res.fun <= vals[k] else (float(grid[k]), float(vals[k]))


#: how the model roughness of a grading row is chosen
FITS = ("albedo", "brdf", "same sigma")


def grade_surface(
    model: str,
    albedo_cols: Mapping[str, NDArray[Any]],
    brdf_cols: Mapping[str, NDArray[Any]],
    geometry: str,
    roughness: float,
    fit: str = "albedo",
) -> dict[str, Any]:
    """Grade one model against one simulated surface; returns a dict (one grading row).

    ``fit``: "albedo" (roughness fitted to the coloured directional albedos), "brdf" (fitted
    to the in-plane BRDF slices, relative error) or "same sigma" (the V-cavity's own sigma,
    for the sigma models).
    """
    from ..models import evaluate
    from ..models.registry import model_info

    if fit not in FITS:
        raise ValueError(f"fit must be one of {FITS}, got {fit!r}")
    rho = np.array(FIT_RHO)
    mu, E, se = sim_albedo(albedo_cols, geometry, roughness, rho)
    wi, wo, f_sim = _slices(brdf_cols, geometry, roughness)
    info = model_info(model)
    if fit == "albedo":
        s, _ = fit_roughness(model, mu, rho, E)
    elif fit == "brdf":
        s, _ = fit_roughness_brdf(model, wi, wo, f_sim)
    else:
        s = roughness
    err = model_albedo(model, mu, s, rho) - E
    # single scattering: the model's rho-linear part (its albedo as rho -> 0, over rho)
    # against the simulated order-1 albedo (rho = 1, i.e. the escape probability after 1 bounce)
    _, E1, _ = sim_albedo(albedo_cols, geometry, roughness, [1.0], column="E1")
    m1 = (model_albedo(model, mu, s, [1e-9]) / 1e-9)[:, 0]
    ss_err = m1 - E1[:, 0]
    f_mod = evaluate(model, wi, wo, s, [BRDF_RHO])[:, 0]
    rel = (f_mod - f_sim) / f_sim
    return {
        "model": model,
        "geometry": geometry,
        "roughness": roughness,
        "fit": fit,
        "roughness_name": info.roughness_name,
        "model_roughness": s,
        "albedo_rms": float(np.sqrt(np.mean(err**2))),
        "albedo_max": float(np.max(np.abs(err))),
        "albedo_stderr": float(np.sqrt(np.mean(se**2))),
        "single_rms": float(np.sqrt(np.mean(ss_err**2))),
        "single_max": float(np.max(np.abs(ss_err))),
        "brdf_rel_rms": float(np.sqrt(np.mean(rel**2))),
        "brdf_rel_max": float(np.max(np.abs(rel))),
        "n_slices": int(len(f_sim)),
    }


def grade_all(
    albedo_cols: Mapping[str, NDArray[Any]],
    brdf_cols: Mapping[str, NDArray[Any]],
    models: Sequence[str] = GRADED_MODELS,
    progress: Callable[[str], object] = lambda msg: None,
) -> list[dict[str, Any]]:
    """Grading rows: every model against every simulated surface, roughness fitted to the albedo
    and to the BRDF slices, and the sigma models also at the V-cavity's own sigma."""
    rows = []
    for geometry, roughness in surfaces(albedo_cols):
        progress(f"grading {geometry} {roughness:g}")
        for model in models:
            for fit in FITS:
                if fit != "same sigma" or (geometry == "vcavity" and model in ("full_on", "qon", "qon_fujii")):
                    rows.append(grade_surface(model, albedo_cols, brdf_cols, geometry, roughness, fit=fit))
    return rows


def eon_colorshift(
    albedo_cols: Mapping[str, NDArray[Any]], geometry: str, roughness: float, r: float, model: str = "eon"
) -> dict[str, Any]:
    """EON's multiple-scattering colour against the simulation, as functions of rho.

    Returns a dict of arrays over the table's rho:

    - ``ms_sim``: simulated multi-bounce average albedo <E_>=2>(rho) / <E_>=2>(1), the colour of
      the light that scattered more than once (1 at rho = 1);
    - ``ms_eon``: EON's rho_ms(rho) (Eq. 18; rho_ms(1) = 1), the same quantity for EON;
    - ``ratio_sim`` / ``ratio_eon``: the albedo's nonlinearity <E>(rho) / rho (1 for Lambert;
      its fall towards small rho is the colour shift: dark channels lose relatively more).
    """
    from ..models import average_albedo
    from ..models.eon import rho_ms
    from ..models.fon import E_F_avg

    rho, E, E_se = sim_average(albedo_cols, geometry, roughness)
    _, E1, _ = sim_average(albedo_cols, geometry, roughness, column="E1")
    ms = E - E1
    ms1 = ms[np.argmin(np.abs(rho - 1.0))]
    avg = float(E_F_avg(r))
    E_eon = np.asarray(average_albedo(model, r, rho)).reshape(-1)
    return {
        "rho": rho,
        "ms_sim": ms / ms1,
        "ms_eon": np.array([rho_ms(x, avg) for x in rho]),
        "ratio_sim": E / rho,
        "ratio_eon": E_eon / rho,
        "E_sim": E,
        "E_se": E_se,
        "E_eon": E_eon,
        "ms_fraction_sim": ms1,
        "ms_fraction_eon": 1.0 - avg,
    }


__all__ = [
    "GRADED_MODELS",
    "FIT_RHO",
    "BRDF_RHO",
    "TABLES",
    "load",
    "read_csv",
    "write_csv",
    "fit_roughness",
    "fit_roughness_brdf",
    "FITS",
    "grade_surface",
    "grade_all",
    "eon_colorshift",
    "sim_albedo",
    "sim_average",
    "slice_directions",
    "surfaces",
]
