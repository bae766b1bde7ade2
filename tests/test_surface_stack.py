"""OpenPBRSurface, the whole lobe stack: coat, fuzz, transmission, subsurface, thin walls.

Grouped by property; each against something independent of the compiled surface:

- white furnace: quadrature of ``eval`` |cos| over the whole sphere (``_quad.sphere_rule``);
- pdf normalisation: quadrature of ``pdf`` over the sphere;
- Monte Carlo through ``sample`` against quadrature of ``eval``;
- chi-square of the sampled directions against ``pdf`` (``_chi2``);
- every lobe's albedo against quadrature of its own BSDF (``lobe_eval``);
- the reduction to the base substrate (coat, fuzz, subsurface, transmission at 0) against a
  second formulation written here with NumPy from the library's public pieces (the
  MaterialX Oren-Nayar node, ``microfacet.ggx``/``fresnel``/``tables``);
- the diffuse lobe's effective weight under a coat and fuzz against the product of the
  spec's factors, each computed here (layer albedos by quadrature of the layer's own BRDF
  written with ``microfacet.ggx``/``fresnel`` and ``microfacet.sheen``).
"""

import math
import warnings

import numpy as np
import pytest
from _chi2 import chi2_test
from _quad import sphere_rule

from openpbr_diffuse.albedo.quadrature import hemisphere_albedo
from openpbr_diffuse.microfacet import fresnel, ggx, sheen
from openpbr_diffuse.microfacet import tables as spec_tables
from openpbr_diffuse.nodes import OpenPBRSurface, OrenNayarDiffuseBSDF

WHITE = dict(base_color=(1, 1, 1), specular_color=(1, 1, 1), coat_color=(1, 1, 1), fuzz_color=(1, 1, 1))
STACKS = {
    "coated": dict(
        base_color=(0.8, 0.3, 0.1),
        base_diffuse_roughness=0.6,
        specular_roughness=0.4,
        coat_weight=0.8,
        coat_roughness=0.3,
        coat_ior=1.6,
        coat_color=(0.9, 0.8, 0.7),
    ),
    "fuzzy": dict(
        base_color=(0.3, 0.5, 0.7),
        base_diffuse_roughness=1.0,
        specular_roughness=0.5,
        fuzz_weight=0.8,
        fuzz_color=(0.9, 0.9, 1.0),
        fuzz_roughness=0.5,
    ),
    "transmissive": dict(
        base_color=(0.9, 0.9, 0.9),
        transmission_weight=0.7,
        transmission_color=(0.8, 0.9, 1.0),
        specular_roughness=0.35,
        base_diffuse_roughness=0.3,
    ),
    "thin_subsurface": dict(
        subsurface_weight=0.6,
        subsurface_color=(0.9, 0.5, 0.4),
        geometry_thin_walled=True,
        subsurface_scatter_anisotropy=0.3,
        specular_roughness=0.5,
        base_diffuse_roughness=0.5,
    ),
    "everything": dict(
        base_color=(0.7, 0.6, 0.5),
        base_metalness=0.3,
        base_diffuse_roughness=0.8,
        specular_roughness=0.45,
        subsurface_weight=0.3,
        subsurface_color=(0.8, 0.4, 0.3),
        transmission_weight=0.2,
        coat_weight=0.5,
        coat_roughness=0.35,
        coat_ior=1.4,
        coat_darkening=0.7,
        fuzz_weight=0.4,
        fuzz_roughness=0.6,
    ),
}


def _wo(mu):
    return np.array([math.sqrt(1.0 - mu * mu), 0.0, mu])


def sphere_albedo(s, mu, n=64):
    """int f(wi, wo) |wi.z| dwi over the whole sphere (reflection and transmission)."""
    wi, w = sphere_rule(mu, n)
    f = s.eval(wi, _wo(mu))
    return np.einsum("tpc,tp->c", f * np.abs(wi[..., 2:3]), w)


def throughput(s, wo, u):
    wi, p = s.sample(wo, u)
    f = s.eval(wi, wo)
    ok = p > 0
    return np.where(ok[:, None], f * np.abs(wi[:, 2:3]) / np.where(ok, p, 1.0)[:, None], 0.0)


