"""Sampling: chi-square goodness of fit, pdf normalisation, the variance curves of Fig. 10-12,
and the paper's "about 100x lower variance at grazing" claim against exact quadrature.

The claim is checked on the theta_o grid of the authors' own script
(portsmouth/EON-diffuse ``scripts/variance_plots.py``: theta_o = (pi/2) linspace(0, 0.999, 64),
rho = 1), with the variance of the throughput weight computed by quadrature
(:func:`openpbr_diffuse.sampling.quality.exact_weight_moments`) instead of Monte Carlo.
"""

from __future__ import annotations

import math

import numpy as np

from .._plot import pyplot, save
from ..model import (
    QUICK_STRATEGIES,
    CheckTable,
    Context,
    Figure,
    SectionResult,
    Table,
    in_quick,
)

TITLE = "Sampling: chi-square, normalisation, variance (Fig. 10-12)"

#: The section's checks, declared once: (id, title, runs in --quick); ``--list-checks`` reads
#: this table, ``--quick`` lists the checks marked False as not run.
CHECKS = CheckTable(
    'sampling',
    [
        ('sampling.chi_square_cosine_mu_o_0_02_r_1_p_value', 'chi-square cosine, mu_o = 0.02, r = 1: p-value', True),
        ('sampling.chi_square_cosine_mu_o_0_3_r_1_p_value', 'chi-square cosine, mu_o = 0.3, r = 1: p-value', False),
        ('sampling.chi_square_cosine_mu_o_0_9_r_1_p_value', 'chi-square cosine, mu_o = 0.9, r = 1: p-value', False),
        ('sampling.chi_square_cosine_mu_o_0_3_r_0_3_p_value', 'chi-square cosine, mu_o = 0.3, r = 0.3: p-value', False),
        ('sampling.chi_square_uniform_mu_o_0_02_r_1_p_value', 'chi-square uniform, mu_o = 0.02, r = 1: p-value', False),
        ('sampling.chi_square_uniform_mu_o_0_3_r_1_p_value', 'chi-square uniform, mu_o = 0.3, r = 1: p-value', False),
        ('sampling.chi_square_uniform_mu_o_0_9_r_1_p_value', 'chi-square uniform, mu_o = 0.9, r = 1: p-value', False),
        (
            'sampling.chi_square_uniform_mu_o_0_3_r_0_3_p_value',
            'chi-square uniform, mu_o = 0.3, r = 0.3: p-value',
            False,
        ),
        ('sampling.chi_square_ltc_mu_o_0_02_r_1_p_value', 'chi-square ltc, mu_o = 0.02, r = 1: p-value', False),
        ('sampling.chi_square_ltc_mu_o_0_3_r_1_p_value', 'chi-square ltc, mu_o = 0.3, r = 1: p-value', False),
        ('sampling.chi_square_ltc_mu_o_0_9_r_1_p_value', 'chi-square ltc, mu_o = 0.9, r = 1: p-value', False),
        ('sampling.chi_square_ltc_mu_o_0_3_r_0_3_p_value', 'chi-square ltc, mu_o = 0.3, r = 0.3: p-value', False),
        (
            'sampling.chi_square_ltc_nonneg_mu_o_0_02_r_1_p_value',
            'chi-square ltc_nonneg, mu_o = 0.02, r = 1: p-value',
            False,
        ),
        (
            'sampling.chi_square_ltc_nonneg_mu_o_0_3_r_1_p_value',
            'chi-square ltc_nonneg, mu_o = 0.3, r = 1: p-value',
            False,
        ),
        (
            'sampling.chi_square_ltc_nonneg_mu_o_0_9_r_1_p_value',
            'chi-square ltc_nonneg, mu_o = 0.9, r = 1: p-value',
            False,
        ),
        (
            'sampling.chi_square_ltc_nonneg_mu_o_0_3_r_0_3_p_value',
            'chi-square ltc_nonneg, mu_o = 0.3, r = 0.3: p-value',
            False,
        ),
        ('sampling.chi_square_cltc_mu_o_0_02_r_1_p_value', 'chi-square cltc, mu_o = 0.02, r = 1: p-value', False),
        ('sampling.chi_square_cltc_mu_o_0_3_r_1_p_value', 'chi-square cltc, mu_o = 0.3, r = 1: p-value', False),
        ('sampling.chi_square_cltc_mu_o_0_9_r_1_p_value', 'chi-square cltc, mu_o = 0.9, r = 1: p-value', False),
        ('sampling.chi_square_cltc_mu_o_0_3_r_0_3_p_value', 'chi-square cltc, mu_o = 0.3, r = 0.3: p-value', False),
        ('sampling.chi_square_eon_mu_o_0_02_r_1_p_value', 'chi-square eon, mu_o = 0.02, r = 1: p-value', True),
        ('sampling.chi_square_eon_mu_o_0_3_r_1_p_value', 'chi-square eon, mu_o = 0.3, r = 1: p-value', False),
        ('sampling.chi_square_eon_mu_o_0_9_r_1_p_value', 'chi-square eon, mu_o = 0.9, r = 1: p-value', False),
        ('sampling.chi_square_eon_mu_o_0_3_r_0_3_p_value', 'chi-square eon, mu_o = 0.3, r = 0.3: p-value', False),
        ('sampling.pdf_normalisation_max_integral_of_pdf_1', 'pdf normalisation: max |integral of pdf - 1|', True),
        (
            'sampling.exact_variance_quadrature_converged_at_theta_o_0_999_pi_2',
            'exact variance quadrature converged at theta_o = 0.999 pi/2',
            True,
        ),
        (
            'sampling.eon_sampler_unbiased_max_e_w_1_on_the_authors_grid',
            "EON sampler unbiased: max |E[w] - 1| on the authors' grid",
            True,
        ),
        (
            'sampling.variance_ratio_cosine_eon_at_the_authors_last_point_theta_o_',
            "variance ratio cosine / EON at the authors' last point (theta_o = 0.999 pi/2)",
            True,
        ),
        (
            'sampling.monte_carlo_variance_vs_exact_quadrature_r_1_theta_o_70_88_8',
            'Monte Carlo variance vs exact quadrature (r = 1, theta_o = 70, 88.854 deg)',
            True,
        ),
    ],
)

