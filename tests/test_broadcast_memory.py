"""Broadcast inputs are never expanded: peak memory is the output plus a few fixed-size blocks.

Outer-product inputs (directional albedo on (n, 1) x (1, n), evaluate on (n, 1, 3) x (1, n, 3),
full_on at 3e4 x 3e4) must not be copied to full size first.  Measured with tracemalloc (NumPy reports its allocations to it).
"""

import tracemalloc

import numpy as np
import pytest

import openpbr_diffuse as od

#: Extra bytes allowed beyond the output: a few blocks of CHUNK rows (~5 MB each), fixed
#: whatever n; the outputs below are 16-32 MB, so an expanded input would exceed it.
EXTRA = 12 << 20


def peak(f):
    f()  # compile / load tables outside the measurement
    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        out = f()
        top = tracemalloc.get_traced_memory()[1] - base
    finally:
        tracemalloc.stop()
    nbytes = sum(o.nbytes for o in out) if isinstance(out, tuple) else out.nbytes
    return out, top - nbytes


def _grid(n, rng):
    z = rng.uniform(0.0, 1.0, n)
    s = np.sqrt(1.0 - z * z)
    phi = rng.uniform(0.0, 2 * np.pi, n)
    return z, np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=-1)


def test_evaluate_outer_product():
    rng = np.random.default_rng(1)
    n = 2000
    _, wi = _grid(n, rng)
    _, wo = _grid(n, rng)
    out, extra = peak(lambda: od.evaluate("eon", wi[:, None, :], wo[None, :, :], 0.5, 0.8))
    assert out.shape == (n, n, 1)
    assert extra <= EXTRA, f"{extra / out.nbytes:.2f} x the output"
    # the values are those of the expanded call
    k = rng.integers(0, n, (50, 2))
    np.testing.assert_array_equal(out[k[:, 0], k[:, 1]], od.evaluate("eon", wi[k[:, 0]], wo[k[:, 1]], 0.5, 0.8))


@pytest.mark.parametrize("model", ["eon", "full_on"])
def test_directional_albedo_outer_product(model):
    rng = np.random.default_rng(2)
    n = 1500 if model == "full_on" else 2000
    mu = rng.uniform(0.0, 1.0, (n, 1))
    r = rng.uniform(0.0, 1.0, (1, n))
    out, extra = peak(lambda: od.directional_albedo(model, mu, r, 0.7))
    assert out.shape == (n, n, 1)
    assert extra <= EXTRA, f"{extra / out.nbytes:.2f} x the output"
    i, j = rng.integers(0, n, 20), rng.integers(0, n, 20)
    np.testing.assert_allclose(out[i, j, 0], od.directional_albedo(model, mu[i, 0], r[0, j], 0.7)[:, 0], rtol=1e-14)


def test_sample_and_pdf_outer_product():
    rng = np.random.default_rng(3)
    n = 1000
    _, wo = _grid(n, rng)
    wo[:, 2] += 0.01
    wo /= np.linalg.norm(wo, axis=-1, keepdims=True)
    u = rng.random((1, n, 2))
    (wi, p), extra = peak(lambda: od.sample("eon", wo[:, None, :], 0.7, u))
    assert wi.shape == (n, n, 3) and extra <= EXTRA
    q, extra = peak(lambda: od.pdf("eon", wo[:, None, :], wi, 0.7))
    assert extra <= EXTRA
    np.testing.assert_allclose(p, q, rtol=1e-13, atol=0)


def test_lut_export_memory_is_bounded_and_shows_progress(tmp_path, capsys):
    """A 1024^2 LUT is computed and written in row blocks; progress goes to stderr."""
    from openpbr_diffuse.albedo.export import export_lut, read_exr

    export_lut("eon", tmp_path, 8)
    tracemalloc.start()
    try:
        export_lut("eon", tmp_path, 1024, progress=True, force=True)
        top = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    image = 1024 * 1024 * 3 * 4
    assert top <= 64 << 20, f"peak {top / 2**20:.0f} MB for a {image / 2**20:.0f} MB image"
    assert "eon_albedo.exr" in capsys.readouterr().err
    img, _ = read_exr(tmp_path / "eon_albedo.exr")
    assert img.shape == (1024, 1024, 3) and np.isfinite(img).all()
