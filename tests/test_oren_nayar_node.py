"""The MaterialX oren_nayar_diffuse_bsdf node: values, albedo, frames, sampling.

References: the classic angle form of qualitative Oren-Nayar as MaterialX's shader code
writes it (a second formulation of QON, with sigma = roughness), the EON paper's checked
values, a hemisphere quadrature of ``eval``, and rotation invariance.
"""

import math

import numpy as np
import pytest

from openpbr_diffuse.albedo.quadrature import hemisphere_albedo
from openpbr_diffuse.nodes import OrenNayarDiffuseBSDF


def _dirs(rng, n, zmin=0.02):
    z = rng.uniform(zmin, 1.0, n)
    phi = rng.uniform(0.0, 2.0 * math.pi, n)
    s = np.sqrt(1.0 - z * z)
    return np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=-1)


def _rotation(rng):
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return q * np.sign(np.linalg.det(q))


def _qon_angles(wi, wo, sigma, rho):
    """QON in Oren & Nayar's angle form: rho/pi (A + B max(0, cos dphi) sin(alpha) tan(beta))."""
    ti, to = np.arccos(wi[..., 2]), np.arccos(wo[..., 2])
    cos_dphi = np.cos(np.arctan2(wi[..., 1], wi[..., 0]) - np.arctan2(wo[..., 1], wo[..., 0]))
    alpha, beta = np.maximum(ti, to), np.minimum(ti, to)
    s2 = sigma * sigma
    A = 1.0 - 0.5 * s2 / (s2 + 0.33)
    B = 0.45 * s2 / (s2 + 0.09)
    return rho / math.pi * (A + B * np.maximum(0.0, cos_dphi) * np.sin(alpha) * np.tan(beta))[..., None]


class TestValues:
    @pytest.mark.parametrize("sigma", [0.0, 0.4, 1.2])
    def test_qon_is_the_angle_form_with_sigma_roughness(self, rng, sigma):
        wi, wo = _dirs(rng, 500), _dirs(rng, 500)
        rho = np.array([0.2, 0.5, 0.9])
        node = OrenNayarDiffuseBSDF(0.7, rho, sigma, False)
        assert np.allclose(node.eval(wi, wo), 0.7 * _qon_angles(wi, wo, sigma, rho), rtol=1e-10, atol=1e-14)

    def test_eon_albedo_matches_paper_and_quadrature(self):
        # EON is energy preserving: white furnace (the EON paper's white furnace)
        white = OrenNayarDiffuseBSDF(1.0, (1.0, 1.0, 1.0), 1.0, True)
        for mu in (0.1, 0.5, 1.0):
            wo = np.array([math.sqrt(1 - mu * mu), 0.0, mu])
            assert np.allclose(white.albedo(wo), 1.0, atol=1e-6)
        node = OrenNayarDiffuseBSDF(0.8, (0.9, 0.5, 0.1), 0.6, True)
        for mu in (0.2, 0.7):
            q = hemisphere_albedo(lambda wi, w: node.eval(wi, w), mu)
            assert np.allclose(node.albedo(np.array([math.sqrt(1 - mu * mu), 0.0, mu])), q, atol=1e-6)

    def test_qon_albedo_against_quadrature(self):
        node = OrenNayarDiffuseBSDF(1.0, (1.0, 0.5, 0.25), math.pi / 4, False)
        mu = 0.5
        wo = np.array([math.sqrt(1 - mu * mu), 0.0, mu])
        assert node.albedo(wo)[0] == pytest.approx(0.791338, abs=1e-6)  # spec/models.md table
        assert np.allclose(node.albedo(wo), hemisphere_albedo(lambda wi, w: node.eval(wi, w), mu), atol=1e-6)

    def test_below_horizon(self):
        node = OrenNayarDiffuseBSDF(energy_compensation=True, roughness=0.5)
        down = np.array([0.6, 0.0, -0.8])
        up = np.array([0.0, 0.0, 1.0])
        assert np.all(node.eval(down, up) == 0) and np.all(node.eval(up, down) == 0)
        assert np.all(node.albedo(down) == 0)

    def test_array_inputs_broadcast(self, rng):
        wi, wo = _dirs(rng, 4), _dirs(rng, 4)
        colors = rng.uniform(0, 1, (4, 3))
        rough = rng.uniform(0, 1, 4)
        node = OrenNayarDiffuseBSDF(1.0, colors, rough, True)
        f = node.eval(wi, wo)
        for k in range(4):
            one = OrenNayarDiffuseBSDF(1.0, colors[k], rough[k], True)
            assert np.array_equal(f[k], one.eval(wi[k], wo[k]))

    def test_float32_in_float32_out(self, rng):
        wi, wo = _dirs(rng, 8).astype(np.float32), _dirs(rng, 8).astype(np.float32)
        assert OrenNayarDiffuseBSDF().eval(wi, wo).dtype == np.float32