ALPHA = 0.01
#: The authors' grid (scripts/variance_plots.py).
AUTHORS_THETA = 0.5 * math.pi * np.linspace(0.0, 0.999, 64)
CURVE_THETA = (0, 30, 45, 60, 70, 75, 80, 84, 86, 88, 88.854, 89.427, 89.91)


_CHI2_REF = "bin integrals of pdf (Gauss-Legendre 6x6 per bin), 16 x 32 bins"


def _chi2(ctx, res):
    from ...sampling import STRATEGIES
    from ...sampling.quality import chi2_test

    points = ((0.02, 1.0),) if ctx.quick else ((0.02, 1.0), (0.3, 1.0), (0.9, 1.0), (0.3, 0.3))
    cases = [(s, mu, r) for s in in_quick(ctx, STRATEGIES, QUICK_STRATEGIES) for mu, r in points]
    sidak = 1.0 - (1.0 - ALPHA) ** (1.0 / len(cases))
    n = 20_000 if ctx.quick else 40_000
    rows = []
    for k, (s, mu, r) in enumerate(cases):
        ctx.progress(f"chi2 {s} mu={mu} r={r}")
        p, chi2, dof, mass = chi2_test(s, mu, r, n, seed=100 + k)
        rows.append([s, mu, r, n, chi2, dof, p])
        res.checks.append(
            CHECKS.check(
                f"chi-square {s}, mu_o = {mu:g}, r = {r:g}: p-value",
                p,
                sidak,
                ">=",
                reference=_CHI2_REF,
                detail=f"chi2 = {chi2:.1f} for {dof} dof; Sidak level for {len(cases)} tests at alpha = {ALPHA}",
            )
        )
    res.tables.append(
        Table(
            "Chi-square goodness of fit of sample() against pdf()",
            ["strategy", "mu_o", "r", "samples", "chi2", "dof", "p-value"],
            rows,
        )
    )


def _normalisation(ctx, res):
    from ...sampling import STRATEGIES
    from ...sampling.quality import pdf_mass

    worst = 0.0
    where = ""
    strategies = in_quick(ctx, STRATEGIES, QUICK_STRATEGIES)
    for s in strategies:
        for mu in (0.02, 0.5, 1.0):
            for r in (0.3, 1.0):
                m = pdf_mass(s, mu, r, res=(24, 48) if ctx.quick else (48, 96))
                if abs(m - 1.0) >= worst:
                    worst, where = abs(m - 1.0), f"{s}, mu_o = {mu}, r = {r}"
    res.checks.append(
        CHECKS.check(
            "pdf normalisation: max |integral of pdf - 1|",
            worst,
            1e-3,
            "<=",
            reference="Gauss-Legendre quadrature of pdf over the hemisphere (sphere for 'ltc')",
            detail=f"{'the strategies ' + ', '.join(strategies) if ctx.quick else 'every strategy'}, mu_o in "
            f"(0.02, 0.5, 1), r in (0.3, 1); worst at {where}",
        )
    )


