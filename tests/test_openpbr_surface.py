"""OpenPBRSurface: the base substrate as a mixture of lobes with albedo-based selection.

Grouped by property.  Independent references: sphere/hemisphere quadrature of ``pdf`` and
``eval`` (``openpbr_diffuse.albedo.quadrature`` and a Gauss-Legendre sphere rule here),
Monte Carlo through ``sample``, a chi-square test of the sampled directions against the
pdf integrated over bins, and the MaterialX Oren-Nayar node for the pure-diffuse case.
"""

import math

import numpy as np
import pytest
from _chi2 import chi2_test
from _quad import gauss_legendre

from openpbr_diffuse.albedo.quadrature import hemisphere_albedo
from openpbr_diffuse.nodes import OpenPBRSurface, OrenNayarDiffuseBSDF

PARAMS = {
    "default": dict(),
    "rough_colored": dict(base_color=(0.9, 0.5, 0.2), base_diffuse_roughness=1.0, specular_roughness=0.5),
    "copper": dict(
        base_metalness=1.0, base_color=(0.95, 0.64, 0.54), specular_color=(0.9, 0.8, 0.7), specular_roughness=0.4
    ),
    "mixed": dict(
        base_metalness=0.5,
        base_color=(0.3, 0.6, 0.9),
        specular_weight=0.6,
        specular_ior=1.8,
        specular_roughness=0.6,
        base_diffuse_roughness=0.4,
        specular_color=(1.0, 0.9, 0.8),
    ),
    "dim_glossy": dict(
        base_weight=0.7,
        base_color=(0.2, 0.2, 0.25),
        specular_roughness=0.25,
        specular_ior=2.2,
        base_diffuse_roughness=0.8,
    ),
}
MUS = (0.15, 0.5, 0.95)


def _wo(mu):
    return np.array([math.sqrt(1.0 - mu * mu), 0.0, mu])


def sphere_integral(fun, mu, n=64):
    """int fun(wi) dwi over the sphere for wo in the xz-plane (integrand even in phi).

    Panel edges in theta at theta_o (specular peak), pi/2 (horizon: the diffuse pdf stops)
    and pi - theta_o (the half vector reaches the horizon: the GGX pdf stops).
    """
    th_o = math.acos(mu)
    T, WT = zip(
        *(
            gauss_legendre(a, b, n)
            for a, b in zip([0, th_o, 0.5 * math.pi, math.pi - th_o], [th_o, 0.5 * math.pi, math.pi - th_o, math.pi])
            if b > a
        )
    )
    P, WP = zip(
        *(
            gauss_legendre(a, b, n)
            for a, b in [(0, 0.5 * math.pi), (0.5 * math.pi, 0.9 * math.pi), (0.9 * math.pi, math.pi)]
        )
    )
    T, WT, P, WP = map(np.concatenate, (T, WT, P, WP))
    t, p = np.meshgrid(T, P, indexing="ij")
    wi = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)
    return np.einsum("tp...,tp->...", fun(wi), np.outer(WT, 2.0 * WP) * np.sin(t))


def quad_albedo(s, mu, n=None):
    """E(mu) by quadrature of eval; the glossy peak near grazing needs the higher order."""
    n = n or (32 if mu < 0.3 else 16)
    return hemisphere_albedo(lambda wi, wo: s.eval(wi, wo), mu, n=n)


def throughput(s, wo, u):
    wi, p = s.sample(wo, u)
    f = s.eval(wi, wo)
    ok = p > 0
    return np.where(ok[:, None], f * np.maximum(wi[:, 2:3], 0.0) / np.where(ok, p, 1.0)[:, None], 0.0)


@pytest.fixture(params=list(PARAMS))
def surface(request):
    return OpenPBRSurface(**PARAMS[request.param])


