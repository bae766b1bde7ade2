"""The layered-surface simulator against closed forms, the furnace, reciprocity and limits.

The closed form of a smooth dielectric over a Lambertian base (Saunderson 1942; Lekner &
Dorf 1988) is re-derived here with its own Fresnel factor (from the s- and
p-polarised amplitudes) and scipy quadrature: the simulator, the library's closed form
and this test's each compute it a different way.
"""

import math

import numpy as np
import pytest
from scipy import integrate

from openpbr_diffuse.simulation.layered import (
    LayeredSurface,
    simulate_layered_albedo,
    simulate_layered_average_albedo,
    simulate_layered_brdf,
    smooth_lambert_albedo,
    smooth_lambert_brdf,
    smooth_lambert_terms,
)


def fresnel_sp(mu, n):
    """Unpolarised Fresnel reflectance from the s and p amplitudes (Born & Wolf 1.5.3)."""
    s2 = (1.0 - mu * mu) / (n * n)
    if s2 >= 1.0:
        return 1.0
    ct = math.sqrt(1.0 - s2)
    rs = (mu - n * ct) / (mu + n * ct)
    rp = (n * mu - ct) / (n * mu + ct)
    return 0.5 * (rs * rs + rp * rp)


def r_external(n):
    return integrate.quad(lambda m: 2 * m * fresnel_sp(m, n), 0, 1, limit=200, epsabs=1e-13)[0]


def r_internal(n):
    mc = math.sqrt(1 - 1 / n**2)
    part = integrate.quad(lambda m: 2 * m * fresnel_sp(m, 1 / n), mc, 1, limit=200, epsabs=1e-13)[0]
    return mc * mc + part  # total internal reflection below the critical cosine


def exact_albedo(n, rho, mu, tau=0.0):
    """Directional albedo of smooth dielectric / absorbing slab / Lambert, by quadrature."""
    T = lambda m: math.exp(-tau / m) if m > 0 else 0.0
    e_out = integrate.quad(lambda m: 2 * m * T(m) * (1 - fresnel_sp(m, 1 / n)), 0, 1, limit=200)[0]
    r_in = integrate.quad(
        lambda m: 2 * m * T(m) ** 2 * fresnel_sp(m, 1 / n), 0, 1, limit=200, points=[math.sqrt(1 - 1 / n**2)]
    )[0]
    F = fresnel_sp(mu, n)
    mut = math.sqrt(1 - (1 - mu * mu) / n**2)
    return F + (1 - F) * T(mut) * rho * e_out / (1 - rho * r_in)


@pytest.mark.parametrize("n", [1.3, 1.5, 2.0])
def test_internal_reflectance_identity(n):
    """r_i = 1 - (1 - r_e)/n^2 (Lekner & Dorf 1988), checked by two quadratures, and the
    library's terms agree with both."""
    ri = r_internal(n)
    assert ri == pytest.approx(1 - (1 - r_external(n)) / n**2, abs=1e-9)
    e, r = smooth_lambert_terms(n)
    assert r[0] == pytest.approx(ri, abs=1e-9)
    assert e[0] == pytest.approx(1 - ri, abs=1e-9)


@pytest.mark.parametrize("n,rho,mu,tau", [(1.5, 0.8, 0.5, 0.0), (1.3, 0.4, 0.9, 0.3), (2.0, 0.95, 0.1, 0.05)])
def test_closed_form_matches_quadrature(n, rho, mu, tau):
    assert float(smooth_lambert_albedo(n, rho, mu, tau)) == pytest.approx(exact_albedo(n, rho, mu, tau), abs=1e-8)


CASES = [(n, rho) for n in (1.3, 1.5, 2.0) for rho in (0.3, 0.8)]


@pytest.mark.parametrize("n,rho", CASES)
def test_simulator_matches_closed_form(n, rho):
    mus = np.array([1.0, 0.5, 0.15])
    e = simulate_layered_albedo(LayeredSurface("smooth", n), mus, rho=rho, paths=60_000, seed=3)
    for i, mu in enumerate(mus):
        ref = exact_albedo(n, rho, mu)
        assert abs(e.total[i, 0] - ref) < 3 * e.total_stderr[i, 0] + 1e-12, (mu, e.total[i, 0], ref)
        assert e.specular[i, 0] == pytest.approx(fresnel_sp(mu, n), abs=1e-12)
        assert e.total_stderr[i, 0] > 0


