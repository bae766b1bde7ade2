"""The compiled microfacet lobes the surface uses: GGX kernels, the sheen LTC, table lookups.

References: the NumPy GGX forms (``microfacet.ggx``, graded against quadrature in
``test_ggx.py``), Gauss-Legendre quadrature of the densities, chi-square of the samplers
against their densities (``_chi2``), and the NumPy table interpolation.
"""

import math
from decimal import Decimal, getcontext

import numpy as np
import pytest
from _chi2 import chi2_test
from _quad import sphere_rule

from openpbr_diffuse.microfacet import ggx, kernels, sheen
from openpbr_diffuse.microfacet import tables as T


def _dirs(rng, n, upper=False):
    w = rng.normal(size=(n, 3))
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    if upper:
        w[:, 2] = np.abs(w[:, 2])
    return w


def test_reflection_kernel_equals_the_numpy_form(rng):
    wi, wo = _dirs(rng, 300), _dirs(rng, 300, upper=True)
    for alpha in (0.05, 0.3, 1.0):
        m, c = ggx.microfacet_terms(wi, wo, alpha)
        k = np.array([kernels.reflection(*a, *b, alpha) for a, b in zip(wi, wo)])
        assert np.allclose(k[:, 0], m, rtol=1e-12, atol=1e-300)
        up = m > 0
        assert np.allclose(k[up, 1], c[up], rtol=1e-12)
        for vndf, name in ((True, "vndf"), (False, "ndf")):
            pk = np.array([kernels.reflection_pdf(*a, *b, alpha, vndf) for a, b in zip(wi, wo)])
            assert np.allclose(pk, ggx.reflection_pdf(wo, wi, alpha, name), rtol=1e-12)


@pytest.mark.parametrize("alpha", (ggx.ALPHA_MIN, 1e-3))
def test_reflection_pdf_near_the_mirror_direction_at_small_alpha(alpha):
    """Near the mirror direction at the smallest alpha, D = a2 / (pi (mu_h^2 (a2 - 1) + 1)^2)
    in float64 cancels (1 - mu_h^2 (1 - a2) ~ a2 + 2 delta): the kernels write D of the
    unnormalised half vector without that cancellation.  Reference: the textbook VNDF pdf
    G1(wo) D / (4 mu_o) in 50-digit decimal arithmetic on the same float64 directions."""
    getcontext().prec = 50
    mu = 0.7
    wo = np.array([math.sqrt(1 - mu * mu), 0.0, mu])
    for off in (1e-7, 1e-6, 1e-5, 1e-4, 1e-3):
        t = math.acos(mu) + off  # wi: the mirror direction turned by `off`
        wi = np.array([-math.sin(t), 0.0, math.cos(t)])
        h = [Decimal(float(a)) + Decimal(float(b)) for a, b in zip(wi, wo)]
        mu_h = h[2] / (h[0] ** 2 + h[1] ** 2 + h[2] ** 2).sqrt()
        a2 = Decimal(alpha) * Decimal(alpha)
        pi = Decimal(math.pi)
        D = a2 / (pi * (mu_h * mu_h * (a2 - 1) + 1) ** 2)
        m = Decimal(float(wo[2]))
        lam = ((1 + a2 * (1 - m * m) / (m * m)).sqrt() - 1) / 2
        want = D / ((1 + lam) * 4 * m)
        got = kernels.reflection_pdf(*wi, *wo, alpha, True)
        assert got == pytest.approx(float(want), rel=1e-13), off


