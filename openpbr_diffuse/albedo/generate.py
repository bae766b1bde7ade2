"""Generation of the reference albedo tables by quadrature of ``evaluate``.

The shipped tables (``openpbr_diffuse/data/albedo_<model>.csv``, read by
``openpbr_diffuse.models.tables``) hold e_g, e_h and the average albedo terms <e_g>, <e_h>
of E = rho e_g + m(rho) e_h, computed by ``quadrature.hemisphere_albedo`` of the model's
``evaluate`` (never a closed-form albedo): the quadrature is run with rho = (1, 1/2) as two
channels and the 2x2 system E(1) = e_g + m(1) e_h, E(1/2) = e_g/2 + m(1/2) e_h is solved.
This is the only table code that needs the models' ``evaluate``; ``tools/make_tables.py``
drives it.  Grid and interpolation: ``openpbr_diffuse.models.tables``.
"""

import functools
import math
import os
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._version import __version__
from ..models.api import evaluate
from ..models.registry import INFO, MIX_LINEAR, MIX_RHO2, MIX_RHO_MS, model_info
from ..models.tables import (
    DECIMALS,
    HALF_PI,
    N_ROUGH,
    N_THETA,
    REGENERATE,
    ROUNDING,
    SIGMA_SCALE,
    data_dir,
    interpolate_grid,
    interpolate_line,
    is_sigma_model,
    load_table,
    mix_weight,
    n_columns,
    roughness_of_u,
    t_of_mu,
    theta_of_t,
)
from .quadrature import DEFAULT_ORDER, GRAZING_DELTA, hemisphere_albedo, hemisphere_average_albedo

#: Quadrature orders used for the shipped tables (value at 2n, error estimate n vs 2n).
ORDER = DEFAULT_ORDER
#: rho of the two quadrature channels from which e_g and e_h are solved.
RHO_PAIR = (1.0, 0.5)
#: Roughness columns per batched quadrature call (memory: ~ MAX_POINTS * block * 2 doubles).
_BLOCK = 7
_MAX_POINTS = 1 << 16


def _map_text(name):
    if name == "lambert":
        return "a single column (Lambert ignores roughness)"
    if is_sigma_model(name):
        return (
            f"sigma_k = {SIGMA_SCALE} sinh(u_k asinh(({HALF_PI:.10f}) / {SIGMA_SCALE})), "
            f"u_k = k/{N_ROUGH}, k = 0..{N_ROUGH}"
        )
    return f"r_k = u_k = k/{N_ROUGH}, k = 0..{N_ROUGH}"


def _solve_terms(name, E, dE, roughness):
    """(e_g, e_h, err) from E at rho = RHO_PAIR (last axis) and its error estimate.

    err bounds the error of rho e_g + m(rho) e_h for every rho in [0, 1] (rho, m <= 1).
    """
    if INFO[name].mix == MIX_LINEAR:
        return E[..., 0], np.zeros_like(E[..., 0]), dE[..., 0]
    r1, r2 = RHO_PAIR
    m1 = mix_weight(name, r1, roughness)
    m2 = mix_weight(name, r2, roughness)
    det = m2 * r1 - m1 * r2
    e_h = (r1 * E[..., 1] - r2 * E[..., 0]) / det
    e_g = (E[..., 0] - m1 * e_h) / r1
    err_h = (r1 * dE[..., 1] + r2 * dE[..., 0]) / np.abs(det)
    err_g = (dE[..., 0] + m1 * err_h) / r1
    return e_g, e_h, err_g + err_h


# --------------------------------------------------------------------------- quadrature


@functools.cache
def model_kinks(name: str) -> tuple[float, ...]:
    """theta_i of kinks of a model's integrand besides theta_i = theta_o and s = 0.

    "eon_approx": the Eq. 14 fit exceeds 1 for mu < 1.3887e-3 (its m = 1 value
    g1 + g2 + g3 + g4 = 0.28825 exceeds c1 = 0.28779), where Listing 1's
    max(eps, 1 - E_F(mu_i)) clamps; the crossing E_F = 1 does not depend on r (the eps
    offset moves it by < 2e-5 in mu for r >= 1/48, negligible).  Found by bisection on
    the model's own ``E_F_approx``.
    """
    if name != "eon_approx":
        return ()
    from ..models.fon import E_F_approx  # the compiled function, called from Python

    lo, hi = 0.0, 0.5
    if not E_F_approx(lo, 1.0) > 1.0:
        return ()
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if E_F_approx(mid, 1.0) > 1.0 else (lo, mid)
    return (float(np.arccos(0.5 * (lo + hi))),)