def test_simulator_with_absorption_matches_closed_form():
    cc = np.array([0.9, 0.6, 0.2])
    tau = -np.log(cc)
    s = LayeredSurface("smooth", 1.5, coat_color=cc)
    mus = np.array([0.8, 0.3])
    e = simulate_layered_albedo(s, mus, rho=0.7, paths=60_000, seed=5)
    for i, mu in enumerate(mus):
        for c in range(3):
            ref = exact_albedo(1.5, 0.7, mu, tau[c])
            assert abs(e.total[i, c] - ref) < 3 * e.total_stderr[i, c], (mu, c)
    # Beer-Lambert form: the same optical depth gives the same paths and numbers
    s2 = LayeredSurface("smooth", 1.5, absorption=tau / 0.5, thickness=0.5)
    e2 = simulate_layered_albedo(s2, mus, rho=0.7, paths=60_000, seed=5)
    np.testing.assert_allclose(e2.total, e.total, rtol=1e-12)


def test_standard_errors_are_honest():
    """The spread of 20 seeds matches the reported standard error (chi-square bounds)."""
    n, rho, mu = 1.5, 0.8, 0.6
    ref = exact_albedo(n, rho, mu)
    means, errs = [], []
    for seed in range(20):
        e = simulate_layered_albedo(LayeredSurface("smooth", n), [mu], rho=rho, paths=8_000, seed=seed)
        means.append(e.total[0, 0])
        errs.append(e.total_stderr[0, 0])
    means, errs = np.array(means), np.array(errs)
    ratio = means.var(ddof=1) / np.mean(errs**2)
    assert 0.35 < ratio < 2.0, ratio  # chi2(19)/19 within its 99.9 % range
    chi2 = np.sum(((means - ref) / errs) ** 2)
    assert 5.0 < chi2 < 45.0, chi2  # chi2(20) within its 99.9 % range


@pytest.mark.parametrize(
    "surface",
    [
        LayeredSurface("smooth", 1.5),
        LayeredSurface("ggx", 1.5, 0.5),
        LayeredSurface("ggx", 1.8, 0.1),
        LayeredSurface("smooth", 1.5, base="eon", roughness=0.7),
    ],
)
def test_white_furnace(surface):
    e = simulate_layered_albedo(surface, [1.0, 0.4, 0.1], rho=1.0, paths=40_000, seed=2)
    assert np.all(e.truncated == 0)
    for i in range(3):
        assert abs(e.total[i, 0] - 1.0) < 3 * e.total_stderr[i, 0] + 1e-12
    a = simulate_layered_average_albedo(surface, rho=1.0, paths=40_000, seed=2)
    assert abs(a.total[0, 0] - 1.0) < 3 * a.total_stderr[0, 0] + 1e-12


def test_rough_interface_conserves_energy_exactly():
    """With rho = 1 and no absorption every path leaves: albedo 1 in every path."""
    e = simulate_layered_albedo(LayeredSurface("ggx", 1.5, 0.8), [0.7, 0.05], rho=1.0, paths=20_000, seed=1)
    np.testing.assert_allclose(e.total, 1.0, atol=1e-12)
    assert np.all(e.specular > 0.02) and np.all(e.diffuse > 0.3)


def test_rough_interface_tends_to_smooth():
    """A nearly smooth GGX interface gives the smooth closed form."""
    mus = np.array([0.9, 0.3])
    e = simulate_layered_albedo(LayeredSurface("ggx", 1.5, 0.005), mus, rho=0.6, paths=60_000, seed=4)
    for i, mu in enumerate(mus):
        assert abs(e.total[i, 0] - exact_albedo(1.5, 0.6, mu)) < 3 * e.total_stderr[i, 0]
        assert abs(e.specular[i, 0] - fresnel_sp(mu, 1.5)) < 3 * e.specular_stderr[i, 0] + 1e-3


def test_brdf_matches_closed_form():
    s = LayeredSurface("smooth", 1.5, coat_color=0.7)
    wi = np.array([[0, 0, 1.0], [0.6, 0, 0.8], [0.95, 0.0, math.sqrt(1 - 0.95**2)]])
    wo = np.array([[0.6, 0, 0.8], [0, 0.8, 0.6], [-0.3, 0.1, math.sqrt(0.9)]])
    b = simulate_layered_brdf(s, wi, wo, rho=0.8, paths=60_000, seed=1)
    ref = smooth_lambert_brdf(1.5, 0.8, wi[:, 2], wo[:, 2], tau=-math.log(0.7))
    assert np.all(np.abs(b.f[:, 0] - ref) < 3 * b.stderr[:, 0])


