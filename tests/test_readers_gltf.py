"""glTF PBR (``ND_gltf_pbr_surfaceshader``) maps onto OpenPBRSurface with a Lambertian diffuse.
Expected values: the glTF 2.0 closed form of the diffuse, f = (1 - metallic) base_color / pi
when the specular layer is off (KHR_materials_specular ``specular`` = 0), the inputs renamed as
MaterialX's gltf_pbr graph uses them, and the colour converted by USD's Gf.ColorSpace."""

import math
import os
import textwrap
from pathlib import Path

import numpy as np
import pytest

from openpbr_diffuse.readers import load_materials

SHARED = Path(os.environ.get("OPENPBR_DIFFUSE_SHARED") or Path(__file__).resolve().parents[1].parent / "shared")
GLTF_EXAMPLES = SHARED / "corpus/realworld/MaterialX/resources/Materials/Examples/GltfPbr"

DOC = """
<?xml version="1.0"?>
<materialx version="1.39" colorspace="lin_rec709">
  <gltf_pbr name="G" type="surfaceshader">
    <input name="base_color" type="color3" value="0.8, 0.4, 0.2" />
    <input name="metallic" type="float" value="{metallic}" />
    <input name="roughness" type="float" value="0.6" />
    <input name="specular" type="float" value="{specular}" />
    <input name="ior" type="float" value="1.45" />
    <input name="alpha" type="float" value="0.7" />
    <input name="alpha_mode" type="integer" value="{alpha_mode}" />
    {extra}
  </gltf_pbr>
  <surfacematerial name="M" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="G" />
  </surfacematerial>
</materialx>
"""


def _load(tmp_path, metallic=0.0, specular=1.0, alpha_mode=0, extra=""):
    p = tmp_path / "g.mtlx"
    p.write_text(
        textwrap.dedent(DOC).lstrip().format(metallic=metallic, specular=specular, alpha_mode=alpha_mode, extra=extra)
    )
    (m,) = load_materials(p)
    return m


def _acescg(rgb):
    from pxr import Gf

    src, dst = Gf.ColorSpace(Gf.ColorSpaceNames.LinearRec709), Gf.ColorSpace(Gf.ColorSpaceNames.LinearAP1)
    return np.array(dst.Convert(src, Gf.Vec3f(*rgb)).GetRGB())


def _dirs(n=5):
    th_i = np.radians(np.linspace(5, 80, n))
    th_o = np.radians(np.linspace(70, 10, n))
    phi = np.radians(np.linspace(0, 300, n))
    wi = np.stack([np.sin(th_i) * np.cos(phi), np.sin(th_i) * np.sin(phi), np.cos(th_i)], axis=1)
    wo = np.stack([np.sin(th_o), np.zeros(n), np.cos(th_o)], axis=1)
    return wi, wo


@pytest.mark.parametrize("metallic", [0.0, 0.4])
def test_gltf_diffuse_is_lambertian(tmp_path, metallic):
    m = _load(tmp_path, metallic=metallic, specular=0.0)
    assert m.supported and m.error == "" and m.diffuse_model == "lambert", (m.error, m.unsupported)
    wi, wo = _dirs()
    f = m.node().eval(wi, wo)
    want = (1.0 - metallic) * _acescg((0.8, 0.4, 0.2)) / math.pi
    np.testing.assert_allclose(f, np.broadcast_to(want, f.shape), rtol=1e-5)


def test_gltf_inputs_are_renamed(tmp_path):
    m = _load(
        tmp_path,
        metallic=0.3,
        alpha_mode=2,
        extra='<input name="clearcoat" type="float" value="0.5" />'
        '<input name="emissive" type="color3" value="1, 0, 0" />',
    )
    ni = m.node_inputs
    np.testing.assert_allclose(ni["base_color"].value, _acescg((0.8, 0.4, 0.2)), atol=3e-6)
    assert ni["base_metalness"].value == pytest.approx(0.3)
    assert ni["specular_roughness"].value == pytest.approx(0.6)
    assert ni["specular_ior"].value == pytest.approx(1.45)
    assert ni["coat_weight"].value == pytest.approx(0.5) and ni["coat_ior"].value == 1.5
    assert ni["geometry_opacity"].value == pytest.approx(0.7)  # BLEND: alpha
    assert any(u.startswith("emissive") for u in m.unsupported), m.unsupported


@pytest.mark.parametrize("mode, want", [(0, 1.0), (1, 1.0), (2, 0.7)])
def test_gltf_alpha_modes(tmp_path, mode, want):
    assert _load(tmp_path, alpha_mode=mode).node_inputs["geometry_opacity"].value == pytest.approx(want)


@pytest.mark.corpus
@pytest.mark.skipif(not GLTF_EXAMPLES.is_dir(), reason="../shared/corpus is absent")
def test_gltf_examples_are_evaluated():
    import MaterialX as mx

    checked = 0
    for f in sorted(GLTF_EXAMPLES.glob("*.mtlx")):
        doc = mx.createDocument()
        mx.readFromXmlFile(doc, str(f))
        want = {n.getName() for n in doc.getMaterialNodes()}
        mats = {m.name: m for m in load_materials(f)}
        assert set(mats) == want
        for m in mats.values():
            assert m.shader_id == "ND_gltf_pbr_surfaceshader" and m.supported and m.error == "", (f, m.unsupported)
            shader = doc.getChild(m.shader_path)
            bc = shader.getInput("base_color")
            if bc is not None and bc.hasValueString() and not bc.getConnectedNode():
                rgb = tuple(float(x) for x in bc.getValue())
                np.testing.assert_allclose(m.node_inputs["base_color"].value, _acescg(rgb), atol=3e-6)
                checked += 1
    assert checked >= 3


def test_surface_over_other_bsdf_names_the_bsdf(tmp_path):
    p = tmp_path / "s.mtlx"
    p.write_text(
        textwrap.dedent("""
        <?xml version="1.0"?>
        <materialx version="1.39">
          <dielectric_bsdf name="d" type="BSDF" />
          <surface name="S" type="surfaceshader">
            <input name="bsdf" type="BSDF" nodename="d" />
          </surface>
          <surfacematerial name="M" type="material">
            <input name="surfaceshader" type="surfaceshader" nodename="S" />
          </surfacematerial>
        </materialx>
        """).lstrip()
    )
    (m,) = load_materials(p)
    assert not m.supported and m.error == ""
    assert "d (ND_dielectric_bsdf)" in m.unsupported[0] and "oren_nayar_diffuse_bsdf" in m.unsupported[0]
