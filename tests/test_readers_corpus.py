"""Real material files written elsewhere (../shared/corpus): every OpenPBR example loads with
the values the document holds (read here with MaterialX directly, not through the reader), and
the USD working group's shader-ball layer gives its seven materials in three variant settings."""
import functools
from pathlib import Path

import numpy as np
import pytest

from openpbr_diffuse.readers import load_materials

SHARED = Path(__file__).resolve().parents[1].parent / "shared"
EXAMPLES = SHARED / "corpus" / "openpbr" / "examples"
SHADERBALL = SHARED / "corpus" / "usd-wg-shaderball" / "layers" / "example_materials.usda"

pytestmark = [pytest.mark.corpus,
              pytest.mark.skipif(not (SHARED / "corpus").is_dir(), reason="../shared/corpus is absent")]

MODELLED_BASE = ("base_color", "base_diffuse_roughness", "base_weight")


def _mx_values(path):
    """{material name: {input: value string}} and the document colour space, via MaterialX."""
    import MaterialX as mx

    doc = mx.createDocument()
    mx.readFromXmlFile(doc, str(path))
    out = {}
    for m in doc.getMaterialNodes():
        shader = m.getInput("surfaceshader").getConnectedNode()
        out[m.getName()] = {i.getName(): i.getValueString() for i in shader.getInputs()}
    return out, doc.getColorSpace()


@functools.lru_cache(maxsize=None)
def _nodedef_default(name):
    import MaterialX as mx

    lib = mx.createDocument()
    mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), lib)
    return lib.getNodeDef("ND_open_pbr_surface_surfaceshader").getActiveInput(name).getValueString()


def _floats(text):
    return [float(x) for x in text.split(",")]


@pytest.mark.parametrize("path", sorted(EXAMPLES.glob("*.mtlx")) if EXAMPLES.is_dir() else [], ids=lambda p: p.stem)
def test_openpbr_example_base_values_match_document(path):
    values, space = _mx_values(path)
    assert space == "acescg"  # the working space: no conversion expected
    mats = load_materials(path)
    assert {m.name for m in mats} == set(values)
    for m in mats:
        assert m.supported and m.shader_id == "ND_open_pbr_surface_surfaceshader"
        for name in MODELLED_BASE:
            text = values[m.name].get(name) or _nodedef_default(name)
            want = _floats(text)
            got = np.atleast_1d(m.parameters[name].value)
            assert np.allclose(got, want, rtol=0, atol=1e-12), (name, got, want)
            assert ("authored" in m.parameters[name].provenance) == (name in values[m.name])


def test_openpbr_examples_list_unsupported_features_per_material():
    by_name = {m.name: m for p in sorted(EXAMPLES.glob("*.mtlx")) for m in load_materials(p)}
    assert len(by_name) == 83
    assert any("coat_weight" in u for u in by_name["Car_Paint"].unsupported)
    assert any("transmission_weight" in u for u in by_name["Glass"].unsupported)
    assert any("subsurface_weight" in u for u in by_name["Skin_I"].unsupported)
    assert any("fuzz_weight" in u for u in by_name["Velvet"].unsupported)
    assert by_name["Brick"].unsupported == [] and by_name["Default"].unsupported == []


def _by_path(mats):
    return {m.path.rsplit("/", 2)[-2] + "/" + m.name: m for m in mats}


def _lin709_to_acescg(rgb):
    from pxr import Gf

    src, dst = Gf.ColorSpace(Gf.ColorSpaceNames.LinearRec709), Gf.ColorSpace(Gf.ColorSpaceNames.LinearAP1)
    v = dst.Convert(src, Gf.Vec3f(*rgb)).GetRGB()
    return np.array([v[0], v[1], v[2]], dtype=np.float64)


@pytest.mark.skipif(not SHADERBALL.is_file(), reason="usd-wg shader ball layer absent")
@pytest.mark.parametrize("variant", [None, "example_material=usdpreview_plastic", "material_model=standard_surface"])
def test_shaderball_gives_seven_materials(variant):
    before = SHADERBALL.read_bytes()
    mats = load_materials(SHADERBALL, variants=[variant] if variant else None)
    assert SHADERBALL.read_bytes() == before
    by = _by_path(mats)
    assert sorted(by) == sorted(["mtlx/plastic", "mtlx/gold", "mtlx/glass", "mtlx/bubblegum",
                                 "usdpreview/plastic", "usdpreview/copper", "usdpreview/glass"])
    preview = [m for m in mats if m.shader_id == "UsdPreviewSurface"]
    assert len(preview) == 3 and all(m.diffuse_model == "lambert" for m in preview)
    assert all(m.supported and m.node() is not None for m in mats)
    mtlx_id = "ND_standard_surface_surfaceshader" if variant == "material_model=standard_surface" \
        else "ND_open_pbr_surface_surfaceshader"
    assert [m.shader_id for m in mats if m.path.split("/")[-2] == "mtlx"] == [mtlx_id] * 4
    # plastic: base_color authored in lin_rec709 in both .mtlx files (Gf.ColorSpace: an independent conversion)
    plastic = by["mtlx/plastic"].parameters["base_color"].value
    assert np.allclose(plastic, _lin709_to_acescg((0.209884, 0.562091, 0.766)), atol=2e-6)
    assert by["mtlx/plastic"].parameters["specular_roughness"].value == 0.15
    gold = by["mtlx/gold"]
    metal = "metalness" if variant == "material_model=standard_surface" else "base_metalness"
    assert gold.parameters[metal].value == 1.0
    assert gold.node_inputs["base_metalness"].value == 1.0
    # the preview plastic: defaults unless the variant authors its inputs
    pp = by["usdpreview/plastic"].parameters
    if variant == "example_material=usdpreview_plastic":
        assert np.allclose(pp["diffuseColor"].value, _lin709_to_acescg((0.825, 0.713625, 0.08250002)), atol=2e-6)
        assert pp["roughness"].value == 0.132
        assert "authored" in pp["roughness"].provenance
    else:
        assert pp["diffuseColor"].value == (0.18, 0.18, 0.18) and pp["diffuseColor"].kind == "default"
        assert pp["roughness"].value == 0.5
    assert by["usdpreview/plastic"].node_inputs["specular_roughness"].value == pp["roughness"].value


@pytest.mark.skipif(not SHADERBALL.is_file(), reason="usd-wg shader ball layer absent")
def test_shaderball_binding_to_mtlx_material_resolves():
    mats = load_materials(SHADERBALL, variants=["example_material=mtlx_gold"],
                          material="/standard_shader_ball_scene/shader_ball")
    assert [m.name for m in mats] == ["gold"]
