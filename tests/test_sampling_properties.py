"""Properties of the samplers (EON paper Section 3.1), each checked against something independent.

- normalisation: pdf integrates to 1 (Gauss-Legendre quadrature over (cos theta, phi));
- agreement: the pdf that ``sample`` reports is ``pdf`` at the sampled direction;
- white furnace: E[f mu_i / pdf] = 1 for EON at rho = 1 (``evaluate`` is verified on its own);
- the paper's variance claim (Fig. 10-12): EON sampling vs cosine sampling at r = 1;
- reductions (r = 0 is cosine sampling), the C yardstick, edge inputs and errors.
"""

import csv
import math
import subprocess
from pathlib import Path

import numpy as np
import pytest
from _quad import gauss_legendre, hemisphere_grid, wo_of
from _system import requires

import openpbr_diffuse as od
from openpbr_diffuse.sampling import INFO, STRATEGIES, pdf, sample, sample_rng
from openpbr_diffuse.sampling.ltc import ltc_coeffs

COVERING = [s for s in STRATEGIES if INFO[s].covers_hemisphere]
NORMALISED_ON_HEMISPHERE = [s for s in STRATEGIES if s != "ltc"]
GRID = [(0.02, 1.0), (0.02, 0.3), (0.3, 1.0), (0.7, 0.5), (1.0, 1.0), (0.5, 0.0)]


def wo_at(mu, phi=0.7):
    s = math.sqrt(max(0.0, 1.0 - mu * mu))
    return np.array([s * math.cos(phi), s * math.sin(phi), mu])


def pdf_integral(strategy, mu, r, z_lo=0.0, z_hi=1.0, phi_o=0.7, n=96):
    """Integral of ``pdf`` over z = cos(theta) in [z_lo, z_hi] and all phi.

    The LTC densities have a kink where the lobe ends: h.z = c (a w.z - d w.x) = 0 in the
    LTC frame, i.e. z_b = t/sqrt(1 + t^2) with t = (d/a) cos(phi_l).  The z integral is
    split there for every phi node, and phi_l (azimuth from wo's) is split at +-pi/2,
    where z_b crosses the horizon.  ``ltc_coeffs`` only places the split points.
    """
    a, _, _, d = ltc_coeffs(mu, r)
    if strategy == "ltc_nonneg":
        d = 0.0
    pl, pw = (
        np.concatenate(v, axis=-1)
        for v in zip(gauss_legendre(-0.5 * np.pi, 0.5 * np.pi, n), gauss_legendre(0.5 * np.pi, 1.5 * np.pi, n))
    )
    pl, pw = pl.ravel(), pw.ravel()
    t = d / a * np.cos(pl)
    zb = np.clip(t / np.sqrt(1.0 + t * t), z_lo, z_hi)
    z1, w1 = gauss_legendre(np.full_like(zb, z_lo), zb, n)
    z2, w2 = gauss_legendre(zb, np.full_like(zb, z_hi), n)
    Z, WZ = np.concatenate([z1, z2], axis=1), np.concatenate([w1, w2], axis=1)  # (n_phi, 2n)
    P = (pl + phi_o)[:, None]
    S = np.sqrt(np.maximum(0.0, 1.0 - Z * Z))
    wi = np.stack(np.broadcast_arrays(S * np.cos(P), S * np.sin(P), Z), axis=-1)
    return float(np.sum(pdf(strategy, wo_at(mu, phi_o), wi, r) * WZ * pw[:, None]))


def weights(strategy, mu, r, n, seed):
    """Throughput weights f_EON(rho = 1) mu_i / pdf of n samples (0 where f = 0)."""
    wo = wo_at(mu)
    wi, p = sample_rng(strategy, wo, r, seed, shape=(n,))
    f = od.evaluate("eon", wi, wo, r, 1.0)[:, 0]
    return np.where(p > 0.0, f * np.maximum(wi[:, 2], 0.0) / np.where(p > 0.0, p, 1.0), 0.0)


# --- normalisation ---------------------------------------------------------------------------