@pytest.mark.parametrize("mu, alpha, vndf", [(0.3, 0.2, True), (0.8, 0.6, True), (0.5, 0.4, False)])
def test_ggx_sampler_follows_its_pdf(rng, mu, alpha, vndf):
    wo = np.array([math.sqrt(1 - mu * mu), 0.0, mu])

    def sample(n):
        u = rng.random((n, 2))
        out = np.array([kernels.sample_reflection(*wo, alpha, a, b, vndf) for a, b in u])
        return out[:, :3], out[:, 3]  # pdf column: ok (1) or failed (0)

    z_edges = np.unique(np.concatenate([np.linspace(-1, 1, 21), [0.0]]))
    phi_edges = np.linspace(-math.pi, math.pi, 33)
    p, chi2, dof, mass = chi2_test(
        sample,
        lambda wi: ggx.reflection_pdf(wo, wi, alpha, "vndf" if vndf else "ndf"),
        40_000,
        z_edges,
        phi_edges,
        nq=8,
    )
    assert p > 1e-3, (chi2, dof)


@pytest.mark.parametrize("mu", (0.1, 0.5, 1.0))
@pytest.mark.parametrize("r", (0.05, 0.4, 1.0))
def test_sheen_density_is_normalised_on_the_upper_hemisphere(mu, r):
    wi, w = sphere_rule(mu, 96)
    d = np.vectorize(sheen.sheen_density)(wi[..., 0], wi[..., 1], wi[..., 2], mu, r)
    assert np.sum(d * w) == pytest.approx(1.0, abs=2e-6)


@pytest.mark.parametrize("mu, r", [(0.3, 0.3), (0.9, 0.8)])
def test_sheen_sampler_follows_its_density(rng, mu, r):
    def sample(n):
        u = rng.random((n, 2))
        wi = np.array([sheen.sheen_sample(mu, r, a, b) for a, b in u])
        return wi, np.ones(n)

    z_edges = np.linspace(0.0, 1.0, 17)
    phi_edges = np.linspace(-math.pi, math.pi, 33)
    dens = np.vectorize(sheen.sheen_density)
    p, chi2, dof, mass = chi2_test(
        sample, lambda wi: dens(wi[..., 0], wi[..., 1], wi[..., 2], mu, r), 40_000, z_edges, phi_edges, nq=8
    )
    assert mass == pytest.approx(1.0, abs=1e-4)
    assert p > 1e-3, (chi2, dof)


def test_sheen_albedo_fit_is_in_range():
    mus, rs = np.linspace(0, 1, 21), np.linspace(0.01, 1, 21)
    R = np.array([[sheen.sheen_albedo(m, r) for r in rs] for m in mus])
    assert np.all(R >= 0.0) and np.all(R < 1.0)


def test_compiled_table_lookups_equal_the_numpy_interpolation(rng):
    """The per-row lookups of the surface (both tables collapsed per material to curves in mu)
    against the NumPy tensor-product interpolation of ``microfacet.tables``."""
    from openpbr_diffuse.nodes import OpenPBRSurface
    from openpbr_diffuse.nodes import _surface_kernels as sk

    for mu, r, ior in rng.random((40, 3)):
        ior = 1.0 + 2.0 * ior
        s = OpenPBRSurface(specular_roughness=float(r), specular_ior=float(ior))
        x = float(s.params[sk.P_X_S])
        E1, E5, E6, E = sk.layer_albedos(s.params, 0, sk.P_E1S, sk.P_E5S, sk.P_E6S, sk.P_CURVE_S, mu, x, False)
        assert np.allclose((E1, E5, E6), T.conductor_basis(mu, r), rtol=1e-12, atol=1e-15)
        assert E == pytest.approx(float(T.dielectric_albedo(mu, r, x)), rel=1e-12, abs=1e-15)
        # the coat's curves (its own roughness and index)
        c = OpenPBRSurface(coat_weight=1.0, coat_roughness=float(r), coat_ior=float(ior))
        xc = float(c.params[sk.P_X_C])
        E1c, _, _, Ec = sk.layer_albedos(c.params, 0, sk.P_E1C, sk.P_E1C, sk.P_E1C, sk.P_CURVE_C, mu, xc, False)
        assert E1c == pytest.approx(float(T.conductor_basis(mu, r)[0]), rel=1e-12, abs=1e-15)
        assert Ec == pytest.approx(float(T.dielectric_albedo(mu, r, xc)), rel=1e-12, abs=1e-15)
