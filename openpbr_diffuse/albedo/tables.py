"""Reference albedo tables: generation by quadrature, CSV storage, interpolation, queries.

Every model is f = rho g + m(rho) h (``models.registry``), so its directional albedo is

    E(mu, roughness; rho) = rho e_g(mu, roughness) + m(rho) e_h(mu, roughness)

with e_g, e_h independent of rho (m = 0, rho^2 or rho_ms(rho, <E_F>) of EON Eq. 18).  The
shipped tables (``openpbr_diffuse/data/albedo_<model>.csv``) hold e_g, e_h and the average
albedo terms <e_g>, <e_h>, computed by ``quadrature.hemisphere_albedo`` of the model's
``evaluate`` (never a closed-form albedo): the quadrature is run with rho = (1, 1/2) as two
channels and the 2x2 system E(1) = e_g + m(1) e_h, E(1/2) = e_g/2 + m(1/2) e_h is solved.

Grid (tensor product, interpolated by 4-point Lagrange cubics in (t, u)):

- rows: t_j = j / N_T, theta_j = (pi/2) (1 - (1 - t_j)^3), mu_j = cos(theta_j).  E is smooth
  in theta (not in mu at mu = 1); the cubic map clusters rows towards grazing, where the full
  Oren-Nayar albedo has a mu ln(mu) term;
- columns: u_k = k / N_R with roughness = u r_max for r in [0, 1] (FON, EON) and
  sigma = s0 sinh(u asinh(r_max / s0)), s0 = 0.3, for sigma in [0, pi/2]: the sigma^2 /
  (sigma^2 + 0.09) factors of the Oren-Nayar family have poles at sigma = +-0.3i, and this
  spacing (proportional to |sigma - 0.3i|) equalises the interpolation error.
"""
import functools
import importlib.resources
import math
import os

import numpy as np

from .. import _arrays as ar
from .._version import __version__
from ..models.registry import INFO, MIX_LINEAR, MIX_RHO2, MIX_RHO_MS, model_info
from .quadrature import DEFAULT_ORDER, GRAZING_DELTA, hemisphere_albedo, hemisphere_average_albedo

HALF_PI = 0.5 * math.pi

#: Rows (theta intervals) and columns (roughness intervals) of the shipped tables.
N_THETA = 64
N_ROUGH = 48
#: Scale of the sinh roughness map for sigma models (the 0.09 = 0.3^2 of B, Eq. 3).
SIGMA_SCALE = 0.3
#: Decimal places of the CSV values (rounding error <= 5e-11).
DECIMALS = 10
ROUNDING = 0.5 * 10.0 ** -DECIMALS
#: Quadrature orders used for the shipped tables (value at 2n, error estimate n vs 2n).
ORDER = DEFAULT_ORDER
#: rho of the two quadrature channels from which e_g and e_h are solved.
RHO_PAIR = (1.0, 0.5)
#: Roughness columns per batched quadrature call (memory: ~ MAX_POINTS * block * 2 doubles).
_BLOCK = 7
_MAX_POINTS = 1 << 16

REGENERATE = "python tools/make_tables.py"


def _data_dir():
    return importlib.resources.files("openpbr_diffuse") / "data"


def table_path(model):
    """Path of the shipped table file of ``model``."""
    return _data_dir() / f"albedo_{model_info(model).name}.csv"


# --------------------------------------------------------------------------- grids


def theta_of_t(t):
    """Row map theta(t) = (pi/2) (1 - (1 - t)^3), t in [0, 1]."""
    return HALF_PI * (1.0 - (1.0 - np.asarray(t, dtype=np.float64)) ** 3)


def t_of_mu(mu):
    """Inverse row map: t(mu) = 1 - (1 - arccos(mu) / (pi/2))^(1/3)."""
    x = 1.0 - np.arccos(np.clip(mu, 0.0, 1.0)) / HALF_PI
    return 1.0 - np.cbrt(np.maximum(x, 0.0))


def _is_sigma(name):
    return INFO[name].roughness_name == "sigma"