@pytest.mark.parametrize("strategy", NORMALISED_ON_HEMISPHERE)
@pytest.mark.parametrize("mu, r", GRID)
def test_pdf_integrates_to_one_over_the_hemisphere(strategy, mu, r):
    assert pdf_integral(strategy, mu, r) == pytest.approx(1.0, abs=1e-4)


@pytest.mark.parametrize("mu, r", GRID)
def test_general_ltc_pdf_is_normalised_on_the_sphere_not_the_hemisphere(mu, r):
    assert pdf_integral("ltc", mu, r, z_lo=-1.0) == pytest.approx(1.0, abs=1e-4)
    upper = pdf_integral("ltc", mu, r)
    lower = pdf_integral("ltc", mu, r, z_lo=-1.0, z_hi=0.0)
    assert upper + lower == pytest.approx(1.0, abs=1e-4)
    d = ltc_coeffs(mu, r)[3]
    if d < -1e-3:  # part of the lobe lies below the horizon
        assert lower > 1e-4 and upper < 1.0 - 1e-4
    else:  # d ~ 0 (r = 0, or mu_o ~ 1 where the fit has 0 < d < 3.5e-3): mass ~ d^2/4
        assert lower <= d * d


def test_normalisation_quadrature_is_converged():
    """With the kink split, 48 and 160 nodes per panel agree (the 1e-4 checks are not noise)."""
    fine = pdf_integral("cltc", 0.02, 1.0, n=160)
    assert pdf_integral("cltc", 0.02, 1.0, n=48) == pytest.approx(fine, abs=1e-6)


# --- sample and pdf agree --------------------------------------------------------------------


@pytest.mark.parametrize("strategy", STRATEGIES)
def test_sample_reports_the_pdf_of_its_direction(strategy, rng):
    n = 20_000
    mu = rng.uniform(1e-3, 1.0, n)
    phi = rng.uniform(0.0, 2.0 * np.pi, n)
    s = np.sqrt(1.0 - mu * mu)
    wo = np.stack([s * np.cos(phi), s * np.sin(phi), mu], axis=-1)
    r = rng.uniform(0.0, 1.0, n)
    wi, p = sample(strategy, wo, r, rng.random((n, 2)))
    assert np.allclose(np.linalg.norm(wi, axis=-1), 1.0, atol=1e-12)
    keep = wi[:, 2] > 1e-9 if strategy != "ltc" else np.ones(n, bool)
    assert keep.mean() > 0.99
    np.testing.assert_allclose(p[keep], pdf(strategy, wo, wi, r)[keep], rtol=1e-9)


def test_general_ltc_returns_samples_below_the_horizon_with_their_density(rng):
    wo = wo_at(0.05)
    wi, p = sample_rng("ltc", wo, 1.0, rng, shape=(50_000,))
    below = wi[:, 2] < 0.0
    assert 0.001 < below.mean() < 0.2
    assert np.all(p[below] > 0.0)
    np.testing.assert_allclose(p[below], pdf("ltc", wo, wi[below], 1.0), rtol=1e-9)
    assert np.all(od.evaluate("eon", wi[below], wo, 1.0)[:, 0] == 0.0)  # weight 0


