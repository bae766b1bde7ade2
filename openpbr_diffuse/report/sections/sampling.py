"""Sampling: chi-square goodness of fit, pdf normalisation, the variance curves of Fig. 10-12,
and the paper's "about 100x lower variance at grazing" claim against exact quadrature.

The claim is checked on the theta_o grid of the authors' own script
(portsmouth/EON-diffuse ``scripts/variance_plots.py``: theta_o = (pi/2) linspace(0, 0.999, 64),
rho = 1), with the variance of the throughput weight computed by quadrature
(:func:`openpbr_diffuse.sampling.quality.exact_weight_moments`) instead of Monte Carlo.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ...result import Result
from .._plot import pyplot
from ..model import (
    QUICK_STRATEGIES,
    CheckTable,
    Context,
    Figure,
    SectionResult,
    Table,
    in_quick,
)
from ._common import label_panels, save_panels

TITLE = "Sampling: chi-square, normalisation, variance (Fig. 10-12)"

#: The section's checks: its rows of the static registry ``data/report_checks.tsv``.
CHECKS = CheckTable.declared("sampling")

ALPHA = 0.01
#: The authors' grid (scripts/variance_plots.py).
AUTHORS_THETA = 0.5 * math.pi * np.linspace(0.0, 0.999, 64)
CURVE_THETA = (0, 30, 45, 60, 70, 75, 80, 84, 86, 88, 88.854, 89.427, 89.91)


_CHI2_REF = "bin integrals of pdf (Gauss-Legendre 6x6 per bin), 16 x 32 bins"


def _chi2(ctx, res):
    """Chi-square goodness of fit of each strategy's samples against its pdf."""
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
    """The largest deviation of a strategy's pdf integral from 1."""
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
    """The variance curves of Fig. 10-12 by Monte Carlo; (data by (r, theta_o, strategy), samples)."""
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
    res.figures.append(
        Figure(
            save_panels(fig, ctx, "sampling_variance.png"),
            "Variance, maximum and mean of the throughput weight by strategy (EON paper Fig. 10-12), Monte Carlo",
        )
    )
    return data, n


class _Exact(NamedTuple):
    """The exact variances of the throughput weight on the authors' theta_o grid (rho = 1, r = 1)."""

    theta: list[float]
    order: int
    cosine: np.ndarray
    eon: np.ndarray
    eon_mean: np.ndarray

    @property
    def ratio(self) -> np.ndarray:
        """Variance ratio cosine / EON at each theta_o."""
        return self.cosine / np.maximum(self.eon, 1e-300)


def _exact(ctx: Context) -> _Exact:
    """The variances of cosine and EON sampling by quadrature on the authors' grid."""
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
    return _Exact(theta, order, np.array(vc), np.array(ve), np.array(me))


def _exact_checks(x: _Exact) -> list[Result]:
    """The quadrature's convergence, the sampler's bias and the variance ratio at the last point."""
    from ...sampling.quality import exact_weight_moments

    last = len(x.theta) - 1
    # convergence of the quadrature at the last (most grazing) point
    _, var_e_fine = exact_weight_moments("eon", math.cos(x.theta[-1]), 1.0, 2 * x.order)
    _, var_c_fine = exact_weight_moments("cosine", math.cos(x.theta[-1]), 1.0, 2 * x.order)
    conv = max(abs(var_e_fine - x.eon[last]) / var_e_fine, abs(var_c_fine - x.cosine[last]) / var_c_fine)
    return [
        CHECKS.check(
            "exact variance quadrature converged at theta_o = 0.999 pi/2",
            conv,
            1e-2,
            "<=",
            reference=f"the same quadrature at order {2 * x.order}",
            detail="relative change of the cosine and EON variances",
        ),
        CHECKS.check(
            "EON sampler unbiased: max |E[w] - 1| on the authors' grid",
            float(np.abs(x.eon_mean - 1).max()),
            1e-5,
            "<=",
            reference="quadrature of f mu_i over {pdf > 0}",
            detail="white furnace through the sampler (rho = 1, r = 1)",
        ),
        CHECKS.check(
            "variance ratio cosine / EON at the authors' last point (theta_o = 0.999 pi/2)",
            float(x.ratio[last]),
            10.0,
            ">=",
            reference="exact quadrature; paper: 'about 100x' / 'exceeds a factor of 100' at grazing",
            detail=f"mu_o = {math.cos(x.theta[-1]):.5f}; the threshold checks a large reduction, not the paper's factor",
        ),
    ]


