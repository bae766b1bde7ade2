"""``openpbr-diffuse eval`` (text and the JSON schema) and ``render`` (EXR linear ACEScg, PNG
sRGB-encoded), checked against the library's node and an independent colour conversion."""

import json
import math

import numpy as np
import pytest

from openpbr_diffuse.cli.main import main
from openpbr_diffuse.readers import BUNDLED_MATERIALS, load_materials

CLAY = str(BUNDLED_MATERIALS / "clay_rough.mtlx")


def _json(capsys, *argv):
    assert main(["eval", *argv, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_eval_json_schema(capsys):
    doc = _json(
        capsys,
        str(BUNDLED_MATERIALS / "terracotta_bound.usda"),
        "--material",
        "/World/Ball",
        "--theta-i",
        "0",
        "45",
        "--theta-o",
        "30",
        "--phi",
        "180",
        "--uv",
        "0.2",
        "0.3",
    )
    assert set(doc) >= {"file", "working_space", "time", "variants", "uv", "directions", "materials"}
    assert doc["working_space"] == "acescg" and doc["uv"] == [0.2, 0.3]
    assert doc["directions"]["theta_i"] == [0.0, 45.0] and doc["directions"]["theta_o"] == [30.0, 30.0]
    (m,) = doc["materials"]
    assert set(m) >= {
        "name",
        "path",
        "file",
        "shader_id",
        "supported",
        "node",
        "diffuse_model",
        "parameters",
        "node_inputs",
        "unsupported",
        "approximations",
        "warnings",
        "evaluation",
    }
    assert m["path"] == "/World/Looks/terracotta" and m["node"] == "OpenPBRSurface" and m["diffuse_model"] == "eon"
    p = m["parameters"]["base_color"]
    assert set(p) >= {"value", "provenance", "kind"} and "terracotta.inputs:colour" in p["provenance"]
    ev = m["evaluation"]
    assert np.shape(ev["brdf"]) == (2, 3) and np.shape(ev["albedo"]) == (2, 3)
    assert set(ev["diffuse"]) == {"weight", "albedo", "probability", "contribution"}
    assert [lb["name"] for lb in ev["lobes"]] == ["diffuse", "specular"]
    assert sum(lb["probability"][0] for lb in ev["lobes"]) == pytest.approx(1.0)


def test_eval_values_are_the_nodes(capsys):
    doc = _json(capsys, CLAY, "--theta-i", "60", "--theta-o", "20", "--phi", "90")
    (m,) = load_materials(CLAY)
    node = m.node()
    ti, to = math.radians(60), math.radians(20)
    wi = np.array([0.0, math.sin(ti), math.cos(ti)])
    wo = np.array([math.sin(to), 0.0, math.cos(to)])
    ev = doc["materials"][0]["evaluation"]
    assert np.allclose(ev["brdf"][0], node.eval(wi, wo), rtol=1e-12)
    assert np.allclose(ev["albedo"][0], node.albedo(wo), rtol=1e-12)
    (d,) = [lb for lb in node.lobes(wo) if lb.name == "diffuse"]
    assert np.allclose(ev["diffuse"]["weight"][0], d.weight) and ev["diffuse"]["probability"][0] == pytest.approx(
        float(d.probability)
    )


def test_eval_time_variant_uv_options(capsys):
    doc = _json(capsys, str(BUNDLED_MATERIALS / "velvet_animated.usda"), "--time", "12.5")
    assert doc["materials"][0]["parameters"]["base_diffuse_roughness"]["value"] == pytest.approx(0.5)
    doc = _json(capsys, str(BUNDLED_MATERIALS / "paint_variants.usda"), "--variant", "finish=gloss")
    assert doc["variants"] == {"finish": "gloss"}
    assert doc["materials"][0]["parameters"]["base_diffuse_roughness"]["value"] == pytest.approx(0.1)
    a = _json(capsys, str(BUNDLED_MATERIALS / "brick_textured.mtlx"), "--uv", "0.1", "0.1")
    b = _json(capsys, str(BUNDLED_MATERIALS / "brick_textured.mtlx"), "--uv", "0.3", "0.4")
    assert (
        a["materials"][0]["parameters"]["base_color"]["value"] != b["materials"][0]["parameters"]["base_color"]["value"]
    )


def test_eval_text_output(capsys):
    assert main(["eval", str(BUNDLED_MATERIALS / "felt_red_standard_surface.mtlx")]) == 0
    out = capsys.readouterr().out
    assert "diffuse qon" in out and "selection probability" in out and "approximation:" in out
    assert "diffuse_roughness = 0.9" in out


def _srgb_encode(x):
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)


def _acescg_to_lin709(rgb):
    from pxr import Gf

    v = Gf.ColorSpace("lin_rec709_scene").Convert(Gf.ColorSpace("lin_ap1_scene"), Gf.Vec3f(*map(float, rgb))).GetRGB()
    return np.array([v[0], v[1], v[2]])


def test_render_exr_and_png(tmp_path, capsys):
    import OpenImageIO as oiio

    size = 64
    exr, png = tmp_path / "c.exr", tmp_path / "c.png"
    assert main(["render", CLAY, "--out", str(exr), "--size", str(size)]) == 0
    assert main(["render", CLAY, "--out", str(png), "--size", str(size)]) == 0
    capsys.readouterr()
    e = oiio.ImageBuf(str(exr))
    p = oiio.ImageBuf(str(png))
    assert (e.spec().width, e.spec().height, e.spec().nchannels) == (2 * size, size, 4)
    assert e.spec().format == oiio.FLOAT and p.spec().format == oiio.UINT8
    E = e.get_pixels(oiio.FLOAT)
    P = p.get_pixels(oiio.UINT8)
    (m,) = load_materials(CLAY)
    node = m.node()
    # furnace half: the pixel at the sphere's centre sees wo = n -> the albedo at mu = 1
    centre = E[size // 2, size + size // 2, :3]
    assert np.allclose(centre, node.albedo(np.array([0.0, 0.0, 1.0])), rtol=2e-3)
    # lit half: where the normal points at the light, wi = n and mu_o = n . view = 1/sqrt(3)
    n = np.array([-1.0, 1.0, 1.0]) / math.sqrt(3)
    col = int(round((n[0] + 1) / 2 * size - 0.5))
    row = int(round((1 - n[1]) / 2 * size - 0.5))
    so = math.sqrt(1 - 1 / 3)
    want = node.eval(np.array([0.0, 0.0, 1.0]), np.array([so, 0.0, 1 / math.sqrt(3)])) * math.pi
    assert np.allclose(E[row, col, :3], want, rtol=0.05)
    # background and coverage
    assert np.all(E[0, 0] == 0.0) and E[size // 2, size // 2, 3] == 1.0
    # PNG = sRGB transfer of the same pixel (converted ACEScg -> lin Rec.709 with Gf.ColorSpace)
    want_png = np.round(_srgb_encode(_acescg_to_lin709(centre)) * 255)
    assert np.all(np.abs(P[size // 2, size + size // 2, :3].astype(float) - want_png) <= 1.0)


MIXED = """<?xml version="1.0"?>
<materialx version="1.39">
  <open_pbr_surface name="Sa" type="surfaceshader">
    <input name="base_color" type="color3" value="0.5, 0.5, 0.5" colorspace="{space}" />
  </open_pbr_surface>
  <surfacematerial name="A" type="material"><input name="surfaceshader" type="surfaceshader" nodename="Sa" /></surfacematerial>
  <disney_principled name="G" type="surfaceshader" />
  <surfacematerial name="Gltf" type="material"><input name="surfaceshader" type="surfaceshader" nodename="G" /></surfacematerial>
</materialx>"""


@pytest.mark.parametrize("space, rc_want", [("lin_rec709", 0), ("gamma99", 1)])
def test_eval_exit_codes_per_material(tmp_path, capfd, space, rc_want):
    """0: every material read (an unsupported shader is listed as unsupported); 1: some
    material could not be evaluated, named with its reason; the others still evaluated."""
    f = tmp_path / "m.mtlx"
    f.write_text(MIXED.format(space=space))
    assert main(["eval", str(f)]) == rc_want
    out, err = capfd.readouterr()
    assert "Traceback" not in err and "# Gltf  [ND_disney_principled]" in out and "not supported" in out
    if rc_want:
        assert "# A  [not evaluated]" in out and "gamma99" in out and "could not be evaluated: A" in err
    else:
        assert "# A  [ND_open_pbr_surface_surfaceshader]" in out and err == ""
    assert main(["eval", str(f), "--json"]) == rc_want
    mats = {m["name"]: m for m in json.loads(capfd.readouterr().out)["materials"]}
    assert mats["Gltf"]["error"] is None and mats["Gltf"]["supported"] is False
    assert (mats["A"]["error"] is not None) == bool(rc_want)
    assert (mats["A"]["evaluation"]["brdf"] is None) == bool(rc_want)


def test_eval_unusable_file_exit_2(tmp_path, capfd):
    f = tmp_path / "m.mtlx"
    f.write_text("<materialx version='1.39'><oops")
    assert main(["eval", str(f)]) == 2
    assert "not a readable MaterialX document" in capfd.readouterr().err


def test_eval_escapes_control_characters_in_names(tmp_path, capfd):
    """A material name holding a terminal escape is printed repr-style, never raw."""
    f = tmp_path / "esc.mtlx"
    f.write_text(MIXED.format(space="lin_rec709").replace('name="A"', 'name="A&#27;[31mred"'))
    import MaterialX as mx

    doc = mx.createDocument()
    mx.readFromXmlFile(doc, str(f))
    assert doc.getMaterialNodes()[0].getName() == "A\x1b[31mred"  # MaterialX itself keeps the byte
    assert main(["eval", str(f)]) == 0
    out = capfd.readouterr().out
    assert "\x1b" not in out and "# A\\x1b[31mred  [" in out