# ----------------------------------------------------------------------------- white furnace
class TestWhiteFurnace:
    """White base, white specular, white coat and fuzz: the full stack preserves energy.

    Tolerance reached (quadrature of eval, order 64 per panel, mu_o in {0.2, 0.5, 1}):
    max |E - 1| = 5.2e-6 at these roughnesses (the GGX albedo tables' accuracy sets it; the
    test allows 5e-5); ``albedo`` itself equals 1 to 1e-12.
    """

    CASES = [
        dict(
            coat_weight=c,
            coat_roughness=rc,
            coat_ior=ior,
            fuzz_weight=fw,
            fuzz_roughness=fr,
            specular_roughness=rs,
            base_diffuse_roughness=rd,
            base_metalness=m,
            transmission_weight=t,
        )
        for c, rc, ior, fw, fr, rs, rd, m, t in [
            (1.0, 0.3, 1.5, 0.0, 0.5, 0.4, 0.5, 0.0, 0.0),
            (0.5, 0.6, 2.0, 0.5, 0.3, 0.6, 1.0, 0.0, 0.0),
            (1.0, 0.25, 1.3, 1.0, 0.8, 0.3, 0.0, 0.5, 0.0),
            (0.3, 0.8, 1.8, 0.7, 1.0, 0.8, 0.7, 0.0, 0.5),
            (0.0, 0.3, 1.5, 1.0, 0.2, 0.5, 0.3, 0.0, 0.0),
        ]
    ]

    @pytest.mark.parametrize("case", range(len(CASES)))
    def test_quadrature_of_eval_is_one(self, case):
        s = OpenPBRSurface(**WHITE, **self.CASES[case])
        for mu in (0.2, 0.5, 1.0):
            assert np.allclose(s.albedo(_wo(mu)), 1.0, atol=1e-12)
            assert np.allclose(sphere_albedo(s, mu), 1.0, atol=5e-5), (case, mu)


# ----------------------------------------------------------------------------- pdf
class TestPdf:
    @pytest.mark.parametrize("name", list(STACKS))
    @pytest.mark.parametrize("mu", (0.15, 0.6, 1.0))
    def test_mixture_pdf_integrates_to_one_over_the_sphere(self, name, mu):
        s = OpenPBRSurface(**STACKS[name])
        wi, w = sphere_rule(mu, 64)
        assert np.sum(s.pdf(_wo(mu), wi) * w) == pytest.approx(1.0, abs=5e-6)  # reached: 6.1e-7

    @pytest.mark.parametrize("name", ["coated", "transmissive", "everything"])
    def test_sampler_matches_pdf_chi2(self, rng, name):
        s = OpenPBRSurface(**STACKS[name])
        wo = _wo(0.4)
        z_edges = np.unique(np.concatenate([np.linspace(-1, 1, 25), [-0.4, 0.0, 0.4]]))
        phi_edges = np.linspace(-math.pi, math.pi, 49)
        pval, chi2, dof, mass = chi2_test(
            lambda m: s.sample(wo, rng.random((m, 3))), lambda wi: s.pdf(wo, wi), 200_000, z_edges, phi_edges, nq=8
        )
        assert mass == pytest.approx(1.0, rel=1e-4)
        assert pval > 1e-3, (chi2, dof)

    def test_returned_pdf_is_the_mixture_pdf(self, rng):
        s = OpenPBRSurface(**STACKS["everything"])
        wo = _wo(0.3)
        for dim in (2, 3):
            wi, p = s.sample(wo, rng.random((5000, dim)))
            assert np.allclose(p, s.pdf(wo, wi), rtol=1e-9, atol=0.0)