def grazing_delta(name: str) -> float:
    """Smallest mu_o of the grazing-limit extrapolation (``hemisphere_albedo``'s delta).

    "eon": f_ms has Listing 1's max(eps, 1 - E_F(mu_o)) with 1 - E_F(mu_o) ~ 0.3 r mu_o near
    grazing, so below mu_o ~ eps / (0.3 r) (< 1.6e-5 for r >= 1/48) the guard, not the
    smooth lobe, sets the value.  The ladder (delta .. 16 delta) starts above that, so the
    mu = 0 row holds the limit of the smooth part (E_EON(0) = rho by Eq. 20 with
    E_F(0) = 1); the guard itself changes E by < 1e-7.  ("eon_approx" is constant below
    mu = 1.39e-3, see ``model_kinks``, so the default ladder lies inside that region.)
    """
    return 1e-4 if name == "eon" else GRAZING_DELTA


def row_kinks(name: str) -> tuple[float, ...]:
    """Row coordinates t of kinks of E(mu_o): by reciprocity those of ``model_kinks``."""
    return tuple(float(t_of_mu(math.cos(k))) for k in model_kinks(name))


def _brdf(name, roughness):
    """f(wi, wo) at rho = RHO_PAIR for a block of roughness values: shape (..., R, 2)."""
    r = np.asarray(roughness, dtype=np.float64)
    rho = np.asarray(RHO_PAIR)

    def f(wi, wo):
        return evaluate(name, wi[..., None, :], wo[..., None, :], r, rho)

    return f


def quadrature_terms(
    model: str, mu: ArrayLike, roughness: ArrayLike, n: int = ORDER
) -> tuple[NDArray[np.float64], ...]:
    """e_g, e_h and error bound by quadrature at every (mu, roughness) pair of a grid.

    Parameters
    ----------
    model : str
    mu : array_like, shape (M,)
    roughness : array_like, shape (R,)

    Returns
    -------
    e_g, e_h, err : ndarray, shape (M, R)
    """
    name = model_info(model).name
    mu = np.atleast_1d(np.asarray(mu, dtype=np.float64))
    roughness = np.atleast_1d(np.asarray(roughness, dtype=np.float64))
    out = [np.empty((mu.size, roughness.size)) for _ in range(3)]
    for k in range(0, roughness.size, _BLOCK):
        r = roughness[k : k + _BLOCK]
        E, dE = hemisphere_albedo(
            _brdf(name, r),
            mu,
            n,
            error=True,
            kinks=model_kinks(name),
            delta=grazing_delta(name),
            max_points=_MAX_POINTS,
        )
        for o, v in zip(out, _solve_terms(name, E, dE, r)):
            o[:, k : k + _BLOCK] = v
    return tuple(out)


def quadrature_average_terms(model: str, roughness: ArrayLike, n: int = ORDER) -> tuple[NDArray[np.float64], ...]:
    """<e_g>, <e_h> and error bound of the average albedo by quadrature, shape (R,)."""
    name = model_info(model).name
    roughness = np.atleast_1d(np.asarray(roughness, dtype=np.float64))
    out = [np.empty(roughness.size) for _ in range(3)]
    for k in range(0, roughness.size, _BLOCK):
        r = roughness[k : k + _BLOCK]
        A, dA = hemisphere_average_albedo(
            _brdf(name, r), n, n_mu=n, error=True, kinks=model_kinks(name), max_points=_MAX_POINTS
        )
        for o, v in zip(out, _solve_terms(name, A, dA, r)):
            o[k : k + _BLOCK] = v
    return tuple(out)


