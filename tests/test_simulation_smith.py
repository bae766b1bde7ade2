"""Smith random walk against the single-scattering microfacet BRDF by quadrature."""

import numpy as np
import pytest
from _smith_quad import first_order_brdf

from openpbr_diffuse.simulation import simulate_brdf


def _dir(theta, phi):
    return np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])


@pytest.mark.parametrize("dist", ["beckmann", "ggx"])
@pytest.mark.parametrize("alpha", [0.3, 0.8])
def test_first_order_brdf_matches_quadrature(dist, alpha):
    pairs = [(_dir(0.3, 0.0), _dir(0.9, 2.5)), (_dir(1.2, 0.0), _dir(1.1, 0.2)), (_dir(1.3, 0.0), _dir(0.5, np.pi))]
    wi = np.array([p[0] for p in pairs])
    wo = np.array([p[1] for p in pairs])
    est = simulate_brdf(f"smith-{dist}", alpha, wi, wo, rho=1.0, paths=150_000, seed=5)
    for k, (a, b) in enumerate(pairs):
        expected, norm = first_order_brdf(dist, alpha, a, b)
        assert abs(norm - 1.0) < 2e-4
        got, err = est.f_by_order[k, 0, 0], est.stderr_by_order[k, 0, 0]
        assert abs(got - expected) < 4.5 * err + 1e-3 * expected, (k, got, expected, err)
