"""Samplers at the ends of [0, 1): the returned pdf is pdf(wo, wi), the horizon promise holds,
and nothing is discarded while wo is above the horizon.

Issue 13, finding 2: "uniform"/"eon" at u1 = 0 returned wi on the horizon with pdf 1/(2 pi)
where pdf() said 0; "cltc"/"eon" at u0 = 1 - 2^-53 returned wi.z < 0 with pdf > 0; "ltc*",
"cltc" and "eon" at that u0 returned pdf 0 for wo above the horizon, and "eon" at r = 0
differed from cosine sampling there.
"""

import numpy as np
import pytest

import openpbr_diffuse as od

BELOW = {"ltc"}  # the general LTC lobe extends below the horizon (weight 0 there)


def edge_u(dtype):
    top = np.nextafter(dtype(1), dtype(0))  # largest value below 1 (1 - 2^-53, 1 - 2^-24)
    ends = np.array(
        [
            0.0,
            np.finfo(dtype).smallest_subnormal,
            1e-300 if dtype == np.float64 else 1e-38,
            0.25,
            0.5,
            0.75,
            1.0 - 1e-16 if dtype == np.float64 else 1.0 - 1e-7,
            top,
        ],
        dtype=dtype,
    )
    ends = np.minimum(ends, top)
    a, b = np.meshgrid(ends, ends, indexing="ij")
    return np.stack([a.ravel(), b.ravel()], axis=-1)


def edge_wo(dtype):
    out = [[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [0.0, -0.6, 0.8]]
    for z in (1e-300, 5e-324, 1e-7, 1e-3, 0.02, 0.3, 0.99995, 1.0 - 1e-16):
        s = np.sqrt(1.0 - z * z)
        out += [[s, 0.0, z], [-0.6 * s, 0.8 * s, z]]
    return np.array(out, dtype=dtype)


@pytest.mark.parametrize("strategy", od.STRATEGIES)
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("r", [0.0, 0.5, 1.0])
def test_edge_u_pdf_matches_and_horizon(strategy, dtype, r):
    u = edge_u(dtype)
    wo = edge_wo(dtype)
    WO = np.repeat(wo, len(u), axis=0)
    U = np.tile(u, (len(wo), 1))
    wi, p = od.sample(strategy, WO, dtype(r), U)
    assert np.isfinite(wi).all() and np.isfinite(p).all()
    q = od.pdf(strategy, WO, wi, dtype(r))
    np.testing.assert_allclose(p, q, rtol=1e-6 if dtype == np.float32 else 1e-12, atol=0)
    up = WO[:, 2] > 0
    assert (p[up] > 0).all(), f"{strategy}: discards at u = {U[up][p[up] <= 0][:3].tolist()}"
    if strategy not in BELOW:
        assert (wi[:, 2] > 0).all(), f"{strategy}: wi.z <= 0 at u = {U[wi[:, 2] <= 0][:3].tolist()}"


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_eon_at_r0_is_cosine_sampling_for_every_u(dtype):
    u = edge_u(dtype)
    rng = np.random.default_rng(5)
    u = np.concatenate([u, rng.random((2000, 2)).astype(dtype)])
    for wo in edge_wo(dtype):
        we, pe = od.sample("eon", wo, dtype(0.0), u)
        wc, pc = od.sample("cosine", wo, dtype(0.0), u)
        tol = 2e-7 if dtype == np.float32 else 1e-12
        np.testing.assert_allclose(we, wc, rtol=0, atol=tol)
        np.testing.assert_allclose(pe, pc, rtol=10 * tol, atol=0)
        assert (pe > 0).all() == (wo[2] > 0)


def test_issue_examples():
    top = np.nextafter(1.0, 0.0)
    wo = np.array([0.6, 0.0, 0.8])
    for strategy in ("uniform", "eon"):
        wi, p = od.sample(strategy, wo, 1.0, np.array([0.0, 0.3]))
        assert wi[2] > 0 and p == od.pdf(strategy, wo, wi, 1.0) and p > 0
    for strategy in ("cltc", "eon", "ltc_nonneg"):
        for u2 in np.linspace(0.0, top, 41):
            wi, p = od.sample(strategy, wo, 1.0, np.array([top, u2]))
            assert wi[2] > 0 and p > 0 and p == od.pdf(strategy, wo, wi, 1.0), (strategy, u2)