def compute_table(
    model: str,
    rows: ArrayLike | None = None,
    columns: ArrayLike | None = None,
    *,
    n: int = ORDER,
    average: bool = True,
    progress: Callable[[int, int], object] | None = None,
) -> dict[str, Any]:
    """Compute (part of) a reference table by quadrature.

    Parameters
    ----------
    model : str
    rows, columns : sequence of int, optional
        Row indices j (of N_THETA + 1) and column indices k; default all.
    n : int
        Gauss-Legendre order per panel (value at 2n, error estimate n vs 2n).
    average : bool
        Also compute the average-albedo terms of the selected columns.
    progress : callable, optional
        ``progress(done, total)`` after each block of columns.

    Returns
    -------
    dict with arrays t, theta, mu (rows), u, roughness (columns), e_g, e_h, err (rows x
    columns) and, with ``average``, avg_g, avg_h, avg_err (columns).
    """
    name = model_info(model).name
    nr = n_columns(name)
    j = np.arange(N_THETA + 1) if rows is None else np.asarray(rows, dtype=np.int64)
    k_cols = np.arange(nr + 1) if columns is None else np.asarray(columns, dtype=np.int64)
    t = j / N_THETA
    theta = theta_of_t(t)
    mu = np.cos(theta)
    mu[j == N_THETA] = 0.0  # exactly grazing (cos(pi/2) = 6e-17)
    u = k_cols / nr if nr else np.zeros(k_cols.size)
    roughness = roughness_of_u(name, u)
    res: dict[str, Any] = {
        "order": n,
        "t": t,
        "theta": theta,
        "mu": mu,
        "u": u,
        "roughness": roughness,
        "e_g": np.empty((j.size, k_cols.size)),
        "e_h": np.empty((j.size, k_cols.size)),
        "err": np.empty((j.size, k_cols.size)),
    }
    if average:
        for key in ("avg_g", "avg_h", "avg_err"):
            res[key] = np.empty(k_cols.size)
    total = k_cols.size
    for k in range(0, total, _BLOCK):
        sl = slice(k, k + _BLOCK)
        res["e_g"][:, sl], res["e_h"][:, sl], res["err"][:, sl] = quadrature_terms(name, mu, roughness[sl], n)
        if average:
            res["avg_g"][sl], res["avg_h"][sl], res["avg_err"][sl] = quadrature_average_terms(name, roughness[sl], n)
        if progress is not None:
            progress(min(k + _BLOCK, total), total)
    return res


def _fmt(v):
    s = f"{v:.{DECIMALS}f}"
    return s[1:] if s.startswith("-") and not float(s) else s  # no "-0.0000000000"


def _fmt_err(v):
    return f"{v:.1e}"


def format_table(model: str, res: dict[str, Any], meta: dict[str, str]) -> str:
    """CSV text of a computed table (``compute_table`` result) with provenance ``meta``."""
    name = model_info(model).name
    lines = [f"# {k}: {v}" for k, v in meta.items()]
    lines.append(",".join(["quantity", "j", "theta", "mu"] + [_fmt(r) for r in res["roughness"]]))
    quantities = [("e_g", _fmt), ("e_h", _fmt), ("err", _fmt_err)]
    if INFO[name].mix == MIX_LINEAR:
        quantities = [("e_g", _fmt), ("err", _fmt_err)]
    for key, fmt in quantities:
        for j in range(len(res["t"])):
            lines.append(
                ",".join(
                    [key, str(round(res["t"][j] * N_THETA)), _fmt(res["theta"][j]), _fmt(res["mu"][j])]
                    + [fmt(v) for v in res[key][j]]
                )
            )
    for key, fmt in (("avg_g", _fmt), ("avg_h", _fmt), ("avg_err", _fmt_err)):
        if key == "avg_h" and INFO[name].mix == MIX_LINEAR:
            continue
        lines.append(",".join([key, "", "", ""] + [fmt(v) for v in res[key]]))
    return "\n".join(lines) + "\n"


