"""Textures inside a .usdz package are read through usd-core's asset resolver: the material
gets the texel, no "does not exist" warning, and nothing is written next to the package.
Expected values: the texel written into the package, decoded from sRGB by the closed form of
IEC 61966-2-1 and converted to ACEScg by USD's own Gf.ColorSpace."""

import os
import textwrap
import zipfile
from pathlib import Path

import numpy as np
import pytest

from openpbr_diffuse.readers import load_materials

SHARED = Path(os.environ.get("OPENPBR_DIFFUSE_SHARED") or Path(__file__).resolve().parents[1].parent / "shared")
ANIMATED_CUBE = (
    SHARED / "corpus" / "realworld" / "usd-wg-assets" / "test_assets" / "USDZ" / "AnimatedCube" / "AnimatedCube.usdz"
)

LAYER = """
#usda 1.0
(
    defaultPrim = "World"
)
def Xform "World"
{
    def Material "M"
    {
        token outputs:surface.connect = </World/M/S.outputs:surface>
        def Shader "S"
        {
            uniform token info:id = "UsdPreviewSurface"
            color3f inputs:diffuseColor.connect = </World/M/T.outputs:rgb>
            token outputs:surface
        }
        def Shader "T"
        {
            uniform token info:id = "UsdUVTexture"
            asset inputs:file = @textures/a.png@
            float2 inputs:st = (0.25, 0.75)
            float3 outputs:rgb
        }
    }
}
"""

#: 2 x 2 sRGB texels, row 0 on top (v = 1): the uv (0.25, 0.75) is the centre of the top-left one.
TEXELS = np.array([[[200, 100, 50], [10, 20, 30]], [[0, 0, 0], [255, 255, 255]]], dtype=np.uint8)


def _srgb_decode(c):
    c = np.asarray(c, dtype=np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def _rec709_to_acescg(rgb):
    from pxr import Gf

    src, dst = Gf.ColorSpace(Gf.ColorSpaceNames.LinearRec709), Gf.ColorSpace(Gf.ColorSpaceNames.LinearAP1)
    return np.array(dst.Convert(src, Gf.Vec3f(*map(float, rgb))).GetRGB())


def _package(tmp_path):
    """pkg/scene.usdz holding scene.usda and textures/a.png; the loose files removed."""
    import OpenImageIO as oiio
    from pxr import Sdf

    src = tmp_path / "src"
    (src / "textures").mkdir(parents=True)
    (src / "scene.usda").write_text(textwrap.dedent(LAYER).lstrip())
    out = oiio.ImageOutput.create(str(src / "textures" / "a.png"))
    assert out.open(str(src / "textures" / "a.png"), oiio.ImageSpec(2, 2, 3, "uint8"))
    assert out.write_image(TEXELS)
    out.close()
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    usdz = pkg / "scene.usdz"
    writer = Sdf.ZipFileWriter.CreateNew(str(usdz))  # the layer first, members 64-byte aligned
    writer.AddFile(str(src / "scene.usda"), "scene.usda")
    writer.AddFile(str(src / "textures" / "a.png"), "textures/a.png")
    writer.Save()
    assert "textures/a.png" in zipfile.ZipFile(usdz).namelist()
    for f in (src / "textures" / "a.png", src / "scene.usda"):
        f.unlink()
    return usdz


def test_usdz_texture_is_read_from_the_package(tmp_path, monkeypatch):
    usdz = _package(tmp_path)
    before = sorted(os.listdir(usdz.parent))
    data = usdz.read_bytes()
    monkeypatch.chdir(tmp_path)
    (m,) = load_materials(usdz)
    assert m.error == "" and m.supported
    assert not [w for w in m.warnings if "does not exist" in w or "fallback" in w], m.warnings
    want = _rec709_to_acescg(_srgb_decode(TEXELS[0, 0] / 255.0))
    # Gf (float32, matrices from the primaries) and the OpenColorIO config agree to ~2e-6
    np.testing.assert_allclose(m.parameters["diffuseColor"].value, want, atol=5e-6)
    assert "a.png at uv (0.25, 0.75)" in m.parameters["diffuseColor"].provenance
    assert sorted(os.listdir(usdz.parent)) == before and usdz.read_bytes() == data


def test_missing_package_member_warns_and_falls_back(tmp_path):
    usdz = _package(tmp_path)
    bad = tmp_path / "bad.usdz"
    with zipfile.ZipFile(usdz) as zin, zipfile.ZipFile(bad, "w", zipfile.ZIP_STORED) as zout:
        for item in zin.infolist():
            if item.filename != "textures/a.png":
                zout.writestr(item, zin.read(item.filename))
    (m,) = load_materials(bad)
    assert m.parameters["diffuseColor"].value == (0.0, 0.0, 0.0)
    assert any("not in its package" in w for w in m.warnings), m.warnings


@pytest.mark.corpus
@pytest.mark.skipif(not ANIMATED_CUBE.is_file(), reason="../shared/corpus is absent")
def test_animated_cube_base_colour(tmp_path):
    import OpenImageIO as oiio

    (m,) = load_materials(ANIMATED_CUBE)
    assert not [w for w in m.warnings if "does not exist" in w], m.warnings
    # independent reading: the member extracted with zipfile, its texel read with OpenImageIO
    with zipfile.ZipFile(ANIMATED_CUBE) as z:
        member = next(n for n in z.namelist() if n.endswith("AnimatedCube_BaseColor.png"))
        png = tmp_path / "base.png"
        png.write_bytes(z.read(member))
    buf = oiio.ImageBuf(str(png))
    texel = np.array(buf.interppixel_NDC(0.5, 0.5))[:3]  # uv (0.5, 0.5): s = 0.5, t = 1 - 0.5
    want = _rec709_to_acescg(_srgb_decode(texel))
    got = np.asarray(m.parameters["diffuseColor"].value)
    np.testing.assert_allclose(got, want, rtol=1e-4)
    np.testing.assert_allclose(got, (0.660, 0.609, 0.501), atol=1e-3)
