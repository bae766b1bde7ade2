"""GGX microfacet terms, Fresnel factors, GGX sampling and the shipped albedo tables.

References used: closed forms (GGX normalisation, E(mu = 1) at alpha = 1), Fresnel's
equations written with Snell's law (s and p polarisations), the defining property of the
F82-tint model, and an independent hemisphere quadrature of the BRDF
(``openpbr_diffuse.albedo.quadrature``, spherical coordinates of wi) against which the
half-vector quadrature that generated the tables and the tables themselves are graded.
"""

import math

import numpy as np
import pytest
from _quad import gauss_legendre

from openpbr_diffuse.albedo.quadrature import hemisphere_albedo
from openpbr_diffuse.microfacet import fresnel, ggx, quadrature, tables


def _wo(mu):
    return np.array([math.sqrt(1.0 - mu * mu), 0.0, mu])


def _quad_albedo(alpha, mu, fresnel, n=48):
    """E(mu) by quadrature of the BRDF in wi (spherical coordinates, panels at theta_o)."""

    def brdf(wi, wo):
        m, c = ggx.microfacet_terms(wi, wo, alpha)
        return m * fresnel(c)

    return float(hemisphere_albedo(brdf, mu, n=n))


# ----------------------------------------------------------------------------- microfacet terms
class TestMicrofacet:
    @pytest.mark.parametrize("alpha", [0.05, 0.3, 1.0])
    def test_ndf_is_normalised(self, alpha):
        # int D(h) mu_h dh = 1 (projected area of the microsurface = 1)
        t, w = gauss_legendre(0.0, 0.5 * math.pi, 400)
        mu = np.cos(t)
        total = 2.0 * math.pi * np.sum(w * ggx.ndf(mu, alpha) * mu * np.sin(t))
        assert total == pytest.approx(1.0, abs=1e-6)

    def test_albedo_at_alpha_one_normal_incidence(self):
        # alpha = 1: D = 1/pi, Lambda(mu) = (1/mu - 1)/2, so at mu_o = 1, f = 1/(2 pi (1 + mu_i))
        # and E = int_0^1 mu/(1 + mu) dmu = 1 - ln 2.
        one = lambda c: np.ones((1,) + np.shape(c))
        assert quadrature.albedo_quadrature(1.0, 1.0, one)[0] == pytest.approx(1.0 - math.log(2.0), abs=1e-12)
        assert _quad_albedo(1.0, 1.0, lambda c: 1.0) == pytest.approx(1.0 - math.log(2.0), abs=1e-9)

    def test_reciprocity(self, rng):
        wi = rng.normal(size=(1000, 3))
        wi[:, 2] = np.abs(wi[:, 2])
        wo = rng.normal(size=(1000, 3))
        wo[:, 2] = np.abs(wo[:, 2])
        wi /= np.linalg.norm(wi, axis=1, keepdims=True)
        wo /= np.linalg.norm(wo, axis=1, keepdims=True)
        a, _ = ggx.microfacet_terms(wi, wo, 0.3)
        b, _ = ggx.microfacet_terms(wo, wi, 0.3)
        assert np.allclose(a, b, rtol=1e-12)

    def test_below_horizon_is_zero(self):
        m, _ = ggx.microfacet_terms(np.array([0.6, 0.0, -0.8]), _wo(0.5), 0.3)
        assert m == 0.0


# ----------------------------------------------------------------------------- Fresnel
class TestFresnel:
    @pytest.mark.parametrize("eta", [1.33, 1.5, 2.4])
    def test_dielectric_against_snell(self, eta):
        c = np.linspace(0.01, 1.0, 50)
        s = np.sqrt(1.0 - c * c) / eta  # Snell: sin t = sin i / eta
        ct = np.sqrt(1.0 - s * s)
        rs = (c - eta * ct) / (c + eta * ct)
        rp = (eta * c - ct) / (eta * c + ct)
        assert np.allclose(fresnel.fresnel_dielectric(c, eta), 0.5 * (rs * rs + rp * rp), atol=1e-14)

    def test_dielectric_limits(self):
        assert fresnel.fresnel_dielectric(1.0, 1.5) == pytest.approx(0.04)
        assert fresnel.fresnel_dielectric(0.0, 1.5) == 1.0
        assert np.all(fresnel.fresnel_dielectric(np.linspace(0, 1, 11), 1.0) == 0.0)

    def test_specular_weight_modulates_f0(self):
        # OpenPBR: eta' is the index whose F0 is specular_weight * F0(eta)
        for w, ior in [(0.5, 1.5), (1.0, 2.0), (0.1, 1.33), (2.0, 1.5)]:
            x = fresnel.modulated_ior_parameter(w, ior)
            assert fresnel.f0_of_eta(fresnel.eta_of_parameter(x)) == pytest.approx(
                w * fresnel.f0_of_eta(ior), rel=1e-12
            )
        assert fresnel.modulated_ior_parameter(0.0, 1.5) == 0.0
        assert fresnel.modulated_ior_parameter(1.0, 1.0 / 1.5) < 0.0  # eta < 1 keeps its side

    def test_f82_tint_defining_properties(self):
        F0 = np.array([[0.9, 0.6, 0.3]])
        tint = np.array([[0.8, 0.5, 1.0]])
        schlick = lambda c: F0 + (1.0 - F0) * (1.0 - c) ** 5
        assert np.allclose(fresnel.fresnel_f82_tint(1.0, F0, tint), F0)
        assert np.allclose(fresnel.fresnel_f82_tint(0.0, F0, tint), 1.0)
        assert np.allclose(fresnel.fresnel_f82_tint(1.0 / 7.0, F0, tint), tint * schlick(1.0 / 7.0))
        # tint = 1 is Schlick everywhere
        c = np.linspace(0, 1, 9)
        assert np.allclose(fresnel.fresnel_f82_tint(c, F0, np.ones((1, 3))), schlick(c[:, None]))


