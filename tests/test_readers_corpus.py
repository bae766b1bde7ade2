"""Real material files written elsewhere (../shared/corpus): every OpenPBR example loads with
the values the document holds (read here with MaterialX directly, not through the reader), and
the USD working group's shader-ball layer gives its seven materials in three variant settings."""

import functools
import os
from pathlib import Path

import numpy as np
import pytest

from openpbr_diffuse.readers import load_materials

SHARED = Path(os.environ.get("OPENPBR_DIFFUSE_SHARED") or Path(__file__).resolve().parents[1].parent / "shared")
EXAMPLES = SHARED / "corpus" / "openpbr" / "examples"
SHADERBALL = SHARED / "corpus" / "usd-wg-shaderball" / "layers" / "example_materials.usda"

pytestmark = [
    pytest.mark.corpus,
    pytest.mark.skipif(not (SHARED / "corpus").is_dir(), reason="../shared/corpus is absent"),
]

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


@functools.cache
def _nodedef_default(name):
    import MaterialX as mx

    lib = mx.createDocument()
    mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), lib)
    return lib.getNodeDef("ND_open_pbr_surface_surfaceshader").getActiveInput(name).getValueString()


def _same_number(a, b):
    try:
        return _floats(a) == _floats(b)
    except ValueError:
        return False


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
    """Every authored, non-default input that the node does not model is listed (unless its
    lobe's weight is 0); modelled inputs never are."""
    from openpbr_diffuse.nodes.openpbr_surface import MODELLED

    gates = {
        "coat_": "coat_weight",
        "fuzz_": "fuzz_weight",
        "subsurface_": "subsurface_weight",
        "transmission_": "transmission_weight",
        "thin_film_": "thin_film_weight",
        "emission_": "emission_luminance",
    }
    listed_somewhere = 0
    for path in sorted(EXAMPLES.glob("*.mtlx")):
        values, _ = _mx_values(path)
        for m in load_materials(path):
            authored = values[m.name]
            listed = {u.split(" = ")[0] for u in m.unsupported}
            assert not (listed & set(MODELLED)), (m.name, listed)
            for name, text in authored.items():
                default = _nodedef_default(name)
                if name in MODELLED or text == default or _same_number(text, default):
                    continue
                gate = next((w for p, w in gates.items() if name.startswith(p) and name != w), None)
                weight = authored.get(gate, _nodedef_default(gate)) if gate else "1"
                if gate and float(weight) == 0.0:
                    continue
                assert name in listed, (m.name, name)
            listed_somewhere += bool(m.unsupported)
    assert listed_somewhere >= 5


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
    assert sorted(by) == sorted(
        [
            "mtlx/plastic",
            "mtlx/gold",
            "mtlx/glass",
            "mtlx/bubblegum",
            "usdpreview/plastic",
            "usdpreview/copper",
            "usdpreview/glass",
        ]
    )
    preview = [m for m in mats if m.shader_id == "UsdPreviewSurface"]
    assert len(preview) == 3 and all(m.diffuse_model == "lambert" for m in preview)
    assert all(m.supported and m.node() is not None for m in mats)
    mtlx_id = (
        "ND_standard_surface_surfaceshader"
        if variant == "material_model=standard_surface"
        else "ND_open_pbr_surface_surfaceshader"
    )
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
    mats = load_materials(
        SHADERBALL, variants=["example_material=mtlx_gold"], material="/standard_shader_ball_scene/shader_ball"
    )
    assert [m.name for m in mats] == ["gold"]
