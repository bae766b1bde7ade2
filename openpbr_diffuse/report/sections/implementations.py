"""Graded implementations: the test vectors, and the grader's self-test on the known deviations.

The reference rounded to float32 must pass; an implementation with each known deviation
(its prediction by :mod:`openpbr_diffuse.conformance.deviations`, rounded to float32 like a
shader's output) must fail and be diagnosed as that deviation.  Real implementations run by
their own code are graded in the next section ("graders").
"""

from __future__ import annotations

import numpy as np

from ..model import CheckTable, Context, SectionResult, Table

TITLE = "Grader self-test: test vectors and known deviations"

#: The section's checks, declared once: (id, title, runs in --quick); ``--list-checks`` reads
#: this table, ``--quick`` lists the checks marked False as not run.
CHECKS = CheckTable(
    'implementations',
    [
        ('implementations.reference_rounded_to_float32_conforms', 'reference rounded to float32 conforms', True),
        (
            'implementations.no_energy_compensation_qon_fails_and_is_diagnosed',
            'no_energy_compensation_qon: fails and is diagnosed',
            True,
        ),
        (
            'implementations.no_energy_compensation_fon_fails_and_is_diagnosed',
            'no_energy_compensation_fon: fails and is diagnosed',
            True,
        ),
        (
            'implementations.rho_ms_extra_inv_pi_fails_and_is_diagnosed',
            'rho_ms_extra_inv_pi: fails and is diagnosed',
            True,
        ),
        ('implementations.rho_ms_extra_rho_fails_and_is_diagnosed', 'rho_ms_extra_rho: fails and is diagnosed', True),
        ('implementations.ldotv_clamped_fails_and_is_diagnosed', 'ldotv_clamped: fails and is diagnosed', True),
        ('implementations.white_tint_fails_and_is_diagnosed', 'white_tint: fails and is diagnosed', True),
        ('implementations.times_cos_theta_i_fails_and_is_diagnosed', 'times_cos_theta_i: fails and is diagnosed', True),
        (
            'implementations.roughness_sigma_vs_r_fails_and_is_diagnosed',
            'roughness_sigma_vs_r: fails and is diagnosed',
            True,
        ),
        ('implementations.roughness_squared_fails_and_is_diagnosed', 'roughness_squared: fails and is diagnosed', True),
        (
            'implementations.no_energy_compensation_lambert_fails_and_is_diagnosed',
            'no_energy_compensation_lambert: fails and is diagnosed',
            True,
        ),
        (
            'implementations.eq14_fit_for_exact_fails_and_is_diagnosed',
            'eq14_fit_for_exact: fails and is diagnosed',
            True,
        ),
        ('implementations.constant_factor_fails_and_is_diagnosed', 'constant_factor: fails and is diagnosed', True),
        ('implementations.ms_missing_inv_pi_fails_and_is_diagnosed', 'ms_missing_inv_pi: fails and is diagnosed', True),
        (
            'implementations.divided_by_cos_theta_i_fails_and_is_diagnosed',
            'divided_by_cos_theta_i: fails and is diagnosed',
            True,
        ),
        ('implementations.roughness_degrees_fails_and_is_diagnosed', 'roughness_degrees: fails and is diagnosed', True),
        ('implementations.rho_srgb_encoded_fails_and_is_diagnosed', 'rho_srgb_encoded: fails and is diagnosed', True),
        ('implementations.mu_floor_fails_and_is_diagnosed', 'mu_floor: fails and is diagnosed', True),
        (
            'implementations.roughness_sigma_over_sqrt2_fails_and_is_diagnosed',
            'roughness_sigma_over_sqrt2: fails and is diagnosed',
            True,
        ),
        (
            'implementations.qon_fujii_constants_fails_and_is_diagnosed',
            'qon_fujii_constants: fails and is diagnosed',
            True,
        ),
        (
            'implementations.rho_ms_from_scalar_rho_fails_and_is_diagnosed',
            'rho_ms_from_scalar_rho: fails and is diagnosed',
            True,
        ),
        (
            'implementations.ms_missing_mu_i_factor_fails_and_is_diagnosed',
            'ms_missing_mu_i_factor: fails and is diagnosed',
            True,
        ),
        (
            'implementations.avg_albedo_constant_fails_and_is_diagnosed',
            'avg_albedo_constant: fails and is diagnosed',
            True,
        ),
        ('implementations.roughness_floor_fails_and_is_diagnosed', 'roughness_floor: fails and is diagnosed', True),
        (
            'implementations.nonzero_below_horizon_fails_and_is_diagnosed',
            'nonzero_below_horizon: fails and is diagnosed',
            True,
        ),
    ],
)


def build(ctx: Context) -> SectionResult:
    from ...conformance.deviations import DEVIATIONS, reference
    from ...conformance.grade import ABS_TOL, REL_TOL, TOLERANCE_REASON, grade
    from ...conformance.vectors import default_vectors

    v = default_vectors()
    ctx.progress("reference values")
    ref = reference(v)
    res = SectionResult("implementations", TITLE)
    res.notes.append(
        f"Test vectors version {v.version}: {len(v)} rows ({int((v.kind == 'brdf').sum())} BRDF, "
        f"{int((v.kind == 'albedo').sum())} albedo) over {', '.join(sorted(set(v.model)))}, including grazing "
        "(mu = 0.01, 0.001), backscatter, s = 0, L.V < 0, below-horizon directions, r = 0 and 1, mu = 0. "
        "Write them with `openpbr-diffuse vectors --out vectors.csv`, append out_r, out_g, out_b, and grade "
        "with `openpbr-diffuse check vectors.csv`."
    )
    res.notes.append(f"Tolerance: {TOLERANCE_REASON}")
    g32 = grade(v, ref.astype(np.float32))
    res.checks.append(
        CHECKS.check(
            "reference rounded to float32 conforms",
            g32.max_normalised_error,
            1.0,
            "<=",
            reference="openpbr_diffuse.conformance.deviations.reference (float64 evaluate / directional_albedo)",
            unit="x tolerance",
            detail=f"max abs error {g32.max_abs_error:.2e} over {g32.n_rows} rows",
        )
    )
    rows = []
    for name, dev in DEVIATIONS.items():
        ctx.progress(f"deviation {name}")
        pred = dev(v)
        known = np.isfinite(pred).all(axis=1)
        sub = v.subset(known)
        g = grade(sub, pred[known].astype(np.float32))
        ok = (not g.passed) and g.diagnosis == name
        detail = g.candidate_details.get(name, {})
        res.checks.append(
            CHECKS.check(
                f"{name}: fails and is diagnosed",
                1.0 if ok else 0.0,
                0.0,
                "==",
                expected=1.0,
                reference=f"{dev.source}; predicted with the library's models ({dev.variants[0][0]})",
                detail=f"diagnosis {g.diagnosis}; {g.n_failed_rows} of {g.n_rows} rows outside the tolerance",
            )
        )
        rows.append(
            [
                name,
                dev.description,
                dev.source,
                g.n_failed_rows,
                g.n_rows,
                g.max_abs_error,
                g.max_normalised_error,
                g.diagnosis or "none",
                detail.get("explained_fraction", float("nan")),
            ]
        )
    res.tables.append(
        Table(
            f"Known deviations as float32 implementations, graded at |out - ref| <= {ABS_TOL:g} + {REL_TOL:g} |ref|",
            [
                "deviation",
                "what",
                "seen in",
                "rows failing",
                "rows",
                "max abs error",
                "max error / tolerance",
                "diagnosis",
                "failing values explained",
            ],
            rows,
        )
    )
    return res
