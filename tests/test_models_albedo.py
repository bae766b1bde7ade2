"""Albedos of the lobe models against quadrature of their own ``evaluate`` and the
values stated in the EON paper [Portsmouth2025]."""

import math

import numpy as np
import pytest
from _quad import gauss_legendre, quad_albedo, quad_average
from conftest import roughness_max

import openpbr_diffuse as od

MUS = (0.01, 0.05, 0.2, 0.5, 0.8, 1.0)
CLOSED_FORM = [m for m in od.MODELS if m != "full_on"]


@pytest.mark.parametrize("model", CLOSED_FORM)
def test_directional_albedo_matches_quadrature(model):
    rmax = roughness_max(model)
    for r in (0.0, 0.3 * rmax, 0.7 * rmax, rmax):
        got = od.directional_albedo(model, np.array(MUS), r, [1.0, 0.4])
        for mu, e in zip(MUS, got):
            np.testing.assert_allclose(
                e, quad_albedo(model, mu, r, [1.0, 0.4]), atol=1e-6, err_msg=f"{model} mu={mu} roughness={r}"
            )


@pytest.mark.parametrize("model", CLOSED_FORM)
def test_average_albedo_matches_quadrature(model):
    r = 0.8 * roughness_max(model)
    np.testing.assert_allclose(
        od.average_albedo(model, r, [1.0, 0.3]), quad_average(model, r, [1.0, 0.3], n=32, n_mu=32), atol=1e-6
    )


def test_average_is_cosine_weighted_mean_of_directional():
    """<E> = 2 int E(mu) mu dmu, integrating the closed-form E (a second route to Eq. 9/15/20)."""
    theta, w = gauss_legendre(0.0, 0.5 * np.pi, 64)
    mu = np.cos(theta)
    weight = w * 2.0 * mu * np.sin(theta)
    for model in CLOSED_FORM:
        r = 0.6 * roughness_max(model)
        E = od.directional_albedo(model, mu, r, [0.9, 0.2])
        np.testing.assert_allclose(weight @ E, od.average_albedo(model, r, [0.9, 0.2]), atol=1e-9, err_msg=model)


# --- the paper's stated values -------------------------------------------------------------
def test_checked_values_fon():
    E = lambda mu, r: float(od.directional_albedo("fon", mu, r)[0])  # noqa: E731
    assert E(1.0, 1.0) == pytest.approx(0.776522, abs=1e-6)
    assert E(0.7, 1.0) == pytest.approx(0.817888, abs=1e-6)
    assert E(0.3, 0.5) == pytest.approx(0.954690, abs=1e-6)
    assert float(od.average_albedo("fon", 0.5)[0]) == pytest.approx(0.905890, abs=1e-6)
    # FON loses energy (the reason EON exists): <E_F>(1) = 0.832811
    assert float(od.average_albedo("fon", 1.0)[0]) == pytest.approx(0.832811, abs=1e-6)


def test_checked_values_qon():
    sigma = math.pi / 4
    assert float(od.directional_albedo("qon", 0.5, sigma)[0]) == pytest.approx(0.791338, abs=1e-6)
    assert float(od.average_albedo("qon", sigma)[0]) == pytest.approx(0.758285, abs=1e-6)


def test_checked_value_full_on_gains_energy_near_grazing():
    """fullON albedo at rho = 1, sigma = 0.5, mu = 0.05 is 1.0047 (> 1)."""
    assert quad_albedo("full_on", 0.05, 0.5, 1.0, n=64)[0] == pytest.approx(1.0047, abs=1e-4)


def test_E_F_approx_is_the_eq14_fit():
    """Eq. 14 against the exact E_F: 0.817687 vs 0.817888 at mu = 0.7, r = 1; max gap 4.7e-4."""
    from openpbr_diffuse.models.fon import E_F_approx, E_F_exact

    assert E_F_exact(0.7, 1.0) == pytest.approx(0.817888, abs=1e-6)
    assert E_F_approx(0.7, 1.0) == pytest.approx(0.817687, abs=1e-6)
    mu = np.linspace(0.0, 1.0, 2001)
    gap = max(abs(E_F_exact(m, r) - E_F_approx(m, r)) for m in mu for r in (0.25, 0.5, 1.0))
    assert 4.0e-4 < gap <= 5e-4  # the paper: < 0.1 %; this page: 4.7e-4 at r = 1


