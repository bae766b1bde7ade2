"""The surface's verbs agree with each other on materials with every lobe.

The compiled drivers compute the selection scores from constants of the material (the weight
of lobe k is a layer factor of mu_o times a constant colour, ``_pack_weights``), not from the
weights and albedos that ``lobes`` returns; the sampler chooses and sums in its own loop.
These tests recompute each quantity in NumPy from the public outputs:

- the probabilities are |w_k E_k| / sum (length), max_c |w_k E_k| / sum (max) or 1/K;
- ``sample``'s pdf is ``pdf`` at the sampled direction (u with 3 and with 2 columns);
- ``albedo`` is sum_k w_k E_k and ``eval`` is sum_k w_k f_k (``lobe_eval``);

on seeded random materials mixing coat, fuzz, transmission, subsurface (thin-walled or not),
metal, and the three diffuse models.  The physics (quadrature, white furnace, the spec's
products) is tested in ``test_surface_stack.py`` and ``test_openpbr_surface.py``.
"""

import math
import warnings

import numpy as np
import pytest

from openpbr_diffuse import OpenPBRSurface


def random_material(rng, **extra):
    c = lambda: tuple(float(v) for v in rng.uniform(0.05, 1.0, 3))  # noqa: E731
    on = lambda p: float(rng.uniform(0.1, 1.0)) if rng.random() < p else 0.0  # noqa: E731
    return dict(
        base_color=c(),
        base_diffuse_roughness=float(rng.uniform(0, 1)),
        base_weight=float(rng.uniform(0.3, 1)),
        base_metalness=on(0.5),
        specular_weight=float(rng.uniform(0.2, 1)),
        specular_color=c(),
        specular_roughness=float(rng.uniform(0.05, 1)),
        specular_ior=float(rng.uniform(1.2, 2.5)),
        transmission_weight=on(0.4),
        transmission_color=c(),
        subsurface_weight=on(0.5),
        subsurface_color=c(),
        subsurface_scatter_anisotropy=float(rng.uniform(-0.8, 0.8)),
        coat_weight=on(0.6),
        coat_color=c(),
        coat_roughness=float(rng.uniform(0, 1)),
        coat_ior=float(rng.uniform(1.2, 2.2)),
        coat_darkening=float(rng.uniform(0, 1)),
        fuzz_weight=on(0.6),
        fuzz_color=c(),
        fuzz_roughness=float(rng.uniform(0.05, 1)),
        geometry_thin_walled=bool(rng.random() < 0.4),
        **extra,
    )


def directions(rng, n, lower=False):
    w = rng.normal(size=(n, 3))
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    if not lower:
        w[:, 2] = np.abs(w[:, 2]) + 1e-3
        w /= np.linalg.norm(w, axis=1, keepdims=True)
    return w


CASES = [
    (seed, model, sel)
    for seed in range(6)
    for model, sel in (("eon", "length"), ("eon", "max"), ("qon", "length"), ("lambert", "max"), ("eon", "uniform"))
]


@pytest.fixture(params=CASES, ids=lambda c: f"seed{c[0]}-{c[1]}-{c[2]}")
def case(request):
    seed, model, sel = request.param
    rng = np.random.default_rng(1000 + seed)
    with warnings.catch_warnings():  # F82 tint below zero, total internal reflection: not tested here
        warnings.simplefilter("ignore")
        s = OpenPBRSurface(**random_material(rng), diffuse_model=model, selection=sel)
    return s, sel, rng


def test_probabilities_are_the_scores_of_the_lobes_weights_and_albedos(case):
    s, sel, rng = case
    wo = directions(rng, 64)
    lobes = s.lobes(wo)
    P = np.stack([lb.probability for lb in lobes])
    wE = np.stack([lb.weight * lb.albedo for lb in lobes])
    if sel == "length":
        score = np.linalg.norm(wE, axis=-1)
    elif sel == "max":
        score = np.max(np.abs(wE), axis=-1)
    else:
        score = np.ones(P.shape)
    assert np.allclose(P.sum(axis=0), 1.0, rtol=0, atol=1e-12)
    assert np.allclose(P, score / score.sum(axis=0), rtol=1e-12, atol=1e-15)


def test_albedo_is_the_sum_of_the_lobes(case):
    s, _, rng = case
    wo = directions(rng, 64)
    total = sum(lb.weight * lb.albedo for lb in s.lobes(wo))
    assert np.allclose(s.albedo(wo), total, rtol=1e-12, atol=1e-15)


def test_eval_is_the_weighted_sum_of_the_lobe_brdfs(case):
    s, _, rng = case
    wo, wi = directions(rng, 200), directions(rng, 200, lower=True)
    total = sum(lb.weight * s.lobe_eval(lb.name, wi, wo) for lb in s.lobes(wo))
    assert np.allclose(s.eval(wi, wo), total, rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("columns", (3, 2))
def test_sampled_pdf_is_pdf_at_the_sample(case, columns):
    s, _, rng = case
    n = 4000
    wo = directions(rng, n)
    wi, q = s.sample(wo, rng.random((n, columns)))
    ok = q > 0
    assert ok.mean() > 0.9
    assert np.allclose(np.linalg.norm(wi, axis=-1), 1.0, rtol=0, atol=1e-14)
    assert np.allclose(q[ok], s.pdf(wo[ok], wi[ok]), rtol=1e-9, atol=0)


def test_sampling_estimates_the_albedo(case):
    """E[f |cos| / pdf] over the sphere through ``sample`` is ``albedo`` (within 5 sigma and
    the 1e-4 of the tabulated GGX albedos): the lobe choice, the lobes' samplers and the
    mixture pdf together make an unbiased estimator."""
    s, _, rng = case
    mu = 0.6
    wo = np.array([math.sqrt(1 - mu * mu), 0.0, mu])
    n = 200_000
    wi, q = s.sample(np.broadcast_to(wo, (n, 3)), rng.random((n, 3)))
    ok = q > 0
    f = s.eval(wi[ok], np.broadcast_to(wo, (ok.sum(), 3)))
    w = np.zeros((n, 3))
    w[ok] = f * np.abs(wi[ok, 2:3]) / q[ok, None]
    est, err = w.mean(axis=0), w.std(axis=0) / math.sqrt(n)
    assert np.all(np.abs(est - s.albedo(wo)) < 5 * err + 1e-4)
