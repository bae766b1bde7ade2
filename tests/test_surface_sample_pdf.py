"""``OpenPBRSurface.sample`` returns the mixture pdf of the direction it returns.

The sampler evaluates the mixture pdf at the sampled directions with the same block passes as
``pdf`` (``nodes._surface_drivers``), compiled into two drivers.  numba compiles for the host
CPU, and LLVM may contract multiply-adds differently in the two drivers and in a loop's vector
body and its remainder (rows of a subset land in other lanes), so the contract that holds on
every x86-64 CPU (AVX, AVX2, AVX-512) is agreement to ``PDF_ULPS`` units in the last place
(bit for bit on the CPUs where both take the same instructions); and a hemisphere lobe never
returns a direction on the horizon, where its own pdf is 0 (the EON sampler's uniform branch
gives z = u at u = 0).  Checked on seeded random materials mixing every lobe, at the edges of
u (0 and the largest float64 below 1) as well as inside, with u of 3 and of 2 columns.
"""

import warnings

import numpy as np
import pytest
from test_surface_scores import directions, random_material

from openpbr_diffuse import OpenPBRSurface

U_TOP = 1.0 - 2.0**-53
#: Bound on |sample's pdf - pdf(wo, wi)|, in units in the last place of the larger.
PDF_ULPS = 4


def assert_within_ulps(a, b, ulps):
    """|a - b| <= ulps * spacing(max(|a|, |b|)) elementwise (and the same zeros)."""
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape
    assert np.array_equal(a == 0.0, b == 0.0)
    gap = np.abs(a - b) / np.spacing(np.maximum(np.abs(a), np.abs(b)))
    assert np.all(gap <= ulps), f"{np.max(gap):.0f} ulp apart (bound {ulps})"


def _u(rng, n, cols):
    u = rng.random((n, cols))
    u[:50] = 0.0
    u[50:100] = U_TOP
    u[100:150, 0] = U_TOP  # the top of the lobe CDF, the lobe's own u inside
    u[150:200, 1:] = 0.0
    return u


@pytest.mark.cpu_portable
@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("cols", [3, 2])
@pytest.mark.parametrize("sampling", ["vndf", "ndf"])
def test_sample_pdf_is_pdf_of_the_sample(seed, cols, sampling):
    rng = np.random.default_rng(300 + seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = OpenPBRSurface(
            **random_material(rng), specular_sampling=sampling, diffuse_model=("eon", "qon", "lambert")[seed % 3]
        )
    wo = directions(rng, 3000, lower=True)
    wo[:1500, 2] = np.abs(wo[:1500, 2])
    wi, q = s.sample(wo, _u(rng, 3000, cols))
    up = wo[:, 2] > 0
    assert np.all(q[~up] == 0.0)
    ok = q > 0
    assert_within_ulps(q[ok], s.pdf(wo[ok], wi[ok]), PDF_ULPS)
    assert np.allclose(np.linalg.norm(wi, axis=1), 1.0, atol=1e-12)
    if sampling == "vndf":
        # visible-normal sampling does not fail while wo is above the horizon, but at the top
        # of u's range (rows 50-150): a VNDF normal on the silhouette, u1 -> 1, reflects wo
        # to -wo, where the visible-normal density, and the pdf, is 0
        assert np.all(ok[200:][up[200:]])


@pytest.mark.cpu_portable
def test_eon_sample_at_u_zero_is_above_the_horizon():
    """The EON sampler's uniform branch returns z = u1 = 0 at u = 0: the surface lifts it to
    the smallest normal number, so the sample stays in the lobe and its pdf is pdf(wo, wi) > 0
    (before, the surface returned z = 0 with the sampler's own density, while pdf() there was
    the diffuse lobe's 0)."""
    s = OpenPBRSurface(base_color=(0.8, 0.5, 0.3), base_diffuse_roughness=0.9, specular_weight=0.0)
    assert [lb.name for lb in s.lobes(np.array([0.0, 0.0, 1.0]))] == ["diffuse"]
    wo = directions(np.random.default_rng(1), 64)
    for u in (np.zeros((64, 2)), np.zeros((64, 3))):
        wi, q = s.sample(wo, u)
        assert np.all(wi[:, 2] > 0.0)
        assert np.all(q > 0.0)
        assert_within_ulps(q, s.pdf(wo, wi), PDF_ULPS)
