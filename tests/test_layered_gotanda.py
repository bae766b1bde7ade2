"""Gotanda 2012 Eq. 1-9: the printed statements checked by quadrature and limits."""

# ruff: noqa: B023  (quadrature integrands use the loop value at once)
import math

import numpy as np
import pytest
from scipy import integrate

from openpbr_diffuse.approximations import gotanda2012_layered as g


def test_eq1_constant_is_the_blinn_phong_ndf_normalisation():
    """0.0397436 s + 0.0856832 fits (s + 2)/(8 pi): the Blinn-Phong NDF (s + 2)/(2 pi) (n.h)^s
    (which integrates to 1 over projected half vectors, checked here) with the 1/(4 max(n.l,
    n.v)) of the Neumann visibility."""
    for s in (1.0, 10.0, 100.0):
        ndf = integrate.quad(
            lambda t: (s + 2) / (2 * math.pi) * math.cos(t) ** s * math.cos(t) * math.sin(t) * 2 * math.pi,
            0,
            math.pi / 2,
        )[0]
        assert ndf == pytest.approx(1.0, abs=1e-10)
    s = np.array([1.0, 3.0, 10.0, 30.0, 100.0, 1000.0, 1e4])
    rel = g.normalisation(s) / ((s + 2) / (8 * math.pi)) - 1
    assert np.all(np.abs(rel) < 0.051)
    assert np.all(np.abs(rel[s >= 100]) < 1.2e-3)


def test_eq1_specular_albedo_at_normal_incidence_below_one():
    """Eq. 1 conserves energy (F = 1, view along the normal: albedo <= 1) but is normalised
    to 1 there only as s -> infinity (0.36 at s = 1, 0.96 at s = 100)."""
    s = np.array([1.0, 10.0, 100.0, 1000.0])
    albedo = []
    for si in s:
        inv = integrate.quad(
            lambda t: math.cos(t / 2) ** si * math.cos(t) * math.sin(t) * 2 * math.pi, 0, math.pi / 2, limit=200
        )[0]
        albedo.append(g.normalisation(si) * inv)
    albedo = np.array(albedo)
    np.testing.assert_allclose(albedo, g.normalisation(s) / g.exact_normalisation(s), rtol=1e-8)
    assert np.all(albedo < 1.0) and albedo[0] == pytest.approx(0.3588, abs=1e-3) and albedo[2] > 0.96


def test_eq1_brdf_parts():
    wi = np.array([0.6, 0.0, 0.8])
    wo = np.array([-0.6, 0.0, 0.8])  # mirror pair: n.h = 1
    f = g.blinn_phong(wi, wo, 50.0, 0.04, [0.5])
    spec = g.normalisation(50.0) * (0.04 + 0.96 * (1 - 0.8) ** 5) / 0.8
    assert f[0] == pytest.approx(0.5 / math.pi * 0.96 + spec, rel=1e-12)


def test_eq2_and_eq3():
    # Eq. 2 at normal incidence: exp(-2 alpha d) whatever the index
    assert float(g.beer_lambert(2.0, 0.1, 1.0, 1.0, 1.7)) == pytest.approx(math.exp(-0.4))
    # refraction shortens the path at oblique angles: transmittance with n > 1 above n = 1
    assert g.beer_lambert(1.0, 0.1, 0.3, 0.3, 1.5) > g.beer_lambert(1.0, 0.1, 0.3, 0.3, 1.0)
    # Eq. 3 is the first-order expansion of Eq. 2 with non-refracted angles (n = 1), alpha' = alpha d
    for mu_l, mu_e in [(1.0, 1.0), (0.5, 0.8)]:
        ad = 1e-4
        lin = float(g.linear_absorption(ad, mu_l, mu_e))
        ex = float(g.beer_lambert(1.0, ad, mu_l, mu_e, 1.0))
        assert abs(lin - ex) < ad * ad * 10
    assert float(g.linear_absorption(0.6, 0.5, 0.5)) == 0.0  # clamped