# ----------------------------------------------------------------------------- albedo and Monte Carlo
class TestAlbedo:
    @pytest.mark.parametrize("name", list(STACKS))
    @pytest.mark.parametrize("mu", (0.25, 0.8))
    def test_albedo_equals_quadrature_of_eval(self, name, mu):
        s = OpenPBRSurface(**STACKS[name])
        assert np.allclose(s.albedo(_wo(mu)), sphere_albedo(s, mu), atol=1e-4)  # reached: 1.1e-5

    @pytest.mark.parametrize("name", list(STACKS))
    def test_lobe_albedos_equal_quadrature_of_their_bsdfs(self, name):
        s = OpenPBRSurface(**STACKS[name])
        mu = 0.55
        wi, w = sphere_rule(mu, 64)
        for lobe in s.lobes(_wo(mu)):
            f = s.lobe_eval(lobe.name, wi, _wo(mu))
            q = np.einsum("tpc,tp->c", f * np.abs(wi[..., 2:3]), w)
            assert np.allclose(lobe.albedo, q, atol=3e-4), lobe.name

    @pytest.mark.parametrize("name", ["coated", "fuzzy", "transmissive"])
    @pytest.mark.parametrize("mu", (0.3, 0.9))
    def test_monte_carlo_through_sample_equals_quadrature(self, rng, name, mu):
        s = OpenPBRSurface(**STACKS[name])
        n = 200_000
        w = throughput(s, _wo(mu), rng.random((n, 3)))
        tol = 4.0 * w.std(axis=0) / math.sqrt(n) + 1e-6
        assert np.all(np.abs(w.mean(axis=0) - sphere_albedo(s, mu)) < tol)


# ----------------------------------------------------------------------------- the base substrate
def base_substrate_numpy(p, wi, wo):
    """eval, albedo and the diffuse/specular/metal probabilities of the base substrate written
    with NumPy: M f_metal + (1 - M)[f_spec + (1 - E_spec) base_weight f_EON] (single material)."""
    bc = np.asarray(p["base_color"], float)
    M, bw, sw = p["base_metalness"], p["base_weight"], p["specular_weight"]
    sc = np.asarray(p["specular_color"], float)
    r = p["specular_roughness"]
    alpha = float(ggx.alpha_of(r))
    x = abs(float(fresnel.modulated_ior_parameter(sw, p["specular_ior"])))
    eta = float(fresnel.eta_of_parameter(x))
    mu_o = wo[..., 2]
    E1 = spec_tables.ggx_albedo(mu_o, r)
    ms_s = 1.0 + x * x * (1.0 - E1) / E1
    Es = spec_tables.dielectric_albedo(mu_o, r, x) * ms_s
    F0m = bw * bc
    ms_m = 1.0 + F0m * ((1.0 - E1) / E1)[..., None]
    m, c = ggx.microfacet_terms(wi, wo, alpha)
    node = OrenNayarDiffuseBSDF(1.0, bc, p["base_diffuse_roughness"], True)
    f = M * sw * fresnel.fresnel_f82_tint(c, F0m, sc) * ms_m * m[..., None] + (1 - M) * (
        sc * (fresnel.fresnel_dielectric(c, eta) * ms_s * m)[..., None] + ((1 - Es) * bw)[..., None] * node.eval(wi, wo)
    )
    w_d = ((1 - M) * bw * (1 - Es))[..., None] * np.ones(3)
    E_d = node.albedo(wo)
    E_m = spec_tables.f82_albedo(mu_o, r, F0m, sc) * ms_m
    albedo = w_d * E_d + (1 - M) * sc * Es[..., None] + M * sw * E_m
    return f, albedo


