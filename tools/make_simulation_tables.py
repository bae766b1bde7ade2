#!/usr/bin/env python
"""Simulate the microsurfaces and grade the lobe models against them (shipped tables + plots).

    python tools/make_simulation_tables.py              # ~5-10 min on 2 cores
    python tools/make_simulation_tables.py --quick      # a small run (minutes less; not shipped)
    python tools/make_simulation_tables.py --grade-only # re-grade from the shipped simulation tables
    python tools/make_simulation_tables.py --out DIR    # somewhere else than openpbr_diffuse/data
    python tools/make_simulation_tables.py --check      # regenerate into a temporary folder, compare

Writes ``simulation_albedo.csv``, ``simulation_brdf.csv`` (Monte Carlo, with standard
errors), ``simulation_grading.csv``, ``simulation_colorshift.csv`` and the figures
``simulation_*.png``.  Seeded: the same command gives the same numbers on any machine with
the same library version (chunks are seeded per (seed, query, chunk)).
"""

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from openpbr_diffuse import __version__  # noqa: E402
from openpbr_diffuse.simulation import CHUNK_PATHS, MAX_BOUNCES, simulate_albedo, simulate_average_albedo, simulate_brdf  # noqa: E402
from openpbr_diffuse.simulation import grading as gr  # noqa: E402

SURFACES = {
    "vcavity": (0.1, 0.2, 0.3, 0.4, 0.5, 0.7, 0.9, 1.2),
    "smith-beckmann": (0.1, 0.2, 0.3, 0.5, 0.7, 1.0, 1.4),
    "smith-ggx": (0.1, 0.2, 0.3, 0.5, 0.7, 1.0, 1.4),
}
THETA = (0.0, 20.0, 35.0, 47.5, 57.5, 66.0, 73.0, 79.0, 84.0, 88.0)  # degrees; mu = cos
RHO = (0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95, 1.0)
SLICE_THETA_I = (30.0, 60.0, 80.0)
SLICE_THETA_O = tuple(float(t) for t in np.arange(-85.0, 86.0, 10.0))  # negative: back-scattering
SLICE_RHO = (0.5, 0.8, 1.0)
SEED = 2025
PATHS = {"albedo": 200_000, "average": 1_000_000, "brdf": 200_000}
QUICK = {"albedo": 20_000, "average": 100_000, "brdf": 20_000}


def log(msg):
    sys.stderr.write(f"[{time.strftime('%H:%M:%S')}] {msg}\n")
    sys.stderr.flush()


def simulate(paths, surfaces):
    mu = np.cos(np.radians(THETA))
    alb_rows, brdf_rows = [], []
    worst_se = {"E": 0.0, "E1": 0.0, "f_rel": 0.0}
    for geometry, roughs in surfaces.items():
        for s in roughs:
            t = time.monotonic()
            est = simulate_albedo(geometry, s, mu, rho=RHO, paths=paths["albedo"], seed=SEED)
            avg = simulate_average_albedo(geometry, s, rho=RHO, paths=paths["average"], seed=SEED)
            for kind, e, mus in (("directional", est, mu), ("average", avg, [float("nan")])):
                for i, m in enumerate(mus):
                    for c, r in enumerate(RHO):
                        alb_rows.append(
                            [
                                geometry,
                                s,
                                kind,
                                m,
                                r,
                                e.albedo[i, c],
                                e.stderr[i, c],
                                *[
                                    v
                                    for o in range(3)
                                    for v in (e.albedo_by_order[i, o, c], e.stderr_by_order[i, o, c])
                                ],
                                e.bounces[i],
                                int(e.truncated[i]),
                            ]
                        )
            worst_se["E"] = max(worst_se["E"], float(est.stderr.max()))
            worst_se["E1"] = max(worst_se["E1"], float(est.stderr_by_order[:, 0].max()))
            ti, to = np.meshgrid(np.radians(SLICE_THETA_I), np.radians(SLICE_THETA_O), indexing="ij")
            wi, wo = gr.slice_directions(ti.ravel(), to.ravel())
            f = simulate_brdf(geometry, s, wi, wo, rho=SLICE_RHO, paths=paths["brdf"], seed=SEED)
            for k in range(len(wi)):
                for c, r in enumerate(SLICE_RHO):
                    brdf_rows.append(
                        [
                            geometry,
                            s,
                            float(np.degrees(ti.ravel()[k])),
                            float(np.degrees(to.ravel()[k])),
                            r,
                            f.f[k, c],
                            f.stderr[k, c],
                            *[v for o in range(3) for v in (f.f_by_order[k, o, c], f.stderr_by_order[k, o, c])],
                        ]
                    )
            worst_se["f_rel"] = max(worst_se["f_rel"], float(np.max(f.stderr / f.f)))
            log(f"{geometry} {s:g}: {time.monotonic() - t:.1f} s")
    return alb_rows, brdf_rows, worst_se