@pytest.mark.parametrize("strategy", [s for s in STRATEGIES if s != "ltc"])
def test_clipped_strategies_never_sample_below_the_horizon(strategy, rng):
    """Including mu_o > 0.9999, where the Listing 2 fit has d > 0 (see ltc.py)."""
    n = 100_000
    mu = np.concatenate([rng.uniform(0.9999, 1.0, n // 2), rng.uniform(0.0, 1.0, n // 2)])
    wo = np.stack([np.sqrt(1.0 - mu * mu), np.zeros(n), mu], axis=-1)
    u = rng.random((n, 2))
    u[: n // 4, 0] = 1.0 - rng.uniform(1e-12, 1e-6, n // 4)  # the rim of the disk
    wi, _ = sample(strategy, wo, 1.0, u)
    assert wi[:, 2].min() >= 0.0


# --- white furnace ---------------------------------------------------------------------------


@pytest.mark.parametrize("strategy", COVERING)
@pytest.mark.parametrize("mu, r", [(0.02, 1.0), (0.3, 0.5), (1.0, 1.0), (0.6, 0.0)])
def test_white_furnace_by_monte_carlo(strategy, mu, r):
    w = weights(strategy, mu, r, 200_000, seed=int(1e4 * mu + 100 * r))
    sigma = w.std() / math.sqrt(w.size)
    assert abs(w.mean() - 1.0) < 5.0 * sigma + 1e-6


@pytest.mark.parametrize("strategy", ["cltc", "ltc"])
def test_strategies_that_miss_a_lune_are_biased_low(strategy):
    """E_CLTC[w] = integral of f mu_i over the covered set {pdf_CLTC > 0} < 1 (Section 3.1).

    The covered integral is estimated independently with the unbiased "eon" sampler:
    E_eon[w * 1(pdf_strategy(wi) > 0)].
    """
    mu, r, n = 0.02, 1.0, 400_000
    w = weights(strategy, mu, r, n, seed=3)
    wo = wo_at(mu)
    wi, p = sample_rng("eon", wo, r, 4, shape=(n,))
    covered = pdf(strategy, wo, wi, r) > 0.0
    v = od.evaluate("eon", wi, wo, r, 1.0)[:, 0] * wi[:, 2] / p * covered
    sigma = math.hypot(w.std(), v.std()) / math.sqrt(n)
    assert abs(w.mean() - v.mean()) < 5.0 * sigma
    assert w.mean() < 1.0 - 5.0 * w.std() / math.sqrt(n)


# --- the paper's variance claim (Fig. 10-12) -------------------------------------------------


@pytest.fixture(scope="module")
def variance_r1():
    """{mu_o: {strategy: (variance, max weight)}} at r = 1, 400k samples each."""
    out = {}
    for mu in (0.01, 0.02, 0.5, 1.0):
        out[mu] = {}
        for s in ("cosine", "eon"):
            w = weights(s, mu, 1.0, 400_000, seed=int(1000 * mu))
            out[mu][s] = (w.var(), w.max())
    return out


@pytest.mark.parametrize("mu", [0.01, 0.02])
def test_eon_sampling_variance_is_30x_lower_at_grazing(variance_r1, mu):
    v = variance_r1[mu]
    assert v["cosine"][0] >= 30.0 * v["eon"][0]
    assert v["eon"][1] < 1.5 < 30.0 < v["cosine"][1]


def test_eon_sampling_variance_is_similar_at_normal_incidence(variance_r1):
    v = variance_r1[1.0]
    assert 0.5 < v["eon"][0] / v["cosine"][0] < 2.0
    assert v["eon"][1] < 1.5


def test_eon_sampling_variance_is_lower_at_mid_angles(variance_r1):
    v = variance_r1[0.5]
    assert v["eon"][0] < v["cosine"][0]
    assert v["eon"][1] < 1.5


@pytest.mark.parametrize("mu, lo, hi", [(0.01, 30.0, np.inf), (0.02, 30.0, np.inf), (1.0, 0.5, 2.0)])
def test_variance_ratio_by_quadrature(mu, lo, hi):
    """Var[w] = integral of f^2 mu_i^2 / pdf - 1 (E[w] = 1): the Monte Carlo claim without noise."""
    wi, weight = hemisphere_grid(mu, 200)  # weight includes mu_i dwi
    f = od.evaluate("eon", wi, wo_of(mu), 1.0)[..., 0]
    var_cos = np.sum(np.pi * f * f * weight) - 1.0
    var_eon = np.sum(f * f * wi[..., 2] * weight / pdf("eon", wo_of(mu), wi, 1.0)) - 1.0
    assert lo <= var_cos / var_eon <= hi


def test_eon_weight_is_bounded_everywhere_at_r1():
    """max over a dense (z, phi) grid of f mu_i / pdf_eon stays below 1.5 for every mu_o."""
    z = np.linspace(1e-4, 1.0, 400)
    phi = np.linspace(-np.pi, np.pi, 401)
    Z, P = np.meshgrid(z, phi, indexing="ij")
    S = np.sqrt(1.0 - Z * Z)
    wi = np.stack([S * np.cos(P), S * np.sin(P), Z], axis=-1)
    for mu in (0.001, 0.02, 0.05, 0.1, 0.3, 0.6, 1.0):
        wo = np.array([math.sqrt(1.0 - mu * mu), 0.0, mu])
        w = od.evaluate("eon", wi, wo, 1.0)[..., 0] * Z / pdf("eon", wo, wi, 1.0)
        assert w.max() < 1.5


# --- reductions and cross-checks -------------------------------------------------------------


def test_eon_at_zero_roughness_is_cosine_sampling(rng):
    n = 50_000
    wo = np.stack([np.zeros(n), np.zeros(n), np.ones(n)], axis=-1)
    wo[: n // 2] = wo_at(0.3)
    u = rng.random((n, 2))
    wi_e, p_e = sample("eon", wo, 0.0, u)
    wi_c, p_c = sample("cosine", wo, 0.0, u)
    np.testing.assert_allclose(wi_e, wi_c, atol=1e-12)
    np.testing.assert_allclose(p_e, p_c, rtol=1e-10)
    np.testing.assert_allclose(p_c, wi_c[:, 2] / np.pi, rtol=1e-12)


def test_cosine_and_uniform_have_the_textbook_marginals(rng):
    """cos(theta) is sqrt(1 - u1) for cosine and u1 for uniform sampling; phi is 2 pi u2 up to a frame."""
    u = rng.random((1000, 2))
    wi, _ = sample("cosine", np.array([0.0, 0.0, 1.0]), 0.5, u)
    np.testing.assert_allclose(wi[:, 2], np.sqrt(1.0 - u[:, 0]), atol=1e-14)
    wi, _ = sample("uniform", wo_at(0.4), 0.5, u)
    np.testing.assert_allclose(wi[:, 2], u[:, 0], atol=1e-15)
    phi = np.mod(np.arctan2(wi[:, 1], wi[:, 0]), 2 * np.pi)
    np.testing.assert_allclose(phi, 2 * np.pi * u[:, 1], atol=1e-12)


def test_azimuth_polynomial_matches_long_double_trig(rng):
    """cos_sin_2pi (the Taylor-series replacement for libm cos/sin) vs numpy long double."""
    from openpbr_diffuse.sampling.simple import cos_sin_2pi

    if np.finfo(np.longdouble).eps > 1e-17:
        pytest.skip("long double is no wider than double on this platform")
    u = np.concatenate([rng.random(3000), np.arange(64) / 64.0, [np.nextafter(1.0, 0.0), 5e-324]])
    got = np.array([cos_sin_2pi(float(v)) for v in u])
    two_pi = 2.0 * np.arccos(np.longdouble(-1.0))
    ref = np.stack([np.cos(two_pi * u.astype(np.longdouble)), np.sin(two_pi * u.astype(np.longdouble))], -1)
    assert np.abs(got - ref).max() < 5e-16


def test_tenth_power_matches_numpy(rng):
    """pow_tenth (the libm-free r^0.1 of P_u) vs numpy, over [0, 1] and down to subnormals."""
    from openpbr_diffuse.sampling.mis import pow_tenth

    r = np.concatenate(
        [
            rng.random(2000),
            10.0 ** rng.uniform(-320.0, 0.0, 2000),
            [1.0, 0.5, 2.0**-0.125, np.nextafter(1.0, 0.0), 2.0**-1022, 5e-324],
        ]
    )
    got = np.array([pow_tenth(float(v)) for v in r])
    np.testing.assert_allclose(got, np.power(r, 0.1), rtol=1e-14, atol=0.0)
    assert pow_tenth(0.0) == 0.0 and pow_tenth(1.0) == 1.0


YARDSTICK = Path(__file__).resolve().parents[2] / "shared" / "bench" / "eon_scalar.c"


@pytest.mark.skipif(not YARDSTICK.exists(), reason="the C yardstick ../shared/bench/eon_scalar.c is absent")
@requires("gcc")
def test_eon_sampler_matches_the_c_yardstick(tmp_path, rng):
    """Listing 4 written independently in C (float32): same directions and pdf for the same u.

    mu_o < 0.9999 only: above it the Listing 2 fit has d > 0 and this library keeps the
    clipped lune on the correct side (documented deviation, see sampling/ltc.py).
    """
    src = tmp_path / "drv.c"
    src.write_text(
        f'#define main yardstick_main\n#include "{YARDSTICK}"\n#undef main\n'
        "int main(void){float wo[3],r,u1,u2,wi[3];\n"
        'while(scanf("%f %f %f %f %f %f",wo,wo+1,wo+2,&r,&u1,&u2)==6){\n'
        "float p=sample_EON(wo,r,u1,u2,wi);"
        'printf("%.9g %.9g %.9g %.9g\\n",wi[0],wi[1],wi[2],p);}return 0;}\n'
    )
    exe = tmp_path / "drv"
    subprocess.run(["gcc", "-O2", "-o", str(exe), str(src), "-lm"], check=True, capture_output=True)
    n = 5000
    mu = rng.uniform(1e-3, 0.9999, n)
    phi = rng.uniform(0.0, 2.0 * np.pi, n)
    s = np.sqrt(1 - mu * mu)
    wo = np.stack([s * np.cos(phi), s * np.sin(phi), mu], -1).astype(np.float32)
    r = rng.random(n).astype(np.float32)
    u = rng.random((n, 2), dtype=np.float32)
    text = "\n".join(" ".join(f"{v:.9g}" for v in row) for row in np.column_stack([wo, r, u]))
    out = np.loadtxt(
        subprocess.run([str(exe)], input=text, capture_output=True, text=True, check=True).stdout.splitlines()
    )
    wi, p = sample("eon", wo, r, u)
    assert np.abs(wi - out[:, :3]).max() < 1e-4
    np.testing.assert_allclose(p, out[:, 3], rtol=1e-3)


# --- shapes, dtypes, reproducibility ---------------------------------------------------------


def test_shapes_broadcast_and_float32_stays_float32():
    wo = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8]], dtype=np.float32)
    u = np.full((4, 1, 2), 0.5, dtype=np.float32)
    wi, p = sample("eon", wo, np.float32(0.5), u)
    assert wi.shape == (4, 2, 3) and p.shape == (4, 2)
    assert wi.dtype == np.float32 and p.dtype == np.float32
    q = pdf("eon", wo, wi, np.array([0.5, 0.5], dtype=np.float32))
    assert q.shape == (4, 2) and q.dtype == np.float32
    np.testing.assert_allclose(q, p, rtol=1e-5)
    wi64, _ = sample("eon", wo.astype(np.float64), 0.5, u.astype(np.float64))
    np.testing.assert_allclose(wi, wi64, atol=1e-6)


def test_sample_rng_is_reproducible():
    wo = wo_at(0.3)
    a = sample_rng("eon", wo, 0.7, 42, shape=(100,))
    b = sample_rng("eon", wo, 0.7, np.random.default_rng(42), shape=(100,))
    c = sample_rng("eon", wo, 0.7, 43, shape=(100,))
    np.testing.assert_array_equal(a[0], b[0])
    assert not np.array_equal(a[0], c[0])
    wi, p = sample_rng("eon", np.stack([wo] * 5), np.full(5, 0.7), 1)
    assert wi.shape == (5, 3) and p.shape == (5,)


# --- edge inputs and errors ------------------------------------------------------------------

EDGE_WO = [np.array([0.0, 0.0, 1.0]), wo_at(1e-6), np.array([1.0, 0.0, 0.0]), np.array([0.6, 0.0, -0.8])]
EDGE_U = np.array(
    [
        [0.0, 0.0],
        [0.0, 0.999],
        [np.nextafter(1.0, 0.0), 0.0],
        [np.nextafter(1.0, 0.0), np.nextafter(1.0, 0.0)],
        [0.5, 0.25],
    ]
)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("strategy", STRATEGIES)
def test_edge_inputs_give_finite_results(strategy, dtype):
    for wo in EDGE_WO:
        for r in (0.0, 1.0):
            u = EDGE_U.astype(dtype)
            u = np.minimum(u, np.nextafter(dtype(1.0), dtype(0.0)))
            wi, p = sample(strategy, wo.astype(dtype), dtype(r), u)
            assert np.isfinite(wi).all() and np.isfinite(p).all() and (p >= 0.0).all()
            assert np.allclose(np.linalg.norm(wi.astype(np.float64), axis=-1), 1.0, atol=1e-5)
            q = pdf(strategy, wo.astype(dtype), wi, dtype(r))
            assert np.isfinite(q).all() and (q >= 0.0).all()
            if wo[2] <= 0.0:  # below (or on) the horizon: nothing to sample
                assert (p == 0.0).all() and (q == 0.0).all()
            else:
                assert (p > 0.0).all()


def test_directions_below_the_horizon_have_zero_pdf_except_general_ltc():
    wo = wo_at(0.05)
    below = wo_at(-0.05)  # just below the horizon on wo's side: inside the LTC's back-scattering lobe
    wi = np.array([below, [0.0, 1.0, 0.0], -wo])
    for s in STRATEGIES:
        q = pdf(s, wo, wi, 1.0)
        if s == "ltc":
            assert q[0] > 0.0 and q[2] == 0.0
        else:
            assert (q == 0.0).all()


@pytest.mark.parametrize("bad_u", [1.0, -0.1, np.nan, np.inf])
def test_invalid_u_raises(bad_u):
    u = np.array([[0.5, 0.5], [0.2, bad_u]])
    with pytest.raises(ValueError, match=r"\bu\b"):
        sample("eon", wo_at(0.5), 0.5, u)


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: sample("eon", wo_at(0.5), 0.5, np.zeros(3)), r"\bu\b"),
        (lambda: sample("eon", wo_at(0.5), 1.5, np.zeros(2)), "roughness"),
        (lambda: sample("eon", [0.0, 0.0, 2.0], 0.5, np.zeros(2)), "wo"),
        (lambda: sample("ggx", wo_at(0.5), 0.5, np.zeros(2)), "strategy"),
        (lambda: pdf("eon", wo_at(0.5), [1.0, 1.0, 1.0], 0.5), "wi"),
        (lambda: pdf("eon", wo_at(0.5), wo_at(0.5), -0.1), "roughness"),
        (lambda: sample("eon", np.zeros((2, 3)) + [0, 0, 1], 0.5, np.zeros((3, 2))), "broadcast"),
    ],
)
def test_bad_arguments_raise_value_error_naming_them(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_strategy_must_be_a_string():
    with pytest.raises(TypeError, match="strategy"):
        sample(3, wo_at(0.5), 0.5, np.zeros(2))


# --- the Fig. 10-12 tool ---------------------------------------------------------------------


def test_variance_curves_tool_writes_table_csv_and_png(tmp_path, capsys):
    import importlib.util

    path = Path(__file__).resolve().parents[1] / "tools" / "variance_curves.py"
    spec = importlib.util.spec_from_file_location("variance_curves", path)
    tool = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tool)
    out = tmp_path / "vc.png"
    assert tool.main(["--samples", "4000", "--theta", "0", "88.854", "--roughness", "1", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "variance of the throughput weight" in text and "regenerate:" in text
    assert out.stat().st_size > 10_000
    lines = (tmp_path / "vc.csv").read_text().splitlines()
    assert lines[0].startswith("# ")  # provenance header
    table = list(csv.DictReader(line for line in lines if not line.startswith("#")))
    assert len(table) == 2 * len(STRATEGIES)
    grazing = {row["strategy"]: float(row["variance"]) for row in table if float(row["theta_o_deg"]) > 80}
    assert grazing["cosine"] > 10.0 * grazing["eon"]
