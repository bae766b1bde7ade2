"""``openpbr-diffuse simulate``: output, JSON schema, errors (one line, exit 2)."""

import json

import numpy as np

from openpbr_diffuse.cli.main import main
from openpbr_diffuse.simulation import simulate_albedo


def test_json_rows_match_the_python_function(capsys):
    rc = main(
        [
            "simulate",
            "--geometry",
            "vcavity",
            "--roughness",
            "0.5",
            "--mu",
            "0.3",
            "0.9",
            "--rho",
            "0.8",
            "0.5",
            "0.2",
            "--paths",
            "5000",
            "--seed",
            "3",
            "--json",
        ]
    )
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    est = simulate_albedo("vcavity", 0.5, [0.3, 0.9], rho=[0.8, 0.5, 0.2], paths=5000, seed=3)
    assert [r["mu"] for r in out["rows"]] == [0.3, 0.9]
    for i, row in enumerate(out["rows"]):
        assert np.allclose(row["albedo"], est.albedo[i])
        assert np.allclose(row["stderr"], est.stderr[i])
        assert np.allclose(row["albedo_by_order"]["1"], est.albedo_by_order[i, 0])
        assert set(row["albedo_by_order"]) == {"1", "2", ">=3"}
        total = sum(np.array(row["albedo_by_order"][k]) for k in ("1", "2", ">=3"))
        assert np.allclose(total, row["albedo"])


def test_text_output_and_average(capsys):
    assert main(["simulate", "--geometry", "smith-ggx", "--roughness", "0.4", "--mu", "0.5", "--paths", "2000"]) == 0
    text = capsys.readouterr().out
    assert "smith-ggx" in text and "0.500000" in text and "+-" in text
    assert (
        main(
            ["simulate", "--geometry", "smith-beckmann", "--roughness", "0.4", "--average", "--paths", "2000", "--json"]
        )
        == 0
    )
    out = json.loads(capsys.readouterr().out)
    assert out["average"] and out["rows"][0]["mu"] is None and out["rows"][0]["albedo"] == [1.0]


def test_bad_input_is_one_line_exit_2(capsys):
    for argv in (
        ["simulate", "--geometry", "vcavity", "--roughness", "3", "--mu", "0.5"],
        ["simulate", "--geometry", "vcavity", "--roughness", "0.5", "--mu", "1.5"],
        ["simulate", "--geometry", "vcavity", "--roughness", "0.5"],
        ["simulate", "--geometry", "cube", "--roughness", "0.5", "--mu", "0.5"],
        ["simulate", "--geometry", "vcavity", "--roughness", "0.5", "--mu", "0.5", "--rho", "2"],
        ["simulate", "--geometry", "vcavity", "--roughness", "0.5", "--mu", "0.5", "--paths", "-3"],
    ):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "error" in err
