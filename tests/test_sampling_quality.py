"""sampling.quality: exact weight moments against closed-form cases, Monte Carlo against exact,
the pooled chi-square against scipy."""

import math

import numpy as np
import pytest

from openpbr_diffuse.sampling.quality import exact_weight_moments, pearson_chi2, weight_stats


@pytest.mark.parametrize("mu", [1.0, 0.5, 0.02])
def test_uniform_sampling_of_lambert_has_variance_one_third(mu):
    """r = 0: w = 2 mu_i with mu_i uniform on [0, 1]: mean 1, variance 4/3 - 1 = 1/3."""
    mean, var = exact_weight_moments("uniform", mu, 0.0)
    assert mean == pytest.approx(1.0, abs=1e-6) and var == pytest.approx(1.0 / 3.0, abs=1e-6)


def test_cosine_sampling_of_lambert_has_zero_variance():
    assert exact_weight_moments("cosine", 0.3, 0.0)[1] == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("strategy, mu", [("eon", 0.05), ("cosine", 0.5), ("ltc_nonneg", 0.3)])
def test_monte_carlo_matches_exact_moments(strategy, mu):
    var, _, mean, se = weight_stats(strategy, mu, 1.0, 200_000, seed=3)
    m_x, v_x = exact_weight_moments(strategy, mu, 1.0)
    assert abs(mean - m_x) < 5 * se
    assert var == pytest.approx(v_x, rel=0.05)


def test_pooled_chi2_matches_scipy_without_pooling():
    from scipy import stats

    rng = np.random.default_rng(5)
    expected = rng.uniform(20.0, 80.0, 50)
    expected *= 1000.0 / expected.sum()
    observed = rng.multinomial(1000, expected / 1000.0).astype(float)
    p, chi2, dof = pearson_chi2(observed, expected)
    ref = stats.chisquare(observed, expected)
    assert dof == 49 and math.isclose(chi2, ref.statistic, rel_tol=1e-12)
    assert math.isclose(p, ref.pvalue, rel_tol=1e-9)


def test_samples_where_the_pdf_expects_none_fail():
    """Pooling must not hide samples in bins of zero expected count."""
    expected = np.array([50.0, 50.0, 0.0])
    p, chi2, _ = pearson_chi2(np.array([48.0, 49.0, 3.0]), expected)
    assert p == 0.0 and chi2 == math.inf
