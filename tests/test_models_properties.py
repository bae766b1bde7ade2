"""Properties every lobe model must have: reciprocity, the Lambert limit, finiteness and
non-negativity at the edges, dtype and shape conventions, and clear errors."""

import math

import numpy as np
import pytest
from conftest import random_directions, roughness_max
from hypothesis import given, settings
from hypothesis import strategies as st

import openpbr_diffuse as od

NONNEGATIVE = [m for m in od.MODELS if m != "full_on"]


def test_reciprocity(model, rng):
    wi = random_directions(rng, 4000)
    wo = random_directions(rng, 4000)
    r = rng.uniform(0.0, roughness_max(model), 4000)
    rho = rng.uniform(0.0, 1.0, (4000, 3))
    np.testing.assert_allclose(
        od.evaluate(model, wi, wo, r, rho), od.evaluate(model, wo, wi, r, rho), rtol=1e-12, atol=1e-15
    )


def test_lambert_limit_at_zero_roughness(model, rng):
    wi = random_directions(rng, 2000)
    wo = random_directions(rng, 2000)
    rho = rng.uniform(0.0, 1.0, (2000, 3))
    # EON keeps f_ms = rho_ms eps/pi at r = 0 (Listing 1's guard): below 1e-7
    np.testing.assert_allclose(od.evaluate(model, wi, wo, 0.0, rho), rho / np.pi, rtol=0, atol=1e-7)


def test_van_ouwerkerk_equals_qon(rng):
    """Two published formulations of the same function agree to rounding (float64)."""
    wi = random_directions(rng, 20000)
    wo = random_directions(rng, 20000)
    sigma = rng.uniform(0.0, math.pi / 2, 20000)
    np.testing.assert_allclose(
        od.evaluate("qon_van_ouwerkerk", wi, wo, sigma), od.evaluate("qon", wi, wo, sigma), rtol=0, atol=1e-12
    )


def test_fujii_qon_is_qon_plus_tint_and_fon_sign(rng):
    """Fujii's A adds 0.17 rho s2/(s2+0.13) (its own paper) and it agrees with full ON's f2 at
    s = 0 -- an independent formulation of the same interreflection term."""
    wi = np.array([0.0, 0.0, 1.0])
    wo = random_directions(rng, 100)
    for sigma in (0.2, 0.9):
        np.testing.assert_allclose(
            od.evaluate("qon_fujii", wi, wo, sigma, [0.3, 0.9]),
            od.evaluate("full_on", wi, wo, sigma, [0.3, 0.9]),
            rtol=1e-12,
        )


def test_full_on_matches_qon_in_the_plane_at_normal_light():
    """With the light at the normal, full ON's first term is C1 + 0 and QON's is A: the same."""
    wi = np.array([0.0, 0.0, 1.0])
    wo = np.array([0.6, 0.0, 0.8])
    sigma = 0.7
    k = sigma**2 / (sigma**2 + 0.13)
    np.testing.assert_allclose(
        od.evaluate("full_on", wi, wo, sigma, 0.5)[0],
        od.evaluate("qon", wi, wo, sigma, 0.5)[0] + 0.17 * 0.25 / np.pi * k,
        rtol=1e-12,
    )


def test_full_on_goes_negative_forward_grazing():
    """Documented property of the published full model: with cos(dphi) = -1 at grazing,
    C2 tan(beta) -> 0.45 k 6/pi exceeds C1 at large sigma, so f < 0 for rho below ~0.8."""
    th = 1.55
    wi = np.array([np.sin(th), 0.0, np.cos(th)])
    wo = np.array([-np.sin(th), 0.0, np.cos(th)])
    f = od.evaluate("full_on", wi, wo, math.pi / 2, [0.2, 1.0])
    assert f[0] < 0.0 < f[1]


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_edge_directions_are_finite(model, dtype):
    eps = np.finfo(dtype).tiny
    c = math.sqrt(0.5)
    z_eps = 1e-7
    s_eps = math.sqrt(1 - z_eps * z_eps)
    dirs = np.array(
        [
            [0.0, 0.0, 1.0],  # mu = 1
            [s_eps, 0.0, z_eps],  # grazing
            [1.0, 0.0, 0.0],  # mu = 0 exactly
            [c, 0.0, c],
            [-c, 0.0, c],  # mirrored
            [0.0, c, c],  # s = 0 against the others
            [0.0, 0.0, -1.0],  # below the horizon
            [c, 0.0, -c],
            [1.0, 0.0, float(eps)],
        ],
        dtype=dtype,
    )
    wi = dirs[:, None, :]
    wo = dirs[None, :, :]
    for r in (0.0, roughness_max(model)):
        f = od.evaluate(model, wi, wo, dtype(r), np.array([0.0, 0.5, 1.0], dtype))
        assert f.dtype == dtype
        assert np.all(np.isfinite(f))
        below = (dirs[:, 2] <= 0)[:, None] | (dirs[:, 2] <= 0)[None, :]
        assert np.all(f[below] == 0.0)
        # wi = wo and wi = mirrored wo are ordinary points: nonzero above the horizon
        assert np.all(f[3, 3, 1:] > 0) and np.all(f[3, 4, 1:] != 0)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_albedo_edges_are_finite(model, dtype):
    mu = np.array([0.0, 1e-30, 1e-7, 0.5, 1.0], dtype)
    for r in (0.0, roughness_max(model)):
        E = od.directional_albedo(model, mu, dtype(r), np.array([0.0, 0.5, 1.0], dtype))
        assert E.dtype == dtype and np.all(np.isfinite(E)) and np.all(E >= 0)
        A = od.average_albedo(model, dtype(r), np.array([0.0, 0.5, 1.0], dtype))
        assert A.dtype == dtype and np.all(np.isfinite(A))