def roughness_of_u(name, u):
    """Column map: roughness(u), u in [0, 1]."""
    u = np.asarray(u, dtype=np.float64)
    info = INFO[name]
    if name == "lambert":
        return np.zeros_like(u)
    if _is_sigma(name):
        return SIGMA_SCALE * np.sinh(u * math.asinh(info.roughness_max / SIGMA_SCALE))
    return u * info.roughness_max


def u_of_roughness(name, roughness):
    """Inverse column map."""
    r = np.asarray(roughness, dtype=np.float64)
    info = INFO[name]
    if name == "lambert":
        return np.zeros_like(r)
    if _is_sigma(name):
        return np.arcsinh(r / SIGMA_SCALE) / math.asinh(info.roughness_max / SIGMA_SCALE)
    return r / info.roughness_max


def n_columns(name):
    """Roughness intervals of a model's table (Lambert's albedo ignores roughness: 0)."""
    return 0 if name == "lambert" else N_ROUGH


def _map_text(name):
    if name == "lambert":
        return "a single column (Lambert ignores roughness)"
    if _is_sigma(name):
        return (f"sigma_k = {SIGMA_SCALE} sinh(u_k asinh(({HALF_PI:.10f}) / {SIGMA_SCALE})), "
                f"u_k = k/{N_ROUGH}, k = 0..{N_ROUGH}")
    return f"r_k = u_k = k/{N_ROUGH}, k = 0..{N_ROUGH}"


# --------------------------------------------------------------------------- rho dependence


def mix_weight(name, rho, roughness):
    """m(rho) of f = rho g + m(rho) h (registry MIX_*): 0, rho^2, or rho_ms (EON Eq. 18)."""
    kind = INFO[name].mix
    rho = np.asarray(rho, dtype=np.float64)
    if kind == MIX_RHO2:
        return rho * rho
    if kind == MIX_RHO_MS:
        from ..models.eon import rho_ms
        from ..models.fon import E_F_avg

        avg = E_F_avg(np.asarray(roughness, dtype=np.float64))
        return rho_ms(rho, avg)
    return np.zeros(np.broadcast_shapes(rho.shape, np.shape(roughness)))


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


@functools.lru_cache(maxsize=None)
def model_kinks(name):
    """theta_i of kinks of a model's integrand besides theta_i = theta_o and s = 0.

    "eon_approx": the Eq. 14 fit exceeds 1 for mu < 1.3887e-3 (its m = 1 value
    g1 + g2 + g3 + g4 = 0.28825 exceeds c1 = 0.28779), where Listing 1's
    max(eps, 1 - E_F(mu_i)) clamps; the crossing E_F = 1 does not depend on r (the eps
    offset moves it by < 2e-5 in mu for r >= 1/48, negligible).  Found by bisection on
    the model's own ``E_F_approx``.
    """
    if name != "eon_approx":
        return ()
    from ..models.fon import E_F_approx

    lo, hi = 0.0, 0.5
    if not E_F_approx(lo, 1.0) > 1.0:
        return ()
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if E_F_approx(mid, 1.0) > 1.0 else (lo, mid)
    return (float(np.arccos(0.5 * (lo + hi))),)


def grazing_delta(name):
    """Smallest mu_o of the grazing-limit extrapolation (``hemisphere_albedo``'s delta).

    "eon": f_ms has Listing 1's max(eps, 1 - E_F(mu_o)) with 1 - E_F(mu_o) ~ 0.3 r mu_o near
    grazing, so below mu_o ~ eps / (0.3 r) (< 1.6e-5 for r >= 1/48) the guard, not the
    smooth lobe, sets the value.  The ladder (delta .. 16 delta) starts above that, so the
    mu = 0 row holds the limit of the smooth part (E_EON(0) = rho by Eq. 20 with
    E_F(0) = 1); the guard itself changes E by < 1e-7.  ("eon_approx" is constant below
    mu = 1.39e-3, see ``model_kinks``, so the default ladder lies inside that region.)
    """
    return 1e-4 if name == "eon" else GRAZING_DELTA


def row_kinks(name):
    """Row coordinates t of kinks of E(mu_o): by reciprocity those of ``model_kinks``."""
    return tuple(float(t_of_mu(math.cos(k))) for k in model_kinks(name))


