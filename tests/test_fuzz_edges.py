"""Seeded fuzz over the edge sets of issue 13, every model and sampling strategy, float32 and float64.

Promises checked (the README states them):

- ``evaluate``: finite, and f >= 0 for every model except "full_on" (its published formula
  is negative at grazing opposite-azimuth pairs for rho below ~0.8 and large sigma; kept
  unclamped, see ``tests/test_models_properties.py``);
- ``sample``: finite unit wi, returned pdf = ``pdf(wo, wi)``, wi.z > 0 for every strategy
  but "ltc", and pdf > 0 (no discard) whenever wo is above the horizon, for every u in
  [0, 1)^2 including 0, subnormals and the largest value below 1;
- broadcast inputs: peak memory beyond the output bounded by a constant (a few blocks).

Rows: 40k per model and dtype for ``evaluate`` (0.8 M), 40k per strategy and dtype for
``sample``/``pdf`` (0.5 M), 1 M for the broadcast check -- about 2.5 M in all.
"""

import math
import tracemalloc

import numpy as np
import pytest

import openpbr_diffuse as od
from openpbr_diffuse import _arrays as ar
from openpbr_diffuse.models.registry import INFO

N = 40_000
Z_EDGES = np.array(
    [0.0, -0.0, 1.0, 1e-300, 5e-324, 1e-310, 2.2250738585072014e-308, 1e-320, 1.0 - 1e-16, 1e-7, 1e-38, 1.4e-45, 0.5]
)
PHI_EDGES = np.array([0.0, 0.5 * math.pi, math.pi, 1.5 * math.pi])


def directions(rng, n):
    """Edge-heavy directions on the upper hemisphere (z >= 0, some exactly 0 or -0)."""
    z = np.where(rng.random(n) < 0.6, rng.choice(Z_EDGES, n), rng.random(n))
    phi = np.where(rng.random(n) < 0.3, rng.choice(PHI_EDGES, n), rng.uniform(0, 2 * math.pi, n))
    s = np.sqrt(1.0 - z * z)
    return np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=-1)


def pairs(rng, n):
    """(wi, wo): independent, equal, opposite, mirrored, reflected, noisy, near-unit lengths."""
    wo = directions(rng, n)
    wi = directions(rng, n)
    kind = rng.integers(0, 7, n)
    wi[kind == 1] = wo[kind == 1]  # wi = wo
    wi[kind == 2] = -wo[kind == 2]  # wi = -wo (below)
    wi[kind == 3] = wo[kind == 3] * [-1.0, -1.0, 1.0]  # opposite azimuth
    wi[kind == 4] = wo[kind == 4] * [1.0, -1.0, 1.0]  # mirrored in the xz-plane
    wi[kind == 5] = wo[kind == 5] * [1.0, 1.0, -1.0]  # reflected in the surface
    noisy = kind == 6
    wi[noisy] = wo[noisy] + rng.normal(0.0, 1e-9, (noisy.sum(), 3))
    scale = 1.0 + ar.UNIT_TOL * rng.uniform(-0.99, 0.99, (n, 2))  # accepted lengths
    scale[rng.random(n) < 0.5] = 1.0
    return wi * scale[:, :1], wo * scale[:, 1:]


def roughness(rng, n, top):
    return np.where(rng.random(n) < 0.5, rng.choice([0.0, top], n), rng.uniform(0.0, top, n))


@pytest.mark.slow
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("model", od.MODELS)
def test_evaluate_edges(model, dtype):
    rng = np.random.default_rng(1300 + INFO[model].id)
    wi, wo = pairs(rng, N)
    top = 1.0 if model == "lambert" else INFO[model].roughness_max
    r = roughness(rng, N, top)
    rho = np.where(rng.random((N, 3)) < 0.5, rng.choice([0.0, 1.0], (N, 3)), rng.random((N, 3)))
    for mode in ("reference", "white_tint"):
        f = od.evaluate(model, wi.astype(dtype), wo.astype(dtype), r.astype(dtype), rho.astype(dtype), color_mode=mode)
        assert f.dtype == dtype and np.isfinite(f).all()
        if model != "full_on":
            assert f.min() >= 0.0, f"{model} {mode}: min f = {f.min()!r}"
        below = (wi.astype(dtype)[:, 2] <= 0) | (wo.astype(dtype)[:, 2] <= 0)
        assert (f[below] == 0).all()


def u_edges(rng, n, dtype):
    top = float(np.nextafter(dtype(1), dtype(0)))
    edges = np.array(
        [0.0, float(np.finfo(dtype).smallest_subnormal), 1e-300, 1e-38, top, 1.0 - 1e-16, 1.0 - 1e-7, 0.25, 0.5, 0.75]
    )
    u = np.where(rng.random((n, 2)) < 0.6, rng.choice(edges, (n, 2)), rng.random((n, 2)))
    return np.minimum(u.astype(dtype), dtype(top))


@pytest.mark.slow
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("strategy", od.STRATEGIES)
def test_sample_edges(strategy, dtype):
    rng = np.random.default_rng(1350 + od.STRATEGIES.index(strategy))
    _, wo = pairs(rng, N)
    wo = wo.astype(dtype)
    r = roughness(rng, N, 1.0).astype(dtype)
    u = u_edges(rng, N, dtype)
    wi, p = od.sample(strategy, wo, r, u)
    assert wi.dtype == dtype and np.isfinite(wi).all() and np.isfinite(p).all()
    np.testing.assert_allclose(np.linalg.norm(wi.astype(np.float64), axis=-1), 1.0, atol=4 * np.finfo(dtype).eps)
    q = od.pdf(strategy, wo, wi, r)
    np.testing.assert_allclose(p, q, rtol=1e-6 if dtype == np.float32 else 1e-12, atol=0)
    up = wo[:, 2] > 0
    assert (p[up] > 0).all(), f"{strategy}: discard at u = {u[up & (p <= 0)][:3].tolist()}"
    assert (p[~up] == 0).all()
    if strategy != "ltc":
        assert (wi[:, 2] > 0).all(), f"{strategy}: wi.z <= 0 at u = {u[wi[:, 2] <= 0][:3].tolist()}"
    if strategy == "eon":  # r = 0 rows are cosine sampling, for every u
        zero = r == 0
        wc, pc = od.sample("cosine", wo[zero], r[zero], u[zero])
        np.testing.assert_allclose(wi[zero], wc, rtol=0, atol=4e-7 if dtype == np.float32 else 1e-12)


@pytest.mark.slow
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_broadcast_edges_memory(dtype):
    rng = np.random.default_rng(1399)
    n = 1000
    wi, wo = pairs(rng, n)
    wi, wo = wi.astype(dtype)[:, None, :], wo.astype(dtype)[None, :, :]
    args = (wi, wo, dtype(0.7), np.array([0.8, 0.5, 0.2], dtype))
    od.evaluate("eon", *args)
    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        f = od.evaluate("eon", *args)
        extra = tracemalloc.get_traced_memory()[1] - base - f.nbytes
    finally:
        tracemalloc.stop()
    assert f.shape == (n, n, 3) and np.isfinite(f).all() and f.min() >= 0.0
    assert extra <= 12 << 20, f"{extra / 2**20:.1f} MB beyond a {f.nbytes / 2**20:.1f} MB output"