# ----------------------------------------------------------------------------- the pdf
class TestPdf:
    @pytest.mark.parametrize("mu", MUS)
    def test_mixture_pdf_integrates_to_one(self, surface, mu):
        total = sphere_integral(lambda wi: surface.pdf(_wo(mu), wi), mu)
        assert total == pytest.approx(1.0, abs=1e-5)

    def test_returned_pdf_is_the_mixture_pdf(self, surface, rng):
        wo = _wo(0.4)
        for dim in (2, 3):
            wi, p = surface.sample(wo, rng.random((5000, dim)))
            assert np.allclose(p, surface.pdf(wo, wi), rtol=1e-10, atol=0.0)

    def test_ndf_sampling_is_defective_where_its_pdf_says(self, rng):
        # NDF sampling fails when the microfacet normal faces away from wo; the pdf then
        # integrates to the success probability, which the sampler must reproduce.
        s = OpenPBRSurface(specular_sampling="ndf", specular_roughness=0.6, base_diffuse_roughness=0.5)
        mu = 0.1
        integral = sphere_integral(lambda wi: s.pdf(_wo(mu), wi), mu)
        n = 200_000
        _, p = s.sample(_wo(mu), rng.random((n, 3)))
        ok = np.mean(p > 0)
        assert integral < 0.999
        assert abs(ok - integral) < 4.0 * math.sqrt(integral * (1 - integral) / n)

    def test_below_horizon_wo(self):
        s = OpenPBRSurface()
        wo = np.array([0.0, 0.6, -0.8])
        wi, p = s.sample(wo, np.array([[0.3, 0.6], [0.9, 0.2]]))
        assert np.all(p == 0) and np.all(np.isfinite(wi))
        assert np.all(s.albedo(wo) == 0) and np.all(s.eval(np.array([0.0, 0.0, 1.0]), wo) == 0)


class TestChiSquare:
    """Sampled directions against the pdf integrated over (z, phi) bins (Mitsuba-style)."""

    @pytest.mark.parametrize("name, mu", [("default", 0.5), ("mixed", 0.2), ("dim_glossy", 0.8)])
    def test_sampler_matches_pdf(self, rng, name, mu):
        s = OpenPBRSurface(**PARAMS[name])
        wo = _wo(mu)
        n = 200_000
        z_edges = np.unique(np.concatenate([np.linspace(-1, 1, 25), [-mu, 0.0]]))
        phi_edges = np.linspace(-math.pi, math.pi, 49)
        pval, chi2, dof, mass = chi2_test(
            lambda m: s.sample(wo, rng.random((m, 2))), lambda wi: s.pdf(wo, wi), n, z_edges, phi_edges, nq=8
        )
        assert mass == pytest.approx(1.0, rel=1e-4)
        assert pval > 1e-3, (chi2, dof)


# ----------------------------------------------------------------------------- albedo
class TestAlbedo:
    @pytest.mark.parametrize("mu", MUS)
    def test_albedo_equals_quadrature_of_eval(self, surface, mu):
        # the tables' documented accuracy for specular_roughness >= 0.2, mu > 0.05
        assert np.allclose(surface.albedo(_wo(mu)), quad_albedo(surface, mu), atol=5e-5)

    @pytest.mark.parametrize("mu", (0.3, 0.9))
    def test_monte_carlo_through_sample(self, surface, rng, mu):
        n = 100_000
        w = throughput(surface, _wo(mu), rng.random((n, 3)))
        tol = 4.0 * w.std(axis=0) / math.sqrt(n) + 1e-6
        assert np.all(np.abs(w.mean(axis=0) - quad_albedo(surface, mu)) < tol)
        assert np.all(np.abs(w.mean(axis=0) - surface.albedo(_wo(mu))) < tol + 5e-5)

    @pytest.mark.slow
    @pytest.mark.parametrize("name", list(PARAMS))
    @pytest.mark.parametrize("mu", (0.08, 0.5, 1.0))
    @pytest.mark.parametrize("udim", (2, 3))
    def test_monte_carlo_through_sample_many(self, rng, name, mu, udim):
        s = OpenPBRSurface(**PARAMS[name])
        n = 2_000_000
        w = throughput(s, _wo(mu), rng.random((n, udim)))
        tol = 4.0 * w.std(axis=0) / math.sqrt(n) + 1e-6
        assert np.all(np.abs(w.mean(axis=0) - quad_albedo(s, mu, n=48)) < tol)

    def test_lobe_albedos_equal_quadrature_of_their_brdfs(self, surface):
        wo = _wo(0.6)
        for lobe in surface.lobes(wo):
            q = hemisphere_albedo(lambda wi, w, k=lobe.name: surface.lobe_eval(k, wi, w), 0.6)
            assert np.allclose(lobe.albedo, q, atol=5e-5), lobe.name

    @pytest.mark.filterwarnings("ignore:the F82-tint")
    def test_energy_is_bounded(self, rng):
        mus = np.linspace(0.02, 1, 30)
        for _ in range(20):
            s = OpenPBRSurface(
                base_color=rng.uniform(0.2, 1, 3),
                base_metalness=rng.uniform(0, 1),
                specular_color=rng.uniform(0, 1, 3),
                specular_weight=rng.uniform(0, 1),
                specular_roughness=rng.uniform(0.1, 1),
                specular_ior=rng.uniform(1, 3),
                base_diffuse_roughness=rng.uniform(0, 1),
                base_weight=rng.uniform(0.5, 1),
            )
            E = s.albedo(np.stack([_wo(m) for m in mus]))
            assert np.all(E >= 0) and np.all(E <= 1 + 1e-6)

    def test_negative_f82_corner_is_announced(self):
        # F82-tint with F0 ~ 0 and tint 0 is negative near mu = 0.5 (published formula)
        with pytest.warns(UserWarning, match="F82-tint"):
            s = OpenPBRSurface(base_metalness=1.0, base_color=(0.02, 0.5, 0.5), specular_color=(0.0, 1.0, 1.0))
        assert s.albedo(_wo(0.5))[0] < 0.0


