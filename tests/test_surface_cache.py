"""The surface's compiled drivers are found in numba's disk cache, and the parallel path
gives what the serial one gives.

Two caching bugs this guards against:
- numba files a cached function under its module, qualified name and line and keys the
  entries by signature, not by compile options: a serial and a parallel build of one
  function shared an entry, so a process that had evaluated one row (serial build) made
  every later process run its 10^6-row calls on one thread;
- numba keys a closure's entries by its pickled cell contents, and a compiled function
  pickles differently in every process (a fresh uuid): a driver that closed over another
  compiled function was compiled anew in every process (a minute of a cold start each time).

The surface now has one compiled block runner per verb and parameter stride, run on the
calling thread for small calls and on a thread pool for large ones (``_surface_drivers``).
"""

import os
import subprocess
import sys
import textwrap

import numba
import numpy as np
import pytest

from openpbr_diffuse import OpenPBRSurface, _launch
from openpbr_diffuse.nodes import _surface_drivers as sd


def test_each_runner_has_its_own_cache_index_and_releases_the_gil():
    files = set()
    for builds in sd.BUILDS.values():
        for run in (builds.one, builds.each):
            assert run.targetoptions.get("nogil")  # the pool's threads run it concurrently
            assert not run.targetoptions.get("parallel")
            files.add(run._cache._cache_file._index_path)
    # closures of one factory share a file; their entries differ by the closure's value (the
    # parameter stride, a plain int that pickles the same in every process)
    assert len(files) == len(sd.BUILDS)
    for builds in sd.BUILDS.values():
        assert builds.one.py_func.__closure__ is not None
        for cell in builds.one.py_func.__closure__:
            assert isinstance(cell.cell_contents, int), "a closure over a compiled function is never cached"


def _material():
    return OpenPBRSurface(
        base_color=(0.8, 0.5, 0.3),
        base_metalness=0.3,
        coat_weight=0.5,
        fuzz_weight=0.4,
        subsurface_weight=0.3,
        transmission_weight=0.2,
        geometry_thin_walled=True,
    )


@pytest.mark.cpu_portable
@pytest.mark.parametrize("rows", [sd.SERIAL_ROWS + 1, 3 * sd.SERIAL_ROWS + 17])
def test_the_thread_pool_gives_the_serial_result(rows):
    """Every verb over more than SERIAL_ROWS rows (split into runs over the pool) equals the
    same rows in small calls (the calling thread alone), including the last, partial block.

    Bit for bit on every CPU by construction: the small calls start at multiples of the block
    size B, so each of their blocks holds the rows of one block of the large call, and both
    run the same compiled runner over it (a row is in the same vector lane in both)."""
    rng = np.random.default_rng(rows)
    s = _material()
    wo = rng.normal(size=(rows, 3))
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    wi = rng.normal(size=(rows, 3))
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    u = rng.random((rows, 3))
    step = 16 * sd.B
    assert step < sd.SERIAL_ROWS
    small = range(0, rows, step)
    big = (s.eval(wi, wo), s.pdf(wo, wi), s.albedo(wo), *s.sample(wo, u))
    parts = [
        (
            s.eval(wi[a : a + step], wo[a : a + step]),
            s.pdf(wo[a : a + step], wi[a : a + step]),
            s.albedo(wo[a : a + step]),
            *s.sample(wo[a : a + step], u[a : a + step]),
        )
        for a in small
    ]
    for k, whole in enumerate(big):
        assert np.array_equal(whole, np.concatenate([p[k] for p in parts]))