def test_E_F_limit_at_grazing_is_one():
    """E_F(0) is the limit 1 for every r, not inf*0 (spec: NaN is a bug).  The Eq. 14 fit
    reaches (1 + r sum(g_k)) / (1 + c1 r) there: 1 + 3.6e-4 at r = 1 (sum(g_k) ~ c1)."""
    from openpbr_diffuse.models.fon import E_F

    for r in (0.0, 0.3, 1.0):
        assert E_F(0.0, r, False) == pytest.approx(1.0, abs=1e-12)
        assert E_F(1e-300, r, False) == pytest.approx(1.0, abs=1e-12)
        assert E_F(0.0, r, True) == pytest.approx(1.0, abs=4e-4)
    np.testing.assert_allclose(od.directional_albedo("fon", [0.0, 1e-12], [0.5, 1.0]), 1.0, atol=1e-9)


def test_float32_agrees_with_float64(model, rng):
    wi = random_directions(rng, 5000)
    wo = random_directions(rng, 5000)
    r = rng.uniform(0.0, roughness_max(model), 5000)
    rho = rng.uniform(0.0, 1.0, (5000, 3))
    f64 = od.evaluate(model, wi, wo, r, rho)
    f32 = od.evaluate(model, wi.astype(np.float32), wo.astype(np.float32), r.astype(np.float32), rho.astype(np.float32))
    assert f32.dtype == np.float32
    np.testing.assert_allclose(f32, f64, rtol=2e-4, atol=2e-6)


# --- property-based -------------------------------------------------------------------------
unit = st.floats(0.0, 1.0, allow_nan=False)


def _dir(z, phi):
    s = math.sqrt(max(0.0, 1.0 - z * z))
    return [s * math.cos(phi), s * math.sin(phi), z]


@settings(max_examples=300, deadline=None)
@given(
    model=st.sampled_from(od.MODELS),
    zi=unit,
    zo=unit,
    pi_=st.floats(0, 2 * math.pi),
    po=st.floats(0, 2 * math.pi),
    rough=unit,
    rho=st.lists(unit, min_size=1, max_size=5),
)
def test_property_finite_nonnegative(model, zi, zo, pi_, po, rough, rho):
    r = rough * roughness_max(model)
    f = od.evaluate(model, _dir(zi, pi_), _dir(zo, po), r, rho)
    assert f.shape == (len(rho),)
    assert np.all(np.isfinite(f))
    if model in NONNEGATIVE:
        assert np.all(f >= 0.0)
    E = od.directional_albedo(model, zo, r, rho)
    assert np.all(np.isfinite(E)) and np.all(E >= 0.0)
    info = od.models.model_info(model)
    if info.energy_conserving:
        assert np.all(E <= np.asarray(rho) + 1e-6)


