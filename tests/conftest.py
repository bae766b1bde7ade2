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


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    """Under OPENPBR_DIFFUSE_REQUIRE_SYSTEM (set by .ci/run) a skip for a missing system program
    (reason starting with tests/_system.PREFIX) is a failure: CI installs every program."""
    import _system

    outcome = yield
    rep = outcome.get_result()
    if not (rep.skipped and _system.required()):
        return
    longrepr = rep.longrepr
    text = longrepr[2] if isinstance(longrepr, tuple) and len(longrepr) == 3 else str(longrepr)
    if _system.PREFIX in text:
        rep.outcome = "failed"
        rep.longrepr = f"{text} -- {_system.REQUIRE_ENV} is set, so a missing system program fails the run"


def pytest_configure(config):
    """The library cache of report/eval (``$OPENPBR_DIFFUSE_CACHE_DIR``) in a folder of this test
    run, so that the tests neither read nor fill the user's cache."""
    import os
    import tempfile

    os.environ.setdefault("OPENPBR_DIFFUSE_CACHE_DIR", tempfile.mkdtemp(prefix="openpbr-diffuse-test-cache-"))