def _brdf(name, roughness):
    """f(wi, wo) at rho = RHO_PAIR for a block of roughness values: shape (..., R, 2)."""
    from ..models.api import evaluate

    r = np.asarray(roughness, dtype=np.float64)
    rho = np.asarray(RHO_PAIR)

    def f(wi, wo):
        return evaluate(name, wi[..., None, :], wo[..., None, :], r, rho)

    return f


def quadrature_terms(model, mu, roughness, n=ORDER):
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
        r = roughness[k:k + _BLOCK]
        E, dE = hemisphere_albedo(_brdf(name, r), mu, n, error=True, kinks=model_kinks(name),
                                  delta=grazing_delta(name), max_points=_MAX_POINTS)
        for o, v in zip(out, _solve_terms(name, E, dE, r)):
            o[:, k:k + _BLOCK] = v
    return tuple(out)


def quadrature_average_terms(model, roughness, n=ORDER):
    """<e_g>, <e_h> and error bound of the average albedo by quadrature, shape (R,)."""
    name = model_info(model).name
    roughness = np.atleast_1d(np.asarray(roughness, dtype=np.float64))
    out = [np.empty(roughness.size) for _ in range(3)]
    for k in range(0, roughness.size, _BLOCK):
        r = roughness[k:k + _BLOCK]
        A, dA = hemisphere_average_albedo(_brdf(name, r), n, n_mu=n, error=True,
                                          kinks=model_kinks(name), max_points=_MAX_POINTS)
        for o, v in zip(out, _solve_terms(name, A, dA, r)):
            o[k:k + _BLOCK] = v
    return tuple(out)


def compute_table(model, rows=None, columns=None, *, n=ORDER, average=True, progress=None):
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
    rows = np.arange(N_THETA + 1) if rows is None else np.asarray(rows, dtype=np.int64)
    columns = np.arange(nr + 1) if columns is None else np.asarray(columns, dtype=np.int64)
    t = rows / N_THETA
    theta = theta_of_t(t)
    mu = np.cos(theta)
    mu[rows == N_THETA] = 0.0                   # exactly grazing (cos(pi/2) = 6e-17)
    u = columns / nr if nr else np.zeros(columns.size)
    roughness = roughness_of_u(name, u)
    res = {"order": n, "t": t, "theta": theta, "mu": mu, "u": u, "roughness": roughness,
           "e_g": np.empty((rows.size, columns.size)), "e_h": np.empty((rows.size, columns.size)),
           "err": np.empty((rows.size, columns.size))}
    if average:
        for key in ("avg_g", "avg_h", "avg_err"):
            res[key] = np.empty(columns.size)
    total = columns.size
    for k in range(0, total, _BLOCK):
        sl = slice(k, k + _BLOCK)
        res["e_g"][:, sl], res["e_h"][:, sl], res["err"][:, sl] = quadrature_terms(
            name, mu, roughness[sl], n)
        if average:
            res["avg_g"][sl], res["avg_h"][sl], res["avg_err"][sl] = quadrature_average_terms(
                name, roughness[sl], n)
        if progress is not None:
            progress(min(k + _BLOCK, total), total)
    return res


# --------------------------------------------------------------------------- interpolation


def _cubic(s, n, kinks=()):
    """Stencil start i0 and 4-point Lagrange weights at continuous index s in [0, n].

    ``kinks`` (continuous indices) are points where the tabulated function has a kink: a
    stencil never straddles one, so on each side the cubic of that side's smooth function
    is used (extrapolated by less than a cell up to the kink).
    """
    if n < 3:
        raise ValueError("cubic interpolation needs at least 4 nodes")
    i0 = np.clip(np.floor(s).astype(np.int64) - 1, 0, n - 3)
    for k in kinks:
        left = int(math.floor(k))                   # last node on the left of the kink
        i0 = np.where(s < k, np.minimum(i0, left - 3), np.maximum(i0, left + 1))
    x = s - i0
    w = np.stack([-(x - 1.0) * (x - 2.0) * (x - 3.0) / 6.0,
                  x * (x - 2.0) * (x - 3.0) / 2.0,
                  -x * (x - 1.0) * (x - 3.0) / 2.0,
                  x * (x - 1.0) * (x - 2.0) / 6.0])
    return i0, w