@pytest.mark.parametrize("per_row", [False, True])
def test_short_calls_give_the_rows_of_a_whole_block(per_row):
    """A call shorter than a block runs its passes over its rows rounded up to the vector
    width (``span``), not the whole block: every verb of 1..9 and 61..63 rows gives the rows
    of a call over whole blocks (the padding rows never leak into a result)."""
    rng = np.random.default_rng(11)
    n = 2 * sd.B
    wo = rng.normal(size=(n, 3))
    wo[:, 2] = np.abs(wo[:, 2])
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    wi = rng.normal(size=(n, 3))
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    u = rng.random((n, 3))
    rowwise = dict(
        base_color=rng.random((n, 3)),
        base_metalness=rng.random(n),
        fuzz_weight=rng.random(n) * 0.5,
        specular_roughness=rng.random(n),
    )
    s = OpenPBRSurface(**rowwise, coat_weight=0.5) if per_row else _material()

    def verbs(sl):
        lobes = s.lobes(wo[sl]) if not per_row else []
        sub = OpenPBRSurface(**{k: v[sl] for k, v in rowwise.items()}, coat_weight=0.5) if per_row else s
        return (
            sub.eval(wi[sl], wo[sl]),
            sub.pdf(wo[sl], wi[sl]),
            sub.albedo(wo[sl]),
            *sub.sample(wo[sl], u[sl]),
            *(x for lobe in lobes for x in (lobe.weight, lobe.albedo, lobe.probability)),
        )

    whole = verbs(slice(None))
    for m in (*range(1, 10), 61, 62, 63):
        for start in (0, 3):
            part = verbs(slice(start, start + m))
            for a, b in zip(part, whole):
                assert np.all(np.isfinite(a))
                np.testing.assert_allclose(a, b[start : start + m], rtol=1e-13, atol=1e-300)


@pytest.mark.cpu_portable
def test_one_thread_gives_the_same_result():
    """Bit for bit by construction: the blocks do not depend on the thread count, and each is
    run by the same compiled runner."""
    s = _material()
    rng = np.random.default_rng(5)
    wo = rng.normal(size=(20000, 3))
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    u = rng.random((20000, 2))
    before = numba.get_num_threads()
    a = s.sample(wo, u)
    try:
        numba.set_num_threads(1)
        b = s.sample(wo, u)
    finally:
        numba.set_num_threads(before)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])


def test_the_pool_is_rebuilt_in_a_forked_child(monkeypatch):
    """A child forked after a large call inherits the pool object but not its threads: the
    pool is made anew per process id.  (Forking itself cannot be tested here: numba's OpenMP
    layer, which other parts of the package use, terminates a forked child that calls it.)"""
    s = _material()
    wo = np.random.default_rng(3).normal(size=(2 * sd.SERIAL_ROWS, 3))
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    expected = s.albedo(wo)
    parent = _launch._pool
    child_pid = os.getpid() + 1
    monkeypatch.setattr(_launch.os, "getpid", lambda: child_pid)
    got = s.albedo(wo)
    assert _launch._pool[2] == child_pid and _launch._pool[0] is not parent[0]
    assert np.array_equal(got, expected)


@pytest.mark.slow
def test_a_second_process_loads_the_drivers_from_the_cache(tmp_path):
    """Process 1 compiles and caches the drivers of a call; process 2 must load them."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    script = textwrap.dedent("""
        import numpy as np
        from openpbr_diffuse import OpenPBRSurface, _launch
        from openpbr_diffuse.nodes import _surface_drivers as sd
        s = OpenPBRSurface(base_color=(0.8, 0.5, 0.3), base_metalness=0.3)
        wo = np.tile([0.0, 0.6, 0.8], (10000, 1))
        s.albedo(wo)
        s.albedo(wo[:1])
        run = sd.ALBEDO.one
        print(sum(run.stats.cache_hits.values()), sum(run.stats.cache_misses.values()))
        """)
    first = subprocess.run(
        [sys.executable, "-c", script], env=env, check=True, timeout=900, capture_output=True, text=True
    ).stdout.split()
    second = subprocess.run(
        [sys.executable, "-c", script], env=env, check=True, timeout=900, capture_output=True, text=True
    ).stdout.split()
    assert list(map(int, first[-2:])) == [0, 1]
    assert list(map(int, second[-2:])) == [1, 0]
