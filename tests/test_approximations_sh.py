"""Order-2 SH lighting of any lobe: basis, zonal rotation, exact transfer and shading, checked
against sphere quadrature written here and the closed-form albedos of the lobe models."""

import math

import numpy as np
import pytest
from conftest import random_directions

import openpbr_diffuse as od
from openpbr_diffuse.approximations import sh


def sphere_grid(n=64):
    x, w = np.polynomial.legendre.leggauss(n)
    phi = (np.arange(2 * n) + 0.5) * math.pi / n
    Z, P = np.meshgrid(x, phi, indexing="ij")
    s = np.sqrt(1 - Z * Z)
    d = np.stack([s * np.cos(P), s * np.sin(P), Z], -1)
    return d, np.outer(w, np.full(2 * n, math.pi / n))


def test_basis_is_orthonormal():
    d, w = sphere_grid()
    Y = sh.basis(d)
    G = np.einsum("abk,abl,ab->kl", Y, Y, w)
    assert np.allclose(G, np.eye(9), atol=1e-12)


@pytest.mark.parametrize(
    "model, rough", [("lambert", 0.0), ("qon", 1.0), ("gotanda", 0.7), ("eon", 0.8), ("full_on", 0.5)]
)
def test_dc_transfer_is_the_albedo(model, rough):
    mu = np.array([0.0, 0.1, 0.5, 0.95, 1.0])
    T = sh.lobe_transfer(model, mu, rough, [0.8, 0.3])
    E = od.reference_albedo(model, mu, rough, [0.8, 0.3])
    assert np.allclose(T[:, 0, :] / sh.C0, E, atol=3e-6)
    assert np.abs(T[:, [1, 4, 5], :]).max() < 1e-12  # odd in y


def test_lambert_transfer_is_the_zonal_cosine(rng):
    zh = sh.zh_project(lambda mu: np.full_like(mu, 1 / math.pi))
    T = sh.lobe_transfer("lambert", 0.4, 0.0)[:, 0]
    assert np.allclose(T, sh.zh_rotate(zh, [0, 0, 1.0]), atol=1e-12)
    n = random_directions(rng, 5)
    d, w = sphere_grid()
    # irradiance-like check: int Y_k(w) max(0, w.n)/pi dw = zh_rotate(zh, n)
    for ni in n:
        direct = np.einsum("abk,ab->k", sh.basis(d), np.maximum(d @ ni, 0) / math.pi * w)
        assert np.allclose(sh.zh_rotate(zh, ni), direct, atol=2e-4)  # kink at the horizon


def test_rotate_is_exact(rng):
    c = rng.normal(size=(4, 9))
    R = sh.frame(random_directions(rng, 4), random_directions(rng, 4))
    w = random_directions(rng, 50)
    for i in range(4):
        lhs = sh.basis(w) @ sh.rotate(c[i], R[i])
        rhs = sh.basis(w @ R[i]) @ c[i]
        assert np.allclose(lhs, rhs, atol=1e-12)


def test_shade_against_world_space_quadrature(rng):
    """Light an EON lobe with an SH environment at a tilted normal; integrate directly in world space."""
    env = rng.normal(0.0, 0.3, (9, 2))
    env[0] = 1.5
    normal = np.array([0.3, -0.4, math.sqrt(1 - 0.25)])
    wo = np.array([-0.5, 0.2, 0.0]) + normal
    wo /= np.linalg.norm(wo)
    got = sh.shade("eon", env, normal, wo, 0.9, [0.7, 0.4], n=32)
    d, w = sphere_grid(160)
    t = np.cross(normal, [1.0, 0, 0])
    t /= np.linalg.norm(t)
    b = np.cross(normal, t)
    F = np.stack([t, b, normal], -1)  # world = F local
    wi_l, wo_l = d @ F, wo @ F
    f = od.evaluate("eon", np.where(wi_l[..., 2:] > 0, wi_l, [0, 0, 1.0]), wo_l, 0.9, [0.7, 0.4])
    f = np.where(wi_l[..., 2:] > 0, f, 0.0)
    L = sh.basis(d) @ env
    ref = np.einsum("abc,ab->c", L * f * np.maximum(wi_l[..., 2:], 0), w)
    assert np.allclose(got, ref, rtol=2e-3)  # the reference grid does not split at the kinks


def test_zh_rotate_matches_the_post_constants():
    assert np.allclose(
        sh.ZH_ROTATION,
        [3.5449077018110320545963349666823, 2.0466534158929769769591032497785, 1.5853309190424044053380115060481],
        rtol=1e-15,
    )
    assert sh.C3 == pytest.approx(0.31539156525252000603089369029571, rel=1e-15)


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: sh.basis([1.0, 1.0, 1.0]), "w"),
        (lambda: sh.zh_rotate([1.0, 2.0], [0, 0, 1.0]), "zh"),
        (lambda: sh.lobe_transfer("qon", 1.2, 0.5), "mu_o"),
        (lambda: sh.lobe_transfer("qon", 0.5, 5.0), "roughness"),
        (lambda: sh.lobe_transfer("qon", 0.5, 0.5, n=2), "n"),
        (lambda: sh.lobe_transfer("nope", 0.5, 0.5), "model"),
        (lambda: sh.shade("qon", np.zeros(9), [0, 0, 1.0], [0, 0, 1.0], 0.5), "env"),
        (lambda: sh.frame([0, 0, 2.0], [0, 0, 1.0]), "normal"),
    ],
)
def test_bad_input_names_the_argument(call, name):
    with pytest.raises(ValueError, match=name):
        call()
