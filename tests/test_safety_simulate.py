"""`simulate`: bounded work, honest range ends and a scheduler that does not answer.

Every case ends within a bounded time with one line and exit 2 (CLI) or a clear exception
(library): a mistyped `--paths 1e12` is refused before any planning, the smallest allowed mu
gives a finite albedo on every geometry, and a TCP service that is not a Dask scheduler is
named as such within the connection timeout.
"""
from __future__ import annotations

import os
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from openpbr_diffuse.simulation import api

ROOT = Path(__file__).resolve().parents[1]


def _cli(*argv, timeout=120):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    t0 = time.monotonic()
    p = subprocess.run([sys.executable, "-m", "openpbr_diffuse", "simulate", *argv], capture_output=True, text=True,
                       env=env, timeout=timeout)
    return p, time.monotonic() - t0


@pytest.mark.parametrize("geometry", ["vcavity", "smith-ggx", "smith-beckmann"])
def test_smallest_mu_gives_a_finite_albedo(geometry):
    mu = np.array([5e-324, 1e-200, 1e-150])
    est = api.simulate_albedo(geometry, 0.5, mu, rho=0.8, paths=3000, seed=4)
    assert np.all(np.isfinite(est.albedo)) and np.all((est.albedo > 0.3) & (est.albedo <= 0.8 + 1e-12))
    # mu -> 0 is a limit: the three rows agree within their standard errors
    spread = np.ptp(est.albedo[:, 0])
    assert spread <= 5 * np.max(est.stderr[:, 0]) + 1e-12


def test_huge_path_count_is_refused_before_planning():
    p, took = _cli("--geometry", "vcavity", "--roughness", "0.5", "--mu", "0.5", "--paths", "1e12")
    assert p.returncode == 2 and "--yes" in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert took < 60


class _Server:
    """A local TCP service that is not a Dask scheduler: silent, or answering junk and closing."""

    def __init__(self, mode):
        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(8)
        self.mode, self.conns, self.stop = mode, [], False
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    @property
    def address(self):
        return f"tcp://127.0.0.1:{self.sock.getsockname()[1]}"

    def _serve(self):
        self.sock.settimeout(0.2)
        while not self.stop:
            try:
                c, _ = self.sock.accept()
            except OSError:
                continue
            if self.mode == "junk":
                c.sendall(b"\xff" * 64)
                c.close()
            else:
                self.conns.append(c)

    def close(self):
        self.stop = True
        self.thread.join(2)
        for c in self.conns:
            c.close()
        self.sock.close()


@pytest.mark.parametrize("mode", ["silent", "junk"])
def test_scheduler_that_does_not_answer(monkeypatch, mode):
    pytest.importorskip("dask.distributed")  # installed by .ci/run (extra 'dask')
    monkeypatch.setattr(api, "SCHEDULER_TIMEOUT", 2.0)
    server = _Server(mode)
    try:
        t0 = time.monotonic()
        with pytest.raises(ConnectionError, match="no Dask scheduler answered"):
            api.simulate_albedo("vcavity", 0.5, [0.5], paths=100, scheduler=server.address)
        assert time.monotonic() - t0 < 30
    finally:
        server.close()