# ----------------------------------------------------------------------------- sampling
class TestSampling:
    @pytest.mark.parametrize("method", ["vndf", "ndf"])
    @pytest.mark.parametrize("mu", [0.2, 0.9])
    def test_returned_pdf_is_reflection_pdf(self, rng, method, mu):
        u = rng.random((2000, 2))
        wi, p = ggx.sample_reflection(np.broadcast_to(_wo(mu), (2000, 3)), 0.4, u[:, 0], u[:, 1], method)
        assert np.allclose(np.linalg.norm(wi, axis=1), 1.0)
        assert np.allclose(p, ggx.reflection_pdf(_wo(mu), wi, 0.4, method), rtol=1e-10)

    @pytest.mark.parametrize("alpha, mu", [(0.09, 0.3), (0.5, 0.1), (1.0, 0.7)])
    def test_vndf_weight_estimates_the_albedo(self, rng, alpha, mu):
        # E1 = mean(f mu_i / pdf) over VNDF samples; reference: wi-space quadrature
        n = 200_000
        u = rng.random((n, 2))
        wo = _wo(mu)
        wi, p = ggx.sample_reflection(np.broadcast_to(wo, (n, 3)), alpha, u[:, 0], u[:, 1])
        m, _ = ggx.microfacet_terms(wi, wo, alpha)
        w = np.where(p > 0, m * np.maximum(wi[:, 2], 0.0) / np.where(p > 0, p, 1.0), 0.0)
        ref = _quad_albedo(alpha, mu, lambda c: 1.0)
        assert abs(w.mean() - ref) < 4.0 * w.std() / math.sqrt(n) + 1e-6


# ----------------------------------------------------------------------------- albedo quadrature and tables
class TestHalfVectorQuadrature:
    @pytest.mark.parametrize(
        "alpha, mu, eta", [(0.09, 0.3, 1.5), (0.25, 0.05, 1.5), (0.6, 0.8, 2.0), (0.0025, 0.5, 1.33), (1.0, 0.02, 1.5)]
    )
    def test_agrees_with_hemisphere_quadrature(self, alpha, mu, eta):
        f = lambda c: fresnel.fresnel_dielectric(c, eta)
        half = quadrature.albedo_quadrature(mu, alpha, lambda c: f(c)[None], 48, 48)[0]
        if alpha < 0.01:  # too peaked for the wi-space grid: compare with a finer half-vector rule
            ref = quadrature.albedo_quadrature(mu, alpha, lambda c: f(c)[None], 128, 128)[0]
        else:
            ref = _quad_albedo(alpha, mu, f, n=64)
        assert half == pytest.approx(ref, abs=2e-6)


class TestTables:
    def test_provenance_headers(self):
        for name, head in tables.provenance().items():
            text = "\n".join(head)
            for key in ("method", "error estimate", "regenerate", "generated", "grid"):
                assert key in text, (name, key)

    def test_exact_zero_without_specular(self):
        assert np.all(tables.dielectric_albedo(np.linspace(0, 1, 7), 0.3, 0.0) == 0.0)

    # Documented accuracy (specular_albedo docstring / README): independent quadrature vs table.
    @pytest.mark.parametrize(
        "r_lo, r_hi, mu_lo, tol", [(0.2, 1.0, 0.05, 2e-4), (0.2, 1.0, 0.0, 6e-4), (0.0, 0.2, 0.05, 3e-3)]
    )
    def test_interpolation_error(self, rng, r_lo, r_hi, mu_lo, tol):
        worst_d = worst_c = 0.0
        for _ in range(12):
            r = rng.uniform(r_lo, r_hi)
            mu = rng.uniform(math.sqrt(mu_lo), 1.0) ** 2
            ior, weight = rng.uniform(1.2, 2.6), rng.choice([1.0, rng.uniform(0.05, 1.0)])
            x = float(fresnel.modulated_ior_parameter(weight, ior))
            alpha = float(ggx.alpha_of(r))
            eta = float(fresnel.eta_of_parameter(x))
            fres = lambda c: np.stack(
                [fresnel.fresnel_dielectric(c, eta), np.ones_like(c), (1 - c) ** 5, c * (1 - c) ** 6]
            )
            ref = quadrature.albedo_quadrature(max(mu, tables.MU0), alpha, fres, 48, 48)
            worst_d = max(worst_d, abs(float(tables.dielectric_albedo(mu, r, x)) - ref[0]))
            worst_c = max(worst_c, float(np.max(np.abs(np.array(tables.conductor_basis(mu, r)) - ref[1:]))))
        assert worst_d < tol and worst_c < tol, (worst_d, worst_c)

    def test_metal_albedo_against_quadrature(self):
        F0 = np.array([0.95, 0.64, 0.54])
        tint = np.array([0.9, 0.7, 0.5])
        for r, mu in [(0.3, 0.4), (0.7, 0.9)]:
            alpha = float(ggx.alpha_of(r))
            ref = [
                _quad_albedo(alpha, mu, lambda c, k=k: fresnel.fresnel_f82_tint(c, F0, tint)[..., k]) for k in range(3)
            ]
            assert np.allclose(tables.f82_albedo(mu, r, F0, tint), ref, atol=3e-4)