def interpolate_grid(values, t, u, t_kinks=()):
    """Tensor-product cubic interpolation of values[j, k] on uniform t_j = j/NT, u_k = k/NU.

    A single column (NU = 0) is constant in u.  t, u broadcast; result has their shape.
    ``t_kinks``: row coordinates of kinks (see ``_cubic``).
    """
    nt = values.shape[0] - 1
    nu = values.shape[1] - 1
    t, u = np.broadcast_arrays(np.asarray(t, dtype=np.float64), np.asarray(u, dtype=np.float64))
    it, wt = _cubic(t * nt, nt, [k * nt for k in t_kinks])
    if nu == 0:
        return sum(wt[a] * values[it + a, 0] for a in range(4))
    iu, wu = _cubic(u * nu, nu)
    out = np.zeros(t.shape)
    for a in range(4):
        for b in range(4):
            out += wt[a] * wu[b] * values[it + a, iu + b]
    return out


def interpolate_line(values, u):
    """Cubic interpolation of values[k] on u_k = k/NU (constant when NU = 0)."""
    values = np.asarray(values)
    nu = values.shape[0] - 1
    u = np.asarray(u, dtype=np.float64)
    if nu == 0:
        return np.full(u.shape, values[0])
    iu, wu = _cubic(u * nu, nu)
    return sum(wu[b] * values[iu + b] for b in range(4))


# --------------------------------------------------------------------------- files


class AlbedoTable:
    """One model's shipped table: grids, e_g/e_h/err (rows x columns), averages, header.

    Attributes
    ----------
    model : str
    meta : dict
        The provenance header (``key: value`` comment lines).
    t, theta, mu : ndarray (rows);  u, roughness : ndarray (columns)
    e_g, e_h, err : ndarray, shape (rows, columns)
    avg_g, avg_h, avg_err : ndarray, shape (columns,)
    quadrature_error : float
        Largest per-entry quadrature error estimate (directional and average).
    interpolation_error : float
        Held-out interpolation error stated in the header (bounds |E_interp - E| for any
        rho in [0, 1], including quadrature and rounding error).
    """

    def __init__(self, model, meta, grid):
        self.model = model
        self.meta = meta
        for key, value in grid.items():
            setattr(self, key, value)
        self.quadrature_error = float(max(self.err.max(), self.avg_err.max()))
        self.interpolation_error = float(meta.get("interpolation_error", "nan").split()[0])
        self.row_kinks = tuple(float(v) for v in meta.get("row_kinks", "").split()[:1] if v != "none")

    def directional_terms(self, mu, roughness):
        """(e_g, e_h) interpolated at (mu, roughness) (broadcast, float64, validated)."""
        t = t_of_mu(mu)
        u = u_of_roughness(self.model, roughness)
        return (interpolate_grid(self.e_g, t, u, self.row_kinks),
                interpolate_grid(self.e_h, t, u, self.row_kinks))

    def average_terms(self, roughness):
        """(<e_g>, <e_h>) interpolated at roughness."""
        u = u_of_roughness(self.model, roughness)
        return interpolate_line(self.avg_g, u), interpolate_line(self.avg_h, u)


def _fmt(v):
    s = f"{v:.{DECIMALS}f}"
    return s[1:] if s.startswith("-") and not float(s) else s   # no "-0.0000000000"


def _fmt_err(v):
    return f"{v:.1e}"


