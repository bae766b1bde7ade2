"""Seeded and reproducible per (seed, query, chunk): independent of workers, of the other
queries in the call, and of running on a Dask cluster."""

import numpy as np
import pytest

from openpbr_diffuse.simulation import CHUNK_PATHS, simulate_albedo, simulate_brdf


def _same(a, b):
    assert np.array_equal(a.albedo, b.albedo) and np.array_equal(a.stderr, b.stderr)
    assert np.array_equal(a.albedo_by_order, b.albedo_by_order)


def test_same_seed_same_result_any_worker_count():
    kw = dict(rho=[0.8, 0.3], paths=3 * CHUNK_PATHS + 123, seed=42)
    a = simulate_albedo("vcavity", 0.6, [0.3, 0.9], workers=1, **kw)
    b = simulate_albedo("vcavity", 0.6, [0.3, 0.9], workers=2, **kw)
    _same(a, b)
    c = simulate_albedo("vcavity", 0.6, [0.9], workers=2, **kw)  # a query alone: same numbers
    assert np.array_equal(c.albedo[0], a.albedo[1])


def test_different_seeds_differ():
    a = simulate_albedo("smith-ggx", 0.6, [0.5], rho=0.5, paths=5000, seed=1)
    b = simulate_albedo("smith-ggx", 0.6, [0.5], rho=0.5, paths=5000, seed=2)
    assert a.albedo[0, 0] != b.albedo[0, 0]


def test_dask_local_cluster_gives_the_local_result():
    distributed = pytest.importorskip("dask.distributed")
    kw = dict(rho=[0.8, 0.3], paths=2 * CHUNK_PATHS + 7, seed=3)
    local = simulate_albedo("smith-beckmann", 0.5, [0.2, 0.7], workers=2, **kw)
    wi = np.array([[0.6, 0.0, 0.8]])
    wo = np.array([[0.0, 0.6, 0.8]])
    flocal = simulate_brdf("vcavity", 0.5, wi, wo, rho=0.5, paths=CHUNK_PATHS + 5, seed=4)
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None
    ) as cluster:
        with distributed.Client(cluster) as client:
            remote = simulate_albedo("smith-beckmann", 0.5, [0.2, 0.7], client=client, **kw)
            fremote = simulate_brdf("vcavity", 0.5, wi, wo, rho=0.5, paths=CHUNK_PATHS + 5, seed=4, client=client)
        by_address = simulate_albedo("smith-beckmann", 0.5, [0.2, 0.7], scheduler=cluster.scheduler_address, **kw)
    _same(local, remote)
    _same(local, by_address)
    assert np.array_equal(flocal.f, fremote.f)


def test_missing_dask_is_a_clear_error(monkeypatch):
    import builtins

    real_import = builtins.__import__

    def no_dask(name, *args, **kwargs):
        if name.startswith("dask"):
            raise ImportError("No module named 'dask'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_dask)
    with pytest.raises(ImportError, match="dask"):
        simulate_albedo("vcavity", 0.5, [0.5], paths=10, scheduler="tcp://127.0.0.1:1")


def test_brdf_value_does_not_depend_on_the_other_view_directions():
    """Next-event estimation draws no random numbers: f(wi, wo) is the same whichever other
    wo share its paths."""
    wi = np.array([0.6, 0.0, 0.8])
    wo = np.array([[0.0, 0.6, 0.8], [-0.8, 0.0, 0.6], [0.28, 0.0, 0.96]])
    many = simulate_brdf("smith-ggx", 0.5, wi, wo, rho=[0.7, 0.2], paths=5000, seed=8)
    one = simulate_brdf("smith-ggx", 0.5, wi, wo[1], rho=[0.7, 0.2], paths=5000, seed=8)
    assert np.array_equal(many.f[1], one.f[0]) and np.array_equal(many.stderr[1], one.stderr[0])
