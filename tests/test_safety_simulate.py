"""``simulate``: scheduler timeout, work budget, honest mu range."""

import socket
import subprocess
import sys
import threading

import pytest

from openpbr_diffuse.cli.main import main
from openpbr_diffuse.simulation import api


def _server(mode):
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    s.listen(8)
    held = []

    def serve():
        while True:
            try:
                c, _ = s.accept()
            except OSError:
                return
            if mode == "close":
                c.close()
            else:
                held.append(c)  # accept and never answer

    threading.Thread(target=serve, daemon=True).start()
    return s, held


@pytest.mark.parametrize("mode", ["silent", "close"])
def test_scheduler_that_is_not_dask_gives_one_line(capsys, monkeypatch, mode):
    pytest.importorskip("distributed")
    from openpbr_diffuse.simulation import _dask

    monkeypatch.setattr(_dask, "SCHEDULER_TIMEOUT_S", 2.0)
    s, held = _server(mode)
    try:
        code = main(
            [
                "simulate",
                "--geometry",
                "vcavity",
                "--roughness",
                "0.5",
                "--mu",
                "0.5",
                "--paths",
                "1000",
                "--scheduler",
                f"tcp://127.0.0.1:{s.getsockname()[1]}",
            ]
        )
    finally:
        s.close()
        for c in held:
            c.close()
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and "scheduler" in err


def test_work_above_budget_refused_quickly():
    r = subprocess.run(
        [
            sys.executable,
            "-m",
            "openpbr_diffuse",
            "simulate",
            "--geometry",
            "vcavity",
            "--roughness",
            "0.5",
            "--mu",
            "0.5",
            "--paths",
            "1e12",
        ],
        check=False,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert r.returncode == 2 and "--yes" in r.stderr and len(r.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize("mu", [1e-200, 1e-320, 0.0])
def test_mu_below_smallest_is_a_value_error_naming_mu(mu):
    with pytest.raises(ValueError, match="mu"):
        api.simulate_albedo("smith-ggx", 0.5, [mu], paths=100)


def test_smallest_mu_computes_and_conserves_energy():
    for g in api.GEOMETRIES:
        est = api.simulate_albedo(g, 0.5, [api.MU_MIN], paths=2000)
        assert est.albedo[0, 0] == pytest.approx(1.0, abs=1e-9)  # rho = 1: every path leaves