def test_brdf_reciprocity_eon_base():
    s = LayeredSurface("smooth", 1.6, base="eon", roughness=0.8, coat_color=[0.8, 0.5])
    wi = np.array([[0.0, 0.0, 1.0], [0.8, 0.0, 0.6], [0.3, 0.9, math.sqrt(1 - 0.9)]])
    wo = np.array([[0.6, 0.0, 0.8], [-0.7, 0.1, math.sqrt(1 - 0.5)], [0.95, 0, math.sqrt(1 - 0.95**2)]])
    a = simulate_layered_brdf(s, wi, wo, rho=[0.9, 0.5], paths=60_000, seed=1)
    b = simulate_layered_brdf(s, wo, wi, rho=[0.9, 0.5], paths=60_000, seed=2)
    z = np.abs(a.f - b.f) / np.hypot(a.stderr, b.stderr)
    assert np.all(z < 3.5), z


def test_index_matched_limit_is_the_base():
    e = simulate_layered_albedo(LayeredSurface("smooth", 1.0), [0.9, 0.2], rho=[0.3, 0.9], paths=5_000, seed=0)
    np.testing.assert_allclose(e.total, [[0.3, 0.9], [0.3, 0.9]], atol=1e-12)
    from openpbr_diffuse.albedo import reference_albedo

    mus = np.array([0.9, 0.4, 0.1])
    s = LayeredSurface("smooth", 1.0, base="eon", roughness=0.6)
    e = simulate_layered_albedo(s, mus, rho=[0.5, 1.0], paths=60_000, seed=0)
    ref = reference_albedo("eon", mus, 0.6, np.array([0.5, 1.0]))
    assert np.all(np.abs(e.total - ref) < 3.5 * e.total_stderr + 2e-5), (e.total, ref)
    assert np.all(e.specular == 0.0)


def test_reproducible_and_independent_of_workers():
    s = LayeredSurface("ggx", 1.4, 0.3, coat_color=0.8)
    a = simulate_layered_albedo(s, [0.5, 0.9], rho=0.5, paths=70_000, seed=9, workers=1)
    b = simulate_layered_albedo(s, [0.9], rho=0.5, paths=70_000, seed=9, workers=2)
    assert np.array_equal(a.total[1], b.total[0]) and np.array_equal(a.total_stderr[1], b.total_stderr[0])
    c = simulate_layered_albedo(s, [0.9], rho=0.5, paths=70_000, seed=10, workers=2)
    assert not np.array_equal(b.total, c.total)


def test_dask_bit_identical():
    distributed = pytest.importorskip("dask.distributed")
    s = LayeredSurface("smooth", 1.5, base="eon", roughness=0.4)
    serial = simulate_layered_albedo(s, [0.5], rho=0.6, paths=70_000, seed=4, workers=1)
    with (
        distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None) as cluster,
        distributed.Client(cluster) as client,
    ):
        dist = simulate_layered_albedo(s, [0.5], rho=0.6, paths=70_000, seed=4, client=client)
    assert np.array_equal(serial.total, dist.total) and np.array_equal(serial.diffuse_stderr, dist.diffuse_stderr)


@pytest.mark.parametrize(
    "kwargs,exc",
    [
        ({"interface": "rough", "ior": 1.5}, ValueError),
        ({"interface": "smooth", "ior": 0.5}, ValueError),
        ({"interface": "smooth", "ior": float("nan")}, ValueError),
        ({"interface": "smooth", "ior": "1.5"}, TypeError),
        ({"interface": "ggx", "ior": 1.5, "interface_alpha": 2.0}, ValueError),
        ({"interface": "smooth", "ior": 1.5, "base": "vgroove"}, ValueError),
        ({"interface": "smooth", "ior": 1.5, "coat_color": 0.5, "absorption": 1.0, "thickness": 1.0}, ValueError),
    ],
)
def test_bad_surface(kwargs, exc):
    with pytest.raises(exc):
        _ = LayeredSurface(**kwargs).tau