class TestReducesToTheBaseSubstrate:
    @pytest.mark.parametrize(
        "p",
        [
            dict(
                base_color=(0.9, 0.5, 0.2),
                base_diffuse_roughness=1.0,
                specular_roughness=0.5,
                base_metalness=0.0,
                base_weight=1.0,
                specular_weight=1.0,
                specular_color=(1, 1, 1),
                specular_ior=1.5,
            ),
            dict(
                base_color=(0.3, 0.6, 0.9),
                base_diffuse_roughness=0.4,
                specular_roughness=0.6,
                base_metalness=0.5,
                base_weight=0.8,
                specular_weight=0.6,
                specular_color=(1.0, 0.9, 0.8),
                specular_ior=1.8,
            ),
        ],
    )
    def test_layers_at_zero_weight_give_the_base_substrate(self, rng, p):
        s = OpenPBRSurface(
            **p,
            coat_weight=0.0,
            fuzz_weight=0.0,
            subsurface_weight=0.0,
            transmission_weight=0.0,
            coat_roughness=0.7,
            coat_ior=2.0,
            fuzz_roughness=0.2,
        )
        wi = rng.normal(size=(400, 3))
        wi /= np.linalg.norm(wi, axis=1, keepdims=True)
        wo = rng.normal(size=(400, 3))
        wo /= np.linalg.norm(wo, axis=1, keepdims=True)
        wo[:, 2] = np.abs(wo[:, 2]) + 0.02
        wo /= np.linalg.norm(wo, axis=1, keepdims=True)
        f, E = base_substrate_numpy(p, wi, wo)
        assert np.allclose(s.eval(wi, wo), f, rtol=1e-9, atol=1e-12)
        assert np.allclose(s.albedo(wo), E, rtol=1e-9, atol=1e-12)
        assert [lb.name for lb in s.lobes(wo)] == (
            ["diffuse", "specular", "metal"] if p["base_metalness"] else ["diffuse", "specular"]
        )


# ----------------------------------------------------------------------------- the diffuse weight
def _gl_hemisphere_albedo(brdf, mu, n=96):
    """int brdf(wi) mu_i dwi over the upper hemisphere, wo in the xz-plane (panels at theta_o)."""
    return float(hemisphere_albedo(lambda wi, wo: brdf(wi, wo), mu, n=n))


def coat_albedo_by_quadrature(mu, roughness, ior):
    """E of the coat's GGX dielectric lobe (with the multiple-scattering factor), by quadrature."""
    alpha = float(ggx.alpha_of(roughness))

    def brdf(wi, wo):
        m, c = ggx.microfacet_terms(wi, wo, alpha)
        return m * fresnel.fresnel_dielectric(c, ior)

    E = _gl_hemisphere_albedo(brdf, mu)
    E1 = _gl_hemisphere_albedo(lambda wi, wo: ggx.microfacet_terms(wi, wo, alpha)[0], mu)
    F0 = float(fresnel.f0_of_eta(ior))
    return E * (1.0 + F0 * (1.0 - E1) / E1)


def sheen_albedo_by_quadrature(mu, roughness):
    """E of the sheen lobe R D(wi)/mu_i by quadrature of its LTC density."""

    def brdf(wi, wo):
        d = np.vectorize(sheen.sheen_density)(wi[..., 0], wi[..., 1], wi[..., 2], mu, roughness)
        return sheen.sheen_albedo(mu, roughness) * d / np.maximum(wi[..., 2], 1e-300)

    return _gl_hemisphere_albedo(brdf, mu, n=48)


