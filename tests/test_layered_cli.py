"""``openpbr-diffuse simulate --layered``: numbers equal the library's, bad input is one line, exit 2."""

import json

import pytest

from openpbr_diffuse.cli.main import main
from openpbr_diffuse.simulation.layered import (
    LayeredSurface,
    simulate_layered_albedo,
    smooth_lambert_albedo,
)


def test_json_matches_the_library(capsys):
    argv = [
        "simulate",
        "--layered",
        "--interface",
        "ggx",
        "--ior",
        "1.4",
        "--interface-roughness",
        "0.2",
        "--coat-color",
        "0.9",
        "0.5",
        "--base",
        "eon",
        "--roughness",
        "0.3",
        "--rho",
        "0.8",
        "0.6",
        "--mu",
        "0.4",
        "1",
        "--paths",
        "4e4",
        "--seed",
        "3",
        "--json",
    ]
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out)
    e = simulate_layered_albedo(
        LayeredSurface("ggx", 1.4, 0.2, coat_color=[0.9, 0.5], base="eon", roughness=0.3),
        [0.4, 1.0],
        rho=[0.8, 0.6],
        paths=40_000,
        seed=3,
    )
    for i, row in enumerate(out["rows"]):
        assert row["total"] == e.total[i].tolist() and row["diffuse_stderr"] == e.diffuse_stderr[i].tolist()
        assert row["specular"] == e.specular[i].tolist()


def test_text_output(capsys):
    assert (
        main(
            [
                "simulate",
                "--layered",
                "--ior",
                "1.5",
                "--rho",
                "0.8",
                "--mu",
                "1",
                "0.2",
                "--absorption",
                "0.2",
                "--thickness",
                "0.5",
                "--paths",
                "30000",
            ]
        )
        == 0
    )
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("# smooth interface, ior 1.5, tau = (0.1)") and "specular" in lines[1]
    total = float(lines[2].split()[7])
    se = float(lines[2].split()[9])
    assert abs(total - float(smooth_lambert_albedo(1.5, 0.8, 1.0, 0.1))) < 4 * se
    assert main(["simulate", "--layered", "--ior", "1.5", "--average", "--paths", "3e4"]) == 0
    assert "average" in capsys.readouterr().out


@pytest.mark.parametrize(
    "extra",
    [
        ["--mu", "0.5"],  # no --ior
        ["--ior", "0.5", "--mu", "0.5"],
        ["--ior", "1.5", "--mu", "1.5"],
        ["--ior", "1.5"],
        ["--ior", "1.5", "--mu", "0.5", "--base", "vcavity"],
        ["--ior", "1.5", "--mu", "0.5", "--absorption", "1"],
        ["--ior", "1.5", "--mu", "0.5", "--coat-color", "0.5", "--absorption", "1", "--thickness", "1"],
        ["--ior", "1.5", "--mu", "0.5", "--interface-roughness", "0.3"],
        ["--ior", "1.5", "--mu", "0.5", "--interface", "ggx", "--interface-roughness", "3"],
        ["--ior", "1.5", "--mu", "0.5", "--roughness", "0.5"],
        ["--ior", "1.5", "--mu", "0.5", "--coat-color", "1.5"],
        ["--ior", "1.5", "--mu", "0.5", "--rho", "-1"],
        ["--ior", "1.5", "--mu", "0.5", "--geometry", "vcavity"],
        ["--ior", "x", "--mu", "0.5"],
    ],
)
def test_bad_input_is_one_line_exit_2(capsys, extra):
    assert main(["simulate", "--layered", *extra, "--paths", "100"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "error" in err


def test_microsurface_simulate_still_needs_geometry(capsys):
    assert main(["simulate", "--mu", "0.5"]) == 2
    assert "--geometry" in capsys.readouterr().err
