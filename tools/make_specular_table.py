#!/usr/bin/env python
"""Regenerate the GGX directional-albedo tables of the OpenPBR specular and metal lobes.

Writes two CSV files under openpbr_diffuse/data/ (each with a '#' provenance header):

- specular_albedo_conductor.csv: the basis albedos E1, E5, E6 of the GGX lobe with Fresnel
  factors 1, (1 - c)^5 and c (1 - c)^6 (c = wo.h); the F82-tint metal albedo is exactly
  F0 (E1 - E5) + E5 - a E6.  One row per (roughness, mu).
- specular_albedo_dielectric.csv: E(mu, r, x) = int F_diel(wo.h; eta) D G2/(4 mu_i mu_o)
  mu_i dwi, the single-scattering albedo of the dielectric specular lobe, with the exact
  Fresnel factor of eta = (1 + x)/(1 - x) >= 1 (x = sqrt(F0)).  One row per (roughness, x),
  one column per mu.  Its grid is a sub-grid of the conductor one.

In both, alpha = max(r^2, ALPHA_MIN) with r = specular_roughness.

Method: microfacet.quadrature.albedo_quadrature (half-vector Gauss-Legendre with panel edges at the
horizon cut, independent of the BRDF evaluation and of the samplers) at order n per panel
for the values and n/2 for the error estimate written in the header (max |Q_n - Q_n/2|).
mu = 0 is the grazing limit, evaluated at mu = MU0.

Usage:  python tools/make_specular_table.py [--n 48] [--out openpbr_diffuse/data]
"""

import argparse
import datetime
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

from openpbr_diffuse import __version__  # noqa: E402
from openpbr_diffuse.microfacet import fresnel, ggx, quadrature  # noqa: E402
from openpbr_diffuse.microfacet.tables import CONDUCTOR_FILE, DIELECTRIC_FILE, MU0, mu_grid, roughness_grid, x_grid  # noqa: E402

#: Conductor (2-D) grid, and the dielectric (3-D) grid, a sub-grid of it in (r, mu).
N_R_C, N_MU_C = 65, 65
N_R_D, N_MU_D, N_X = 33, 33, 33


def dielectric_fresnels(xs):
    def fresnels(c):
        out = np.empty((len(xs),) + c.shape)
        for k, x in enumerate(xs):
            # x = 1 is eta = infinity: F = 1 (the formula would give inf/inf)
            out[k] = 1.0 if x >= 1.0 else fresnel.fresnel_dielectric(c, fresnel.eta_of_parameter(x))
        return out

    return fresnels


def conductor_fresnels(c):
    return np.stack([np.ones_like(c), (1.0 - c) ** 5, c * (1.0 - c) ** 6])


