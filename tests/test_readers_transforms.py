"""UsdTransform2d texture transforms and primvar readers other than the uv one.

Expected values are computed here: the transformed uv by hand from the attributes read with
pxr, as the UsdPreviewSurface specification defines it (st' = R(rotation, counter-clockwise,
degrees) . (scale * st) + translation), and the texel sampled with OpenImageIO's
TextureSystem directly at that uv (bilinear, t = 1 - v)."""

import os
import textwrap
from pathlib import Path

import numpy as np
import pytest

from openpbr_diffuse.readers import load_materials

SHARED = Path(os.environ.get("OPENPBR_DIFFUSE_SHARED") or Path(__file__).resolve().parents[1].parent / "shared")
TRANSFORM_TEST = SHARED / "corpus/realworld/usd-wg-assets/test_assets/TextureTransformTest/TextureTransformTest.usd"

LAYER = """
#usda 1.0
def Material "M"
{
    token outputs:surface.connect = </M/S.outputs:surface>
    def Shader "S"
    {
        uniform token info:id = "UsdPreviewSurface"
        float inputs:roughness.connect = </M/T.outputs:r>
        float inputs:metallic.connect = </M/P.outputs:result>
        color3f inputs:diffuseColor.connect = </M/P3.outputs:result>
        token outputs:surface
    }
    def Shader "uv"
    {
        uniform token info:id = "UsdPrimvarReader_float2"
        string inputs:varname = "st"
        float2 outputs:result
    }
    def Shader "X"
    {
        uniform token info:id = "UsdTransform2d"
        token inputs:in.connect = </M/uv.outputs:result>
        float inputs:rotation = 30
        float2 inputs:scale = (2, 0.5)
        float2 inputs:translation = (0.1, 0.2)
        float2 outputs:result
    }
    def Shader "T"
    {
        uniform token info:id = "UsdUVTexture"
        asset inputs:file = @ramp.exr@
        float2 inputs:st.connect = </M/X.outputs:result>
        token inputs:wrapS = "repeat"
        token inputs:wrapT = "repeat"
        token inputs:sourceColorSpace = "raw"
        float outputs:r
    }
    def Shader "P"
    {
        uniform token info:id = "UsdPrimvarReader_float"
        string inputs:varname = "metal"
        float inputs:fallback = 0.25
        float outputs:result
    }
    def Shader "P3"
    {
        uniform token info:id = "UsdPrimvarReader_float3"
        string inputs:varname = "displayColor"
        float3 inputs:fallback = (0.2, 0.4, 0.6)
        float3 outputs:result
    }
}
"""


def _write(tmp_path):
    import OpenImageIO as oiio

    rng = np.random.default_rng(7)
    img = rng.uniform(0.05, 0.95, size=(8, 8, 3)).astype(np.float32)
    out = oiio.ImageOutput.create(str(tmp_path / "ramp.exr"))
    assert out.open(str(tmp_path / "ramp.exr"), oiio.ImageSpec(8, 8, 3, "float"))
    assert out.write_image(img)
    out.close()
    p = tmp_path / "scene.usda"
    p.write_text(textwrap.dedent(LAYER).lstrip())
    return p


def _by_hand(stage, path, uv):
    """The spec's transform of ``uv`` with the attributes of the UsdTransform2d at ``path``."""
    prim = stage.GetPrimAtPath(path)
    rot = np.radians(prim.GetAttribute("inputs:rotation").Get() or 0.0)
    scale = np.array(prim.GetAttribute("inputs:scale").Get() or (1.0, 1.0), dtype=np.float64)
    trans = np.array(prim.GetAttribute("inputs:translation").Get() or (0.0, 0.0), dtype=np.float64)
    c, s = np.cos(rot), np.sin(rot)
    return np.array([[c, -s], [s, c]]) @ (scale * np.asarray(uv, dtype=np.float64)) + trans


def _oiio_sample(path, st, wrap):
    import OpenImageIO as oiio

    ts = oiio.TextureSystem(shared=False)
    opt = oiio.TextureOpt()
    opt.swrap = opt.twrap = wrap
    opt.interpmode = oiio.InterpMode.Bilinear
    return np.asarray(ts.texture(str(path), opt, float(st[0]), 1.0 - float(st[1]), 0, 0, 0, 0, 3))


@pytest.mark.parametrize("uv", [(0.3, 0.6), (0.85, 0.1)])
def test_usd_transform2d_is_applied(tmp_path, uv):
    import OpenImageIO as oiio
    from pxr import Usd

    p = _write(tmp_path)
    st = _by_hand(Usd.Stage.Open(str(p)), "/M/X", uv)
    want = _oiio_sample(tmp_path / "ramp.exr", st, oiio.Wrap.Periodic)[0]
    (m,) = load_materials(p, uv=uv)
    assert m.error == "", m.error
    assert not [u for u in m.unsupported if "UsdTransform2d" in u], m.unsupported
    assert m.parameters["roughness"].value == pytest.approx(float(want), abs=1e-6)
    # without the transform the texel differs: the test can tell
    assert abs(_oiio_sample(tmp_path / "ramp.exr", uv, oiio.Wrap.Periodic)[0] - want) > 1e-3


def test_primvar_readers_use_their_fallback_with_a_warning(tmp_path):
    (m,) = load_materials(_write(tmp_path))
    assert m.parameters["metallic"].value == pytest.approx(0.25)
    np.testing.assert_allclose(m.parameters["diffuseColor"].value, (0.2, 0.4, 0.6), rtol=1e-6)
    for name in ("metal", "displayColor"):
        assert any(f"primvar '{name}'" in w and "fallback" in w for w in m.warnings), m.warnings
    assert not [u for u in m.unsupported if "PrimvarReader" in u], m.unsupported