def format_table(model, res, meta):
    """CSV text of a computed table (``compute_table`` result) with provenance ``meta``."""
    name = model_info(model).name
    lines = [f"# {k}: {v}" for k, v in meta.items()]
    lines.append(",".join(["quantity", "j", "theta", "mu"] + [_fmt(r) for r in res["roughness"]]))
    quantities = [("e_g", _fmt), ("e_h", _fmt), ("err", _fmt_err)]
    if INFO[name].mix == MIX_LINEAR:
        quantities = [("e_g", _fmt), ("err", _fmt_err)]
    for key, fmt in quantities:
        for j in range(len(res["t"])):
            lines.append(",".join([key, str(round(res["t"][j] * N_THETA)), _fmt(res["theta"][j]),
                                   _fmt(res["mu"][j])] + [fmt(v) for v in res[key][j]]))
    for key, fmt in (("avg_g", _fmt), ("avg_h", _fmt), ("avg_err", _fmt_err)):
        if key == "avg_h" and INFO[name].mix == MIX_LINEAR:
            continue
        lines.append(",".join([key, "", "", ""] + [fmt(v) for v in res[key]]))
    return "\n".join(lines) + "\n"


def parse_table(model, text):
    """Parse CSV text into an ``AlbedoTable``; checks the grid against this module's maps."""
    name = model_info(model).name
    meta, data = {}, {}
    header = None
    for line in text.splitlines():
        if not line.strip():
            continue
        if line.startswith("#"):
            key, _, value = line[1:].partition(":")
            meta[key.strip()] = value.strip()
            continue
        cells = line.split(",")
        if header is None:
            header = cells
            continue
        data.setdefault(cells[0], []).append(cells[1:])
    if header is None or "e_g" not in data:
        raise ValueError(f"{name}: table file has no data rows")
    roughness = np.array([float(c) for c in header[4:]])
    rows = data["e_g"]
    j = np.array([int(r[0]) for r in rows])
    nr = n_columns(name)
    if len(rows) != N_THETA + 1 or roughness.size != nr + 1 or not np.array_equal(j, np.arange(N_THETA + 1)):
        raise ValueError(f"{name}: table grid is {len(rows)} x {roughness.size}, "
                         f"expected {N_THETA + 1} x {nr + 1}; regenerate with {REGENERATE}")
    u = np.arange(nr + 1) / nr if nr else np.zeros(1)
    if not np.allclose(roughness, roughness_of_u(name, u), rtol=0, atol=2 * ROUNDING):
        raise ValueError(f"{name}: table roughness columns do not match the grid map")

    def block(key):
        if key not in data:
            return np.zeros((N_THETA + 1, nr + 1))
        return np.array([[float(c) for c in r[3:]] for r in data[key]])

    def line(key):
        if key not in data:
            return np.zeros(nr + 1)
        return np.array([float(c) for c in data[key][0][3:]])

    # The grid is the exact map (the file's columns are rounded to 1e-10 and checked).
    t = j / N_THETA
    theta = theta_of_t(t)
    mu = np.cos(theta)
    mu[-1] = 0.0
    if not np.allclose(mu, [float(r[2]) for r in rows], rtol=0, atol=2 * ROUNDING):
        raise ValueError(f"{name}: table mu rows do not match the grid map")
    grid = {"t": t, "theta": theta, "mu": mu, "u": u, "roughness": roughness_of_u(name, u),
            "e_g": block("e_g"), "e_h": block("e_h"), "err": block("err"),
            "avg_g": line("avg_g"), "avg_h": line("avg_h"), "avg_err": line("avg_err")}
    return AlbedoTable(name, meta, grid)


@functools.lru_cache(maxsize=None)
def load_table(model):
    """The shipped ``AlbedoTable`` of ``model`` (read once, cached)."""
    name = model_info(model).name
    path = table_path(name)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise FileNotFoundError(f"reference table for {name!r} missing ({path}); "
                                f"regenerate with {REGENERATE}") from None
    return parse_table(name, text)