def test_bad_queries():
    s = LayeredSurface("smooth", 1.5)
    for mu in ([0.0], [1.5], [], [[0.5]]):
        with pytest.raises(ValueError, match="mu"):
            simulate_layered_albedo(s, mu, paths=10)
    with pytest.raises(ValueError, match="rho"):
        simulate_layered_albedo(s, [0.5], rho=1.5, paths=10)
    with pytest.raises(ValueError, match="paths"):
        simulate_layered_albedo(s, [0.5], paths=0)
    with pytest.raises(ValueError, match="smooth"):
        simulate_layered_brdf(LayeredSurface("ggx", 1.5, 0.2), [0, 0, 1.0], [0, 0, 1.0], paths=10)
    with pytest.raises(ValueError, match="coat_color"):
        _ = LayeredSurface("smooth", 1.5, coat_color=-0.1).tau


@pytest.mark.parametrize("alpha", [0.1, 0.5])
def test_rough_specular_part_against_single_scattering_table(alpha):
    """The first-interface reflection of the rough interface is the GGX dielectric lobe's
    albedo (the library's single-scattering table) plus a multiple-scattering gain that is
    at most the energy single scattering misses, 1 - E1 (E1: the GGX albedo with F = 1)."""
    from openpbr_diffuse.microfacet.tables import dielectric_albedo, ggx_albedo

    mus = np.array([0.9, 0.5, 0.2])
    e = simulate_layered_albedo(LayeredSurface("ggx", 1.5, alpha), mus, rho=0.5, paths=100_000, seed=7)
    single = np.asarray(dielectric_albedo(mus, math.sqrt(alpha), 0.2), dtype=float).reshape(-1)
    gain = e.specular[:, 0] - single
    assert np.all(gain > -3 * e.specular_stderr[:, 0]), gain
    missed = 1.0 - np.asarray(ggx_albedo(mus, math.sqrt(alpha)), dtype=float).reshape(-1)
    assert np.all(gain < missed + 3 * e.specular_stderr[:, 0]), (gain, missed)


def test_standard_errors_are_honest_rough_eon_absorbing():
    """Spread of 20 seeds against the reported error for the random-choice walk (GGX
    interface, EON base, absorbing slab), per part."""
    s = LayeredSurface("ggx", 1.6, 0.3, coat_color=0.7, base="eon", roughness=0.6)
    runs = [simulate_layered_albedo(s, [0.4], rho=0.9, paths=6_000, seed=seed) for seed in range(20)]
    for part in ("specular", "diffuse", "total"):
        means = np.array([getattr(e, part)[0, 0] for e in runs])
        errs = np.array([getattr(e, part + "_stderr")[0, 0] for e in runs])
        ratio = means.var(ddof=1) / np.mean(errs**2)
        assert 0.35 < ratio < 2.0, (part, ratio)


def test_microsurface_base_index_matched_is_the_microsurface_simulator():
    """n = 1: the layer over a Smith GGX Lambertian microsurface is that microsurface, as the
    microsurface simulator (a separate kernel) computes it."""
    from openpbr_diffuse.simulation import simulate_albedo

    mus = np.array([0.9, 0.3])
    e = simulate_layered_albedo(
        LayeredSurface("smooth", 1.0, base="smith-ggx", roughness=0.8), mus, rho=[0.5, 1.0], paths=60_000, seed=1
    )
    ref = simulate_albedo("smith-ggx", 0.8, mus, rho=[0.5, 1.0], paths=60_000, seed=2)
    z = np.abs(e.total[:, 0] - ref.albedo[:, 0]) / np.hypot(e.total_stderr[:, 0], ref.stderr[:, 0])
    assert np.all(z < 3.5), z
    np.testing.assert_allclose(e.total[:, 1], 1.0, atol=1e-12)  # rho = 1: every path leaves
    # under a smooth n = 1.5 interface the microsurface base is darker than the Lambertian
    # base of the same facet albedo (its albedo is below rho) but conserves energy at rho = 1
    w = simulate_layered_albedo(
        LayeredSurface("smooth", 1.5, base="smith-ggx", roughness=0.8), [0.5], rho=[0.5, 1.0], paths=40_000, seed=1
    )
    assert abs(w.total[0, 1] - 1.0) < 3 * w.total_stderr[0, 1] + 1e-12
    assert w.total[0, 0] < float(smooth_lambert_albedo(1.5, 0.5, 0.5))