def test_eq4_limits_and_symmetry():
    mu = np.linspace(0.05, 1.0, 20)
    assert np.all(g.bottom_fresnel(mu, 1.4, 1.4) == 0.0)  # no bottom interface
    mt = g.refracted_cos(mu, 1.33333)
    np.testing.assert_allclose(1 - g.fresnel(mt, 1 / 1.33333), 1 - g.fresnel(mu, 1.33333), atol=1e-12)
    # at normal incidence Eq. 4 is Eq. 5's transmittance times its constant
    assert float(g.bottom_fresnel(1.0, 1.33333, 1.5)) == pytest.approx(
        float(g.transmittance(1.0, 1.33333) * g.bottom_fresnel_constant(1.33333, 1.5)), rel=1e-12
    )


def test_figure1_bottom_fresnel_is_almost_flat():
    """Figure 1 (n1 = 1.33333, n2 = 1.5): Eq. 4 stays within 2 % of Eq. 5's constant up to
    30 degrees, 12 % up to 50 degrees, rises to +27 % near 66 degrees and falls to 0 at
    grazing (it is flat relative to the top layer's Fresnel, which rises from 0.02 to 1).
    Eq. 5's split, transmittance(mu) x constant, is within 2 % only up to 30 degrees."""
    c = float(g.bottom_fresnel_constant(1.33333, 1.5))
    th = np.radians(np.linspace(0.0, 89.9, 1000))
    r = g.bottom_fresnel(np.cos(th), 1.33333, 1.5) / c
    assert np.all(np.abs(r[th <= np.radians(30)] - 1) < 0.021)
    assert np.all(np.abs(r[th <= np.radians(50)] - 1) < 0.12)
    assert 1.25 < r.max() < 1.30 and np.degrees(th[r.argmax()]) == pytest.approx(66, abs=2)
    split = g.bottom_fresnel(np.cos(th), 1.33333, 1.5) / (g.transmittance(np.cos(th), 1.33333) * c)
    assert np.all(np.abs(split[th <= np.radians(30)] - 1) < 0.02)
    assert np.abs(split[th <= np.radians(60)] - 1).max() > 0.3
    assert r[-1] < 0.01


def test_eq8_by_quadrature():
    for mu_r in (1.0, 0.5, 0.2):
        val = integrate.dblquad(
            lambda t, p: (1 / mu_r + 1 / math.cos(t)) * math.cos(t) / math.pi * math.sin(t),
            -math.pi,
            math.pi,
            0,
            math.pi / 2,
        )[0]
        assert val == pytest.approx(float(g.hemispherical_path_factor(mu_r)), rel=1e-8)


def test_eq9_is_the_integral_of_eq3_only_without_the_clamp():
    """Eq. 9 integrates Eq. 3 before clamping: the clamp inside the integral (the actual
    cosine-weighted average of Eq. 3) differs, since 1/N.L is unbounded at grazing light."""
    ap, mu_e = 0.05, 0.8
    clamped = integrate.quad(
        lambda m: 2 * m * max(0.0, 1 - ap * (1 / m + 1 / mu_e)), 0, 1, points=[ap / (1 - ap / mu_e)]
    )[0]
    eq9 = float(g.ibl_diffuse_factor(ap, mu_e, 1.5, 1.5))  # F_bottom = 0
    unclamped = 1 - ap * (2 + 1 / mu_e)
    assert eq9 == pytest.approx(unclamped, rel=1e-12)
    assert clamped > eq9 and clamped - eq9 == pytest.approx(ap * ap / (1 - ap / mu_e) ** 1 * 1.0, rel=0.2)


def test_bad_input():
    with pytest.raises(ValueError, match="mu"):
        g.bottom_fresnel(0.0, 1.3, 1.5)
    with pytest.raises(ValueError, match="n1"):
        g.bottom_fresnel_constant(-1.0, 1.5)
    with pytest.raises(ValueError, match="mu_l"):
        g.linear_absorption(0.1, 1.5, 0.5)