class TestWhiteFurnace:
    """base_color = specular_color = 1: the layered base preserves energy (to table accuracy)."""

    @pytest.mark.parametrize(
        "metalness, r_spec, r_diff, ior",
        [(0.0, 0.3, 0.0, 1.5), (0.0, 0.6, 1.0, 2.5), (1.0, 0.9, 0.0, 1.5), (0.4, 0.2, 0.7, 1.33)],
    )
    def test_quadrature_of_eval_is_one(self, metalness, r_spec, r_diff, ior):
        s = OpenPBRSurface(
            base_color=(1, 1, 1),
            specular_color=(1, 1, 1),
            base_metalness=metalness,
            specular_roughness=r_spec,
            base_diffuse_roughness=r_diff,
            specular_ior=ior,
        )
        for mu in (0.1, 0.5, 1.0):
            assert np.allclose(quad_albedo(s, mu), 1.0, atol=2e-4)
            assert np.allclose(s.albedo(_wo(mu)), 1.0, atol=1e-9)

    def test_single_scattering_metal_loses_energy(self):
        # without the compensation the GGX lobe keeps E1 < 1: the factor is what restores it
        s = OpenPBRSurface(base_color=(1, 1, 1), base_metalness=1.0, specular_roughness=0.9, multiscatter=False)
        E = quad_albedo(s, 0.5)
        assert np.all(E < 0.9)
        assert np.allclose(s.albedo(_wo(0.5)), E, atol=5e-5)


# ----------------------------------------------------------------------------- lobe selection
class TestSelection:
    @pytest.mark.parametrize("selection", ["length", "max", "uniform"])
    def test_probabilities(self, surface, selection):
        s = OpenPBRSurface(**{**surface.inputs, "selection": selection})
        wo = np.stack([_wo(m) for m in (0.05, 0.3, 0.7, 1.0)])
        lobes = s.lobes(wo)
        P = np.stack([lobe.probability for lobe in lobes])
        assert np.allclose(P.sum(axis=0), 1.0, atol=1e-12)
        score = np.stack([lobe.weight * lobe.albedo for lobe in lobes])
        if selection == "length":
            want = np.linalg.norm(score, axis=-1)
        elif selection == "max":
            want = np.max(score, axis=-1)
        else:
            want = np.ones(P.shape)
        assert np.allclose(P, want / want.sum(axis=0), rtol=1e-12)

    def test_probabilities_follow_quadrature_albedos(self):
        s = OpenPBRSurface(**PARAMS["mixed"])
        mu = 0.45
        lobes = s.lobes(_wo(mu))
        q = [lobe.weight * hemisphere_albedo(lambda wi, w, k=lobe.name: s.lobe_eval(k, wi, w), mu) for lobe in lobes]
        norms = np.array([np.linalg.norm(v) for v in q])
        assert np.allclose([lobe.probability for lobe in lobes], norms / norms.sum(), atol=1e-4)

    def test_active_lobes(self):
        assert [lb.name for lb in OpenPBRSurface().lobes(_wo(0.5))] == ["diffuse", "specular"]
        assert [lb.name for lb in OpenPBRSurface(base_metalness=1.0).lobes(_wo(0.5))] == ["metal"]
        assert [lb.name for lb in OpenPBRSurface(specular_weight=0.0).lobes(_wo(0.5))] == ["diffuse"]
        assert [lb.name for lb in OpenPBRSurface(base_metalness=0.3).lobes(_wo(0.5))] == [
            "diffuse",
            "specular",
            "metal",
        ]
        black = OpenPBRSurface(base_weight=0.0, specular_weight=0.0)
        assert [lb.name for lb in black.lobes(_wo(0.5))] == ["diffuse"]
        assert np.all(black.albedo(_wo(0.5)) == 0)

    def test_variance_lower_than_uniform_selection(self, rng):
        # rough diffuse + glossy specular: albedo-based selection sends few samples to the
        # dim specular lobe, which uniform selection over-samples
        p = dict(base_color=(0.8, 0.8, 0.8), base_diffuse_roughness=1.0, specular_roughness=0.25)
        n = 100_000
        for mu, min_ratio in ((0.5, 5.0), (0.9, 10.0)):
            u = rng.random((n, 3))
            var = [
                throughput(OpenPBRSurface(**p, selection=sel), _wo(mu), u)[:, 1].var() for sel in ("length", "uniform")
            ]
            assert var[1] / var[0] > min_ratio, var


