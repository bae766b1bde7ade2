"""A BRDF is never negative: not even for not-quite-unit directions at grazing, opposite azimuth.

Issue 13, finding 1.  Directions are accepted within |w| = 1 +- UNIT_TOL; for such vectors
s = wi.wo - mu_i mu_o reached -(1 + 2 UNIT_TOL), and FON's 1 + r s/t (hence FON, EON and
"eon_approx") went negative.  Full Oren-Nayar is excepted: its published formula is negative
at forward-grazing pairs (README, kept unclamped).
"""

import math

import numpy as np
import pytest

import openpbr_diffuse as od
from openpbr_diffuse import _arrays as ar

NON_NEGATIVE = [m for m in od.MODELS if m != "full_on"]


def _top(model):
    from openpbr_diffuse.models.registry import INFO

    return 1.0 if INFO[model].roughness_name == "r" else math.pi / 2


def test_issue_example_float32():
    wi = np.float32([0.3, 0.954, 1e-7])
    wo = np.float32([-0.3, -0.954, 1e-7])
    f = od.evaluate("eon", wi, wo, np.float32(1), np.float32(1))
    assert f.dtype == np.float32 and f[0] >= 0.0


@pytest.mark.parametrize("model", NON_NEGATIVE)
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_grazing_opposite_azimuth_with_lengths_at_the_tolerance(model, dtype):
    rng = np.random.default_rng(13)
    n = 20_000
    phi = rng.uniform(0.0, 2.0 * np.pi, n)
    z = 10.0 ** rng.uniform(-12, -2, n)
    z[:100] = 0.0
    s = np.sqrt(1.0 - z * z)
    wi = np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=-1)
    wo = wi * np.array([-1.0, -1.0, 1.0])  # opposite azimuth, both grazing
    scale = 1.0 + ar.UNIT_TOL * rng.uniform(0.5, 0.999, (n, 1))  # accepted: |w| - 1 < UNIT_TOL
    wi, wo = (wi * scale).astype(dtype), (wo * scale).astype(dtype)
    wi[:, 2] = np.abs(wi[:, 2])
    for r in (_top(model), 0.5 * _top(model)):
        f = od.evaluate(model, wi, wo, dtype(r), dtype(1.0))
        assert np.isfinite(f).all()
        assert f.min() >= 0.0, f"{model}: f = {f.min():.3g} at r = {r}"


def test_float64_vectors_of_length_1_plus_1e_5():
    w = np.array([0.3, 0.954, 1e-7])
    w = w / np.linalg.norm(w) * (1.0 + 1e-5)
    for model in NON_NEGATIVE:
        f = od.evaluate(model, w, w * [-1, -1, 1], _top(model), 1.0)
        assert f[0] >= 0.0, model


def test_full_on_keeps_its_published_negative_values():
    """The clamp is on s, not on f: full Oren-Nayar still goes negative where its formula does."""
    t = 1.55
    wi = np.array([np.sin(t), 0.0, np.cos(t)])
    wo = np.array([-np.sin(t), 0.0, np.cos(t)])  # grazing, opposite azimuth (s ~ -1)
    assert od.evaluate("full_on", wi, wo, math.pi / 2, 0.2)[0] < 0.0
