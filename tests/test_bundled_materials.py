"""The bundled material library: what it holds, that every file loads and evaluates, and
that it is found after a plain non-editable install run from another directory."""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import openpbr_diffuse as od
from openpbr_diffuse.readers import BUNDLED_MATERIALS, find_material_files, load_materials
from openpbr_diffuse.readers.evaluate import evaluate, evaluate_many

REPO = Path(__file__).resolve().parents[1]


def _all():
    out = []
    for f in find_material_files([BUNDLED_MATERIALS]):
        out += load_materials(f)
    return out


def test_library_has_the_required_range():
    files = find_material_files([BUNDLED_MATERIALS])
    assert sum(f.suffix == ".usda" for f in files) >= 5 and sum(f.suffix == ".mtlx" for f in files) >= 5
    mats = _all()
    assert len(mats) >= 12 and all(m.supported for m in mats)
    ids = {m.shader_id for m in mats}
    assert {
        "ND_open_pbr_surface_surfaceshader",
        "ND_standard_surface_surfaceshader",
        "UsdPreviewSurface",
        "ND_oren_nayar_diffuse_bsdf",
    } <= ids
    rough = sorted(
        {
            round(float(m.node_inputs.get("base_diffuse_roughness", m.node_inputs.get("roughness")).value), 2)
            for m in mats
        }
    )
    assert rough[0] == 0.0 and rough[-1] >= 0.9 and len(rough) >= 6
    assert any(m.node_inputs.get("coat_weight") and m.node_inputs["coat_weight"].value > 0 for m in mats)
    assert any(p.kind == "texture" for m in mats for p in m.parameters.values())
    colours = np.array([m.node_inputs.get("base_color", m.node_inputs.get("color")).value for m in mats])
    assert np.ptp(colours, axis=0).min() > 0.3  # a range of colours in every channel


def test_time_sampled_variant_and_bound_materials():
    f = BUNDLED_MATERIALS / "velvet_animated.usda"
    r = [load_materials(f, time=t)[0].parameters["base_diffuse_roughness"].value for t in (1, 12.5, 24)]
    assert r == pytest.approx([0.0, 0.5, 1.0])
    f = BUNDLED_MATERIALS / "paint_variants.usda"
    r = {
        v: load_materials(f, variants=[f"finish={v}"])[0].parameters["base_diffuse_roughness"].value
        for v in ("matte", "eggshell", "gloss")
    }
    assert r == pytest.approx({"matte": 0.9, "eggshell": 0.45, "gloss": 0.1})
    f = BUNDLED_MATERIALS / "terracotta_bound.usda"
    assert [m.path for m in load_materials(f, material="/World/Ball")] == ["/World/Looks/terracotta"]
    assert [m.path for m in load_materials(f, material="/World/Ball", purpose="preview")] == [
        "/World/Looks/terracotta_preview"
    ]


def test_bare_oren_nayar_material_evaluates_as_the_model():
    """The evaluator's angles and the node's values against the models' own functions."""
    (m,) = load_materials(BUNDLED_MATERIALS / "sand_oren_nayar.mtlx")
    rho = np.array(m.node_inputs["color"].value)
    r = evaluate(m, theta_i=[60.0, 20.0], theta_o=[30.0, 70.0], phi=[180.0, 90.0])
    wi = np.array([[-np.sin(np.pi / 3), 0.0, 0.5], [0.0, np.sin(np.radians(20)), np.cos(np.radians(20))]])
    wo = np.array([[0.5, 0.0, np.cos(np.pi / 6)], [np.sin(np.radians(70)), 0.0, np.cos(np.radians(70))]])
    assert np.allclose(r["brdf"], od.evaluate("eon", wi, wo, 0.6, rho), rtol=1e-12)
    assert np.allclose(r["albedo"], od.directional_albedo("eon", wo[:, 2], 0.6, rho), rtol=1e-12)
    assert r["diffuse"]["probability"] == [1.0, 1.0]


