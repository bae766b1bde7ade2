"""Properties of an implementation itself, measured through its own BRDF and albedo functions.

Each property is a check with a stable id and a finding in words; none compares a value with
the reference directly (the values are graded by :mod:`.grade`), so a property names *what
kind* of mistake the values have:

==============================  ===================================================================
id                              passes when
==============================  ===================================================================
``property.reciprocity``        f(wi, wo) = f(wo, wi)
``property.energy``             the BRDF integrated by Gauss-Legendre quadrature over the hemisphere,
                                ∫ f μ_i dω_i, equals the implementation's own albedo function
``property.white_furnace``      that integral is 1 at ρ = 1 (EON and Lambert promise it)
``property.channels``           a channel depends only on its own ρ
``property.rho_dependence``     f(ρ) = ρ g + ρ_ms(ρ) h (EON, Eq. 16-18; ρ g for the others,
                                ρ g + ρ² h for Fujii's QON), with h > 0 for EON at r > 0
``property.horizon``            f = 0 when wi.z ≤ 0 or wo.z ≤ 0
``property.lambert_at_zero``    at roughness 0, f = ρ/π and E = ρ
``property.clamp``              no input range over which the output stops changing where the
                                model's does not (a clamp or floor, reported with its bound)
``property.azimuth``            f depends on φ only through cos φ: f(φ_o + Δ) = f(φ_o − Δ)
==============================  ===================================================================

Every BRDF query is made in one call of the implementation's function, every albedo query in
another (a shader or compiled harness runs once).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..result import sub_check

if TYPE_CHECKING:
    from .vectors import VectorSet

#: ids of the property checks, in report order
PROPERTY_IDS = (
    "property.reciprocity",
    "property.energy",
    "property.white_furnace",
    "property.channels",
    "property.rho_dependence",
    "property.horizon",
    "property.lambert_at_zero",
    "property.clamp",
    "property.azimuth",
)
#: Gauss-Legendre nodes per interval of the energy quadrature (theta: 2 intervals split at
#: theta_o; phi: 2 intervals split at the s = 0 azimuths): the reference EON integrates to its
#: albedo within 1e-13 (measured)
QUAD_NODES = 24
#: |int f mu dw - E|: the quadrature error is < 2e-6 on the reference; float32 values add < 1e-6
ENERGY_TOL = 2e-4
#: eon_approx: the Eq. 14 lobe's true albedo and Listing 1's differ by up to 5e-4 (both legitimate);
#: for the exact model a difference up to this is a warning (the size of the Eq. 14 fit), not a failure
ENERGY_TOL_APPROX = 1e-3
#: a flat stretch of a sweep is a clamp when the model changes over it by more than this many tolerances
CLAMP_FACTOR = 20.0
#: the fewest consecutive flat sweep points that make a clamp
CLAMP_MIN_POINTS = 3

_EON = ("eon", "eon_approx")
_FURNACE = ("eon", "eon_approx", "lambert")


@dataclass
class _Batch:
    """BRDF queries gathered from every property, evaluated in one call."""

    wi: list = field(default_factory=list)
    wo: list = field(default_factory=list)
    r: list = field(default_factory=list)
    rho: list = field(default_factory=list)
    n: int = 0

    def add(self, wi: Any, wo: Any, r: Any, rho: Any) -> slice:
        wi = np.atleast_2d(np.asarray(wi, np.float64))
        m = wi.shape[0]
        self.wi.append(wi)
        self.wo.append(np.broadcast_to(np.asarray(wo, np.float64), (m, 3)))
        self.r.append(np.broadcast_to(np.asarray(r, np.float64), (m,)))
        self.rho.append(np.broadcast_to(np.asarray(rho, np.float64), (m, 3)))
        s = slice(self.n, self.n + m)
        self.n += m
        return s

    def run(self, fn):
        if self.n == 0:
            return np.zeros((0, 3))
        out = fn(
            np.concatenate(self.wi),
            np.concatenate(self.wo),
            np.concatenate(self.r),
            np.concatenate(self.rho),
        )
        return np.asarray(out, np.float64).reshape(self.n, 3)


def _dir(mu, phi):
    mu = np.asarray(mu, np.float64)
    phi = np.asarray(phi, np.float64)
    s = np.sqrt(np.clip(1.0 - mu * mu, 0.0, None))
    return np.stack(np.broadcast_arrays(s * np.cos(phi), s * np.sin(phi), mu), axis=-1)


def _check(pid, status, detail, measured=None, threshold=None):
    return sub_check(pid, status, measured, threshold, detail).to_dict()


def _tol(x, rel, ab):
    return ab + rel * np.abs(x)


def _gl(a, b, n):
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (b - a) * x + 0.5 * (b + a), 0.5 * (b - a) * w


def _quadrature(mu_o):
    """(mu_i, phi offset, weight) of a rule for int f mu_i dw over the upper hemisphere: theta in
    [0, theta_o] and [theta_o, pi/2], phi - phi_o in [-pi/2, pi/2] and [pi/2, 3pi/2] (the kinks of
    t = max(mu_i, mu_o) and of s = 0 on interval ends); weight includes sin cos dtheta."""
    t_o = math.acos(mu_o)
    ts, tw = zip(*(_gl(a, b, QUAD_NODES) for a, b in ((0.0, t_o), (t_o, 0.5 * math.pi)) if b > a), strict=True)
    th, wth = np.concatenate(ts), np.concatenate(tw)
    ps, pw = zip(
        *(_gl(a, b, QUAD_NODES) for a, b in ((-0.5 * math.pi, 0.5 * math.pi), (0.5 * math.pi, 1.5 * math.pi))),
        strict=True,
    )
    ph, wph = np.concatenate(ps), np.concatenate(pw)
    T, P = np.meshgrid(th, ph, indexing="ij")
    W = (wth * np.sin(th) * np.cos(th))[:, None] * wph[None, :]
    return np.cos(T).ravel(), P.ravel(), W.ravel()


def _rough_max(model):
    return 0.5 * math.pi if model in ("qon", "qon_fujii") else 1.0


def _rho_ms(rho, r):
    from ..models.eon import rho_ms
    from ..models.fon import E_F_avg

    return np.asarray(rho_ms(np.asarray(rho, np.float64), np.asarray(E_F_avg(r), np.float64)), np.float64)


def _random_pairs(rng, n, lo=0.05):
    mu = rng.uniform(lo, 1.0, (n, 2))
    phi = rng.uniform(0.0, 2.0 * math.pi, (n, 2))
    return _dir(mu[:, 0], phi[:, 0]), _dir(mu[:, 1], phi[:, 1])


def check_properties(
    brdf: Callable | None,
    albedo: Callable | None = None,
    *,
    model: str = "eon",
    tolerance: tuple | None = None,
    seed: int = 7,
) -> list[dict]:
    """Measure the properties of an implementation's own functions (see the module docstring).

    Parameters
    ----------
    brdf : callable or None
        ``brdf(wi (n,3), wo (n,3), roughness (n,), rho (n,3)) -> (n,3)``, no cosine.
    albedo : callable or None
        ``albedo(mu (n,), roughness (n,), rho (n,3)) -> (n,3)``.
    model : str
        The model the implementation claims (sets what "as the model prescribes" means).
    tolerance : (float, float), optional
        (relative, absolute) of the implementation's values (default that of ``grade``).
    seed : int
        Seed of the random directions.

    Returns
    -------
    list of dict
        One per id of :data:`PROPERTY_IDS`: ``{"id", "status" ("pass", "warn", "fail" or "skip"),
        "measured", "threshold", "detail"}``; ``detail`` is the finding in words.

    Examples
    --------
    >>> import openpbr_diffuse as od
    >>> f = lambda wi, wo, r, rho: od.evaluate("eon", wi, wo, r, rho)
    >>> e = lambda mu, r, rho: od.directional_albedo("eon", mu, r, rho)
    >>> sorted({c["status"] for c in check_properties(f, e)})
    ['pass']
    >>> swap = lambda wi, wo, r, rho: od.evaluate("eon", wi, wo, r, rho) * (0.5 + wi[:, 2:])
    >>> [c["id"] for c in check_properties(swap, e) if c["status"] == "fail"][0]
    'property.reciprocity'
    """
    from .tolerance import ABS_TOL, REL_TOL

    rel, ab = (REL_TOL, ABS_TOL) if tolerance is None else (float(tolerance[0]), float(tolerance[1]))
    if brdf is None:
        out = [_check(pid, "skip", "no BRDF function given") for pid in PROPERTY_IDS]
        if albedo is not None:
            out[PROPERTY_IDS.index("property.lambert_at_zero")] = _lambert_albedo_only(albedo, rel, ab)
        return out
    rng = np.random.default_rng(seed)
    rmax = _rough_max(model)
    b = _Batch()
    plan: dict = {}
    with np.errstate(all="ignore"):
        plan["recip"] = _plan_reciprocity(b, rng, rmax)
        plan["energy"] = _plan_energy(b, rmax)
        plan["channels"] = _plan_channels(b, rng, rmax)
        plan["rho"] = _plan_rho(b, rng, rmax)
        plan["horizon"] = _plan_horizon(b, rmax)
        plan["lambert"] = _plan_lambert(b, rng)
        plan["clamp"] = _plan_clamp(b, rmax)
        plan["azimuth"] = _plan_azimuth(b, rng, rmax)
        f = b.run(brdf)
        e_alb = None
        if albedo is not None:
            mus = np.array([p[0] for p in plan["energy"]["cases"]] + list(plan["lambert"]["alb_mu"]))
            rs = np.array([p[1] for p in plan["energy"]["cases"]] + [0.0] * len(plan["lambert"]["alb_mu"]))
            rhos = np.array([plan["energy"]["rho"]] * len(plan["energy"]["cases"]) + list(plan["lambert"]["alb_rho"]))
            e_alb = np.asarray(albedo(mus, rs, rhos), np.float64).reshape(len(mus), 3)
        return [
            _reciprocity(f, plan["recip"], rel, ab),
            _energy(f, plan["energy"], e_alb, model, rel, ab),
            _furnace(f, plan["energy"], e_alb, model),
            _channels(f, plan["channels"], rel, ab),
            _rho_dependence(f, plan["rho"], model, rel, ab),
            _horizon(f, plan["horizon"], ab),
            _lambert(f, plan["lambert"], e_alb, len(plan["energy"]["cases"]), rel, ab),
            _clamp(f, plan["clamp"], model, rel, ab),
            _azimuth(f, plan["azimuth"], rel, ab),
        ]


# ----------------------------------------------------------------------------- reciprocity


def _plan_reciprocity(b, rng, rmax):
    wi, wo = _random_pairs(rng, 48, lo=0.02)
    # grazing against steep, both ways: a factor of one direction only shows most there
    g = np.array([0.02, 0.05, 0.1, 0.2])
    wi = np.concatenate([wi, _dir(g, 0.4)])
    wo = np.concatenate([wo, _dir(np.full(4, 0.9), 1.3)])
    m = len(wi)
    r = np.resize(np.array([0.25, 0.5, 1.0]) * rmax, m)
    rho = np.resize(np.array([[1.0, 1.0, 1.0], [0.8, 0.5, 0.2], [0.05, 0.3, 0.9]]), (m, 3))
    return {"a": b.add(wi, wo, r, rho), "b": b.add(wo, wi, r, rho), "mu_i": wi[:, 2], "mu_o": wo[:, 2]}


def _reciprocity(f, p, rel, ab):
    pid = "property.reciprocity"
    fa, fb = f[p["a"]], f[p["b"]]
    bad_nf = ~(np.isfinite(fa).all(1) & np.isfinite(fb).all(1))
    d = np.abs(fa - fb) / (2.0 * _tol(np.maximum(np.abs(fa), np.abs(fb)), rel, ab))
    d = np.where(bad_nf[:, None], 0.0, d).max(axis=1)
    if not (d > 1.0).any():
        return _check(pid, "pass", f"reciprocal: f(wi, wo) = f(wo, wi) on {len(d)} pairs", float(d.max()), 1.0)
    with np.errstate(all="ignore"):
        ratio = np.where(np.abs(fb) > 0, fa / fb, np.inf)
    ratio = np.where(np.isfinite(ratio), ratio, 1.0)
    dev = np.abs(np.log(np.maximum(ratio, 1e-300))).max(axis=1)
    k = int(np.argmax(dev))
    c = int(np.argmax(np.abs(np.log(np.maximum(ratio[k], 1e-300)))))
    mu_i, mu_o = p["mu_i"][k], p["mu_o"][k]
    top = ratio[k, c]
    if top < 1.0:  # stated as the larger over the smaller, at the (mu_i, mu_o) of the larger
        top, mu_i, mu_o = 1.0 / top, mu_o, mu_i
    bad = d > 1.0
    # which direction the factor follows: log ratio against log(mu_i / mu_o)
    lr = np.log(np.maximum(ratio[:, c], 1e-300))[bad]
    lm = np.log(p["mu_i"] / p["mu_o"])[bad]
    hint = ""
    if lr.size >= 3 and np.std(lm) > 0 and np.std(lr) > 0:
        corr = float(np.corrcoef(lr, lm)[0, 1])
        if abs(corr) > 0.7:
            larger = "smaller" if corr < 0 else "larger"
            hint = (
                f" -- f(wi, wo) is the larger one where mu_i is the {larger} angle cosine: a factor depends on one "
                "direction only (e.g. f_ms without (1 - E_F(mu_i)), or a cosine folded into f)"
            )
    return _check(
        pid,
        "fail",
        f"not reciprocal: f(wi,wo)/f(wo,wi) up to {top:.3g} at mu_i {mu_i:.3g}, mu_o {mu_o:.3g} "
        f"({int(bad.sum())} of {len(bad)} pairs){hint}",
        float(d.max()),
        1.0,
    )


# ----------------------------------------------------------------------------- energy


_ENERGY_MU = (0.15, 0.5, 0.9)
_ENERGY_R = (0.5, 1.0)
_ENERGY_RHO = (1.0, 0.6, 0.2)  # channel 0 white: the white furnace from the same integral


def _plan_energy(b, rmax):
    cases, slices = [], []
    phi_o = 0.3
    for mu in _ENERGY_MU:
        mu_i, dphi, w = _quadrature(mu)
        wi = _dir(mu_i, phi_o + dphi)
        for r in _ENERGY_R:
            cases.append((mu, r * rmax))
            slices.append((b.add(wi, _dir(mu, phi_o), r * rmax, _ENERGY_RHO), w))
    return {"cases": cases, "slices": slices, "rho": _ENERGY_RHO}


def _integrals(f, p):
    return np.array([np.einsum("n,nc->c", w, f[s]) for s, w in p["slices"]])


def _energy(f, p, e_alb, model, rel, ab):
    pid = "property.energy"
    if e_alb is None:
        return _check(pid, "skip", "no albedo function given: the BRDF's integral is not compared")
    q = _integrals(f, p)
    e = e_alb[: len(p["cases"])]
    tol = ENERGY_TOL_APPROX if model == "eon_approx" else ENERGY_TOL
    d = np.abs(q - e)
    d = np.where(np.isfinite(d), d, np.inf)
    k, c = np.unravel_index(int(np.argmax(d)), d.shape)
    mu, r = p["cases"][k]
    where = f"at mu_o {mu:g}, roughness {r:.3g}, rho {p['rho'][c]:g}"
    if d.max() <= tol:
        return _check(
            pid,
            "pass",
            f"the BRDF integrates to its albedo function within {d.max():.2g} ({len(d)} (mu_o, roughness) cases)",
            float(d.max()),
            tol,
        )
    return _check(
        pid,
        "warn" if d.max() <= ENERGY_TOL_APPROX else "fail",
        f"its BRDF and its albedo disagree: the integral of f mu_i over the hemisphere is {q[k, c]:.5g} but its "
        f"albedo function gives {e[k, c]:.5g} {where} ({'larger' if q[k, c] > e[k, c] else 'smaller'} by "
        f"{abs(q[k, c] / e[k, c] - 1) if e[k, c] else math.inf:.2%})",
        float(d.max()),
        tol,
    )


def _furnace(f, p, e_alb, model):
    pid = "property.white_furnace"
    if model not in _FURNACE:
        return _check(pid, "skip", f"{model} does not promise a white furnace (it loses energy by design)")
    tol = ENERGY_TOL_APPROX if model == "eon_approx" else ENERGY_TOL
    q = _integrals(f, p)[:, 0]  # channel 0: rho = 1
    parts = [("the integral of its BRDF", q)]
    if e_alb is not None:
        parts.append(("its albedo function", e_alb[: len(p["cases"]), 0]))
    worst = max(((name, v, int(np.argmax(np.abs(v - 1.0)))) for name, v in parts), key=lambda t: abs(t[1][t[2]] - 1))
    name, v, k = worst
    err = abs(v[k] - 1.0)
    mu, r = p["cases"][k]
    if err <= tol:
        return _check(
            pid,
            "pass",
            f"white furnace: E = 1 at rho = 1 within {err:.2g} (its BRDF integrated{', its albedo' if len(parts) > 1 else ''})",
            float(err),
            tol,
        )
    verb = "loses" if v[k] < 1 else "gains"
    return _check(
        pid,
        "warn" if err <= ENERGY_TOL_APPROX else "fail",
        f"{verb} energy at rho = 1: {name} is {v[k]:.5g} at mu_o {mu:g}, roughness {r:.3g} ({model} promises 1)",
        float(err),
        tol,
    )


# ----------------------------------------------------------------------------- channels


_BASE_RHO = np.array([0.7, 0.4, 0.2])


def _plan_channels(b, rng, rmax):
    wi, wo = _random_pairs(rng, 8)
    r = np.resize(np.array([0.5, 1.0]) * rmax, 8)
    s = {"base": b.add(wi, wo, r, _BASE_RHO)}
    for c in range(3):
        rho = _BASE_RHO.copy()
        rho[c] = 0.95
        s[c] = b.add(wi, wo, r, rho)
    return s


def _channels(f, p, rel, ab):
    pid = "property.channels"
    base = f[p["base"]]
    worst, where = 0.0, ""
    names = "rgb"
    for c in range(3):
        other = [k for k in range(3) if k != c]
        d = np.abs(f[p[c]][:, other] - base[:, other]) / _tol(base[:, other], rel, ab)
        d = np.where(np.isfinite(d), d, 0.0)
        if d.max() > worst:
            worst = float(d.max())
            i, j = np.unravel_index(int(np.argmax(d)), d.shape)
            ch = names[other[j]]
            rel_ch = abs(f[p[c]][i, other[j]] / base[i, other[j]] - 1.0) if base[i, other[j]] else math.inf
            where = (
                f"changing only rho_{names[c]} ({_BASE_RHO[c]:g} -> 0.95) changes channel {ch} by {rel_ch:.2%}: "
                "a channel depends on another's rho (e.g. rho_ms from a grey (luminance or mean) rho)"
            )
    if worst <= 1.0:
        return _check(pid, "pass", "channels independent: each depends only on its own rho", worst, 1.0)
    return _check(pid, "fail", where, worst, 1.0)


# ----------------------------------------------------------------------------- rho dependence


_RHO_GRID = np.array([0.0, 0.1, 0.25, 0.4, 0.55, 0.7, 0.85, 1.0])


def _plan_rho(b, rng, rmax):
    wi, wo = _random_pairs(rng, 6)
    cases, sl = [], []
    for k in range(len(wi)):
        for r in (0.5, 1.0):
            rho = np.repeat(_RHO_GRID[:, None], 3, axis=1)
            sl.append(b.add(np.repeat(wi[k : k + 1], len(_RHO_GRID), 0), wo[k], r * rmax, rho))
            cases.append((float(wi[k, 2]), float(wo[k, 2]), r * rmax, r))
    return {"cases": cases, "slices": sl}


def _basis(model, r01):
    x = _RHO_GRID
    if model in _EON:
        return np.stack([x, _rho_ms(x, r01)], 1), "rho g + rho_ms(rho) h (Eq. 16-18)"
    if model == "qon_fujii":
        return np.stack([x, x * x], 1), "rho g + rho^2 h (Fujii's A)"
    return x[:, None], "rho g (linear)"


def _rho_dependence(f, p, model, rel, ab):
    pid = "property.rho_dependence"
    alternatives = {
        "linear in rho (rho g: no rho_ms term)": lambda r01: _RHO_GRID[:, None],
        "rho g + rho rho_ms(rho) h (f_ms with an extra rho)": lambda r01: np.stack(
            [_RHO_GRID, _RHO_GRID * _rho_ms(_RHO_GRID, r01)], 1
        ),
        "rho g + rho^2 h": lambda r01: np.stack([_RHO_GRID, _RHO_GRID**2], 1),
        "rho g + rho_ms(rho) h": lambda r01: np.stack([_RHO_GRID, _rho_ms(_RHO_GRID, r01)], 1),
    }
    worst, wcase, no_ms = 0.0, None, 0
    resid_alt = dict.fromkeys(alternatives, 0.0)
    for (mi, mo, r, r01), s in zip(p["cases"], p["slices"], strict=True):
        y = f[s][:, 0]
        if not np.isfinite(y).all():
            worst, wcase = math.inf, (mi, mo, r)
            continue
        X, form = _basis(model, r01)
        coef, *_ = np.linalg.lstsq(X, y, rcond=None)
        d = float(np.max(np.abs(X @ coef - y) / _tol(y, rel, ab)))
        if model in _EON and r01 > 0 and coef[1] <= 1e-3 * max(abs(coef[0]), 1e-12):
            no_ms += 1
        if d > worst:
            worst, wcase = d, (mi, mo, r)
        for name, fn in alternatives.items():
            Xa = fn(r01)
            ca, *_ = np.linalg.lstsq(Xa, y, rcond=None)
            resid_alt[name] = max(resid_alt[name], float(np.max(np.abs(Xa @ ca - y) / _tol(y, rel, ab))))
    form = _basis(model, 0.5)[1]
    n = len(p["cases"])
    if worst <= 1.0 and not no_ms:
        return _check(pid, "pass", f"f(rho) = {form} at every one of {n} (direction, roughness) cases", worst, 1.0)
    if worst <= 1.0 and no_ms:
        return _check(
            pid,
            "fail",
            f"f is linear in rho at {no_ms} of {n} cases with roughness > 0: no rho_ms term (EON's f_ms is "
            "missing, or the white result is tinted by rho)",
            worst,
            1.0,
        )
    fits = sorted((v, k) for k, v in resid_alt.items() if v <= 1.0)
    mi, mo, r = wcase
    hint = f"; it fits {fits[0][1]}" if fits else "; no simple form in rho fits"
    return _check(
        pid,
        "fail",
        f"f(rho) is not {form}: off by {worst:.3g} tolerances at mu_i {mi:.3g}, mu_o {mo:.3g}, roughness {r:.3g}{hint}",
        worst,
        1.0,
    )


# ----------------------------------------------------------------------------- horizon


def _plan_horizon(b, rmax):
    up = _dir(np.array([0.3, 0.7, 1.0]), np.array([0.2, 2.0, 0.0]))
    down = np.concatenate([_dir(np.array([1e-3, 0.2, 0.9]), np.array([0.5, 1.5, 3.0])), [[1.0, 0.0, 0.0]]])
    down[:3, 2] *= -1.0
    wi = np.concatenate([np.repeat(up, len(down), 0), np.tile(down, (len(up), 1)), down])
    wo = np.concatenate([np.tile(down, (len(up), 1)), np.repeat(up, len(down), 0), down[::-1]])
    r = np.resize(np.array([0.0, 0.5, 1.0]) * rmax, len(wi))
    return {"s": b.add(wi, wo, r, (0.8, 0.5, 0.2)), "wi": wi, "wo": wo}


def _horizon(f, p, ab):
    pid = "property.horizon"
    v = f[p["s"]]
    bad = ~(np.abs(np.nan_to_num(v, nan=np.inf)) <= ab).all(axis=1)
    if not bad.any():
        return _check(pid, "pass", f"f = 0 below the horizon ({len(v)} pairs, z = 0 included)", 0.0, ab)
    k = int(np.argmax(bad))
    return _check(
        pid,
        "fail",
        f"f is not 0 below the horizon at {int(bad.sum())} of {len(v)} pairs, e.g. {v[k, 0]:.4g} at wi.z "
        f"{p['wi'][k, 2]:.3g}, wo.z {p['wo'][k, 2]:.3g} (a missing or `z < 0` horizon test, or a two-sided lobe)",
        float(np.max(np.nan_to_num(np.abs(v), nan=np.inf))),
        ab,
    )


# ----------------------------------------------------------------------------- r = 0


_LAMBERT_RHO = ((0.8, 0.5, 0.2), (1.0, 1.0, 1.0))


def _plan_lambert(b, rng):
    wi, wo = _random_pairs(rng, 12, lo=0.01)
    rho = np.resize(np.array(_LAMBERT_RHO), (12, 3))
    return {
        "s": b.add(wi, wo, 0.0, rho),
        "rho": rho,
        "alb_mu": np.array([0.05, 0.5, 1.0]),
        "alb_rho": np.resize(np.array(_LAMBERT_RHO), (3, 3)),
    }


def _lambert(f, p, e_alb, skip, rel, ab):
    pid = "property.lambert_at_zero"
    v = f[p["s"]]
    ref = p["rho"] / math.pi
    d = np.abs(v - ref) / _tol(ref, rel, ab)
    d = float(np.max(np.nan_to_num(d, nan=np.inf)))
    da = 0.0
    if e_alb is not None:
        ea = e_alb[skip:]
        da = float(np.max(np.nan_to_num(np.abs(ea - p["alb_rho"]) / _tol(p["alb_rho"], rel, ab), nan=np.inf)))
    if max(d, da) <= 1.0:
        return _check(
            pid,
            "pass",
            "roughness 0 is Lambert: f = rho/pi" + (", E = rho" if e_alb is not None else ""),
            max(d, da),
            1.0,
        )
    if d > 1.0:
        k = int(np.argmax(np.nan_to_num(np.abs(v - ref).max(1), nan=np.inf)))
        ratio = v[k, 0] / ref[k, 0] if ref[k, 0] else math.inf
        text = f"at roughness 0, f = {v[k, 0]:.5g} where Lambert's rho/pi = {ref[k, 0]:.5g} (x {ratio:.4g})"
    else:
        k = int(np.argmax(np.abs(e_alb[skip:] - p["alb_rho"]).max(1)))  # type: ignore[index]
        text = f"at roughness 0, the albedo is {e_alb[skip + k, 0]:.5g} where Lambert's is rho = {p['alb_rho'][k, 0]:g}"  # type: ignore[index]
    return _check(pid, "fail", text, max(d, da), 1.0)


def _lambert_albedo_only(albedo, rel, ab):
    mu = np.array([0.05, 0.5, 1.0])
    rho = np.resize(np.array(_LAMBERT_RHO), (3, 3))
    e = np.asarray(albedo(mu, np.zeros(3), rho), np.float64)
    d = float(np.max(np.nan_to_num(np.abs(e - rho) / _tol(rho, rel, ab), nan=np.inf)))
    status = "pass" if d <= 1.0 else "fail"
    return _check("property.lambert_at_zero", status, f"albedo at roughness 0 against rho: {d:.3g} tolerances", d, 1.0)


# ----------------------------------------------------------------------------- clamps


_SWEEP_MU = np.geomspace(1e-4, 1.0, 161)
_SWEEP_R = np.linspace(0.0, 1.0, 101)
_SWEEP_PHI = np.linspace(0.0, math.pi, 91)


def _plan_clamp(b, rmax):
    """Sweeps (name, x, slice, (wi, wo, roughness)) of mu_o, mu_i, roughness and the azimuth."""
    rho = (0.8, 0.5, 0.2)
    n, m, k = len(_SWEEP_MU), len(_SWEEP_R), len(_SWEEP_PHI)
    # the other direction grazing at the same azimuth: f ~ s / max(mu_i, mu_o) ~ 1 / mu there,
    # so a floor of either mu shows
    fixed = np.repeat(_dir(_SWEEP_MU[0], 0.2)[None], n, 0)
    grazing = _dir(_SWEEP_MU, 0.2)
    wi_r, wo_r = np.repeat(_dir(0.6, 0.3)[None], m, 0), np.repeat(_dir(0.4, 2.0)[None], m, 0)
    wi_p, wo_p = _dir(0.6, 0.4 + _SWEEP_PHI), np.repeat(_dir(0.5, 0.4)[None], k, 0)
    sweeps = []
    for name, x, wi, wo, r in (
        ("mu_o", _SWEEP_MU, fixed, grazing, np.full(n, rmax)),
        ("mu_i", _SWEEP_MU, grazing, fixed, np.full(n, rmax)),
        ("roughness", _SWEEP_R * rmax, wi_r, wo_r, _SWEEP_R * rmax),
        ("the azimuth difference phi (rad)", _SWEEP_PHI, wi_p, wo_p, np.full(k, rmax)),
    ):
        sweeps.append((name, x, b.add(wi, wo, r, rho), (wi, wo, r)))
    return sweeps


def _flat_end(y, yref, rel, ab):
    """(side, count) of the longest flat run at either end of ``y`` over which ``yref`` changes by
    more than CLAMP_FACTOR tolerances; (None, 0) when there is none."""
    best = (None, 0)
    for side, yy, rr in (("low", y, yref), ("high", y[::-1], yref[::-1])):
        tol = _tol(yy[0], rel, ab)
        flat = np.abs(yy - yy[0]) <= tol
        n = int(np.argmin(flat)) if not flat.all() else len(flat)
        if n >= CLAMP_MIN_POINTS and n < len(yy) and abs(rr[n - 1] - rr[0]) > CLAMP_FACTOR * _tol(rr[0], rel, ab):
            if n > best[1]:
                best = (side, n)
    return best


def _clamp(f, sweeps, model, rel, ab):
    pid = "property.clamp"
    from ..models import evaluate

    found = []
    for name, x, s, (wi, wo, r) in sweeps:
        y = f[s][:, 0]
        if not np.isfinite(y).all():
            continue
        yref = np.asarray(evaluate(model, wi, wo, r, (0.8, 0.5, 0.2)), np.float64)[:, 0]
        side, n = _flat_end(y, yref, rel, ab)
        if side is None:
            continue
        xs = x if side == "low" else x[::-1]
        # the sweeps of mu are geometric: the bound is the geometric mean of the two points
        bound = math.sqrt(xs[n - 1] * xs[n]) if name.startswith("mu") else 0.5 * (xs[n - 1] + xs[n])
        rel_word = "below" if side == "low" else "above"
        found.append(
            f"the output stops changing for {name} {rel_word} {bound:.3g} (a {'floor' if side == 'low' else 'clamp'} "
            f"at about {bound:.3g}, between {min(xs[n - 1], xs[n]):.3g} and {max(xs[n - 1], xs[n]):.3g}) where "
            f"{model} keeps changing"
        )
    if not found:
        return _check(
            pid, "pass", "no clamp or floor: the output follows mu_i, mu_o, roughness and phi over their ranges", 0, 0
        )
    return _check(pid, "fail", "; ".join(found), len(found), 0)


# ----------------------------------------------------------------------------- azimuth


def _plan_azimuth(b, rng, rmax):
    n = 16
    mu = rng.uniform(0.05, 1.0, (n, 2))
    phi_o = rng.uniform(0.0, 2.0 * math.pi, n)
    delta = rng.uniform(0.1, math.pi - 0.1, n)
    wo = _dir(mu[:, 1], phi_o)
    r = np.resize(np.array([0.5, 1.0]) * rmax, n)
    return {
        "p": b.add(_dir(mu[:, 0], phi_o + delta), wo, r, (0.8, 0.5, 0.2)),
        "m": b.add(_dir(mu[:, 0], phi_o - delta), wo, r, (0.8, 0.5, 0.2)),
        "delta": delta,
    }


def _azimuth(f, p, rel, ab):
    pid = "property.azimuth"
    a, m = f[p["p"]], f[p["m"]]
    d = np.abs(a - m) / (2.0 * _tol(np.maximum(np.abs(a), np.abs(m)), rel, ab))
    d = np.nan_to_num(d, nan=0.0).max(axis=1)
    if not (d > 1.0).any():
        return _check(pid, "pass", f"azimuthally symmetric: f(phi) = f(-phi) on {len(d)} pairs", float(d.max()), 1.0)
    k = int(np.argmax(d))
    return _check(
        pid,
        "fail",
        f"not azimuthally symmetric: f(phi_o + {p['delta'][k]:.3g}) = {a[k, 0]:.5g} but f(phi_o - {p['delta'][k]:.3g}) "
        f"= {m[k, 0]:.5g} ({int((d > 1).sum())} of {len(d)} pairs): f must depend on the azimuth only through "
        "cos(phi_i - phi_o), i.e. through L.V (e.g. a sign error in s = L.V - mu_i mu_o's y term)",
        float(d.max()),
        1.0,
    )


# ----------------------------------------------------------------------------- from vector rows

#: ids of the properties a vector file's rows can show (the others need queries of their own)
VECTOR_PROPERTY_IDS = ("property.reciprocity", "property.horizon", "property.lambert_at_zero")


def vector_properties(
    vectors: VectorSet, out: Any, rel: float = 1e-4, ab: float = 1e-6, half: bool = False
) -> list[dict]:
    """The properties a file of answered vectors can show, from its rows alone.

    ``property.reciprocity`` from every pair of BRDF rows of one model, roughness and rho
    whose directions are swapped (the default set holds such pairs, ``vectors.SWAPPED_PAIRS``);
    ``property.horizon`` from the rows with wi.z <= 0 or wo.z <= 0; ``property.lambert_at_zero``
    from the rows at roughness 0 (f = rho/pi, E = rho).  A property with no such rows is "skip".
    ``half``: the values are declared float16: one float16 ulp (<= 2^-10 relative, 2^-24
    absolute) more is allowed.

    Examples
    --------
    >>> from openpbr_diffuse.conformance.vectors import default_vectors
    >>> from openpbr_diffuse.conformance.deviations import reference
    >>> v = default_vectors(["eon"])
    >>> out = reference(v)
    >>> [c["status"] for c in vector_properties(v, out)]
    ['pass', 'pass', 'pass']
    >>> mu_i = np.where(v.kind == "brdf", v.wi[:, 2], 1.0)[:, None]
    >>> vector_properties(v, out * (1 + mu_i))[0]["detail"][:40]
    'not reciprocal: f(wi,wo)/f(wo,wi) up to '
    """
    out = np.asarray(out, np.float64)
    if half:
        rel, ab = rel + 2.0**-10, ab + 2.0**-24
    brdf = vectors.kind == "brdf"
    fin = np.isfinite(out).all(axis=1)
    checks = []
    # reciprocity: swapped pairs, matched on inputs rounded to 1e-5 (vectorised keys)
    idx = np.flatnonzero(brdf & fin & (vectors.wi[:, 2] > 0) & (vectors.wo[:, 2] > 0))
    base = np.concatenate(
        [np.round(np.nan_to_num(vectors.roughness[idx], nan=-1.0), 5)[:, None], np.round(vectors.rho[idx], 5)], 1
    )
    wi_r, wo_r = np.round(vectors.wi[idx], 5), np.round(vectors.wo[idx], 5)
    models = vectors.model[idx].tolist()
    keys = [(m, *k) for m, k in zip(models, np.concatenate([base, wi_r, wo_r], 1).tolist(), strict=True)]
    swapped = [(m, *k) for m, k in zip(models, np.concatenate([base, wo_r, wi_r], 1).tolist(), strict=True)]
    key: dict[tuple, int] = {}
    for pos, k in enumerate(keys):
        key.setdefault(k, pos)
    same = np.all(wi_r == wo_r, axis=1)
    a_rows, b_rows = [], []
    for pos, k in enumerate(swapped):
        j = key.get(k)
        if j is not None and j > pos and not same[pos]:
            a_rows.append(int(idx[pos]))
            b_rows.append(int(idx[j]))
    if a_rows:
        a, b = np.array(a_rows), np.array(b_rows)
        plan = {
            "a": slice(0, len(a)),
            "b": slice(len(a), 2 * len(a)),
            "mu_i": vectors.wi[a, 2],
            "mu_o": vectors.wo[a, 2],
        }
        checks.append(_reciprocity(np.concatenate([out[a], out[b]]), plan, rel, ab))
        checks[-1]["detail"] += " (from the swapped pairs among the rows)"
    else:
        checks.append(_check("property.reciprocity", "skip", "no pair of rows with wi and wo swapped"))
    # horizon
    below = brdf & ((vectors.wi[:, 2] <= 0) | (vectors.wo[:, 2] <= 0))
    if below.any():
        plan = {"s": np.flatnonzero(below), "wi": vectors.wi[below], "wo": vectors.wo[below]}
        checks.append(_horizon(out, plan, ab))
    else:
        checks.append(_check("property.horizon", "skip", "no row below the horizon"))
    # roughness 0: Lambert
    zero = (vectors.roughness == 0) & fin & (~brdf | ~below)
    if zero.any():
        ref = np.where(brdf[zero, None], vectors.rho[zero] / math.pi, vectors.rho[zero])
        albedo_zero = ~brdf[zero] & (vectors.mu[zero] == 0)  # mu = 0: 0 (single-sided) is accepted
        got = out[zero]
        d = np.abs(got - ref) / _tol(ref, rel, ab)
        d = np.where(albedo_zero[:, None] & (np.abs(got) <= ab), 0.0, d)
        worst = float(d.max())
        if worst <= 1.0:
            checks.append(_check("property.lambert_at_zero", "pass", "roughness-0 rows are Lambert", worst, 1.0))
        else:
            j = int(np.argmax(d.max(axis=1)))
            what = "f" if brdf[zero][j] else "the albedo"
            checks.append(
                _check(
                    "property.lambert_at_zero",
                    "fail",
                    f"at roughness 0, {what} = {got[j, 0]:.5g} where Lambert gives {ref[j, 0]:.5g} "
                    f"(row {vectors.id[zero][j]})",
                    worst,
                    1.0,
                )
            )
    else:
        checks.append(_check("property.lambert_at_zero", "skip", "no row at roughness 0"))
    return checks


__all__ = ["PROPERTY_IDS", "VECTOR_PROPERTY_IDS", "check_properties", "vector_properties"]