def provenance(model: str, res: dict[str, Any], interpolation_error: float) -> dict[str, str]:
    """The header of a table file (ordered dict of ``key: value``)."""
    name = model_info(model).name
    info = INFO[name]
    kinks = model_kinks(name)
    delta = grazing_delta(name)
    mix = {
        MIX_LINEAR: "0 (linear in rho; e_h omitted)",
        MIX_RHO2: "rho^2",
        MIX_RHO_MS: "rho_ms(rho, <E_F>(r)) = rho^2 <E_F> / (1 - rho (1 - <E_F>)) (EON Eq. 18)",
    }
    meta = {
        "title": f"openpbr-diffuse reference albedo table, model {name!r} ({info.description})",
        "quantity": (
            f"directional albedo E(mu, {info.roughness_name}; rho) = rho e_g + m(rho) e_h "
            f"and average albedo <E> = rho avg_g + m(rho) avg_h, m(rho) = {mix[info.mix]}"
        ),
        "rows": (
            f"j = 0..{N_THETA}: theta_j = (pi/2) (1 - (1 - j/{N_THETA})^3), mu_j = cos(theta_j) "
            "(mu = 0 row: the limit mu -> 0)"
        ),
        "columns": _map_text(name),
        "method": (
            "numerical integration of openpbr_diffuse.evaluate (no closed-form albedo): "
            "Gauss-Legendre x Gauss-Legendre in (theta_i, phi_i), panels split at "
            "theta_i = theta_o (graded towards it) and phi = pi/2, phi in [0, pi] by symmetry"
            + (f", extra panel edge at theta_i = {kinks[0]:.10f} (eps clamp of the Eq. 14 fit)" if kinks else "")
            + f"; order {2 * res['order']} per panel (error estimate: order {res['order']}); rho = {RHO_PAIR} as two channels, "
            "2x2 solve for e_g, e_h; mu = 0 by fitting E0 + a mu ln mu + b mu + c mu^2 at "
            f"mu = {delta:g} * (1, 2, 4, 8) (error estimate: * (2, 4, 8, 16)); averages by "
            "Gauss-Legendre in theta_o on panels graded towards the horizon"
        ),
        "error": (
            f"err / avg_err: estimated error (|Q_n - Q_2n| + 64 ulp; at mu = 0 plus the fit's) "
            f"of rho e_g + m(rho) e_h for any rho in [0, 1]; "
            f"max {max(res['err'].max(), res['avg_err'].max()):.1e}; values rounded to "
            f"{DECIMALS} decimals (+-{ROUNDING:.0e})"
        ),
        "interpolation": (
            "tensor-product 4-point Lagrange cubic in (t, u), t = 1 - (1 - acos(mu)/(pi/2))^(1/3), "
            "u the column coordinate; stencils clipped at the edges and never across a row kink"
        ),
        "row_kinks": (
            " ".join(f"{k:.12f}" for k in row_kinks(name)) + " (t of the eps clamp kink of E)"
            if model_kinks(name)
            else "none"
        ),
        "interpolation_error": (
            f"{interpolation_error:.1e} (max |interpolated - quadrature| of "
            "|e_g| + |e_h| errors at all cell centres, held out of the grid)"
        ),
        "library": f"openpbr-diffuse {__version__}",
        "regenerate": f"{REGENERATE} --models {name}",
    }
    return meta


def held_out_error(
    model: str,
    table_values: dict[str, Any],
    n: int = ORDER,
    rows: ArrayLike | None = None,
    columns: ArrayLike | None = None,
) -> tuple[float, float, NDArray[np.float64]]:
    """Max interpolation error of a grid (``compute_table`` result) at held-out cell centres.

    Cell centres (j + 1/2, k + 1/2) are the points farthest from the nodes; the error is
    |e_g interp - e_g| + |e_h interp - e_h| plus the quadrature error of the held-out value.
    Also checks the average terms at column centres.
    """
    name = model_info(model).name
    nr = n_columns(name)
    tc = (np.arange(N_THETA) + 0.5) / N_THETA if rows is None else np.asarray(rows, float)
    if nr:
        uc = (np.arange(nr) + 0.5) / nr if columns is None else np.asarray(columns, float)
    else:
        uc = np.zeros(1)
    mu = np.cos(theta_of_t(tc))
    rough = roughness_of_u(name, uc)
    e_g, e_h, err = quadrature_terms(name, mu, rough, n)
    kinks = row_kinks(name)
    ig = interpolate_grid(table_values["e_g"], tc[:, None], uc[None, :], kinks)
    ih = interpolate_grid(table_values["e_h"], tc[:, None], uc[None, :], kinks)
    directional = np.abs(ig - e_g) + np.abs(ih - e_h) + err
    a_g, a_h, a_err = quadrature_average_terms(name, rough, n)
    average = (
        np.abs(interpolate_line(table_values["avg_g"], uc) - a_g)
        + np.abs(interpolate_line(table_values["avg_h"], uc) - a_h)
        + a_err
    )
    return float(directional.max()), float(average.max()), directional


def write_table(
    model: str, res: dict[str, Any], interpolation_error: float, directory: str | os.PathLike[str] | None = None
) -> str:
    """Write a computed table to ``directory`` (default: the package data directory)."""
    name = model_info(model).name
    directory = os.fspath(directory) if directory is not None else os.fspath(data_dir())  # type: ignore[call-overload]
    os.makedirs(directory, exist_ok=True)
    path = os.path.join(directory, f"albedo_{name}.csv")
    text = format_table(name, res, provenance(name, res, interpolation_error))
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write(text)
    load_table.cache_clear()
    return path