# --- shapes and dtypes ----------------------------------------------------------------------
def test_broadcasting_shapes(rng):
    wi = random_directions(rng, 6).reshape(2, 3, 3)
    wo = random_directions(rng, 3)  # (3, 3) -> broadcasts with (2, 3)
    r = np.array([0.2, 0.5, 0.9])
    spectral = np.linspace(0.1, 0.9, 16)  # N spectral channels
    f = od.evaluate("eon", wi, wo, r, spectral)
    assert f.shape == (2, 3, 16)
    g = od.evaluate("eon", wi[1, 2], wo[2], r[2], spectral)
    np.testing.assert_allclose(f[1, 2], g, rtol=1e-15)
    assert od.evaluate("eon", wi, wo, 0.5).shape == (2, 3, 1)  # grey
    assert od.directional_albedo("eon", np.ones((4, 1)), r, [0.5, 0.5, 0.5]).shape == (4, 3, 3)
    assert od.average_albedo("qon", r[:, None], np.full((2, 3), 0.5)).shape == (3, 2, 3)


def test_dtype_rules():
    wi32 = np.array([0.0, 0.0, 1.0], np.float32)
    wo64 = np.array([0.0, 0.0, 1.0])
    assert od.evaluate("eon", wi32, wi32, 0.5, 0.5).dtype == np.float32  # scalars do not promote
    assert od.evaluate("eon", wi32, wi32, 0.5, [0.5, 0.5]).dtype == np.float32
    assert od.evaluate("eon", wi32, wo64, 0.5).dtype == np.float64  # mixed -> float64
    assert od.evaluate("eon", [0, 0, 1], [0, 0, 1], 0.5).dtype == np.float64
    assert od.directional_albedo("eon", np.float32(0.5), 0.5).dtype == np.float32


def test_evaluate_does_not_modify_inputs(rng):
    wi = random_directions(rng, 10)
    before = wi.copy()
    od.evaluate("eon", wi, wi, 0.5, 0.5)
    np.testing.assert_array_equal(wi, before)


# --- errors ---------------------------------------------------------------------------------
Z = [0.0, 0.0, 1.0]


@pytest.mark.parametrize(
    "call, exc, words",
    [
        (lambda: od.evaluate("oren", Z, Z, 0.5), ValueError, ["model", "eon"]),
        (lambda: od.evaluate(3, Z, Z, 0.5), TypeError, ["model"]),
        (lambda: od.evaluate("eon", [0, 0, 2.0], Z, 0.5), ValueError, ["wi", "unit"]),
        (lambda: od.evaluate("eon", Z, [0, np.nan, 1.0], 0.5), ValueError, ["wo", "finite"]),
        (lambda: od.evaluate("eon", [0, 1.0], Z, 0.5), ValueError, ["wi", "(..., 3)"]),
        (lambda: od.evaluate("eon", Z, Z, 1.5), ValueError, ["roughness", "[0, 1]"]),
        (lambda: od.evaluate("qon", Z, Z, 2.0), ValueError, ["roughness", "1.5707963267948966", "sigma"]),
        (lambda: od.evaluate("eon", Z, Z, -0.1), ValueError, ["roughness"]),
        (lambda: od.evaluate("eon", Z, Z, np.inf), ValueError, ["roughness", "finite"]),
        (lambda: od.evaluate("eon", Z, Z, 0.5, 1.2), ValueError, ["rho", "[0, 1]"]),
        (lambda: od.evaluate("eon", Z, Z, 0.5, "red"), TypeError, ["rho"]),
        (lambda: od.evaluate("eon", Z, Z, 0.5, color_mode="tint"), ValueError, ["color_mode"]),
        (lambda: od.evaluate("eon", np.tile(Z, (2, 1)), np.tile(Z, (3, 1)), 0.5), ValueError, ["wi", "wo"]),
        (lambda: od.directional_albedo("eon", 1.5, 0.5), ValueError, ["mu", "[0, 1]"]),
        (lambda: od.directional_albedo("eon", -0.1, 0.5), ValueError, ["mu"]),
        (lambda: od.average_albedo("fon", 2.0), ValueError, ["roughness"]),
    ],
)
def test_bad_input_names_the_argument(call, exc, words):
    with pytest.raises(exc) as info:
        call()
    for w in words:
        assert w in str(info.value), (w, str(info.value))


def test_subnormal_mu_stays_finite(model):
    """Directions a subnormal mu above the horizon: s / max(mu) must not overflow
    (found by hypothesis; the denominators are floored at 1e-7)."""
    z = 5e-324
    s = math.sqrt(1.0 - z * z)
    wi = np.array([s, 0.0, z])
    for dtype in (np.float64, np.float32):
        for r in (0.0, roughness_max(model)):
            f = od.evaluate(model, wi.astype(dtype), wi.astype(dtype), dtype(r), np.array([0.0, 1.0], dtype))
            assert np.all(np.isfinite(f)) and np.all(f >= 0), (dtype, r, f)
