"""The batch machinery under the public verbs: the vectorisable arccos, the specialised
drivers (every input layout and channel count gives the row-by-row result), the fast input
checks (same verdicts and messages as the NumPy ones), float32 accuracy and memory use."""

import math
import tracemalloc

import numpy as np
import pytest
from conftest import random_directions, roughness_max

import openpbr_diffuse as od
from openpbr_diffuse import _arrays as ar
from openpbr_diffuse import _launch
from openpbr_diffuse._jit import acos


# --- arccos ---------------------------------------------------------------------------------
@pytest.mark.cpu_portable
def test_acos_matches_libm_to_two_ulp():
    x = np.concatenate(
        [
            np.linspace(-1.0, 1.0, 200_001),
            [0.5, -0.5, np.nextafter(0.5, 1.0), 1e-300, -0.0],
            1.0 - np.logspace(-16, -1, 200),
            -1.0 + np.logspace(-16, -1, 200),
        ]
    )
    got = np.array([acos(v) for v in x[::7]] + [acos(v) for v in x[-410:]])
    xs = np.concatenate([x[::7], x[-410:]])
    ref = np.array([math.acos(v) for v in xs])
    assert np.max(np.abs(got - ref) / np.spacing(ref)) <= 2.0


@pytest.mark.cpu_portable
def test_acos_endpoints_and_outside():
    assert acos(1.0) == 0.0
    assert acos(-1.0) == math.pi
    assert acos(0.0) == math.pi / 2
    assert math.isnan(acos(1.0 + 1e-9)) and math.isnan(acos(math.nan))


# --- drivers: layouts, broadcasting, channel counts -----------------------------------------
def _rowwise(model, wi, wo, r, rho):
    """Reference: every input expanded to full, C-contiguous rows first."""
    lead = np.broadcast_shapes(wi.shape[:-1], wo.shape[:-1], np.shape(r), rho.shape[:-1])
    C = rho.shape[-1]
    full = [np.ascontiguousarray(np.broadcast_to(a, lead + (k,))) for a, k in ((wi, 3), (wo, 3), (rho, C))]
    return od.evaluate(model, full[0], full[1], np.ascontiguousarray(np.broadcast_to(r, lead)), full[2])


@pytest.mark.cpu_portable
@pytest.mark.parametrize("model", ["eon", "qon_fujii", "full_on"])
def test_layouts_give_the_rowwise_result(model, rng):
    n = 300
    wi = random_directions(rng, n)
    wo = random_directions(rng, n)
    r = rng.uniform(0.0, roughness_max(model), n)
    rho = rng.uniform(0.0, 1.0, (n, 3))
    ref = od.evaluate(model, wi, wo, r, rho)
    cases = [
        (np.asfortranarray(wi), wo[::-1][::-1], r, rho),  # Fortran order, reversed view
        (np.repeat(wi, 2, axis=0)[::2], wo, r, np.asfortranarray(rho)),  # strided rows
    ]
    for args in cases:
        np.testing.assert_allclose(od.evaluate(model, *args), ref, rtol=1e-14, atol=0)
    # tiled: one wo, one roughness, one rho for every row; outer products
    for args in [
        (wi, wo[7], r, rho),
        (wi, wo, r[3], rho),
        (wi, wo, r, rho[5]),
        (wi, wo[7], r[3], rho[5]),
        (wi[:20, None], wo[None, :30], r[None, :30], rho[:20, None]),
    ]:
        args = tuple(np.asarray(a) for a in args)
        np.testing.assert_allclose(od.evaluate(model, *args), _rowwise(model, *args), rtol=1e-14, atol=0)


@pytest.mark.cpu_portable
def test_tiled_inputs_across_chunks(rng):
    """More rows than one driver call takes: scalar roughness and a single rho are tiled per chunk."""
    n = 2 * _launch.CHUNK + 123
    wi = random_directions(rng, n)
    wo = random_directions(rng, n)
    rho = np.array([0.2, 0.5, 0.9])
    got = od.evaluate("eon", wi, wo, 0.4, rho)
    # rows may land in the vector body in one call and in the scalar remainder in the
    # other (different FMA contraction): equal to rounding, not bit for bit
    np.testing.assert_allclose(
        got, od.evaluate("eon", wi, wo, np.full(n, 0.4), np.tile(rho, (n, 1))), rtol=1e-14, atol=0
    )
    E = od.directional_albedo("eon_approx", wo[:, 2], 0.4, rho)
    np.testing.assert_allclose(
        E, od.directional_albedo("eon_approx", wo[:, 2], np.full(n, 0.4), np.tile(rho, (n, 1))), rtol=1e-14, atol=0
    )


