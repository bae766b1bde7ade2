"""V-cavity simulator against an independent quadrature of the same single-bounce geometry,
and against Oren and Nayar's own single-scattering model."""

import numpy as np
import pytest
from _vgroove_quad import single_bounce_albedo

import openpbr_diffuse as od
from openpbr_diffuse.simulation import simulate_albedo


@pytest.mark.parametrize("sigma", [0.15, 0.5, 1.0])
@pytest.mark.parametrize("mu", [0.07, 0.45, 0.9])
def test_single_bounce_albedo_matches_quadrature(sigma, mu):
    expected, reached = single_bounce_albedo(mu, sigma)
    assert abs(reached - 1.0) < 1e-12  # the shadowing formula accounts for the whole beam
    est = simulate_albedo("vcavity", sigma, [mu], rho=1.0, paths=200_000, seed=11)
    got, err = est.albedo_by_order[0, 0, 0], est.stderr_by_order[0, 0, 0]
    assert abs(got - expected) < 4.5 * err + 2e-5, (got, expected, err)


def test_single_bounce_quadrature_detects_a_wrong_geometry():
    # the quadrature is sensitive enough: half-Gaussian slopes (no sin) differ by >> the error
    a, _ = single_bounce_albedo(0.5, 0.5)
    b, _ = single_bounce_albedo(0.5, 0.35)
    assert abs(a - b) > 0.02


@pytest.mark.parametrize("sigma", [0.2, 0.35, 0.5])
def test_single_bounce_close_to_oren_nayar_f1(sigma):
    """Oren-Nayar's f1 (the rho-linear term of full_on) was fitted to this very geometry:
    its albedo agrees with the exact single bounce to a few hundredths (measured: max abs
    difference 0.008 / 0.017 / 0.022 / 0.015 at sigma = 0.1 / 0.2 / 0.3 / 0.5 over mu in
    [0.05, 1]: the accuracy of their functional fit)."""
    mu = np.array([0.1, 0.3, 0.6, 1.0])
    exact = np.array([single_bounce_albedo(m, sigma)[0] for m in mu])
    # e_g of full_on: the albedo of the rho-linear term (rho -> 0 limit of E / rho)
    on_f1 = od.directional_albedo("full_on", mu, sigma, 1e-9)[:, 0] / 1e-9
    assert np.max(np.abs(on_f1 - exact)) < 0.03
