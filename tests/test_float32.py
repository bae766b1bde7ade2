"""float32 input is computed in float32, within a stated bound of the float64 path.

The reference for each float32 result is the float64 path on the same inputs widened to
float64 (widening is exact), so the measured error is that of the float32 arithmetic
alone.  The bounds are those stated in ``models.api.evaluate`` / ``directional_albedo``
and docs/guide/models.md; they are checked on a seeded random sample that includes the
edges (mu -> 0, normal incidence, opposite and equal azimuths, r = 0 and the largest
roughness, rho = 0 and 1).  No test compares differently vectorised loops bit for bit.
"""

import numpy as np
import pytest
from numba import types

from openpbr_diffuse import average_albedo, directional_albedo, evaluate
from openpbr_diffuse._float32 import float32_twin
from openpbr_diffuse.models import eon, fon, lambert, qon
from openpbr_diffuse.models.registry import INFO, MODELS

#: |f32 - f64| <= EVAL_ULPS ulp (float32) of max(|f|, rho/pi): relative to f, except where
#: f cancels to near 0 (FON's 1 + r s/t at opposite azimuth), where it is absolute at the
#: scale rho/pi of the lobe.  Full Oren-Nayar's interreflection term cancels further.
EVAL_ULPS = 16
EVAL_ULPS_FULL_ON = 256
#: |E32 - E64| <= ALBEDO_ULPS ulp of E (directional and average albedo, closed forms).
ALBEDO_ULPS = 8

N = 60_000


def _largest_float32_at_most(x):
    x32 = np.float32(x)
    return x32 if float(x32) <= x else np.nextafter(x32, np.float32(0))


def _directions(rng, n):
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2])
    k = n // 10
    v[:k, 2] *= 10.0 ** rng.uniform(-8, -1, k)  # grazing: mu -> 0
    v[k : 2 * k, :2] *= 10.0 ** rng.uniform(-8, -1, (k, 1))  # near the normal
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    return v.astype(np.float32)