def _curves(ctx, res):
    from ...sampling import STRATEGIES
    from ...sampling.quality import weight_stats

    n = 4_000 if ctx.quick else 15_000
    rs = (1.0,) if ctx.quick else (0.25, 0.5, 1.0)
    thetas = tuple(sorted(set(CURVE_THETA[::2] + (CURVE_THETA[-1],)))) if ctx.quick else CURVE_THETA
    data = {}
    k = 0
    strategies = in_quick(ctx, STRATEGIES, QUICK_STRATEGIES)
    for r in rs:
        ctx.progress(f"variance curves r={r}")
        for th in thetas:
            for s in strategies:
                data[(r, th, s)] = weight_stats(s, math.cos(math.radians(th)), r, n, 7 + k)
                k += 1
    plt = pyplot()
    fig, axes = plt.subplots(len(rs), 3, figsize=(15, 3.4 * len(rs)), squeeze=False)
    styles = {
        "cosine": ("tab:red", "-"),
        "uniform": ("black", ":"),
        "ltc": ("tab:blue", "-"),
        "ltc_nonneg": ("tab:blue", ":"),
        "cltc": ("tab:green", "--"),
        "eon": ("tab:green", "-"),
    }
    for i, r in enumerate(rs):
        for s in strategies:
            color, ls = styles[s]
            for j, q in enumerate((0, 1, 2)):
                axes[i, j].plot(
                    thetas,
                    [data[(r, th, s)][q] for th in thetas],
                    color=color,
                    ls=ls,
                    label="CLTC + uniform (MIS)" if s == "eon" else s,
                )
        for j, name in enumerate(("variance", "maximum weight", "mean weight")):
            axes[i, j].set_title(f"{name}, r = {r:g}")
            axes[i, j].set_xlabel("theta_o (deg)")
            axes[i, j].grid(True, alpha=0.3)
            if j < 2:
                axes[i, j].set_yscale("log")
        axes[i, 0].legend(fontsize=7)
    fig.suptitle(f"Throughput weight f mu_i / pdf, EON rho = 1 (Fig. 10-12), {n} samples per point", fontsize=10)
    fig.subplots_adjust(left=0.07, right=0.98, bottom=0.15, top=0.85, wspace=0.28, hspace=0.5)
    res.figures.append(
        Figure(
            save(fig, ctx, "sampling_variance.png"),
            "Variance, maximum and mean of the throughput weight by strategy (EON paper Fig. 10-12), Monte Carlo",
        )
    )
    return data, n