class TestDiffuseWeight:
    def test_coated_fuzzy_diffuse_weight_is_the_product_of_the_spec_factors(self):
        p = dict(
            base_color=np.array([0.7, 0.5, 0.3]),
            base_weight=0.9,
            base_diffuse_roughness=0.5,
            specular_roughness=0.4,
            specular_ior=1.5,
            coat_weight=0.7,
            coat_roughness=0.3,
            coat_ior=1.6,
            coat_color=np.array([0.9, 0.85, 0.8]),
            coat_darkening=0.6,
            fuzz_weight=0.5,
            fuzz_roughness=0.4,
        )
        s = OpenPBRSurface(**p)
        mu = 0.6
        (diffuse,) = [lb for lb in s.lobes(_wo(mu)) if lb.name == "diffuse"]
        C, F = p["coat_weight"], p["fuzz_weight"]
        # the spec's terms (OpenPBR 1.1 "Coat", "Fuzz", "Glossy-diffuse"; graph node names)
        E_fuzz = sheen_albedo_by_quadrature(mu, p["fuzz_roughness"])
        E_coat = coat_albedo_by_quadrature(mu, p["coat_roughness"], p["coat_ior"])
        r_eff = (1 - C) * p["specular_roughness"] + C * min(
            1.0, 2 * p["coat_roughness"] ** 4 + p["specular_roughness"] ** 4
        ) ** 0.25
        eta_s = (1 - C) * p["specular_ior"] + C * p["coat_ior"] / p["specular_ior"]  # ior ratio < 1: inverted
        E_spec = coat_albedo_by_quadrature(mu, r_eff, eta_s)
        F0c = ((p["coat_ior"] - 1) / (p["coat_ior"] + 1)) ** 2
        K = 1 - (1 - F0c) / p["coat_ior"] ** 2
        darkening = 1 + C * p["coat_darkening"] * ((1 - K) / (1 - p["base_color"] * K) - 1)
        attenuation = 1 + C * (p["coat_color"] - 1)
        want = (1 - F * E_fuzz) * (1 - C * E_coat) * attenuation * darkening * (1 - E_spec) * p["base_weight"]
        assert np.allclose(diffuse.weight, want, rtol=5e-4)
        # the probability is its share of |w E| (lengths), E the EON albedo
        scores = {lb.name: np.linalg.norm(lb.weight * lb.albedo) for lb in s.lobes(_wo(mu))}
        assert diffuse.probability == pytest.approx(scores["diffuse"] / sum(scores.values()), rel=1e-12)

    def test_transmission_and_subsurface_take_their_share(self):
        base = OpenPBRSurface(base_color=(0.8, 0.8, 0.8))
        mixed = OpenPBRSurface(base_color=(0.8, 0.8, 0.8), transmission_weight=0.25, subsurface_weight=0.4)
        wo = _wo(0.7)
        wd = {lb.name: lb.weight for lb in mixed.lobes(wo)}
        w0 = base.lobes(wo)[0].weight
        assert np.allclose(wd["diffuse"], w0 * 0.75 * 0.6, rtol=1e-12)
        assert np.allclose(wd["subsurface"], w0 * 0.75 * 0.4, rtol=1e-12)
        assert np.allclose(wd["transmission"], w0 * 0.25, rtol=1e-12)


# ----------------------------------------------------------------------------- inputs
class TestInputs:
    def test_unmodelled_inputs_are_reported(self):
        with pytest.warns(UserWarning, match="thin_film_weight"):
            s = OpenPBRSurface(thin_film_weight=0.5, coat_weight=0.5)
        assert set(s.ignored_inputs) == {"thin_film_weight"}

    def test_modelled_layers_are_not_reported(self):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            s = OpenPBRSurface(
                coat_weight=0.5,
                fuzz_weight=0.3,
                transmission_weight=0.2,
                subsurface_weight=0.1,
                geometry_thin_walled=True,
            )
        assert s.ignored_inputs == {}

    def test_array_materials_match_single_ones(self, rng):
        n = 4
        p = dict(
            coat_weight=rng.uniform(0, 1, n),
            fuzz_weight=rng.uniform(0, 1, n),
            transmission_weight=rng.uniform(0, 1, n),
            base_color=rng.uniform(0, 1, (n, 3)),
            coat_roughness=rng.uniform(0.2, 1, n),
        )
        s = OpenPBRSurface(**p)
        wo = np.stack([_wo(m) for m in rng.uniform(0.1, 1, n)])
        wi = np.stack([_wo(m) for m in rng.uniform(-1, 1, n)]) * np.array([-1.0, 1.0, 1.0])
        u = rng.random((n, 3))
        f, E, pdf = s.eval(wi, wo), s.albedo(wo), s.pdf(wo, wi)
        wi_s, p_s = s.sample(wo, u)
        for k in range(n):
            one = OpenPBRSurface(**{key: v[k] for key, v in p.items()})
            assert np.allclose(f[k], one.eval(wi[k], wo[k]), rtol=1e-12)
            assert np.allclose(E[k], one.albedo(wo[k]), rtol=1e-12)
            assert np.allclose(pdf[k], one.pdf(wo[k], wi[k]), rtol=1e-12)
            wk, pk = one.sample(wo[k], u[k])
            assert np.allclose(wi_s[k], wk, rtol=1e-12) and np.allclose(p_s[k], pk, rtol=1e-12)