def provenance(title, quantity, method, resolution, error):
    return {
        "title": title,
        "quantity": quantity,
        "method": method,
        "resolution": resolution,
        "error": error,
        "library": f"openpbr-diffuse {__version__}",
        "regenerate": "python tools/make_simulation_tables.py",
    }


def write_simulation(out, paths, alb_rows, brdf_rows, worst_se):
    surf = "; ".join(f"{g}: {', '.join(f'{s:g}' for s in r)}" for g, r in SURFACES.items())
    method = (
        "Monte Carlo light transport (openpbr_diffuse.simulation): V-cavities of Oren & Nayar 1994 (slope-area "
        "density ~ exp(-theta_a^2/2sigma^2) sin(theta_a), uniform groove azimuth, masking, shadowing and all "
        "interreflections) and the Smith random walk of Heitz et al. 2016 with Lambertian microfacets "
        f"(Beckmann, GGX); paths cut after {MAX_BOUNCES} bounces scored rho^k (exact at rho = 1); "
        f"seed {SEED}, chunks of {CHUNK_PATHS} paths"
    )
    gr.write_csv(
        out / gr.TABLES["albedo"],
        provenance(
            "simulated albedo of rough Lambertian microsurfaces",
            "E (directional: mu = cos theta_i; average: <E> = 2 int E mu dmu, mu empty) per microfacet albedo rho, "
            "total and by bounce order (E1, E2, E3 = orders 1, 2, >= 3), each with its standard error (_se); "
            "bounces: mean bounces per path; truncated: paths cut at the bounce limit",
            method,
            f"surfaces (roughness: sigma rad / alpha): {surf}; theta_i (deg): {', '.join(f'{t:g}' for t in THETA)}; "
            f"rho: {', '.join(f'{r:g}' for r in RHO)}; {paths['albedo']} paths per (surface, mu), "
            f"{paths['average']} per average (all rho share paths)",
            f"standard errors per entry; max {worst_se['E']:.1e} (E), {worst_se['E1']:.1e} (E1)",
        ),
        [
            "geometry",
            "roughness",
            "kind",
            "mu",
            "rho",
            "E",
            "E_se",
            "E1",
            "E1_se",
            "E2",
            "E2_se",
            "E3",
            "E3_se",
            "bounces",
            "truncated",
        ],
        alb_rows,
    )
    gr.write_csv(
        out / gr.TABLES["brdf"],
        provenance(
            "simulated BRDF slices of rough Lambertian microsurfaces",
            "f(wi, wo) without the cosine, in the plane of incidence: wi = (sin theta_i, 0, cos theta_i), "
            "wo = (-sin theta_o, 0, cos theta_o) (theta_o < 0: back towards the light), total and by bounce order "
            "(f1, f2, f3 = orders 1, 2, >= 3), standard errors _se",
            method + "; next-event estimation towards wo at every bounce (no binning)",
            f"theta_i (deg): {', '.join(f'{t:g}' for t in SLICE_THETA_I)}; theta_o (deg): -85..85 step 10; "
            f"rho: {', '.join(f'{r:g}' for r in SLICE_RHO)}; {paths['brdf']} paths per (surface, theta_i)",
            f"standard errors per entry; max relative {worst_se['f_rel']:.1e}",
        ),
        [
            "geometry",
            "roughness",
            "theta_i",
            "theta_o",
            "rho",
            "f",
            "f_se",
            "f1",
            "f1_se",
            "f2",
            "f2_se",
            "f3",
            "f3_se",
        ],
        brdf_rows,
    )


