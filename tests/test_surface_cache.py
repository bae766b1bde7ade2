"""The serial and parallel builds of each surface driver have cache entries of their own.

numba files a cached function under its module, qualified name and line and keys the entries
by signature and CPU, not by the compile options, so compiling one Python function both with
and without ``parallel=True`` made the two builds share an entry: once a process had
evaluated a single row (serial build), every later process loaded that serial code for its
10^6-row calls too, and ran them on one thread.
"""
import os
import subprocess
import sys
import textwrap

import pytest

from openpbr_diffuse.nodes import _surface_kernels as sk


def test_each_build_has_its_own_cache_file():
    """No cache file holds both a parallel and a serial build.  (The pdf and sample drivers
    are closures over their slot bound: their two variants of each build share a file, with
    entries told apart by the closure's value, which numba's cache keys do include.)"""
    parallel_files, serial_files = set(), set()
    for f, (parallel, serial) in sk._DRIVERS.items():
        assert parallel.targetoptions.get("parallel") and not serial.targetoptions.get("parallel")
        parallel_files.add(parallel._cache._cache_file._index_path)
        serial_files.add(serial._cache._cache_file._index_path)
    assert not parallel_files & serial_files
    assert len(parallel_files) == len(serial_files) == 5   # lobes, albedo, eval, pdf, sample


@pytest.mark.slow
def test_a_cached_serial_build_is_not_loaded_for_the_parallel_call(tmp_path):
    """Process 1 evaluates one row (the serial build is compiled and cached); process 2 then
    evaluates 10^4 rows: its parallel driver must not come from process 1's cache entry."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    head = textwrap.dedent("""
        import numpy as np
        from openpbr_diffuse import OpenPBRSurface
        from openpbr_diffuse.nodes import _surface_kernels as sk
        s = OpenPBRSurface(base_color=(0.8, 0.5, 0.3), base_metalness=0.3)
        wo = np.tile([0.0, 0.6, 0.8], (10000, 1))
        """)
    subprocess.run([sys.executable, "-c", head + "s.albedo(wo[:1])"], env=env, check=True, timeout=600)
    out = subprocess.run([sys.executable, "-c", head + textwrap.dedent("""
        s.albedo(wo)
        par, ser = sk._DRIVERS[sk._albedo_drive]
        print(sum(par.stats.cache_hits.values()), sum(par.stats.cache_misses.values()))
        """)], env=env, check=True, timeout=600, capture_output=True, text=True).stdout.split()
    hits, misses = map(int, out[-2:])
    assert hits == 0 and misses == 1
