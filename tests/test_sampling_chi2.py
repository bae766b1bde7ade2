"""Sampling matches its pdf: chi-square goodness of fit, as in Mitsuba 3's ``chi2`` test.

For each strategy and (mu_o, r): draw n directions with ``sample``, bin them over
cos(theta) x phi (the upper hemisphere; the whole sphere for the general "ltc", whose lobe
extends below the horizon), and compare the counts with the expected counts n * integral
of ``pdf`` over each bin (Gauss-Legendre in cos(theta) and phi per bin).  Bins expected to
hold < 5 samples are pooled (Mitsuba's rule); the p-value comes from scipy.stats.chi2 and
the null hypothesis is rejected at the Sidak-corrected level 1 - (1 - ALPHA)^(1/M) for the
M tests of this module.  Deliberately wrong pdfs must be rejected by the same test.
"""

import numpy as np
import pytest
from _chi2 import chi2_pvalue
from _chi2 import chi2_test as chi2_goodness
from scipy import stats

from openpbr_diffuse.sampling import STRATEGIES, pdf, sample_rng

ALPHA = 0.01
PHI_O = 0.7  # wo off the x axis, so the LTC frame is exercised

MUS = (0.02, 0.2, 0.6, 1.0)
RS = (0.3, 1.0)
CASES = [(s, mu, r) for s in STRATEGIES for mu in MUS for r in RS]
N_FAST, RES_FAST = 200_000, (16, 32)
N_SLOW, RES_SLOW = 2_000_000, (40, 80)
WRONG = [  # (strategy sampled, strategy / r of the pdf tested against), at mu_o = 0.02
    ("eon", 1.0, "cltc", 1.0),  # the MIS pdf without its uniform share
    ("eon", 1.0, "eon", 0.9),  # right strategy, roughness off by 10 %
    ("cltc", 1.0, "ltc", 1.0),  # clipping ignored
    ("ltc_nonneg", 1.0, "ltc_nonneg", 0.9),
    ("cosine", 1.0, "uniform", 1.0),
]
M_TESTS = 2 * len(CASES) + len(WRONG)
SIDAK = 1.0 - (1.0 - ALPHA) ** (1.0 / M_TESTS)


def wo_at(mu, phi=PHI_O):
    s = np.sqrt(1.0 - mu * mu)
    return np.array([s * np.cos(phi), s * np.sin(phi), mu])


def chi2_test(strategy, mu, r, n, res, seed, pdf_strategy=None, pdf_r=None):
    """Return (p-value, chi2, dof, expected-mass) of samples of ``strategy`` vs a pdf."""
    wo = wo_at(mu)
    sphere = strategy == "ltc" or pdf_strategy == "ltc"
    z_edges = np.linspace(-1.0 if sphere else 0.0, 1.0, (2 if sphere else 1) * res[0] + 1)
    phi_edges = np.linspace(0.0, 2.0 * np.pi, res[1] + 1)
    pdf_r = r if pdf_r is None else pdf_r
    # every returned direction counts (sample_rng's pdf is > 0 for wo above the horizon)
    return chi2_goodness(
        lambda m: sample_rng(strategy, wo, r, seed, shape=(m,)),
        lambda wi: pdf(pdf_strategy or strategy, wo, wi, pdf_r),
        n,
        z_edges,
        phi_edges,
    )


def _case_id(case):
    return "{}-mu{}-r{}".format(*case)


@pytest.mark.parametrize("case", CASES, ids=_case_id)
def test_chi2_samples_follow_pdf(case):
    strategy, mu, r = case
    p, chi2, dof, mass = chi2_test(strategy, mu, r, N_FAST, RES_FAST, seed=CASES.index(case))
    assert abs(mass - 1.0) < 1e-3  # the binned quadrature sees the whole distribution
    assert p >= SIDAK, f"chi2 = {chi2:.1f} for {dof} dof, p = {p:.3g} < {SIDAK:.3g}"


@pytest.mark.slow
@pytest.mark.parametrize("case", CASES, ids=_case_id)
def test_chi2_samples_follow_pdf_fine(case):
    strategy, mu, r = case
    p, chi2, dof, mass = chi2_test(strategy, mu, r, N_SLOW, RES_SLOW, seed=1000 + CASES.index(case))
    assert abs(mass - 1.0) < 1e-3
    assert p >= SIDAK, f"chi2 = {chi2:.1f} for {dof} dof, p = {p:.3g} < {SIDAK:.3g}"


@pytest.mark.parametrize("wrong", WRONG, ids=lambda w: "{}-r{}-vs-{}-r{}".format(*w))
def test_chi2_rejects_a_wrong_pdf(wrong):
    strategy, r, pdf_strategy, pdf_r = wrong
    p, chi2, dof, _ = chi2_test(strategy, 0.02, r, N_FAST, RES_FAST, seed=11, pdf_strategy=pdf_strategy, pdf_r=pdf_r)
    assert p < SIDAK, f"wrong pdf accepted: chi2 = {chi2:.1f} for {dof} dof, p = {p:.3g}"


def test_chi2_statistic_matches_scipy_without_pooling():
    """The pooled statistic reduces to scipy's Pearson chi2 when every bin expects >= 5."""
    rng = np.random.default_rng(5)
    expected = rng.uniform(20.0, 80.0, 50)
    expected *= 1000.0 / expected.sum()
    observed = rng.multinomial(1000, expected / 1000.0).astype(float)
    p, chi2, dof = chi2_pvalue(observed, expected)
    ref = stats.chisquare(observed, expected)
    assert dof == 49 and np.isclose(chi2, ref.statistic) and np.isclose(p, ref.pvalue)