@pytest.mark.cpu_portable
@pytest.mark.parametrize("C", [1, 2, 3, 5])
def test_each_channel_count_matches_single_channels(C, rng):
    """The C = 3 and C = 1 drivers are unrolled, others loop: all give the per-channel result."""
    n = 500
    wi, wo = random_directions(rng, n), random_directions(rng, n)
    r = rng.uniform(0.0, 1.0, n)
    rho = rng.uniform(0.0, 1.0, (n, C))
    for tint in ("reference", "white_tint"):
        f = od.evaluate("eon", wi, wo, r, rho, color_mode=tint)
        E = od.directional_albedo("eon", wo[:, 2], r, rho, color_mode=tint)
        A = od.average_albedo("qon_fujii", r, rho, color_mode=tint)
        for k in range(C):
            one = rho[:, k : k + 1]
            np.testing.assert_allclose(
                f[:, k], od.evaluate("eon", wi, wo, r, one, color_mode=tint)[:, 0], rtol=1e-14, atol=0
            )
            np.testing.assert_allclose(
                E[:, k], od.directional_albedo("eon", wo[:, 2], r, one, color_mode=tint)[:, 0], rtol=1e-14, atol=0
            )
            np.testing.assert_allclose(
                A[:, k], od.average_albedo("qon_fujii", r, one, color_mode=tint)[:, 0], rtol=1e-14, atol=0
            )


def test_empty_batches():
    assert od.evaluate("eon", np.zeros((0, 3)), [0, 0, 1.0], 0.5, [0.1, 0.2, 0.3]).shape == (0, 3)
    assert od.directional_albedo("eon", np.zeros((0,)), 0.5).shape == (0, 1)


def test_below_horizon_is_zero_in_a_vectorised_batch(rng):
    wi = random_directions(rng, 1000)
    wo = random_directions(rng, 1000)
    wi[::3, 2] *= -1.0
    wo[::5] = [1.0, 0.0, 0.0]
    for model in od.MODELS:
        f = od.evaluate(model, wi, wo, 0.5, [0.3, 0.6, 0.9])
        below = (wi[:, 2] <= 0) | (wo[:, 2] <= 0)
        assert np.all(f[below] == 0.0) and np.all(np.isfinite(f))


# --- float32 --------------------------------------------------------------------------------
@pytest.mark.cpu_portable
def test_float32_close_to_the_float64_result(model, rng):
    """float32 input is computed in float32, within the bound of ``tests/test_float32.py``."""
    n = 4000
    wi = random_directions(rng, n).astype(np.float32)
    wo = random_directions(rng, n).astype(np.float32)
    r = rng.uniform(0.0, roughness_max(model), n).astype(np.float32)
    rho = rng.uniform(0.0, 1.0, (n, 3)).astype(np.float32)
    f32 = od.evaluate(model, wi, wo, r, rho)
    f64 = od.evaluate(model, wi.astype(np.float64), wo.astype(np.float64), r.astype(np.float64), rho.astype(np.float64))
    ulp = np.spacing(np.maximum(np.abs(f64), rho / np.pi).astype(np.float32)).astype(np.float64)
    assert np.all(np.abs(f32 - f64) <= (256 if model == "full_on" else 16) * ulp)
    if od.models.model_info(model).closed_form_albedo:
        E32 = od.directional_albedo(model, wo[:, 2], r, rho)
        E64 = od.directional_albedo(model, wo[:, 2].astype(np.float64), r.astype(np.float64), rho.astype(np.float64))
        np.testing.assert_allclose(E32, E64, rtol=8 * 2.0**-23, atol=0)


# --- fast input checks ----------------------------------------------------------------------
N_BIG = 2 * ar._PARALLEL_MIN


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_fast_checks_report_like_the_numpy_ones(dtype, rng):
    w = random_directions(rng, N_BIG).astype(dtype)
    w[1234] = [0.0, 0.0, 1.01]
    with pytest.raises(ValueError, match=r"wi\[1234\] = .* has length 1\.01"):
        ar.directions("wi", w, np.dtype(dtype))
    w[1234] = [0.0, np.nan, 1.0]
    with pytest.raises(ValueError, match=r"wi\[1234\] .* is not finite"):
        ar.directions("wi", w, np.dtype(dtype))
    r = np.full(N_BIG, 0.5, dtype)
    r[999] = np.inf
    with pytest.raises(ValueError, match="roughness must be finite"):
        ar.in_range("roughness", r, np.dtype(dtype), 0.0, 1.0)
    r[999] = -1e-6
    with pytest.raises(ValueError, match=r"roughness must lie in \[0, 1\]; got -1e-06"):
        ar.in_range("roughness", r, np.dtype(dtype), 0.0, 1.0)
    r[999] = 1.0
    with pytest.raises(ValueError, match=r"u must lie in \[0, 1\)"):
        ar.in_range("u", r, np.dtype(dtype), 0.0, 1.0, hi_open=True)
    assert ar.in_range("u", r, np.dtype(dtype), 0.0, 1.0) is r


def test_fast_range_check_compares_in_the_array_dtype():
    """sigma = float32(pi/2) is above pi/2 in float64, but NumPy accepts it (float32 compare)."""
    top = np.float32(math.pi / 2)
    assert float(top) > math.pi / 2
    for n in (3, N_BIG):
        s = np.full(n, top)
        assert ar.in_range("roughness", s, np.dtype(np.float32), 0.0, math.pi / 2) is s