def test_materialx_place2d_is_evaluated(tmp_path):
    """place2d (MaterialX's library nodegraph: subtract pivot, divide by scale, rotate2d,
    subtract offset, add pivot) -- by hand with rotate2d's own formula (c x + s y, -s x + c y)."""
    _write(tmp_path)
    doc = tmp_path / "place.mtlx"
    doc.write_text(
        textwrap.dedent("""
        <?xml version="1.0"?>
        <materialx version="1.39">
          <texcoord name="tc" type="vector2" />
          <place2d name="pl" type="vector2">
            <input name="texcoord" type="vector2" nodename="tc" />
            <input name="pivot" type="vector2" value="0.5, 0.5" />
            <input name="scale" type="vector2" value="2, 0.5" />
            <input name="rotate" type="float" value="30" />
            <input name="offset" type="vector2" value="0.1, 0.2" />
          </place2d>
          <image name="im" type="float">
            <input name="file" type="filename" value="ramp.exr" />
            <input name="texcoord" type="vector2" nodename="pl" />
          </image>
          <open_pbr_surface name="S" type="surfaceshader">
            <input name="specular_roughness" type="float" nodename="im" />
          </open_pbr_surface>
          <surfacematerial name="M" type="material">
            <input name="surfaceshader" type="surfaceshader" nodename="S" />
          </surfacematerial>
        </materialx>
        """).lstrip()
    )
    import OpenImageIO as oiio

    uv = np.array([0.3, 0.6])
    a = np.radians(30.0)
    q = (uv - 0.5) / np.array([2.0, 0.5])
    q = np.array([np.cos(a) * q[0] + np.sin(a) * q[1], -np.sin(a) * q[0] + np.cos(a) * q[1]])
    st = q - np.array([0.1, 0.2]) + 0.5
    want = _oiio_sample(tmp_path / "ramp.exr", st, oiio.Wrap.Periodic)[0]
    (m,) = load_materials(doc, uv=tuple(uv))
    assert m.error == "" and not m.unsupported, (m.error, m.unsupported)
    assert m.parameters["specular_roughness"].value == pytest.approx(float(want), abs=1e-6)


@pytest.mark.corpus
@pytest.mark.skipif(not TRANSFORM_TEST.is_file(), reason="../shared/corpus is absent")
@pytest.mark.parametrize("uv", [(0.5, 0.5), (0.3, 0.6)])
def test_texture_transform_test_asset(uv):
    import OpenImageIO as oiio
    from pxr import Gf, Usd, UsdShade

    stage = Usd.Stage.Open(str(TRANSFORM_TEST))
    mats = {m.path: m for m in load_materials(TRANSFORM_TEST, uv=uv)}
    src, dst = Gf.ColorSpace(Gf.ColorSpaceNames.LinearRec709), Gf.ColorSpace(Gf.ColorSpaceNames.LinearAP1)
    checked = 0
    for prim in stage.Traverse():
        if not (prim.IsA(UsdShade.Shader) and UsdShade.Shader(prim).GetShaderId() == "UsdTransform2d"):
            continue
        mat = str(prim.GetPath().GetParentPath())
        tex = stage.GetPrimAtPath(mat + "/_BaseColorTexture")
        file = tex.GetAttribute("inputs:file").Get().resolvedPath
        wrap = {"clamp": oiio.Wrap.Clamp, "repeat": oiio.Wrap.Periodic}[tex.GetAttribute("inputs:wrapS").Get()]
        texel = _oiio_sample(file, _by_hand(stage, prim.GetPath(), uv), wrap)
        lin = np.where(texel <= 0.04045, texel / 12.92, ((texel + 0.055) / 1.055) ** 2.4)  # 8-bit RGB: sRGB
        want = np.array(dst.Convert(src, Gf.Vec3f(*map(float, lin))).GetRGB())
        m = mats[mat]
        assert m.error == "", m.error
        np.testing.assert_allclose(m.parameters["diffuseColor"].value, want, atol=5e-6)
        assert not [w for w in m.warnings if "outside" in w], m.warnings
        checked += 1
    assert checked == 6


def test_white_srgb_texel_is_not_out_of_range(tmp_path):
    """An 8-bit white texel decodes to exactly 1 (IEC 61966-2-1), so white in ACEScg is white
    within round-off: no clamp warning."""
    import OpenImageIO as oiio

    png = tmp_path / "white.png"
    out = oiio.ImageOutput.create(str(png))
    assert out.open(str(png), oiio.ImageSpec(2, 2, 3, "uint8"))
    assert out.write_image(np.full((2, 2, 3), 255, dtype=np.uint8))
    out.close()
    p = tmp_path / "white.usda"
    p.write_text(
        textwrap.dedent(LAYER)
        .lstrip()
        .replace("ramp.exr", "white.png")
        .replace('"raw"', '"auto"')
        .replace(
            "float inputs:roughness.connect = </M/T.outputs:r>",
            "color3f inputs:diffuseColor.connect = </M/T.outputs:rgb>",
        )
        .replace("color3f inputs:diffuseColor.connect = </M/P3.outputs:result>", "")
        .replace("float outputs:r", "float3 outputs:rgb")
    )
    (m,) = load_materials(p)
    np.testing.assert_allclose(m.parameters["diffuseColor"].value, (1.0, 1.0, 1.0), atol=1e-7)
    assert not [w for w in m.warnings if "outside" in w], m.warnings
