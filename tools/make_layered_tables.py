"""Regenerate the layered-surface grading tables and figure shipped in openpbr_diffuse/data/.

- layered_grading.csv: the diffuse part of the directional albedo of a Lambertian base
  under a dielectric layer, physics (exact closed form for a smooth interface, simulation
  for GGX) and every rule of ``approximations.layering_grading``;
- layered_grading_eon.csv: the same for an EON base (OpenPBR's rules);
- layered_gotanda_absorption.csv: Gotanda 2012 Eq. 3 against Eq. 2, and Eq. 9 against the
  cosine-weighted integral of Eq. 2;
- layered_grading.png: relative error of each rule against the physics.

Usage: python tools/make_layered_tables.py [--paths N] [--seed S] [--workers W]
Writes each file to a temporary name and renames it when complete.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from openpbr_diffuse._version import __version__
from openpbr_diffuse.approximations import gotanda2012_layered as g
from openpbr_diffuse.approximations import layering_grading as lg
from openpbr_diffuse.simulation.layered import (
    LayeredSurface,
    simulate_layered_albedo,
    smooth_lambert_albedo,
)

N = (1.3, 1.5, 1.7, 2.0)
ALPHA = (0.0, 0.04, 0.25, 0.64)
TAU = (0.0, 0.1, 0.5)
MU = (1.0, 0.7, 0.4, 0.2, 0.1)
RHO = (0.2, 0.5, 0.8, 1.0)


def _write(path: Path, header: list[str], names: list[str], rows: list[list]) -> None:
    tmp = path.with_suffix(path.suffix + ".tmp")
    with tmp.open("w", encoding="utf-8") as fh:
        for h in header:
            fh.write(f"# {h}\n")
        fh.write(",".join(names) + "\n")
        for r in rows:
            fh.write(",".join(f"{v:.10g}" if isinstance(v, float) else str(v) for v in r) + "\n")
    os.replace(tmp, path)


def grading(paths: int, seed: int, workers: int | None) -> tuple[list[str], list[list]]:
    names = [
        "interface_alpha",
        "roughness",
        "n",
        "tau",
        "mu",
        "rho",
        "physics",
        "physics_se",
        "physics_specular",
        "physics_specular_se",
        "openpbr_E_spec",
        *lg.RULES,
    ]
    rows = []
    mu = np.array(MU)
    rho = np.array(RHO)
    for a in ALPHA:
        for n in N:
            for tau in TAU:
                r = math.sqrt(a)
                if a == 0.0:
                    phys = np.array([smooth_lambert_albedo(n, rho, m, tau) - g.fresnel(m, n) for m in mu])
                    se = np.zeros_like(phys)
                    spec = np.repeat(g.fresnel(mu, n)[:, None], rho.size, axis=1)
                    spec_se = np.zeros_like(spec)
                else:
                    s = LayeredSurface("ggx", n, a, absorption=tau, thickness=1.0)
                    e = simulate_layered_albedo(s, mu, rho=rho, paths=paths, seed=seed, workers=workers)
                    phys, se, spec, spec_se = e.diffuse, e.diffuse_stderr, e.specular, e.specular_stderr
                es = lg.spec_albedo(mu, n, r)
                vals = [
                    np.broadcast_to(lg.diffuse_albedo(rule, mu[:, None], n, rho[None, :], r, tau), phys.shape)
                    for rule in lg.RULES
                ]
                for i, m in enumerate(mu):
                    for c, p in enumerate(rho):
                        rows.append(
                            [
                                a,
                                r,
                                n,
                                tau,
                                float(m),
                                float(p),
                                float(phys[i, c]),
                                float(se[i, c]),
                                float(spec[i, c]),
                                float(spec_se[i, c]),
                                float(es[i]),
                                *(float(v[i, c]) for v in vals),
                            ]
                        )
    return names, rows


def eon_grading(paths: int, seed: int, workers: int | None) -> tuple[list[str], list[list]]:
    names = ["interface_alpha", "n", "r", "mu", "rho", "physics", "physics_se", "openpbr", "openpbr_coat"]
    rows = []
    mu = np.array(MU)
    rho = np.array(RHO)
    for a in (0.0, 0.25):
        for r in (0.5, 1.0):
            s = LayeredSurface("smooth" if a == 0 else "ggx", 1.5, a, base="eon", roughness=r)
            e = simulate_layered_albedo(s, mu, rho=rho, paths=paths, seed=seed, workers=workers)
            vals = [
                np.broadcast_to(
                    lg.eon_base_albedo(rule, mu[:, None], 1.5, rho[None, :], r, math.sqrt(a)), e.diffuse.shape
                )
                for rule in ("openpbr", "openpbr_coat")
            ]
            for i, m in enumerate(mu):
                for c, p in enumerate(rho):
                    rows.append(
                        [
                            a,
                            1.5,
                            r,
                            float(m),
                            float(p),
                            float(e.diffuse[i, c]),
                            float(e.diffuse_stderr[i, c]),
                            float(vals[0][i, c]),
                            float(vals[1][i, c]),
                        ]
                    )
    return names, rows


def gotanda_absorption() -> tuple[list[str], list[list]]:
    names = [
        "n",
        "tau",
        "mu_l",
        "mu_e",
        "eq2",
        "eq3",
        "eq3_minus_eq2",
        "eq9_ibl",
        "eq2_cosine_weighted",
        "eq9_minus_exact",
    ]
    x, w = np.polynomial.legendre.leggauss(400)
    ml, wl = 0.5 * (x + 1), 0.5 * w
    rows = []
    for n in (1.33, 1.5):
        for tau in (0.01, 0.05, 0.1, 0.2):
            for mu_e in MU:
                exact = float((2 * ml * g.beer_lambert(tau, 1.0, ml, mu_e, n) * wl).sum())
                eq9 = float(g.ibl_diffuse_factor(tau, mu_e, n, n))
                for mu_l in MU:
                    e2 = float(g.beer_lambert(tau, 1.0, mu_l, mu_e, n))
                    e3 = float(g.linear_absorption(tau, mu_l, mu_e))
                    rows.append([n, tau, mu_l, mu_e, e2, e3, e3 - e2, eq9, exact, eq9 - exact])
    return names, rows


def figure(rows_names, rows, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    idx = {k: i for i, k in enumerate(rows_names)}
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    for ax, a in zip(axes, (0.0, 0.25)):
        sel = [
            r
            for r in rows
            if r[idx["n"]] == 1.5 and r[idx["rho"]] == 0.8 and r[idx["tau"]] == 0.0 and r[idx["interface_alpha"]] == a
        ]
        mu = [r[idx["mu"]] for r in sel]
        for rule in lg.RULES:
            if rule == "kulla_conty":
                continue
            ax.plot(mu, [100 * (r[idx[rule]] / r[idx["physics"]] - 1) for r in sel], marker="o", label=rule)
        ax.axhline(0, color="k", lw=0.8)
        ax.set_xlabel("mu (cosine of view)")
        ax.set_ylabel("diffuse albedo error vs physics (%)")
        ax.set_title(f"n = 1.5, rho = 0.8, {'smooth' if a == 0 else f'GGX alpha = {a:g}'}, no absorption")
    axes[0].legend(fontsize=8)
    tmp = path.with_suffix(".tmp.png")
    fig.savefig(tmp, dpi=90)
    os.replace(tmp, path)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--paths", type=int, default=150_000)
    ap.add_argument("--seed", type=int, default=2026)
    ap.add_argument("--workers", type=int, default=None)
    args = ap.parse_args(argv)
    t0 = time.time()
    names, rows = grading(args.paths, args.seed, args.workers)
    se_max = max(r[names.index("physics_se")] for r in rows)
    _write(
        lg.TABLE,
        [
            "title: diffuse albedo of a Lambertian base under a dielectric layer: physics and layering rules",
            (
                "quantity: E_d(mu), the diffuse part of the directional albedo (light that reached the base), per rule of "
                "openpbr_diffuse.approximations.layering_grading; physics_specular: the first-interface reflection; "
                "openpbr_E_spec: OpenPBR's E_spec(mu) of the same interface"
            ),
            (
                "method: smooth interface (interface_alpha 0): exact closed form with all internal reflections "
                "(simulation.layered.smooth_lambert_albedo); GGX interface: position-free random walk "
                f"(simulation.layered, Heitz 2016 dielectric microsurface walk), {args.paths} paths per (surface, mu), "
                f"all rho share paths, seed {args.seed}; slab optical depth tau = absorption x thickness (coat_color = exp(-tau))"
            ),
            f"resolution: interface_alpha {ALPHA}; n {N}; tau {TAU}; mu {MU}; rho {RHO}",
            f"error: physics_se per entry (max {se_max:.1e}); 0 for the closed form",
            f"library: openpbr-diffuse {__version__}",
            "regenerate: python tools/make_layered_tables.py",
        ],
        names,
        rows,
    )
    en, erows = eon_grading(args.paths, args.seed, args.workers)
    _write(
        lg.DATA / "layered_grading_eon.csv",
        [
            "title: diffuse albedo of an EON base under a dielectric layer (n 1.5): simulation and OpenPBR's rules",
            (
                "quantity: E_d(mu), the diffuse part of the directional albedo; openpbr: (1 - E_spec) E_EON; openpbr_coat: "
                "(1 - E_coat)(1 - K)/(1 - rho K) E_EON (approximations.layering_grading.eon_base_albedo)"
            ),
            (
                f"method: position-free random walk (simulation.layered), EON base sampled with the library's EON sampler, "
                f"{args.paths} paths per (surface, mu), seed {args.seed}"
            ),
            f"resolution: interface_alpha (0, 0.25); r (0.5, 1); mu {MU}; rho {RHO}",
            f"error: physics_se per entry (max {max(r[6] for r in erows):.1e})",
            f"library: openpbr-diffuse {__version__}",
            "regenerate: python tools/make_layered_tables.py",
        ],
        en,
        erows,
    )
    gn, grows = gotanda_absorption()
    _write(
        lg.DATA / "layered_gotanda_absorption.csv",
        [
            (
                "title: Gotanda 2012 absorption: Eq. 3 (linear, non-refracted) against Eq. 2 (Beer-Lambert, refracted), "
                "Eq. 9 (IBL) against the cosine-weighted integral of Eq. 2 over the light"
            ),
            "quantity: transmittance I/I0 with alpha' = alpha d = tau",
            "method: closed forms; eq2_cosine_weighted by 400-point Gauss-Legendre over mu_l",
            "resolution: n (1.33, 1.5); tau (0.01, 0.05, 0.1, 0.2); mu_l, mu_e " + str(MU),
            "error: quadrature < 1e-10",
            f"library: openpbr-diffuse {__version__}",
            "regenerate: python tools/make_layered_tables.py",
        ],
        gn,
        grows,
    )
    figure(names, rows, lg.DATA / "layered_grading.png")
    print(
        f"wrote {lg.TABLE.name} ({len(rows)} rows), layered_gotanda_absorption.csv, layered_grading.png "
        f"in {time.time() - t0:.0f} s"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