def test_standard_surface_diffuse_is_qon_with_sigma_diffuse_roughness():
    (m,) = load_materials(BUNDLED_MATERIALS / "felt_red_standard_surface.mtlx")
    node = m.node()
    wo = np.array([0.0, 0.6, 0.8])
    (d,) = [lb for lb in node.lobes(wo) if lb.name == "diffuse"]
    rho = np.array(m.node_inputs["base_color"].value)
    assert np.allclose(d.albedo, od.directional_albedo("qon", 0.8, 0.9, rho), rtol=1e-9)


def test_white_preview_surface_is_a_white_furnace():
    """UsdPreviewSurface -> Lambert diffuse under the specular layer: white preserves energy."""
    from openpbr_diffuse.readers import mapping
    from openpbr_diffuse.readers.material import Material, Parameter

    (m,) = load_materials(BUNDLED_MATERIALS / "plaster_preview.usda")
    m.node_inputs["base_color"] = Parameter((1.0, 1.0, 1.0), "test", "authored")
    albedo = m.node().albedo(np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [0.8, 0.0, 0.6]]))
    assert np.allclose(albedo, 1.0, atol=2e-3)
    assert m.diffuse_model == "lambert" and isinstance(m, Material) and mapping.family(m.shader_id)


def test_evaluate_many_equals_one_by_one():
    mats = _all()
    many = evaluate_many(mats, 40.0, 25.0, 150.0)
    for k, m in enumerate(mats):
        one = evaluate(m, [40.0], [25.0], [150.0])
        assert np.allclose(many["brdf"][k], one["brdf"][0], rtol=1e-10, atol=1e-14), m.path
        assert np.allclose(many["albedo"][k], one["albedo"][0], rtol=1e-10)
        assert many["diffuse_probability"][k] == pytest.approx(one["diffuse"]["probability"][0])


def test_reported_albedo_is_the_surface_albedo():
    """``evaluate``'s albedo (the sum of the lobes' w_k E_k) equals the node's own albedo
    driver, a separately compiled sum, at several view angles; and the diffuse lobe's
    contribution is one of its terms."""
    theta_o = [0.0, 30.0, 60.0, 85.0, 89.5]
    for m in _all():
        node = m.node()
        out = evaluate(m, [30.0] * 5, theta_o, [180.0] * 5)
        wo = np.stack([np.sin(np.radians(theta_o)), np.zeros(5), np.cos(np.radians(theta_o))], axis=-1)
        np.testing.assert_allclose(out["albedo"], node.albedo(wo), rtol=1e-13, atol=1e-15, err_msg=m.path)
        assert np.all(np.asarray(out["diffuse"]["contribution"]) <= np.asarray(out["albedo"]) + 1e-15), m.path


@pytest.mark.slow
def test_found_after_non_editable_install_from_another_directory(tmp_path):
    src = tmp_path / "src"
    shutil.copytree(
        REPO,
        src,
        symlinks=True,
        ignore=shutil.ignore_patterns(".git", "__pycache__", "build", "*.egg-info", ".pytest_cache"),
    )
    target = tmp_path / "target"
    proc = subprocess.run(
        [sys.executable, "-m", "pip", "install", "--no-deps", "--target", str(target), str(src)],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=600,
    )
    if proc.returncode != 0 and (
        "Could not find a version" in proc.stderr or "No matching distribution" in proc.stderr
    ):
        pytest.skip("pip cannot fetch the build backend (offline)")
    assert proc.returncode == 0, proc.stderr[-2000:]
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    code = (
        "import openpbr_diffuse.readers as r, sys; "
        "fs = r.find_material_files([r.BUNDLED_MATERIALS]); "
        "ms = [m for f in fs for m in r.load_materials(f)]; "
        "print(r.__file__); print(r.BUNDLED_MATERIALS); print(len(fs), len(ms), all(m.supported for m in ms))"
    )
    env = dict(os.environ, PYTHONPATH=str(target))
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=elsewhere, env=env, timeout=600
    )
    assert out.returncode == 0, out.stderr[-2000:]
    module, folder, counts = out.stdout.strip().splitlines()[-3:]
    assert module.startswith(str(target)) and folder.startswith(str(target))
    n_files, n_mats, ok = counts.split()
    assert int(n_files) >= 12 and int(n_mats) >= 12 and ok == "True"
    assert not (Path(folder) / "textures" / "brick_albedo.png").is_symlink()