# ----------------------------------------------------------------------------- the pure-diffuse case
class TestReducesToEON:
    @pytest.mark.parametrize("normal", [None, (0.0, 0.6, 0.8)])
    def test_equals_the_node(self, rng, normal):
        # the same compiled formulas, inlined in another loop: equal to rounding
        color, rough, weight = (0.7, 0.4, 0.2), 0.8, 0.9
        kw = {} if normal is None else {"geometry_normal": normal}
        s = OpenPBRSurface(
            base_color=color,
            base_diffuse_roughness=rough,
            base_weight=weight,
            base_metalness=0.0,
            specular_weight=0.0,
            **kw,
        )
        node = OrenNayarDiffuseBSDF(weight, color, rough, True, **({} if normal is None else {"normal": normal}))
        n0 = np.array([0.0, 0.0, 1.0]) if normal is None else np.array(normal)
        wi, wo = rng.normal(size=(500, 3)), rng.normal(size=(500, 3))
        wi /= np.linalg.norm(wi, axis=1, keepdims=True)
        wo /= np.linalg.norm(wo, axis=1, keepdims=True)
        wo *= np.sign(wo @ n0)[:, None]
        same = lambda a, b: np.allclose(a, b, rtol=1e-13, atol=1e-15)  # noqa: E731
        assert same(s.eval(wi, wo), node.eval(wi, wo))
        assert same(s.albedo(wo), node.albedo(wo))
        assert same(s.pdf(wo, wi), node.pdf(wo, wi))
        u = rng.random((500, 2))
        for a, b in zip(s.sample(wo, u), node.sample(wo, u)):
            assert same(a, b)


# ----------------------------------------------------------------------------- frames and arrays
class TestFramesAndArrays:
    def test_world_space_normal(self, rng):
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        R = q * np.sign(np.linalg.det(q))
        local = OpenPBRSurface(**PARAMS["mixed"])
        world = OpenPBRSurface(**PARAMS["mixed"], geometry_normal=R[:, 2])
        wi = rng.normal(size=(200, 3))
        wi /= np.linalg.norm(wi, axis=1, keepdims=True)
        wo = rng.normal(size=(200, 3))
        wo /= np.linalg.norm(wo, axis=1, keepdims=True)
        wo[:, 2] = np.abs(wo[:, 2])
        assert np.allclose(world.eval(wi @ R.T, wo @ R.T), local.eval(wi, wo), rtol=1e-8, atol=1e-12)
        assert np.allclose(world.pdf(wo @ R.T, wi @ R.T), local.pdf(wo, wi), rtol=1e-8, atol=1e-12)
        assert np.allclose(world.albedo(wo @ R.T), local.albedo(wo), rtol=1e-9)
        u = rng.random((200, 3))
        wi_w, p_w = world.sample(wo @ R.T, u)
        assert np.allclose(p_w, world.pdf(wo @ R.T, wi_w), rtol=1e-9)

    def test_array_parameters(self, rng):
        n = 5
        p = dict(
            base_color=rng.uniform(0, 1, (n, 3)),
            base_metalness=rng.uniform(0, 1, n),
            specular_roughness=rng.uniform(0.2, 1, n),
            specular_ior=rng.uniform(1.2, 2.5, n),
            base_diffuse_roughness=rng.uniform(0, 1, n),
        )
        s = OpenPBRSurface(**p)
        wo = np.stack([_wo(m) for m in rng.uniform(0.1, 1, n)])
        wi = np.stack([_wo(m) for m in rng.uniform(0.1, 1, n)]) * np.array([-1.0, 1.0, 1.0])
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
