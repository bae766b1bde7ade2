"""``openpbr-diffuse albedo``: query output, errors, and the EXR lookup-texture export."""

import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest

import openpbr_diffuse as od
from openpbr_diffuse.albedo import load_table, reference_albedo, reference_average_albedo
from openpbr_diffuse.albedo.export import read_exr, texel_centres
from openpbr_diffuse.cli.main import main


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


class TestQuery:
    def test_table_output(self, capsys):
        code, out, err = run(capsys, "albedo", "fon", "--roughness", "1", "--mu", "1", "0.7")
        assert code == 0 and not err
        lines = out.strip().splitlines()
        assert lines[0].startswith("# model fon")
        assert lines[1].split() == ["mu", "E"]
        rows = [list(map(float, line.split())) for line in lines[2:]]
        # EON paper values E_F(1, 1) and E_F(0.7, 1)
        assert rows[0][1] == pytest.approx(0.776522, abs=1e-6)
        assert rows[1][1] == pytest.approx(0.817888, abs=1e-6)

    def test_json_rgb(self, capsys):
        code, out, _ = run(
            capsys, "albedo", "eon", "--roughness", "1", "--mu", "0.3", "0.8", "--rho", "0.5", "0.5", "1", "--json"
        )
        assert code == 0
        data = json.loads(out)
        assert data["model"] == "eon" and data["mu"] == [0.3, 0.8]
        E = np.array(data["albedo"])
        assert E.shape == (2, 3)
        assert E[0, 0] == pytest.approx(0.4780, abs=1e-4)  # independent quadrature; Blender's 0.4689 is wrong
        assert E[:, 2] == pytest.approx([1.0, 1.0], abs=1e-6)  # white furnace

    def test_reference_column(self, capsys):
        code, out, _ = run(
            capsys, "albedo", "qon", "--roughness", str(math.pi / 4), "--mu", "0.5", "--reference", "--json"
        )
        data = json.loads(out)
        assert code == 0
        assert data["albedo"][0][0] == pytest.approx(0.791338, abs=1e-6)
        assert data["reference_albedo"][0][0] == pytest.approx(0.791338, abs=1e-6)
        assert abs(data["difference"][0][0]) <= data["reference_error"]
        code, out, _ = run(capsys, "albedo", "qon", "--roughness", "0.7", "--mu", "0.5", "--reference")
        assert out.splitlines()[1].split() == ["mu", "E", "ref", "diff"]

    def test_average(self, capsys):
        code, out, _ = run(capsys, "albedo", "fon", "--roughness", "0.5", "--average", "--json")
        assert code == 0 and json.loads(out)["average_albedo"][0] == pytest.approx(0.905890, abs=1e-6)
        code, out, _ = run(capsys, "albedo", "full_on", "--roughness", "0.5", "--average", "--reference")
        assert code == 0 and "<E>" in out and "reference table" in out

    def test_full_on_checked_value(self, capsys):
        code, out, _ = run(capsys, "albedo", "full_on", "--roughness", "0.5", "--mu", "0.05", "--json")
        data = json.loads(out)
        assert data["source"] == "reference table"
        assert data["albedo"][0][0] == pytest.approx(1.0047, abs=5e-5)

    def test_console_script(self):
        exe = os.path.join(os.path.dirname(sys.executable), "openpbr-diffuse")
        if not os.path.exists(exe):
            pytest.skip("console script not installed")
        proc = subprocess.run([exe, "albedo", "lambert", "--mu", "0.5", "--json"], capture_output=True, text=True)
        assert proc.returncode == 0 and json.loads(proc.stdout)["albedo"] == [[1.0]]


class TestErrors:
    @pytest.mark.parametrize(
        "argv,needle",
        [
            (["albedo", "oren", "--roughness", "0.5", "--mu", "0.5"], "unknown model"),
            (["albedo", "qon", "--roughness", "2", "--mu", "0.5"], "roughness"),
            (["albedo", "eon", "--roughness", "-0.1", "--mu", "0.5"], "roughness"),
            (["albedo", "qon", "--roughness", "0.5", "--mu", "1.2"], "mu"),
            (["albedo", "qon", "--roughness", "0.5", "--mu", "nan"], "mu"),
            (["albedo", "qon", "--roughness", "0.5", "--mu", "abc"], "mu"),
            (["albedo", "qon", "--roughness", "0.5", "--mu", "0.5", "--rho", "1.5"], "rho"),
            (["albedo", "qon", "--mu", "0.5"], "--roughness"),
            (["albedo", "qon", "--roughness", "0.5"], "--mu"),
            (["albedo", "qon", "--roughness", "0.5", "--mu", "0.5", "--size", "8"], "--size"),
            (["albedo", "qon", "--export", "/tmp/x", "--size", "2"], "size"),
        ],
    )
    def test_one_line_exit_2(self, capsys, argv, needle):
        code, out, err = run(capsys, *argv)
        assert code == 2
        assert not out
        assert len(err.strip().splitlines()) == 1 and needle in err


class TestExport:
    @pytest.mark.parametrize("model,size", [("eon", 16), ("full_on", 8), ("lambert", 4)])
    def test_exr_reads_back(self, tmp_path, capsys, model, size):
        code, out, _ = run(capsys, "albedo", model, "--export", str(tmp_path), "--size", str(size))
        assert code == 0
        p2, p1 = out.split()
        assert os.path.basename(p2) == f"{model}_albedo.exr"
        img, meta = read_exr(p2)
        assert img.shape == (size, size, 3) and img.dtype == np.float32
        assert meta["openpbr_diffuse:model"] == model
        assert "(i + 0.5)" in meta["openpbr_diffuse:x_axis"]
        # texel centres: column i at mu = (i + 0.5)/N, row j at roughness = (j + 0.5)/N * max
        mu = texel_centres(size)
        rmax = float(meta["openpbr_diffuse:roughness_max"])
        rough = texel_centres(size) * rmax
        ref = reference_albedo(model, mu[None, :], rough[:, None], 1.0)[..., 0]
        np.testing.assert_allclose(img[..., 0], ref, rtol=1e-7, atol=1e-7)
        # G, B give any rho: E(rho) = rho G + m(rho) B
        rho = 0.4
        from openpbr_diffuse.albedo.tables import mix_weight

        E = rho * img[..., 1] + mix_weight(model, rho, rough[:, None]) * img[..., 2]
        np.testing.assert_allclose(E, reference_albedo(model, mu[None, :], rough[:, None], rho)[..., 0], atol=1e-6)
        avg, meta1 = read_exr(p1)
        assert avg.shape == (1, size, 3)
        np.testing.assert_allclose(
            avg[0, :, 0], reference_average_albedo(model, rough, 1.0)[:, 0], rtol=1e-7, atol=1e-7
        )
        assert meta1["openpbr_diffuse:y_axis"] == "single row"

    def test_export_function_and_accuracy(self, tmp_path):
        """The LUT is within the table's interpolation error of the closed form (EON)."""
        from openpbr_diffuse.albedo.export import export_lut

        p2, _ = export_lut("eon", tmp_path, 8)
        img, _ = read_exr(p2)
        mu = texel_centres(8)
        r = texel_centres(8)
        closed = od.directional_albedo("eon", mu[None, :], r[:, None], 0.5)[..., 0]
        from openpbr_diffuse.albedo.tables import mix_weight

        E = 0.5 * img[..., 1] + mix_weight("eon", 0.5, r[:, None]) * img[..., 2]
        assert np.abs(E - closed).max() < load_table("eon").interpolation_error + 1e-6