def quad(mu, alpha, fresnels, n):
    m = max(mu, MU0)
    hi = quadrature.albedo_quadrature(m, alpha, fresnels, n, n)
    lo = quadrature.albedo_quadrature(m, alpha, fresnels, n // 2, n // 2)
    return hi, float(np.max(np.abs(hi - lo)))


def tabulate_conductor(n):
    out = np.empty((N_R_C, N_MU_C, 3))
    err = 0.0
    for i, r in enumerate(roughness_grid(N_R_C)):
        alpha = float(ggx.alpha_of(r))
        for j, mu in enumerate(mu_grid(N_MU_C)):
            out[i, j], e = quad(mu, alpha, conductor_fresnels, n)
            err = max(err, e)
    return out, err


def tabulate_dielectric(n):
    xs = x_grid(N_X)
    fres = dielectric_fresnels(xs)
    out = np.empty((N_R_D, N_X, N_MU_D))
    err = 0.0
    for i, r in enumerate(roughness_grid(N_R_D)):
        alpha = float(ggx.alpha_of(r))
        for j, mu in enumerate(mu_grid(N_MU_D)):
            out[i, :, j], e = quad(mu, alpha, fres, n)
            err = max(err, e)
    return out, err


def header(what, n, err, extra):
    return "\n".join(
        [
            f"# {what}",
            "# model: GGX NDF, Smith height-correlated G2, alpha = max(roughness^2, "
            f"{ggx.ALPHA_MIN:g}) (roughness = OpenPBR specular_roughness), single scattering",
            "# method: half-vector Gauss-Legendre quadrature with panel edges at the horizon cut "
            f"(openpbr_diffuse.microfacet.quadrature.albedo_quadrature), order {n} per panel",
            f"# error estimate of the quadrature: max |Q_{n} - Q_{n // 2}| over the table = {err:.1e} "
            f"(bounds the error of Q_{n // 2}; the stored Q_{n} is more accurate)",
            "# interpolated accuracy (tests/test_ggx.py, against an independent quadrature): <= 2e-4 for "
            "roughness >= 0.2 and mu >= 0.05, <= 6e-4 for roughness >= 0.2, <= 3e-3 for roughness < 0.2 "
            "and mu >= 0.05",
            f"# mu = 0 nodes: the grazing limit, evaluated at mu = {MU0:g}",
            *extra,
            f"# generated {datetime.date.today().isoformat()} by openpbr-diffuse {__version__} "
            f"(numpy {np.__version__})",
            "# regenerate: python tools/make_specular_table.py",
        ]
    )


def main(argv=None):
    ap = argparse.ArgumentParser(description="Regenerate the GGX albedo tables of the OpenPBR base.")
    ap.add_argument("--n", type=int, default=48, help="Gauss-Legendre order per panel (default 48)")
    ap.add_argument("--out", default=os.path.join(os.path.dirname(HERE), "openpbr_diffuse", "data"))
    args = ap.parse_args(argv)
    t0 = time.time()

    cond, err_c = tabulate_conductor(args.n)
    hc = header(
        "Basis albedos of the GGX lobe of the OpenPBR metal: E1, E5, E6 for Fresnel "
        "factors 1, (1-c)^5, c(1-c)^6 (c = wo.h)",
        args.n,
        err_c,
        [
            "# F82-tint metal albedo = F0 (E1 - E5) + E5 - a E6 (a: microfacet.fresnel.f82_coefficient)",
            f"# grid: roughness = k/{N_R_C - 1}, mu = (k/{N_MU_C - 1})^2; interpolation "
            "(microfacet.tables): Catmull-Rom in both node coordinates",
        ],
    )
    with open(os.path.join(args.out, CONDUCTOR_FILE), "w") as fh:
        fh.write(hc + "\nroughness,mu,E1,E5,E6\n")
        for i, r in enumerate(roughness_grid(N_R_C)):
            for j, mu in enumerate(mu_grid(N_MU_C)):
                fh.write(f"{r:.9g},{mu:.9g}," + ",".join(f"{v:.7f}" for v in cond[i, j]) + "\n")

    diel, err_d = tabulate_dielectric(args.n)
    hd = header(
        "Directional albedo E(mu, roughness, x) of the OpenPBR dielectric specular "
        "reflection lobe (exact dielectric Fresnel)",
        args.n,
        err_d,
        [
            "# x = sqrt(F0) of the (specular_weight-modulated) index eta = (1 + x)/(1 - x) >= 1; x = 1 means F = 1",
            f"# grid: roughness = k/{N_R_D - 1}, x = sin^2(pi k/{2 * (N_X - 1)}), mu = (k/{N_MU_D - 1})^2 (columns)",
            "# interpolation (microfacet.tables): E/E1 by tensor-product Catmull-Rom in the node "
            "coordinates of roughness, x and mu, times E1 from the conductor table",
        ],
    )
    mu_cols = ",".join(f"{m:.9g}" for m in mu_grid(N_MU_D))
    with open(os.path.join(args.out, DIELECTRIC_FILE), "w") as fh:
        fh.write(hd + f"\nroughness,x,{mu_cols}\n")
        for i, r in enumerate(roughness_grid(N_R_D)):
            for k, x in enumerate(x_grid(N_X)):
                fh.write(f"{r:.9g},{x:.9g}," + ",".join(f"{v:.6f}" for v in diel[i, k]) + "\n")
    print(
        f"wrote {CONDUCTOR_FILE} (quadrature error {err_c:.1e}) and {DIELECTRIC_FILE} "
        f"(quadrature error {err_d:.1e}) in {time.time() - t0:.0f} s"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