def _claim(ctx, res, mc, n_mc):
    from ...sampling.quality import exact_weight_moments

    theta = AUTHORS_THETA[::8].tolist() + [AUTHORS_THETA[-1]] if ctx.quick else AUTHORS_THETA.tolist()
    order = 5 if ctx.quick else 6
    vc, ve, me = [], [], []
    for k, th in enumerate(theta):
        if k % 8 == 0:
            ctx.progress(f"exact variance {k}/{len(theta)}")
        mu = math.cos(th)
        m1c, var_c = exact_weight_moments("cosine", mu, 1.0, order)
        m1e, var_e = exact_weight_moments("eon", mu, 1.0, order)
        vc.append(var_c)
        ve.append(var_e)
        me.append(m1e)
    vc, ve, me = np.array(vc), np.array(ve), np.array(me)
    ratio = vc / np.maximum(ve, 1e-300)
    last = len(theta) - 1
    # convergence of the quadrature at the last (most grazing) point
    _, var_e_fine = exact_weight_moments("eon", math.cos(theta[-1]), 1.0, 2 * order)
    _, var_c_fine = exact_weight_moments("cosine", math.cos(theta[-1]), 1.0, 2 * order)
    conv = max(abs(var_e_fine - ve[last]) / var_e_fine, abs(var_c_fine - vc[last]) / var_c_fine)
    res.checks.append(
        CHECKS.check(
            "exact variance quadrature converged at theta_o = 0.999 pi/2",
            conv,
            1e-2,
            "<=",
            reference=f"the same quadrature at order {2 * order}",
            detail="relative change of the cosine and EON variances",
        )
    )
    res.checks.append(
        CHECKS.check(
            "EON sampler unbiased: max |E[w] - 1| on the authors' grid",
            float(np.abs(me - 1).max()),
            1e-5,
            "<=",
            reference="quadrature of f mu_i over {pdf > 0}",
            detail="white furnace through the sampler (rho = 1, r = 1)",
        )
    )
    res.checks.append(
        CHECKS.check(
            "variance ratio cosine / EON at the authors' last point (theta_o = 0.999 pi/2)",
            float(ratio[last]),
            10.0,
            ">=",
            reference="exact quadrature; paper: 'about 100x' / 'exceeds a factor of 100' at grazing",
            detail=f"mu_o = {math.cos(theta[-1]):.5f}; the threshold checks a large reduction, not the paper's factor",
        )
    )
    # Monte Carlo against exact at r = 1 where both exist
    worst = 0.0
    # cosine sampling's weight is heavy-tailed at grazing (max ~ 40x the mean): its sample
    # variance converges slowly there, so it is compared at 70 deg only
    for th_deg, s in ((70.0, "cosine"), (70.0, "eon"), (88.854, "eon")):
        if (1.0, th_deg, s) in mc:
            var_mc = mc[(1.0, th_deg, s)][0]
            _, var_x = exact_weight_moments(s, math.cos(math.radians(th_deg)), 1.0, order)
            worst = max(worst, abs(var_mc - var_x) / var_x)
    res.checks.append(
        CHECKS.check(
            "Monte Carlo variance vs exact quadrature (r = 1, theta_o = 70, 88.854 deg)",
            worst,
            0.25 if ctx.quick else 0.1,
            "<=",
            reference="exact_weight_moments",
            detail=f"relative difference, {n_mc} samples per point",
        )
    )
    pick = sorted(set(np.linspace(0, last, 9).astype(int).tolist() + [last]))
    rows = [[math.degrees(theta[i]), math.cos(theta[i]), vc[i], ve[i], ratio[i]] for i in pick]
    for mu in (0.02, 0.01):
        _, a = exact_weight_moments("cosine", mu, 1.0, order)
        _, b = exact_weight_moments("eon", mu, 1.0, order)
        rows.append([math.degrees(math.acos(mu)), mu, a, b, a / b])
    res.tables.append(
        Table(
            "Variance of the throughput weight at rho = 1, r = 1 by exact quadrature, on the authors' "
            "theta_o grid (last rows: mu_o = 0.02, 0.01)",
            ["theta_o (deg)", "mu_o", "var cosine", "var EON (CLTC + uniform)", "ratio"],
            rows,
        )
    )
    imax = int(np.argmax(ratio))
    res.notes.append(
        f"The paper's claim (Section 3.1/3.2: variance 'about 100x' lower than cosine sampling at grazing angles, "
        f"'exceeds a factor of 100'): exact quadrature on the authors' grid gives a ratio of {ratio[last]:.1f}x at "
        f"its last point theta_o = 0.999 pi/2 (mu_o = {math.cos(theta[-1]):.5f}), the largest on the grid being "
        f"{ratio[imax]:.1f}x at theta_o = {math.degrees(theta[imax]):.2f} deg; {rows[-2][4]:.1f}x at mu_o = 0.02 and "
        f"{rows[-1][4]:.1f}x at mu_o = 0.01. The factor of 100 is not reproduced; the reduction is real and large."
    )
    plt = pyplot()
    fig, ax = plt.subplots(1, 2, figsize=(13, 4))
    deg = np.degrees(theta)
    ax[0].semilogy(deg, vc, "r--", label="cosine")
    ax[0].semilogy(deg, ve, "g-", label="CLTC + uniform (MIS)")
    ax[0].set_title("exact variance of the throughput weight, r = 1")
    ax[1].plot(deg, ratio, "k-")
    ax[1].axhline(100.0, color="tab:red", ls=":", label="paper: about 100x")
    ax[1].set_title("variance ratio cosine / EON (exact)")
    for a in ax:
        a.set_xlabel("theta_o (deg), authors' grid up to 0.999 pi/2")
        a.grid(True, alpha=0.3)
        a.legend(fontsize=8)
    fig.subplots_adjust(left=0.07, right=0.98, bottom=0.15, top=0.85, wspace=0.28, hspace=0.5)
    res.figures.append(
        Figure(
            save(fig, ctx, "sampling_claim.png"), "The '100x lower variance at grazing' claim against exact quadrature"
        )
    )


def build(ctx: Context) -> SectionResult:
    res = SectionResult("sampling", TITLE)
    _chi2(ctx, res)
    _normalisation(ctx, res)
    mc, n_mc = _curves(ctx, res)
    _claim(ctx, res, mc, n_mc)
    return res
