"""The conformance chart's scenes: geometry checked independently (ray casting, plane fits),
and every format read back by its own library (usd-core, MaterialX, JSON + buffer)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from openpbr_diffuse.chart.layout import INTERREFLECTION_MAX, build_scene, build_scenes
from openpbr_diffuse.cli.main import main

RES = 256


@pytest.fixture(scope="module")
def scenes():
    return build_scenes("distant", RES)


def _pixel_to_world(x, y, s):
    return (x - s["width"] / 2) * 0.01, (s["height"] / 2 - y) * 0.01


def test_tiles_project_onto_their_rectangles_with_their_normal(scenes):
    for s in scenes:
        for t in s["tiles"]:
            c = np.array(t["corners"])
            x0, y0, x1, y1 = t["rect"]
            xs, ys = zip(*(_pixel_to_world(x, y, s) for x, y in [(x0, y1), (x1, y1), (x1, y0), (x0, y0)]), strict=True)
            np.testing.assert_allclose(c[:, 0], xs, atol=1e-9)
            np.testing.assert_allclose(c[:, 1], ys, atol=1e-9)
            n = np.cross(c[1] - c[0], c[2] - c[0])  # the plane of the corners, counter-clockwise
            np.testing.assert_allclose(n / np.linalg.norm(n), t["normal"], atol=1e-9)
            assert 0 < x1 - x0 and (x1 - x0) * 0.7 >= 7  # interior at this resolution


def test_wi_wo_are_the_world_light_and_view_in_the_tiles_frame(scenes):
    for s in scenes:
        l = np.array(s["light"]["direction"])
        for t in s["tiles"]:
            wi, wo, n = np.array(t["wi"]), np.array(t["wo"]), np.array(t["normal"])
            assert math.isclose(wi[2], l @ n, abs_tol=1e-12) and math.isclose(wo[2], n[2], abs_tol=1e-12)
            assert math.isclose(wi @ wo, l[2], abs_tol=1e-12)  # the angle between them is kept
            assert wi[2] > 0.05 and wo[2] > 0.05


def test_the_scenes_cover_the_domain(scenes):
    rows = [
        (t["wi"][2], t["wo"][2], np.dot(t["wi"], t["wo"]), t["roughness"], tuple(t["rho"]))
        for s in scenes
        for t in s["tiles"]
        if t["role"] == "test"
    ]
    mu_i, mu_o, ldotv, r, rho = zip(*rows, strict=True)
    assert min(mu_i) < 0.1 and min(mu_o) < 0.1 and max(mu_i) == pytest.approx(1.0)
    assert min(ldotv) < -0.5 and max(ldotv) > 0.9 and sum(x < 0 for x in ldotv) > 100
    assert set(r) == {0.0, 0.25, 0.5, 0.75, 1.0} and len(set(rho)) == 2


def _hits(origin, d, quads):
    """Whether the ray origin + t d (t > 0) crosses each quad (two triangles, Moller-Trumbore)."""
    hit = np.zeros(len(quads), bool)
    for a, b, c in ((0, 1, 2), (0, 2, 3)):
        v0 = quads[:, a]
        e1, e2 = quads[:, b] - v0, quads[:, c] - v0
        p = np.cross(d, e2)
        det = np.einsum("ij,ij->i", e1, p)
        ok = np.abs(det) > 1e-15
        det = np.where(ok, det, 1.0)
        s = origin - v0
        u = np.einsum("ij,ij->i", s, p) / det
        q = np.cross(s, e1)
        v = (q @ d) / det
        t = np.einsum("ij,ij->i", e2, q) / det
        hit |= ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 1e-9)
    return hit


@pytest.mark.parametrize("k", [1, 2, 3, 4])
def test_no_tile_shadows_another(scenes, k):
    s = scenes[k]
    l = np.array(s["light"]["direction"])
    quads = np.array([t["corners"] for t in s["tiles"]])
    for i, q in enumerate(quads):
        others = np.delete(quads, i, axis=0)
        for p in (*(0.98 * q + 0.02 * q.mean(axis=0)), q.mean(axis=0)):  # corners (just inside), centre
            assert not _hits(p, l, others).any(), (i, s["id"])
    # a check of the check: the ray from below a tile towards it does hit it
    q = quads[50]
    assert _hits(q.mean(axis=0) - 5 * l, l, quads[50:51]).all()


def test_tiles_stay_far_apart_interreflection_bounded(scenes):
    for s in scenes:
        assert s["interreflection_bound"] <= INTERREFLECTION_MAX
        c = np.array([t["centre"] for t in s["tiles"]])
        d = np.linalg.norm(c[:, None] - c[None], axis=2) + np.eye(len(c)) * 1e9
        assert d.min() > 20 * 0.01 * s["width"] / 16  # centres > 20 grid pitches apart


def test_calibration_tiles_are_lambert_at_known_values():
    s = build_scene(35.0, "distant", RES)
    white = [t for t in s["tiles"] if t["role"] == "white"]
    ramp = [t for t in s["tiles"] if t["role"] == "ramp"]
    assert len(white) == 1 and white[0]["wi"][2] == pytest.approx(1.0) and white[0]["roughness"] == 0
    assert len(ramp) == 8 and [t["rho"][0] for t in ramp] == pytest.approx(np.linspace(0.05, 1, 8), abs=1e-6)


def test_point_light_tiles_state_their_variation():
    s = build_scene(70.0, "point", RES)
    assert s["light"]["kind"] == "point" and len(s["light"]["position"]) == 3
    assert max(t["variation"] for t in s["tiles"]) < 1e-4


def test_bad_arguments_raise():
    with pytest.raises(ValueError, match="resolution"):
        build_scene(35.0, resolution=100)
    with pytest.raises(ValueError, match="light"):
        build_scene(35.0, light="spot")


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    d = tmp_path_factory.mktemp("w") / "chart"
    assert main(["chart", "--format", "all", "--out", str(d), "--resolution", str(RES)]) == 0
    return d


def test_usd_reads_back_with_usd_core_and_with_eval(written, capsys):
    from pxr import Usd, UsdGeom, UsdLux, UsdShade

    chart = json.loads((written / "scene_01" / "chart.json").read_text())
    stage = Usd.Stage.Open(str(written / "scene_01" / "chart.usda"))
    cam = UsdGeom.Camera(stage.GetPrimAtPath("/Chart/Camera"))
    assert cam.GetProjectionAttr().Get() == "orthographic"
    assert cam.GetHorizontalApertureAttr().Get() == pytest.approx(10 * chart["camera"]["extent"][0])
    light = UsdLux.DistantLight(stage.GetPrimAtPath("/Chart/Light"))
    assert light.GetIntensityAttr().Get() == pytest.approx(chart["light"]["irradiance"])
    # the light shines along -l: its -z axis rotated into the world
    m = UsdGeom.Xformable(light.GetPrim()).ComputeLocalToWorldTransform(Usd.TimeCode.Default())
    z = m.TransformDir((0, 0, 1))
    np.testing.assert_allclose(list(z), chart["light"]["direction"], atol=1e-6)
    for t in chart["tiles"][::40]:
        mesh = stage.GetPrimAtPath(f"/Chart/Tiles/{t['id']}")
        mat, _ = UsdShade.MaterialBindingAPI(mesh).ComputeBoundMaterial()
        assert mat.GetPath() == f"/Chart/Materials/M_{t['id']}"
        np.testing.assert_allclose(np.array(UsdGeom.Mesh(mesh).GetPointsAttr().Get()), t["corners"], atol=1e-5)
        assert main(["eval", str(written / "scene_01" / "chart.usda"), "--material", str(mat.GetPath()), "--json"]) == 0
        m = json.loads(capsys.readouterr().out)["materials"][0]
        assert m["diffuse_model"] == "eon" and m["parameters"]["base_diffuse_roughness"]["value"] == pytest.approx(
            t["roughness"]
        )
        assert m["parameters"]["specular_weight"]["value"] == 0.0


def test_gltf_is_consistent(written):
    doc = json.loads((written / "scene_01" / "chart.gltf").read_text())
    blob = (written / "scene_01" / "chart.bin").read_bytes()
    chart = json.loads((written / "scene_01" / "chart.json").read_text())
    assert doc["buffers"][0]["byteLength"] == len(blob)
    assert len(doc["meshes"]) == len(chart["tiles"])
    assert doc["cameras"][0]["type"] == "orthographic"
    for k in (0, 100):
        prim = doc["meshes"][k]["primitives"][0]
        acc = doc["accessors"][prim["attributes"]["POSITION"]]
        view = doc["bufferViews"][acc["bufferView"]]
        pts = np.frombuffer(blob, "<f4", 12, view["byteOffset"]).reshape(4, 3)
        np.testing.assert_allclose(pts, chart["tiles"][k]["corners"], rtol=1e-6, atol=1e-4)
        mat = doc["materials"][prim["material"]]
        ext = mat["extensions"]
        assert ext["KHR_materials_diffuse_roughness"]["diffuseRoughnessFactor"] == chart["tiles"][k]["roughness"]
        assert ext["KHR_materials_specular"]["specularFactor"] == 0.0
        assert mat["pbrMetallicRoughness"]["metallicFactor"] == 0.0
    # the directional light shines along its node's -z: +z of its rotation is the chart's l
    q = next(n for n in doc["nodes"] if n.get("name") == "Light")["rotation"]
    x, y, z, w = q
    zaxis = [2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)]
    np.testing.assert_allclose(zaxis, chart["light"]["direction"], atol=1e-12)


def test_mtlx_has_one_open_pbr_material_per_tile(written):
    import MaterialX as mx

    chart = json.loads((written / "scene_01" / "chart.json").read_text())
    doc = mx.createDocument()
    mx.readFromXmlFile(doc, str(written / "scene_01" / "chart.mtlx"))
    shaders = doc.getNodes("open_pbr_surface") if hasattr(doc, "getNodes") else []
    assert len(doc.getMaterialNodes()) == len(chart["tiles"])
    t = chart["tiles"][50]
    node = doc.getNode(f"M_{t['id']}_surface")
    assert node.getInputValue("base_diffuse_roughness") == pytest.approx(t["roughness"])
    assert node.getInputValue("specular_weight") == 0.0
    assert shaders is not None


def test_blender_script_compiles_and_readme_names_the_settings(written):
    src = (written / "scene_01" / "render_blender.py").read_text()
    compile(src, "render_blender.py", "exec")
    for word in ('"Standard"', "Diffuse Roughness", "Specular IOR Level", "use_denoising = False", '"SUN"'):
        assert word in src
    readme = (written / "README.md").read_text()
    assert "No tone mapping" in readme and "denoiser" in readme and "geometry separately" in readme


def test_chart_refuses_a_folder_that_is_not_empty(written, tmp_path, capsys):
    before = sorted(p.name for p in written.iterdir())
    assert main(["chart", "--out", str(written), "--resolution", str(RES)]) == 2
    assert sorted(p.name for p in written.iterdir()) == before
    assert main(["chart", "--out", str(tmp_path / "x"), "--resolution", "100"]) == 2
    assert not (tmp_path / "x").exists()
    assert main(["chart", "--out", str(tmp_path / "no" / "x")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 3 and all(e.startswith("openpbr-diffuse chart: error: ") for e in err)