def _inputs(model, seed=20250):
    rng = np.random.default_rng(seed)
    wi, wo = _directions(rng, N), _directions(rng, N)
    k = N // 20
    wo[:k] = wi[:k] * np.float32([-1, -1, 1])  # opposite azimuth: FON's s/t = -1 at grazing
    wo[k : 2 * k] = wi[k : 2 * k]  # same direction
    rmax = INFO[model].roughness_max if np.isfinite(INFO[model].roughness_max) else 1.0
    top = _largest_float32_at_most(rmax)
    r = np.minimum(rng.uniform(0, rmax, N).astype(np.float32), top)
    r[: N // 7], r[N // 7 : 2 * N // 7] = 0, top
    rho = rng.uniform(0, 1, (N, 3)).astype(np.float32)
    rho[: N // 9], rho[N // 9 : 2 * N // 9] = 0, 1
    mu = rng.uniform(0, 1, N).astype(np.float32)
    mu[: N // 10] = 10.0 ** rng.uniform(-8, -1, N // 10)
    mu[:50], mu[50:100] = 0, 1
    return wi, wo, r, rho, mu


def _ulps(err, scale):
    return err / np.spacing(np.abs(scale).astype(np.float32)).astype(np.float64)


def _wide(*arrays):
    return tuple(a.astype(np.float64) for a in arrays)


@pytest.mark.cpu_portable
@pytest.mark.parametrize("model", MODELS)
def test_evaluate_float32_within_bound(model):
    wi, wo, r, rho, _ = _inputs(model)
    f32 = evaluate(model, wi, wo, r, rho)
    f64 = evaluate(model, *_wide(wi, wo, r, rho))
    assert f32.dtype == np.float32 and f64.dtype == np.float64
    err = np.abs(f32.astype(np.float64) - f64)
    ulps = _ulps(err, np.maximum(np.abs(f64), rho / np.pi))
    bound = EVAL_ULPS_FULL_ON if model == "full_on" else EVAL_ULPS
    assert ulps.max() <= bound, (model, float(ulps.max()))
    assert np.array_equal(f32 == 0, f64 == 0) or model == "full_on"  # zeros stay exact zeros


@pytest.mark.cpu_portable
@pytest.mark.parametrize("model", [m for m in MODELS if INFO[m].closed_form_albedo])
def test_albedo_float32_within_bound(model):
    _, _, r, rho, mu = _inputs(model)
    e32 = directional_albedo(model, mu, r, rho)
    e64 = directional_albedo(model, *_wide(mu, r, rho))
    a32, a64 = average_albedo(model, r, rho), average_albedo(model, *_wide(r, rho))
    assert e32.dtype == a32.dtype == np.float32
    for x32, x64 in ((e32, e64), (a32, a64)):
        ulps = _ulps(np.abs(x32.astype(np.float64) - x64), x64)
        assert ulps.max() <= ALBEDO_ULPS, (model, float(ulps.max()))


# The formulas the float32 drivers call, with float32 arguments: every value they compute
# is float32 (a Python float constant left in a formula would promote it to float64).
F32, B = types.float32, types.boolean
_FORMULAS = [
    (eon.eon_terms, (F32, F32, F32, F32, B)),
    (eon.eon_albedo_terms, (F32, F32, B)),
    (eon.eon_average_terms, (F32, B)),
    (fon.fon_terms, (F32, F32, F32, F32)),
    (fon.fon_albedo, (F32, F32, B)),
    (qon.qon_terms, (F32, F32, F32, F32, F32)),
    (qon.qon_albedo, (F32, F32, F32)),
    (lambert.lambert_terms, ()),
]


@pytest.mark.parametrize(("formula", "sig"), _FORMULAS, ids=lambda x: getattr(x, "__name__", ""))
def test_twins_compute_in_float32(formula, sig):
    twin = float32_twin(formula)
    twin.compile(sig)
    cres = twin.overloads[tuple(sig)]
    ret = cres.signature.return_type
    assert all(t == F32 for t in getattr(ret, "types", (ret,))), ret
    floats = {str(t) for t in cres.type_annotation.typemap.values() if isinstance(t, types.Float)}
    assert floats <= {"float32"}, (formula.__name__, floats)
    # the float64 formula itself is unchanged: float32 arguments still give float64 there
    formula.compile(sig)
    ret64 = formula.overloads[tuple(sig)].signature.return_type
    assert sig == () or types.float64 in getattr(ret64, "types", (ret64,))


def test_float32_arithmetic_is_used():
    """Results of float32 input are not the float64 ones rounded (as a float64 loop would give)."""
    wi, wo, r, rho, _ = _inputs("eon")
    f32 = evaluate("eon", wi, wo, r, rho)
    rounded = evaluate("eon", *_wide(wi, wo, r, rho)).astype(np.float32)
    assert np.mean(f32 != rounded) > 0.05


def test_mixed_dtypes_follow_the_rule():
    """float32 only when every float array is float32; Python scalars and lists do not promote."""
    w32 = np.array([0.0, 0.0, 1.0], np.float32)
    w64 = w32.astype(np.float64)
    assert evaluate("eon", w32, w32, 0.5, 0.8).dtype == np.float32
    assert evaluate("eon", w32, w32, np.float32(0.5), [0.8, 0.5, 0.2]).dtype == np.float32
    assert evaluate("eon", w32, w64, 0.5, 0.8).dtype == np.float64
    assert evaluate("eon", w32, w32, np.float64(0.5), 0.8).dtype == np.float64
    assert evaluate("eon", w32, w32, 0.5, np.array([0.8])).dtype == np.float64
    assert directional_albedo("eon", np.float32(0.5), np.float32(1.0)).dtype == np.float32
    assert directional_albedo("eon", np.float32(0.5), 1.0, np.array(0.5)).dtype == np.float64


def test_float32_checks_still_raise():
    """The fused input checks of the float32 loop reject what the float64 loop rejects."""
    w = np.tile(np.array([0.0, 0.0, 1.0], np.float32), (40_000, 1))
    bad = w.copy()
    bad[12345] = [0.0, 0.0, 1.01]
    with pytest.raises(ValueError, match=r"wo\[12345\]"):
        evaluate("eon", w, bad, np.float32(0.5), np.float32(0.5))
    with pytest.raises(ValueError, match="roughness"):
        evaluate("eon", w, w, np.full(40_000, 1.5, np.float32), np.float32(0.5))
    with pytest.raises(ValueError, match="rho"):
        directional_albedo("fon", np.float32(0.5), np.float32(0.5), np.full((40_000, 3), 2.0, np.float32))


def _bench():
    import importlib.util
    from pathlib import Path

    spec = importlib.util.spec_from_file_location("bench", Path(__file__).parents[1] / "tools" / "bench.py")
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    return bench


def test_bench_float32_comparison_reports_medians_and_load():
    bench = _bench()
    res = bench.dtype_comparison(n=4000, reps=3, with_drjit=False)
    assert set(res["ns"]) == {"float64", "float32"} and all(v > 0 for v in res["ns"].values())
    assert res["f64_over_f32"] == pytest.approx(res["ns"]["float64"] / res["ns"]["float32"])
    assert res["max_ulp_f32"] <= EVAL_ULPS and len(res["load"]) == 2
    text = bench.format_dtype_comparison(res)
    assert "median" in text and "Dr.Jit skipped: disabled" in text


def test_bench_skips_drjit_with_one_line_when_missing():
    import importlib.util

    if importlib.util.find_spec("drjit") is not None:
        pytest.skip("drjit is installed here")
    assert _bench()._drjit_probe() == "drjit not importable"