# --- memory ---------------------------------------------------------------------------------
@pytest.mark.parametrize("case", ["dense", "tiled"])
def test_peak_extra_memory_is_below_three_outputs(case, rng):
    n = 200_000
    wi = random_directions(rng, n).astype(np.float32)
    wo = random_directions(rng, n).astype(np.float32)
    r = rng.uniform(0.0, 1.0, n).astype(np.float32)
    rho = rng.uniform(0.0, 1.0, (n, 3)).astype(np.float32)
    args = (wi, wo, r, rho) if case == "dense" else (wi, wo[0], np.float32(0.5), rho[0])
    out, peak = _eval_peak_memory(args)
    assert peak - out.nbytes <= 3 * out.nbytes


# --- benchmark tool -------------------------------------------------------------------------
@pytest.mark.slow
def test_bench_runs_and_reports_every_call():
    import importlib.util
    from pathlib import Path

    spec = importlib.util.spec_from_file_location("bench", Path(__file__).parents[1] / "tools" / "bench.py")
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    res = bench.run_bench(n=2000, reps=1, dtypes=(np.float32,), with_c=False, with_startup=False)
    names = {(r["kind"], r["name"]) for r in res["rows"]}
    assert {("evaluate", m) for m in od.MODELS} <= names
    assert {("albedo", m) for m in od.MODELS} <= names
    assert "ns/call" in bench.format_table(res)


def test_tiled_buffers_stay_below_the_output_size(rng):
    """Grey output (C = 1) with one fixed wo, roughness and rho: the tiled rows are bounded."""
    n = 100_000
    wi = random_directions(rng, n)
    args = (wi, np.array([0.0, 0.6, 0.8]), 0.5, 0.3)
    out, peak = _eval_peak_memory(args)
    assert out.shape == (n, 1)
    assert peak - out.nbytes <= 3 * out.nbytes


def _eval_peak_memory(args):
    """(result, peak traced bytes) of ``evaluate("eon", *args)``, compiled beforehand."""
    od.evaluate("eon", *args)  # compile outside the measurement
    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        out = od.evaluate("eon", *args)
        peak = tracemalloc.get_traced_memory()[1] - base
    finally:
        tracemalloc.stop()
    return out, peak


def _full_on_libm(wi, wo, sigma, rho):
    """Oren & Nayar 1994 Eq. 27-30 written directly with NumPy's arccos and tan (libm), rows
    above the horizon: the formula the compiled, libm-free ``full_on`` must reproduce."""
    mi, mo = wi[:, 2], wo[:, 2]
    ti, to = np.arccos(mi), np.arccos(mo)
    alpha, beta = np.maximum(ti, to), np.minimum(ti, to)
    si, so = np.sin(ti), np.sin(to)
    cos_dphi = np.clip((wi[:, 0] * wo[:, 0] + wi[:, 1] * wo[:, 1]) / (si * so), -1.0, 1.0)
    s2 = sigma * sigma
    C1 = 1.0 - 0.5 * s2 / (s2 + 0.33)
    k = s2 / (s2 + 0.09)
    C2 = np.where(cos_dphi >= 0.0, 0.45 * k * np.sin(alpha), 0.45 * k * (np.sin(alpha) - (2.0 * beta / np.pi) ** 3))
    C3 = 0.125 * k * (4.0 * alpha * beta / np.pi**2) ** 2
    g = (C1 + cos_dphi * C2 * np.tan(beta) + (1.0 - np.abs(cos_dphi)) * C3 * np.tan(0.5 * (alpha + beta))) / np.pi
    h = 0.17 * s2 / (s2 + 0.13) * (1.0 - cos_dphi * (2.0 * beta / np.pi) ** 2) / np.pi
    return rho * g[:, None] + rho * rho * h[:, None]


@pytest.mark.cpu_portable
def test_full_on_matches_the_libm_formula(rng):
    """The vectorised full Oren-Nayar (polynomial acos, half-angle tan) against Eq. 27-30 with
    libm's arccos and tan, over directions from mu = 1e-3 to 1 (below that tan(beta) and
    tan((alpha + beta)/2) are so ill-conditioned that the two differ by input rounding)."""
    n = 20000
    wi, wo = random_directions(rng, n), random_directions(rng, n)
    for w in (wi, wo):
        w[:, 2] = np.abs(w[:, 2])
        w[:] = np.where(w[:, 2:] < 1e-3, [[0.6, 0.0, 0.8]], w)
    sigma = rng.uniform(0.0, np.pi / 2, n)
    rho = rng.uniform(0.0, 1.0, (n, 3))
    np.testing.assert_allclose(
        od.evaluate("full_on", wi, wo, sigma, rho), _full_on_libm(wi, wo, sigma, rho), rtol=1e-10, atol=1e-14
    )
