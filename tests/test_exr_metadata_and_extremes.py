"""Metadata and text match the data."""

import json

import numpy as np
import pytest

import openpbr_diffuse as od
from openpbr_diffuse.albedo.export import export_lut, read_exr
from openpbr_diffuse.cli.main import main
from openpbr_diffuse.models.tables import load_table


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("model", ["eon", "qon", "lambert"])
def test_average_texture_axis_names_its_own_axis(tmp_path, model):
    _, p1 = export_lut(model, tmp_path, 8)
    img, meta = read_exr(p1)
    assert img.shape == (1, 8, 3)
    x = meta["openpbr_diffuse:x_axis"]
    assert "j" not in x.replace("Lambert", "").split("=")[-1] or model == "lambert"
    if model != "lambert":
        assert "(i + 0.5)/8" in x and "i = column" in x


def test_source_is_complete(tmp_path):
    p2, _ = export_lut("eon", tmp_path, 4)
    _, meta = read_exr(p2)
    table = load_table("eon")
    src = meta["openpbr_diffuse:source"]
    assert table.meta["method"] in src and "..." not in src
    assert repr(table.interpolation_error) in src


def test_header_error_is_the_json_error(capsys):
    code, out, _ = run(capsys, "albedo", "eon", "--roughness", "0.5", "--mu", "0.5", "--reference", "--json")
    err = json.loads(out)["reference_error"]
    code, out, _ = run(capsys, "albedo", "eon", "--roughness", "0.5", "--mu", "0.5", "--reference")
    assert f"accurate to {err:.2g}" in out.splitlines()[0]


def test_full_on_reference_is_independent_of_the_table(capsys):
    """full_on's value is the table's; --reference integrates evaluate instead."""
    code, out, _ = run(
        capsys, "albedo", "full_on", "--roughness", "0.5", "--mu", "0.05", "0.5", "--reference", "--json"
    )
    data = json.loads(out)
    assert code == 0 and data["reference_source"] == "quadrature of evaluate"
    diff = np.abs(np.array(data["difference"]))
    assert (diff > 0).all()  # not the table against itself
    assert diff.max() <= load_table("full_on").interpolation_error  # and the table is that close


def test_full_on_largest_albedo():
    """README: fullON's largest albedo (rho = 1) is 1.0510, at mu = 0 and sigma ~ 0.31.

    Independent of the tables' interpolation: the maximum over the table nodes, then a
    direct quadrature of ``evaluate`` near the grazing limit at the maximising sigma.
    """
    from openpbr_diffuse.albedo.quadrature import hemisphere_albedo

    table = load_table("full_on")
    E = table.e_g + table.e_h  # rho = 1: E = e_g + rho^2 e_h
    j, k = np.unravel_index(np.argmax(E), E.shape)
    assert table.mu[j] == 0.0 and E.max() == pytest.approx(1.0510, abs=5e-5)
    sig = np.linspace(0.2, 0.45, 251)
    fine = od.reference_albedo("full_on", 0.0, sig, 1.0)[:, 0]
    s_best = sig[np.argmax(fine)]
    assert s_best == pytest.approx(0.31, abs=0.01) and fine.max() == pytest.approx(1.0510, abs=5e-5)
    quad = hemisphere_albedo(lambda wi, wo: od.evaluate("full_on", wi, wo, s_best, 1.0)[..., 0], 0.0, 12)
    assert float(quad) == pytest.approx(1.0510, abs=5e-5)
    # the value the README quoted before (sigma = 0.5, mu = 0.05) is not the largest
    assert od.reference_albedo("full_on", 0.05, 0.5)[0] < fine.max() - 0.04
