"""Physical properties of the simulated microsurfaces: Lambert limit, white furnace,
reciprocity, albedo = integral of the BRDF, and rejection of bad input."""

import math

import numpy as np
import pytest

from openpbr_diffuse.simulation import GEOMETRIES, simulate_albedo, simulate_average_albedo, simulate_brdf

SMOOTH = {"vcavity": 1e-4, "smith-beckmann": 1e-4, "smith-ggx": 1e-4}


@pytest.mark.parametrize("geometry", list(GEOMETRIES))
def test_smooth_limit_is_lambert(geometry):
    rho = np.array([0.9, 0.5, 0.1])
    est = simulate_albedo(geometry, SMOOTH[geometry], [0.1, 0.6, 1.0], rho=rho, paths=20_000, seed=1)
    assert np.allclose(est.albedo, rho, atol=2e-4)
    assert np.all(est.albedo_by_order[:, 0] >= rho - 2e-4)  # one bounce
    wi = np.array([[0.6, 0.0, 0.8], [0.0, 0.0, 1.0]])
    wo = np.array([[-0.28, 0.96, 0.0], [0.8, 0.0, 0.6]])
    wo[0] = [-0.28 * 0.6, 0.96 * 0.6, 0.8]
    f = simulate_brdf(geometry, SMOOTH[geometry], wi, wo, rho=rho, paths=20_000, seed=2)
    assert np.allclose(f.f, rho / math.pi, rtol=2e-3)


@pytest.mark.parametrize(
    "geometry,roughness",
    [
        ("vcavity", 0.3),
        ("vcavity", 1.2),
        ("smith-beckmann", 0.5),
        ("smith-beckmann", 1.5),
        ("smith-ggx", 0.4),
        ("smith-ggx", 1.5),
    ],
)
def test_white_furnace_every_path_leaves(geometry, roughness):
    """At rho = 1 nothing is absorbed: albedo 1.  (Scored rho^k, so this checks that every
    path ends by leaving; paths cut at the bounce limit are counted and must be rare.)"""
    est = simulate_albedo(geometry, roughness, [0.05, 0.5, 0.95], rho=[1.0, 0.7], paths=30_000, seed=3)
    assert np.all(est.albedo[:, 0] == pytest.approx(1.0, abs=1e-12))
    assert np.all(est.truncated <= 2e-3 * est.paths)
    assert np.allclose(est.albedo_by_order.sum(axis=1), est.albedo, atol=1e-12)
    assert np.all(est.albedo[:, 1] < 1.0)


@pytest.mark.parametrize("geometry,roughness", [("vcavity", 0.6), ("smith-beckmann", 0.7), ("smith-ggx", 0.6)])
def test_brdf_reciprocal(geometry, roughness):
    rng = np.random.default_rng(7)
    z = rng.uniform(0.15, 1.0, (4, 2))
    ph = rng.uniform(0, 2 * np.pi, (4, 2))
    s = np.sqrt(1 - z * z)
    d = np.stack([s * np.cos(ph), s * np.sin(ph), z], axis=-1)
    a, b = d[:, 0], d[:, 1]
    f_ab = simulate_brdf(geometry, roughness, a, b, rho=0.8, paths=80_000, seed=1)
    f_ba = simulate_brdf(geometry, roughness, b, a, rho=0.8, paths=80_000, seed=2)
    z_score = (f_ab.f - f_ba.f) / np.hypot(f_ab.stderr, f_ba.stderr)
    assert np.all(np.abs(z_score) < 4.5), z_score
    # the order-1 term is reciprocal on its own
    z1 = (f_ab.f_by_order[:, 0] - f_ba.f_by_order[:, 0]) / np.hypot(
        f_ab.stderr_by_order[:, 0], f_ba.stderr_by_order[:, 0]
    )
    assert np.all(np.abs(z1) < 4.5), z1


@pytest.mark.parametrize("geometry,roughness", [("vcavity", 0.5), ("smith-ggx", 0.7)])
def test_albedo_is_the_integral_of_the_brdf(geometry, roughness):
    """E(wi) = int f(wi, wo) mu_o dwo: the next-event BRDF integrated by Gauss-Legendre over
    wo against the albedo estimator (paths that leave), both per bounce order."""
    mu_i = 0.6
    wi = np.array([math.sqrt(1 - mu_i**2), 0.0, mu_i])
    x, w = np.polynomial.legendre.leggauss(10)
    mu_o = 0.5 * (x + 1)
    wmu = 0.5 * w
    n_phi = 12
    phi = (np.arange(n_phi) + 0.5) * np.pi / n_phi  # symmetric in phi -> [0, pi]
    M, P = np.meshgrid(mu_o, phi, indexing="ij")
    S = np.sqrt(1 - M * M)
    wo = np.stack([S * np.cos(P), S * np.sin(P), M], axis=-1).reshape(-1, 3)
    f = simulate_brdf(geometry, roughness, wi, wo, rho=0.7, paths=60_000, seed=4)
    weights = (wmu[:, None] * M * (2 * np.pi / n_phi) * np.ones_like(P)).reshape(-1)
    E_from_f = weights @ f.f[:, 0]
    E = simulate_albedo(geometry, roughness, [mu_i], rho=0.7, paths=200_000, seed=9)
    # f varies smoothly except the back-scattering peak: quadrature error ~ 1e-3
    assert abs(E_from_f - E.albedo[0, 0]) < 6e-3


def test_average_albedo_is_the_cosine_mean():
    est = simulate_average_albedo("vcavity", 0.5, rho=0.5, paths=200_000, seed=1)
    x, w = np.polynomial.legendre.leggauss(6)
    mu = 0.5 * (x + 1)
    E = simulate_albedo("vcavity", 0.5, mu, rho=0.5, paths=100_000, seed=2)
    avg = np.sum(0.5 * w * 2 * mu * E.albedo[:, 0])
    assert abs(avg - est.albedo[0, 0]) < 4.5 * est.stderr[0, 0] + 1e-3


@pytest.mark.parametrize(
    "kwargs,match",
    [
        (dict(geometry="cube"), "geometry"),
        (dict(roughness=-0.1), "roughness"),
        (dict(roughness=2.0), "roughness"),
        (dict(mu=[0.0]), "mu"),
        (dict(mu=[1.5]), "mu"),
        (dict(mu=[np.nan]), "mu"),
        (dict(rho=[1.2]), "rho"),
        (dict(paths=0), "paths"),
        (dict(seed=-1), "seed"),
        (dict(workers=0), "workers"),
    ],
)
def test_bad_input_names_the_argument(kwargs, match):
    args = dict(geometry="vcavity", roughness=0.5, mu=[0.5], rho=1.0, paths=100, seed=0)
    args.update(kwargs)
    with pytest.raises((ValueError, TypeError), match=match):
        simulate_albedo(args.pop("geometry"), args.pop("roughness"), args.pop("mu"), **args)


def test_brdf_rejects_directions_below_the_horizon():
    with pytest.raises(ValueError, match="wo"):
        simulate_brdf("vcavity", 0.5, [0, 0, 1.0], [0.6, 0, -0.8], paths=10)
    with pytest.raises(TypeError, match="roughness"):
        simulate_brdf("vcavity", "rough", [0, 0, 1.0], [0, 0, 1.0], paths=10)