# --- energy ---------------------------------------------------------------------------------
@pytest.mark.parametrize("model", ["eon", "eon_approx"])
def test_eon_white_furnace_by_quadrature(model):
    """At rho = 1 EON reflects everything: E(mu) = 1 for all mu, r (Eq. 20)."""
    tol = 1e-6 if model == "eon" else 6e-4  # eon_approx: its f_ms uses the Eq. 14 fit
    for r in (0.1, 0.5, 1.0):
        for mu in (0.02, 0.3, 0.7, 1.0):
            assert quad_albedo(model, mu, r, 1.0)[0] == pytest.approx(1.0, abs=tol), (model, r, mu)


def test_eon_white_furnace_closed_form_everywhere():
    mu = np.linspace(0.0, 1.0, 101)[:, None]
    r = np.linspace(0.0, 1.0, 51)[None, :]
    np.testing.assert_allclose(od.directional_albedo("eon", mu, r, 1.0), 1.0, atol=1e-6)
    np.testing.assert_allclose(od.average_albedo("eon", r, 1.0), 1.0, atol=1e-6)


def test_eon_approx_albedo_within_paper_error_of_eq20():
    """The exact albedo of the eon_approx lobe stays within the paper's 0.1 % of Eq. 20."""
    from openpbr_diffuse.models.eon import rho_ms
    from openpbr_diffuse.models.fon import E_F_approx, E_F_avg

    for r in (0.3, 1.0):
        for mu in (0.05, 0.5, 1.0):
            for rho in (0.2, 0.8, 1.0):
                eq20 = rho * E_F_approx(mu, r) + rho_ms(rho, E_F_avg(r)) * (1.0 - E_F_approx(mu, r))
                got = od.directional_albedo("eon_approx", mu, r, rho)[0]
                assert abs(got - eq20) < 1e-3 * max(eq20, 1e-3)


def test_eon_colour_shift_and_white_tint():
    """Reference mode: rho_ms is nonlinear, so E/rho differs per channel (Eq. 18).
    White-then-tint: E = rho * E(rho=1) = rho exactly (no colour shift)."""
    rho = [0.8, 0.4, 0.1]
    ref = od.directional_albedo("eon", 0.5, 1.0, rho)
    tint = od.directional_albedo("eon", 0.5, 1.0, rho, color_mode="white_tint")
    np.testing.assert_allclose(tint, rho, atol=1e-6)
    ratio = ref / np.array(rho)
    assert ratio[0] > ratio[1] > ratio[2]  # darker channels lose relatively more
    assert np.all(ref <= np.array(rho) + 1e-12)  # and none gains
    # the same by quadrature of evaluate in each mode
    np.testing.assert_allclose(quad_albedo("eon", 0.5, 1.0, rho), ref, atol=1e-6)
    np.testing.assert_allclose(quad_albedo("eon", 0.5, 1.0, rho, color_mode="white_tint"), tint, atol=1e-6)


def _max_albedo(model, rho=1.0):
    mu = np.linspace(0.0, 1.0, 201)[:, None]
    r = np.linspace(0.0, roughness_max(model), 101)[None, :]
    E = od.directional_albedo(model, mu, r, rho)[..., 0]
    i, j = np.unravel_index(np.argmax(E), E.shape)
    return E[i, j], mu[i, 0], r[0, j]


@pytest.mark.parametrize("model", ["lambert", "fon", "eon"])
def test_energy_conserving_models_never_exceed_unit_albedo(model):
    for rho in (1.0, 0.5):
        assert _max_albedo(model, rho)[0] <= rho + 1e-6
    assert od.models.model_info(model).energy_conserving


def test_eon_approx_gains_at_most_the_fit_error():
    """eon_approx's f_ms uses the Eq. 14 fit, whose cosine-weighted mean is not <E_F>:
    its albedo overshoots 1 by up to ~1.5e-4 (documented, well inside the paper's 0.1 %)."""
    E, mu, r = _max_albedo("eon_approx")
    assert 1.0 < E < 1.0 + 2e-4
    assert quad_albedo("eon_approx", mu, r, 1.0)[0] == pytest.approx(E, abs=1e-6)
    assert not od.models.model_info("eon_approx").energy_conserving


@pytest.mark.parametrize("model", ["qon", "qon_footnote", "gotanda", "qon_fujii"])
def test_models_that_gain_energy_near_grazing(model):
    """Documented: QON-type lobes exceed unit albedo at grazing view and small roughness
    (E(0) = A + B G(0)/pi with B growing faster than 1 - A), Fujii QON at high rho."""
    E, mu, r = _max_albedo(model)
    assert E > 1.0 and mu < 0.2
    # the closed form is right there too: confirm by quadrature
    assert quad_albedo(model, max(mu, 1e-3), r, 1.0)[0] > 1.0
    assert not od.models.model_info(model).energy_conserving