def grade(out):
    _, alb = gr.read_csv(out / gr.TABLES["albedo"])
    _, brdf = gr.read_csv(out / gr.TABLES["brdf"])
    rows = gr.grade_all(alb, brdf, progress=log)
    cols = [
        "model",
        "geometry",
        "roughness",
        "fit",
        "roughness_name",
        "model_roughness",
        "albedo_rms",
        "albedo_max",
        "albedo_stderr",
        "single_rms",
        "single_max",
        "brdf_rel_rms",
        "brdf_rel_max",
        "n_slices",
    ]
    gr.write_csv(
        out / gr.TABLES["grading"],
        provenance(
            "lobe models graded against the simulated microsurfaces",
            "per model and simulated surface: model_roughness (sigma or r) fitted to minimise the RMS of "
            f"E_model(mu; rho) - E_sim(mu; rho) over the table's mu and rho in {gr.FIT_RHO} (fit = 'albedo'), or "
            f"the RMS relative error of the BRDF slices at rho = {gr.BRDF_RHO} (fit = 'brdf'); "
            "'same sigma': the V-cavity's own sigma, sigma models only; albedo_rms / albedo_max: that albedo error; "
            "albedo_stderr: RMS standard error of the simulated values; single_rms / single_max: the model's "
            "rho-linear albedo (rho -> 0 of E/rho) against the simulated order-1 albedo at rho = 1; brdf_rel_rms / "
            f"brdf_rel_max: relative error of f against the simulated in-plane slices at rho = {gr.BRDF_RHO}",
            "openpbr_diffuse.simulation.grading.grade_all on simulation_albedo.csv and simulation_brdf.csv "
            "(models by openpbr_diffuse.directional_albedo / evaluate; full_on albedo from its reference table)",
            "every graded model x every simulated surface",
            "see the standard errors of the simulation tables",
        ),
        cols,
        [[r[c] for c in cols] for r in rows],
    )
    # colour shift: EON at its fitted r for each surface
    cs_rows = []
    for r in rows:
        if r["model"] != "eon" or r["fit"] != "albedo":
            continue
        cs = gr.eon_colorshift(alb, r["geometry"], r["roughness"], r["model_roughness"])
        for k, x in enumerate(cs["rho"]):
            cs_rows.append(
                [
                    r["geometry"],
                    r["roughness"],
                    r["model_roughness"],
                    x,
                    cs["E_sim"][k],
                    cs["E_se"][k],
                    cs["E_eon"][k],
                    cs["ms_sim"][k],
                    cs["ms_eon"][k],
                    cs["ratio_sim"][k],
                    cs["ratio_eon"][k],
                    cs["ms_fraction_sim"],
                    cs["ms_fraction_eon"],
                ]
            )
    gr.write_csv(
        out / gr.TABLES["colorshift"],
        provenance(
            "EON's multiple-scattering colour shift against the simulated microsurfaces",
            "per simulated surface and rho, EON at its fitted r: E_sim / E_eon average albedo <E>(rho); ms_sim = "
            "<E_>=2>(rho) / <E_>=2>(1) (simulated multi-bounce albedo, normalised), ms_eon = rho_ms(rho) (EON Eq. 18, "
            "rho_ms(1) = 1); ratio_* = <E>(rho) / rho (the albedo's nonlinearity in rho); ms_fraction_sim = <E_>=2>(1), "
            "ms_fraction_eon = 1 - <E_F> (the share of multiple scattering at rho = 1)",
            "openpbr_diffuse.simulation.grading.eon_colorshift on simulation_albedo.csv (average-albedo rows)",
            "the rho grid of simulation_albedo.csv",
            "see E_se (standard error of E_sim)",
        ),
        [
            "geometry",
            "roughness",
            "r_eon",
            "rho",
            "E_sim",
            "E_se",
            "E_eon",
            "ms_sim",
            "ms_eon",
            "ratio_sim",
            "ratio_eon",
            "ms_fraction_sim",
            "ms_fraction_eon",
        ],
        cs_rows,
    )
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ROOT / "openpbr_diffuse" / "data")
    ap.add_argument("--quick", action="store_true", help="10x fewer paths")
    ap.add_argument("--grade-only", action="store_true", help="re-grade and re-plot from existing simulation tables")
    ap.add_argument("--no-plots", action="store_true")
    ap.add_argument(
        "--check",
        action="store_true",
        help="regenerate into a temporary folder and compare with the tables in --out (exit 1 if they differ)",
    )
    args = ap.parse_args(argv)
    if args.check:
        import tempfile

        with tempfile.TemporaryDirectory() as tmp:
            main(["--out", tmp, "--no-plots"] + (["--quick"] if args.quick else []))
            bad = []
            for name in gr.TABLES.values():
                rows = lambda path: [line for line in Path(path).read_text().splitlines() if not line.startswith("#")]
                same = rows(Path(tmp) / name) == rows(args.out / name)
                log(f"{name}: {'identical' if same else 'DIFFERS'}")
                bad += [] if same else [name]
        return 1 if bad else 0
    args.out.mkdir(parents=True, exist_ok=True)
    start = time.monotonic()
    if not args.grade_only:
        paths = QUICK if args.quick else PATHS
        alb, brdf, worst = simulate(paths, SURFACES)
        write_simulation(args.out, paths, alb, brdf, worst)
    grade(args.out)
    if not args.no_plots:
        from openpbr_diffuse.report.sections.simulation import plot_all

        for p in plot_all(args.out, args.out):
            log(f"wrote {p}")
    log(f"done in {time.monotonic() - start:.0f} s")


if __name__ == "__main__":
    sys.exit(main())
