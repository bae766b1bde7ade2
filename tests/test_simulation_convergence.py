"""The standard errors are honest: independent seeds scatter around a long run with the
spread the standard errors claim (z-scores ~ N(0, 1)), and shrink as 1/sqrt(paths)."""

import numpy as np
import pytest
from scipy import stats

from openpbr_diffuse.simulation import simulate_albedo, simulate_brdf


@pytest.mark.slow
@pytest.mark.parametrize("geometry,roughness", [("vcavity", 0.7), ("smith-beckmann", 0.8), ("smith-ggx", 0.8)])
def test_z_scores_of_independent_seeds(geometry, roughness):
    mu = [0.2, 0.8]
    rho = [0.9, 0.4]
    ref = simulate_albedo(geometry, roughness, mu, rho=rho, paths=4_000_000, seed=1000)
    z = []
    for seed in range(12):
        est = simulate_albedo(geometry, roughness, mu, rho=rho, paths=40_000, seed=seed)
        d = est.albedo_by_order - ref.albedo_by_order
        s = np.hypot(est.stderr_by_order, ref.stderr_by_order)
        z.append((d / s).ravel())
        z.append(((est.albedo - ref.albedo) / np.hypot(est.stderr, ref.stderr)).ravel())
    z = np.concatenate(z)
    # the z-scores share the reference run, so they are not independent: test the spread
    # loosely (chi-square of the per-seed means) and the two-sided KS against N(0, 1)
    assert 0.75 < np.std(z) < 1.3, np.std(z)
    assert stats.kstest(z, "norm").pvalue > 1e-3


@pytest.mark.slow
def test_brdf_z_scores_and_rate():
    wi = np.array([[0.8, 0.0, 0.6]] * 3)
    wo = np.array([[0.8, 0.0, 0.6], [-0.6, 0.0, 0.8], [0.0, 0.28, 0.96]])
    ref = simulate_brdf("vcavity", 0.6, wi, wo, rho=0.8, paths=3_000_000, seed=99)
    z = []
    for seed in range(15):
        est = simulate_brdf("vcavity", 0.6, wi, wo, rho=0.8, paths=30_000, seed=seed)
        z.append(((est.f - ref.f) / np.hypot(est.stderr, ref.stderr)).ravel())
    z = np.concatenate(z)
    assert 0.7 < np.std(z) < 1.35 and abs(np.mean(z)) < 0.7
    small = simulate_brdf("vcavity", 0.6, wi, wo, rho=0.8, paths=30_000, seed=1)
    ratio = ref.stderr / small.stderr
    assert np.allclose(ratio, 0.1, rtol=0.25)  # 100x the paths: 1/10 the error


def test_stderr_shrinks_as_inverse_sqrt_paths():
    a = simulate_albedo("vcavity", 0.5, [0.4], rho=0.6, paths=20_000, seed=1)
    b = simulate_albedo("vcavity", 0.5, [0.4], rho=0.6, paths=320_000, seed=2)
    assert b.stderr[0, 0] / a.stderr[0, 0] == pytest.approx(0.25, rel=0.1)
    # the spread over seeds matches the claimed error
    vals = [simulate_albedo("vcavity", 0.5, [0.4], rho=0.6, paths=20_000, seed=s).albedo[0, 0] for s in range(10, 30)]
    assert 0.6 < np.std(vals, ddof=1) / a.stderr[0, 0] < 1.5
