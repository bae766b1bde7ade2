"""Layering rules for the diffuse lobe under a dielectric layer, graded against physics.

Each rule gives the diffuse part of the directional albedo, E_d(mu), of a Lambertian base
of albedo rho under a dielectric interface of index n (GGX roughness r = sqrt(alpha), r = 0
smooth) over a slab of normal optical depth tau (coat_color = exp(-tau)):

- ``openpbr``: OpenPBR's albedo scaling of the dielectric base, as ``OpenPBRSurface``
  computes it: rho (1 - E_spec(mu)), E_spec the albedo of the GGX dielectric lobe
  (``microfacet.tables.dielectric_albedo``, times the surface's default multiple-scattering
  factor); no absorption term (the
  dielectric base has none);
- ``openpbr_coat``: the coat over a base without specular (specular_weight = 0), coat
  darkening 1: rho (1 - E_coat(mu)) coat_color (1 - K)/(1 - rho K), K = 1 - (1 -
  F0)/n^2 (OpenPBR 1.1, "Coat"; ``OpenPBRSurface``);
- ``reciprocal``: the reciprocal scaling f_base (1 - E(mu_i))(1 - E(mu_o)) (Adobe
  Standard Material style), E_d = rho (1 - E(mu)) (1 - <E>);
- ``kulla_conty``: the energy-normalised reciprocal form (1 - E(mu_i))(1 - E(mu_o))/(1 - <E>)
  (Kulla & Conty 2017): for a Lambertian base its albedo equals ``openpbr``'s exactly;
- ``gotanda_1mF0``: Gotanda 2012 Eq. 1, rho (1 - F0);
- ``gotanda_layered``: Gotanda 2012 Eq. 5 and 9, rho (1 - F(mu)) max(0, 1 - tau (2 + 1/mu));
- ``weidlich_wilkie``: Weidlich & Wilkie 2007 (``weidlich_wilkie.diffuse_albedo``).

The physics: the exact closed form for a smooth interface (``simulation.layered.
smooth_lambert_albedo``), the simulation's diffuse part for rough ones (the shipped table
``data/layered_grading.csv``, ``tools/make_layered_tables.py``).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..microfacet.tables import dielectric_albedo, ggx_albedo
from . import gotanda2012_layered as g
from . import weidlich_wilkie as ww

RULES = ("openpbr", "openpbr_coat", "reciprocal", "kulla_conty", "gotanda_1mF0", "gotanda_layered", "weidlich_wilkie")
DATA = Path(__file__).resolve().parent.parent / "data"
TABLE = DATA / "layered_grading.csv"


def spec_albedo(mu: ArrayLike, n: float, roughness: float, multiscatter: bool = True) -> np.ndarray:
    """E_spec(mu) of OpenPBR's GGX dielectric lobe (index n, perceptual roughness), with
    ``OpenPBRSurface``'s default multiple-scattering factor 1 + F0 (1 - E1)/E1 (Turquin 2019).

    Example
    -------
    >>> round(float(spec_albedo(1.0, 1.5, 0.3)), 4)
    0.0397
    """
    x = math.sqrt(float(g.f0(n)))
    mu = np.asarray(mu, dtype=float)
    e = np.asarray(dielectric_albedo(mu, roughness, x), dtype=float)
    if multiscatter:
        e1 = np.asarray(ggx_albedo(mu, roughness), dtype=float)
        e = e * (1.0 + x * x * (1.0 - e1) / e1)
    return e


def spec_average(n: float, roughness: float, nq: int = 64) -> float:
    """<E_spec> = 2 int E_spec(mu) mu dmu (Gauss-Legendre).

    Example
    -------
    >>> 0.04 < spec_average(1.5, 0.0) < 0.12
    True
    """
    x, w = np.polynomial.legendre.leggauss(nq)
    mu, wm = 0.5 * (x + 1), 0.5 * w
    return float((2 * mu * spec_albedo(mu, n, roughness) * wm).sum())


def diffuse_albedo(
    rule: str, mu: ArrayLike, n: float, rho: ArrayLike, roughness: float = 0.0, tau: float = 0.0
) -> np.ndarray:
    """E_d(mu) of a Lambertian base of albedo rho under the layer, by ``rule`` (``RULES``).

    Example
    -------
    >>> round(float(diffuse_albedo("openpbr", 1.0, 1.5, 0.8, 0.0)), 3)
    0.768
    >>> round(float(diffuse_albedo("gotanda_1mF0", 0.2, 1.5, 0.8)), 3)
    0.768
    """
    mu = np.asarray(mu, dtype=float)
    rho = np.asarray(rho, dtype=float)
    if rule == "openpbr" or rule == "kulla_conty":
        return rho * (1 - spec_albedo(mu, n, roughness))
    if rule == "openpbr_coat":
        K = 1 - (1 - g.f0(n)) / n**2
        return rho * (1 - spec_albedo(mu, n, roughness)) * math.exp(-tau) * (1 - K) / (1 - rho * K)
    if rule == "reciprocal":
        return rho * (1 - spec_albedo(mu, n, roughness)) * (1 - spec_average(n, roughness))
    if rule == "gotanda_1mF0":
        return rho * (1 - g.f0(n)) * np.ones_like(mu)
    if rule == "gotanda_layered":
        return g.layered_diffuse_albedo(mu, n, rho, tau)
    if rule == "weidlich_wilkie":
        return ww.diffuse_albedo(mu, n, rho, tau)
    raise ValueError(f"rule must be one of {', '.join(RULES)}, got {rule!r}")


def eon_base_albedo(rule: str, mu: ArrayLike, n: float, rho: ArrayLike, r: float, roughness: float = 0.0) -> np.ndarray:
    """E_d(mu) of an EON base (roughness r, albedo rho) under the layer by OpenPBR's rules:
    ``openpbr`` (1 - E_spec(mu)) E_EON(mu) or ``openpbr_coat`` (1 - E_coat(mu)) (1 - K)/(1 -
    rho K) E_EON(mu) (no absorption); E_EON from the library's reference tables.

    Example
    -------
    >>> round(float(eon_base_albedo("openpbr", 1.0, 1.0, 0.8, 0.5)), 4) == round(float(
    ...     __import__("openpbr_diffuse").albedo.reference_albedo("eon", 1.0, 0.5, [0.8])[0]), 4)
    True
    """
    from ..albedo import reference_albedo

    mu, rho = np.broadcast_arrays(np.asarray(mu, dtype=float), np.asarray(rho, dtype=float))
    e = np.asarray(reference_albedo("eon", mu, r, rho[..., None]), dtype=float)[..., 0]
    if rule == "openpbr":
        return (1 - spec_albedo(mu, n, roughness)) * e
    if rule == "openpbr_coat":
        K = 1 - (1 - g.f0(n)) / n**2
        return (1 - spec_albedo(mu, n, roughness)) * (1 - K) / (1 - rho * K) * e
    raise ValueError(f"rule must be 'openpbr' or 'openpbr_coat', got {rule!r}")


def load_table(path: Path | str = TABLE) -> tuple[dict, list[dict]]:
    """(provenance header, rows as dicts of floats/str) of the shipped grading table.

    Example
    -------
    >>> header, rows = load_table()
    >>> "regenerate" in header and len(rows) > 100
    True
    """
    from .._csv import read_headed_csv

    header, names, rows = read_headed_csv(path)
    out = []
    for r in rows:
        d: dict[str, Any] = {}
        for k, v in zip(names, r):
            try:
                d[k] = float(v)
            except ValueError:
                d[k] = v
        out.append(d)
    return header, out


def error_summary(rows: list[dict[str, Any]], rule: str, **where: float) -> dict[str, Any]:
    """Largest and mean relative error |E_rule/E_phys - 1| over the rows matching ``where``.

    Example
    -------
    >>> _, rows = load_table()
    >>> s = error_summary(rows, "openpbr", interface_alpha=0.0, tau=0.0)
    >>> s["max"] > 0.1
    True
    """
    sel = [r for r in rows if all(abs(r[k] - v) < 1e-9 for k, v in where.items())]
    if not sel:
        raise ValueError(f"no rows match {where}")
    err = np.array([r[rule] / r["physics"] - 1.0 for r in sel if r["physics"] > 0])
    worst = sel[int(np.argmax(np.abs(err)))]
    return {
        "max": float(np.max(np.abs(err))),
        "mean": float(np.mean(np.abs(err))),
        "signed_worst": float(err[np.argmax(np.abs(err))]),
        "n_rows": len(sel),
        "worst_row": worst,
    }
