"""The one thread pool of ``_launch``: a large call runs on it, and a call made from one of its
threads runs its rows itself instead of waiting on the pool (which would deadlock it)."""

import numba
import numpy as np
import pytest

import openpbr_diffuse as od
from openpbr_diffuse import _launch


def _inputs(n):
    rng = np.random.default_rng(7)
    wi = rng.normal(size=(n, 3))
    wi[:, 2] = np.abs(wi[:, 2])
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    return wi, wi[::-1].copy(), rng.uniform(0.0, 1.0, n), rng.uniform(0.0, 1.0, (n, 3))


def test_no_driver_is_compiled_parallel():
    from openpbr_diffuse.models import _kernels as mk
    from openpbr_diffuse.sampling import _kernels as sk

    for drive in (mk.eval_driver(mk.EON, 3), mk.albedo_driver(mk.QON, 1), sk.sample_driver(1)):
        assert drive.targetoptions.get("nogil") and not drive.targetoptions.get("parallel")


@pytest.mark.skipif(numba.get_num_threads() < 2, reason="needs 2 numba threads")
def test_a_call_from_a_pool_thread_runs_and_matches():
    n = 2 * _launch.SPLIT_ROWS + 5
    wi, wo, r, rho = _inputs(n)
    direct = od.evaluate("eon", wi, wo, r, rho)
    job = _launch.executor(numba.get_num_threads()).submit(od.evaluate, "eon", wi, wo, r, rho)
    nested = job.result(timeout=120)  # a deadlock would time out here
    np.testing.assert_allclose(nested, direct, rtol=1e-14, atol=0)


@pytest.mark.skipif(numba.get_num_threads() < 2, reason="needs 2 numba threads")
def test_a_split_call_counts_every_bad_row():
    """The runs' counts of rows failing the checks are summed: a bad roughness in the last
    run (not the calling thread's) still raises."""
    n = 2 * _launch.SPLIT_ROWS + 5
    wi, wo, r, rho = _inputs(n)
    r[-1] = 2.0
    with pytest.raises(ValueError, match="roughness"):
        od.evaluate("eon", wi, wo, r, rho)
