import math

import numpy as np
import pytest

import openpbr_diffuse as od


def roughness_max(model):
    """Upper end of a model's roughness domain (Lambert: any; test it up to 1)."""
    from openpbr_diffuse.models.registry import INFO

    return min(INFO[model].roughness_max, 1.0 if INFO[model].roughness_name == "r" else math.pi / 2)


def random_directions(rng, n, zmin=0.0):
    """Uniform directions on the upper hemisphere (z > zmin)."""
    z = rng.uniform(zmin, 1.0, n)
    phi = rng.uniform(0.0, 2.0 * np.pi, n)
    s = np.sqrt(1.0 - z * z)
    return np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=-1)


@pytest.fixture
def rng():
    return np.random.default_rng(20241024)


@pytest.fixture(params=od.MODELS)
def model(request):
    return request.param