class TestFrame:
    @pytest.mark.parametrize("ec", [False, True])
    def test_world_space_equals_local_after_rotation(self, rng, ec):
        R = _rotation(rng)
        wi, wo = _dirs(rng, 300), _dirs(rng, 300)
        local = OrenNayarDiffuseBSDF(1.0, (0.3, 0.6, 0.9), 0.8, ec)
        world = OrenNayarDiffuseBSDF(1.0, (0.3, 0.6, 0.9), 0.8, ec, normal=R[:, 2])
        assert np.allclose(world.eval(wi @ R.T, wo @ R.T), local.eval(wi, wo), rtol=1e-9, atol=1e-13)
        assert np.allclose(world.albedo(wo @ R.T), local.albedo(wo), rtol=1e-9)
        assert np.allclose(world.pdf(wo @ R.T, wi @ R.T), local.pdf(wo, wi), rtol=1e-9)

    def test_sampled_directions_are_world_space(self, rng):
        n = np.array([0.0, -0.6, 0.8])
        node = OrenNayarDiffuseBSDF(1.0, (0.5, 0.5, 0.5), 1.0, True, normal=n)
        wo = np.array([0.0, 0.0, 1.0])
        wi, p = node.sample(wo, rng.random((1000, 2)))
        assert np.all(wi @ n >= 0.0)
        assert np.allclose(p, node.pdf(wo, wi), rtol=1e-9)

    def test_normals_facing_down(self, rng):
        # the branchless frame flips at n.z = 0; both sides must be orthonormal frames
        for nz in (-1.0, -0.3, 0.0, 0.3):
            n = np.array([math.sqrt(1 - nz * nz), 0.0, nz])
            node = OrenNayarDiffuseBSDF(normal=n)
            F = np.stack([node.frame.t, node.frame.b, node.frame.normal])
            assert np.allclose(F @ F.T, np.eye(3), atol=1e-12) and np.linalg.det(F) > 0


class TestSampling:
    def test_strategies(self, rng):
        wo = _dirs(rng, 50)
        wi = _dirs(rng, 50)
        qon = OrenNayarDiffuseBSDF(roughness=1.2)
        assert np.allclose(qon.pdf(wo, wi), wi[:, 2] / math.pi)  # cosine sampling
        assert OrenNayarDiffuseBSDF(energy_compensation=True).strategy == "eon"

    @pytest.mark.parametrize("ec, roughness", [(True, 1.0), (False, 1.0)])
    def test_throughput_estimates_albedo(self, rng, ec, roughness):
        node = OrenNayarDiffuseBSDF(1.0, (0.9, 0.6, 0.3), roughness, ec)
        wo = np.array([0.8, 0.0, 0.6])
        n = 100_000
        wi, p = node.sample(wo, rng.random((n, 2)))
        w = node.eval(wi, wo) * wi[:, 2:3] / p[:, None]
        err = 4.0 * w.std(axis=0) / math.sqrt(n)
        assert np.all(np.abs(w.mean(axis=0) - node.albedo(wo)) < err)