def provenance(model, res, interpolation_error):
    """The header of a table file (ordered dict of ``key: value``)."""
    name = model_info(model).name
    info = INFO[name]
    kinks = model_kinks(name)
    delta = grazing_delta(name)
    mix = {MIX_LINEAR: "0 (linear in rho; e_h omitted)", MIX_RHO2: "rho^2",
           MIX_RHO_MS: "rho_ms(rho, <E_F>(r)) = rho^2 <E_F> / (1 - rho (1 - <E_F>)) (EON Eq. 18)"}
    meta = {
        "title": f"openpbr-diffuse reference albedo table, model {name!r} ({info.description})",
        "quantity": (f"directional albedo E(mu, {info.roughness_name}; rho) = rho e_g + m(rho) e_h "
                     f"and average albedo <E> = rho avg_g + m(rho) avg_h, m(rho) = {mix[info.mix]}"),
        "rows": (f"j = 0..{N_THETA}: theta_j = (pi/2) (1 - (1 - j/{N_THETA})^3), mu_j = cos(theta_j) "
                 "(mu = 0 row: the limit mu -> 0)"),
        "columns": _map_text(name),
        "method": (f"numerical integration of openpbr_diffuse.evaluate (no closed-form albedo): "
                   f"Gauss-Legendre x Gauss-Legendre in (theta_i, phi_i), panels split at "
                   f"theta_i = theta_o (graded towards it) and phi = pi/2, phi in [0, pi] by symmetry"
                   + (f", extra panel edge at theta_i = {kinks[0]:.10f} (eps clamp of the Eq. 14 fit)"
                      if kinks else "")
                   + f"; order {2 * res['order']} per panel (error estimate: order {res['order']}); rho = {RHO_PAIR} as two channels, "
                   "2x2 solve for e_g, e_h; mu = 0 by fitting E0 + a mu ln mu + b mu + c mu^2 at "
                   f"mu = {delta:g} * (1, 2, 4, 8) (error estimate: * (2, 4, 8, 16)); averages by "
                   "Gauss-Legendre in theta_o on panels graded towards the horizon"),
        "error": (f"err / avg_err: estimated error (|Q_n - Q_2n| + 64 ulp; at mu = 0 plus the fit's) "
                  f"of rho e_g + m(rho) e_h for any rho in [0, 1]; "
                  f"max {max(res['err'].max(), res['avg_err'].max()):.1e}; values rounded to "
                  f"{DECIMALS} decimals (+-{ROUNDING:.0e})"),
        "interpolation": ("tensor-product 4-point Lagrange cubic in (t, u), t = 1 - (1 - acos(mu)/(pi/2))^(1/3), "
                          "u the column coordinate; stencils clipped at the edges and never across a row kink"),
        "row_kinks": (" ".join(f"{k:.12f}" for k in row_kinks(name)) + " (t of the eps clamp kink of E)"
                      if model_kinks(name) else "none"),
        "interpolation_error": (f"{interpolation_error:.1e} (max |interpolated - quadrature| of "
                                "|e_g| + |e_h| errors at all cell centres, held out of the grid)"),
        "library": f"openpbr-diffuse {__version__}",
        "regenerate": f"{REGENERATE} --models {name}",
    }
    return meta


def held_out_error(model, table_values, n=ORDER, rows=None, columns=None):
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
    average = (np.abs(interpolate_line(table_values["avg_g"], uc) - a_g)
               + np.abs(interpolate_line(table_values["avg_h"], uc) - a_h) + a_err)
    return float(directional.max()), float(average.max()), directional


# --------------------------------------------------------------------------- queries


#: rows per interpolation pass of ``table_albedo`` (bounds its float64 temporaries)
_CHUNK = 1 << 14