def _monte_carlo_check(ctx: Context, x: _Exact, mc: dict, n_mc: int) -> Result:
    """The Monte Carlo variances of the curves against exact quadrature at r = 1."""
    from ...sampling.quality import exact_weight_moments

    worst = 0.0
    # cosine sampling's weight is heavy-tailed at grazing (max ~ 40x the mean): its sample
    # variance converges slowly there, so it is compared at 70 deg only
    for th_deg, s in ((70.0, "cosine"), (70.0, "eon"), (88.854, "eon")):
        if (1.0, th_deg, s) in mc:
            var_mc = mc[(1.0, th_deg, s)][0]
            _, var_x = exact_weight_moments(s, math.cos(math.radians(th_deg)), 1.0, x.order)
            worst = max(worst, abs(var_mc - var_x) / var_x)
    return CHECKS.check(
        "Monte Carlo variance vs exact quadrature (r = 1, theta_o = 70, 88.854 deg)",
        worst,
        0.25 if ctx.quick else 0.1,
        "<=",
        reference="exact_weight_moments",
        detail=f"relative difference, {n_mc} samples per point",
    )


def _claim_table(res: SectionResult, x: _Exact) -> list[list[float]]:
    """The variances on a subset of the grid and at mu_o = 0.02, 0.01: the table, and its rows."""
    from ...sampling.quality import exact_weight_moments

    last = len(x.theta) - 1
    ratio = x.ratio
    pick = sorted(set(np.linspace(0, last, 9).astype(int).tolist() + [last]))
    rows = [[math.degrees(x.theta[i]), math.cos(x.theta[i]), x.cosine[i], x.eon[i], ratio[i]] for i in pick]
    for mu in (0.02, 0.01):
        _, a = exact_weight_moments("cosine", mu, 1.0, x.order)
        _, b = exact_weight_moments("eon", mu, 1.0, x.order)
        rows.append([math.degrees(math.acos(mu)), mu, a, b, a / b])
    res.tables.append(
        Table(
            "Variance of the throughput weight at rho = 1, r = 1 by exact quadrature, on the authors' "
            "theta_o grid (last rows: mu_o = 0.02, 0.01)",
            ["theta_o (deg)", "mu_o", "var cosine", "var EON (CLTC + uniform)", "ratio"],
            rows,
        )
    )
    return rows


def _claim_note(x: _Exact, rows: list[list[float]]) -> str:
    """The verdict on the paper's '100x' claim."""
    ratio, last = x.ratio, len(x.theta) - 1
    imax = int(np.argmax(ratio))
    return (
        f"The paper's claim (Section 3.1/3.2: variance 'about 100x' lower than cosine sampling at grazing angles, "
        f"'exceeds a factor of 100'): exact quadrature on the authors' grid gives a ratio of {ratio[last]:.1f}x at "
        f"its last point theta_o = 0.999 pi/2 (mu_o = {math.cos(x.theta[-1]):.5f}), the largest on the grid being "
        f"{ratio[imax]:.1f}x at theta_o = {math.degrees(x.theta[imax]):.2f} deg; {rows[-2][4]:.1f}x at mu_o = 0.02 and "
        f"{rows[-1][4]:.1f}x at mu_o = 0.01. The factor of 100 is not reproduced; the reduction is real and large."
    )


def _claim_figure(ctx: Context, x: _Exact) -> Figure:
    """The exact variances and their ratio against theta_o."""
    plt = pyplot()
    fig, ax = plt.subplots(1, 2, figsize=(13, 4))
    deg = np.degrees(x.theta)
    ax[0].semilogy(deg, x.cosine, "r--", label="cosine")
    ax[0].semilogy(deg, x.eon, "g-", label="CLTC + uniform (MIS)")
    ax[0].set_title("exact variance of the throughput weight, r = 1")
    ax[1].plot(deg, x.ratio, "k-")
    ax[1].axhline(100.0, color="tab:red", ls=":", label="paper: about 100x")
    ax[1].set_title("variance ratio cosine / EON (exact)")
    label_panels(ax, "theta_o (deg), authors' grid up to 0.999 pi/2", 8)
    return Figure(
        save_panels(fig, ctx, "sampling_claim.png"),
        "The '100x lower variance at grazing' claim against exact quadrature",
    )


def _claim(ctx: Context, res: SectionResult, mc: dict, n_mc: int) -> None:
    """The paper's "about 100x lower variance at grazing" against exact quadrature."""
    x = _exact(ctx)
    res.checks += _exact_checks(x)
    res.checks.append(_monte_carlo_check(ctx, x, mc, n_mc))
    rows = _claim_table(res, x)
    res.notes.append(_claim_note(x, rows))
    res.figures.append(_claim_figure(ctx, x))


def build(ctx: Context) -> SectionResult:
    """Chi-square, normalisation, the variance curves and the "100x" claim."""
    res = SectionResult("sampling", TITLE)
    _chi2(ctx, res)
    _normalisation(ctx, res)
    mc, n_mc = _curves(ctx, res)
    _claim(ctx, res, mc, n_mc)
    return res