def table_albedo(name, mu, roughness, rho, average=False, tint=False):
    """E (or <E> when ``average``) of a model from its reference table.

    Parameters
    ----------
    name : str
        Model name.
    mu : array_like or None
        Cosine of the view angle in [0, 1] (ignored when ``average``).
    roughness : array_like
        In the model's domain.
    rho : array_like, shape (..., C)
    average : bool
        Return the average albedo <E>(roughness).
    tint : bool
        "white_tint" colour mode: rho * E(rho = 1).

    Returns
    -------
    ndarray, shape broadcast(mu, roughness, rho leading axes) + (C,)
    """
    info = model_info(name)
    dtype = ar.result_dtype(roughness, rho) if average else ar.result_dtype(mu, roughness, rho)
    if not average:
        mu = ar.in_range("mu", mu, dtype, 0.0, 1.0, " (cosine of the view angle)")
    r = ar.model_roughness(info, roughness, dtype)
    rho = ar.rho_array("rho", rho, dtype)
    table = load_table(info.name)
    if average:
        lead = ar.broadcast_leading(roughness=r.shape, rho=rho.shape[:-1])
        mu = r  # not read
    else:
        lead = ar.broadcast_leading(mu=mu.shape, roughness=r.shape, rho=rho.shape[:-1])
    C = rho.shape[-1]
    out = np.empty(lead + (C,), dtype=dtype)
    flat_out = out.reshape(-1, C)
    mu, r, rho = ar.flat(mu, lead), ar.flat(r, lead), ar.flat(rho, lead, C)
    # in chunks: the float64 interpolation temporaries stay a fixed size (speed issue:
    # peak extra memory <= 3x the output)
    for s in range(0, flat_out.shape[0], _CHUNK):
        e = s + _CHUNK
        r64 = r[s:e].astype(np.float64)
        if average:
            e_g, e_h = table.average_terms(r64)
        else:
            e_g, e_h = table.directional_terms(mu[s:e].astype(np.float64), r64)
        e_g, e_h, r64 = e_g[:, None], e_h[:, None], r64[:, None]
        rho64 = rho[s:e].astype(np.float64)
        if tint:
            flat_out[s:e] = rho64 * (e_g + mix_weight(info.name, 1.0, r64) * e_h)
        else:
            flat_out[s:e] = rho64 * e_g + mix_weight(info.name, rho64, r64) * e_h
    return out



def reference_albedo(model, mu, roughness, rho=1.0, *, color_mode="reference"):
    """Directional albedo E(mu) interpolated from the shipped reference tables.

    The tables are an independent numerical integration of each model's ``evaluate``
    (see ``openpbr_diffuse/data/albedo_<model>.csv`` for provenance and stated errors); the
    rho dependence is exact (E = rho e_g + m(rho) e_h, tabulated e_g and e_h), so chromatic
    rho is covered for Fujii QON, full Oren-Nayar and EON.  Accuracy: the file's
    ``interpolation_error`` (< 1e-5; ``load_table(model).interpolation_error``).

    Parameters
    ----------
    model : str
        One of ``MODELS``.
    mu : array_like, shape (...)
        Cosine of the outgoing direction in [0, 1] (mu = 0: the limit).
    roughness : array_like, shape (...)
        sigma in [0, pi/2] or r in [0, 1] as in ``evaluate``.
    rho : array_like, shape (..., C)
    color_mode : {"reference", "white_tint"}

    Returns
    -------
    ndarray, shape broadcast(leading axes) + (C,)

    Examples
    --------
    >>> round(float(reference_albedo("fon", 1.0, 1.0)[0]), 5)     # EON paper: E_F(1, 1)
    0.77652
    >>> round(float(reference_albedo("full_on", 0.05, 0.5)[0]), 4)  # fullON gains energy
    1.0047
    """
    return table_albedo(model, mu, roughness, rho, average=False, tint=ar.white_tint(color_mode))


def reference_average_albedo(model, roughness, rho=1.0, *, color_mode="reference"):
    """Average albedo <E> = 2 int E(mu) mu dmu interpolated from the reference tables.

    Same conventions as ``reference_albedo``; the averages are integrated directly (not from
    the tabulated E).

    Examples
    --------
    >>> round(float(reference_average_albedo("fon", 1.0)[0]), 6)   # EON paper: <E_F>(1)
    0.832811
    """
    return table_albedo(model, None, roughness, rho, average=True, tint=ar.white_tint(color_mode))


def write_table(model, res, interpolation_error, directory=None):
    """Write a computed table to ``directory`` (default: the package data directory)."""
    name = model_info(model).name
    directory = os.fspath(directory) if directory is not None else os.fspath(_data_dir())
    os.makedirs(directory, exist_ok=True)
    path = os.path.join(directory, f"albedo_{name}.csv")
    text = format_table(name, res, provenance(name, res, interpolation_error))
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write(text)
    load_table.cache_clear()
    return path


__all__ = ["AlbedoTable", "load_table", "compute_table", "reference_albedo",
           "reference_average_albedo", "table_albedo", "quadrature_terms",
           "quadrature_average_terms", "interpolate_grid", "interpolate_line"]
