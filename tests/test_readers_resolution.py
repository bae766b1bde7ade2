"""Value resolution on stages and documents written here (USD API / MaterialX API in a tmp
dir): interface connections, NodeGraphs, constant nodes, time samples, variants, bindings and
purposes, textures (wrap modes, scale/bias, fallback, sRGB), colour spaces.  Expected values
are computed by hand in each test (colour conversions with USD's own Gf.ColorSpace, an
implementation independent of the colour-science path the readers use)."""

import itertools
import re

import numpy as np
import pytest

from openpbr_diffuse.readers import load_materials

OPENPBR = "ND_open_pbr_surface_surfaceshader"
_COUNTER = itertools.count()


# ----------------------------------------------------------------------------- helpers
def _gf_convert(rgb, src, dst="lin_ap1_scene"):
    from pxr import Gf

    v = Gf.ColorSpace(dst).Convert(Gf.ColorSpace(src), Gf.Vec3f(*rgb)).GetRGB()
    return np.array([v[0], v[1], v[2]], dtype=np.float64)


def _srgb_decode(c):
    c = np.asarray(c, dtype=np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def _stage(tmp_path, name="s.usda"):
    from pxr import Usd

    return Usd.Stage.CreateNew(str(tmp_path / name))


def _material(stage, path, shader_id=OPENPBR, output="out", context="mtlx"):
    from pxr import Sdf, UsdShade

    mat = UsdShade.Material.Define(stage, path)
    sh = UsdShade.Shader.Define(stage, f"{path}/Shader")
    sh.CreateIdAttr(shader_id)
    out = sh.CreateOutput(output, Sdf.ValueTypeNames.Token)
    if context:
        mat.CreateSurfaceOutput(context).ConnectToSource(out)
    else:
        mat.CreateSurfaceOutput().ConnectToSource(out)
    return mat, sh


def _write_exr(path, pixels):
    import OpenImageIO as oiio

    buf = oiio.ImageBuf(np.ascontiguousarray(pixels, dtype=np.float32))
    assert buf.write(str(path), "float")


def _texels():
    """A 4x4 RGB image; row 0 is the TOP of the image (v = 1)."""
    a = np.zeros((4, 4, 3))
    for j in range(4):
        for i in range(4):
            a[j, i] = (0.1 + 0.2 * i, 0.05 + 0.2 * j, 0.5)
    return a


# ----------------------------------------------------------------------------- USD
def test_interface_connection_and_nodegraph_output(tmp_path):
    from pxr import Sdf, UsdShade

    st = _stage(tmp_path)
    mat, sh = _material(st, "/M")
    mat.CreateInput("tint", Sdf.ValueTypeNames.Color3f).Set((0.2, 0.4, 0.6))
    sh.CreateInput("base_color", Sdf.ValueTypeNames.Color3f).ConnectToSource(mat.GetInput("tint"))
    ng = UsdShade.NodeGraph.Define(st, "/M/Graph")
    const = UsdShade.Shader.Define(st, "/M/Graph/Rough")
    const.CreateIdAttr("ND_constant_float")
    const.CreateInput("value", Sdf.ValueTypeNames.Float).Set(0.625)
    # a NodeGraph output whose name is not "out": follow the connection, whatever its name
    ng_out = ng.CreateOutput("roughness_result", Sdf.ValueTypeNames.Float)
    ng_out.ConnectToSource(const.CreateOutput("out", Sdf.ValueTypeNames.Float))
    sh.CreateInput("base_diffuse_roughness", Sdf.ValueTypeNames.Float).ConnectToSource(ng_out)
    st.Save()
    colour = "lin_ap1_scene"
    from pxr import Usd

    Usd.ColorSpaceAPI.Apply(st.GetPrimAtPath("/M")).CreateColorSpaceNameAttr(colour)
    st.Save()
    (m,) = load_materials(tmp_path / "s.usda")
    bc = m.parameters["base_color"]
    assert np.allclose(bc.value, (0.2, 0.4, 0.6), atol=1e-7)
    assert "/M.inputs:tint" in bc.provenance and bc.kind == "connection"
    r = m.parameters["base_diffuse_roughness"]
    assert r.value == 0.625 and "/M/Graph/Rough" in r.provenance
    assert m.parameters["base_weight"].kind == "default" and m.parameters["base_weight"].value == 1.0
    assert m.node_inputs["base_diffuse_roughness"].value == 0.625


def test_stdlib_math_nodes_in_usd(tmp_path):
    from pxr import Sdf, UsdShade

    st = _stage(tmp_path)
    mat, sh = _material(st, "/M")
    mul = UsdShade.Shader.Define(st, "/M/Mul")
    mul.CreateIdAttr("ND_multiply_color3FA")
    mul.CreateInput("in1", Sdf.ValueTypeNames.Color3f).Set((0.5, 0.8, 1.0))
    mul.CreateInput("in2", Sdf.ValueTypeNames.Float).Set(0.5)
    sh.CreateInput("base_color", Sdf.ValueTypeNames.Color3f).ConnectToSource(
        mul.CreateOutput("out", Sdf.ValueTypeNames.Color3f)
    )
    Usd = __import__("pxr.Usd", fromlist=["Usd"])
    Usd.ColorSpaceAPI.Apply(st.GetPrimAtPath("/M")).CreateColorSpaceNameAttr("lin_ap1_scene")
    st.Save()
    (m,) = load_materials(tmp_path / "s.usda")
    assert np.allclose(m.parameters["base_color"].value, (0.25, 0.4, 0.5), atol=1e-7)


def test_time_samples(tmp_path):
    from pxr import Sdf

    st = _stage(tmp_path)
    _, sh = _material(st, "/M")
    a = sh.CreateInput("base_diffuse_roughness", Sdf.ValueTypeNames.Float)
    a.Set(0.2, 10.0)
    a.Set(0.6, 20.0)
    st.Save()
    f = tmp_path / "s.usda"
    at = {t: load_materials(f, time=t)[0].parameters["base_diffuse_roughness"] for t in (5.0, 10.0, 15.0, 20.0, 30.0)}
    # USD holds the first/last sample outside the range and interpolates linearly between
    assert at[5.0].value == pytest.approx(0.2) and at[30.0].value == pytest.approx(0.6)
    assert at[15.0].value == pytest.approx(0.4, abs=1e-7)
    assert "time 15" in at[15.0].provenance
    none = load_materials(f)[0].parameters["base_diffuse_roughness"]
    assert none.value == pytest.approx(0.2) and "earliest sample" in none.provenance


def test_variants_in_session_layer_file_untouched(tmp_path):
    from pxr import Sdf

    st = _stage(tmp_path)
    mat, sh = _material(st, "/M")
    vs = mat.GetPrim().GetVariantSets().AddVariantSet("look")
    for name, value in (("soft", 0.9), ("hard", 0.1)):
        vs.AddVariant(name)
        vs.SetVariantSelection(name)
        with vs.GetVariantEditContext():
            sh.CreateInput("base_diffuse_roughness", Sdf.ValueTypeNames.Float).Set(value)
    vs.SetVariantSelection("soft")
    st.Save()
    f = tmp_path / "s.usda"
    before = f.read_bytes()
    assert load_materials(f)[0].parameters["base_diffuse_roughness"].value == pytest.approx(0.9)
    assert load_materials(f, variants=["look=hard"])[0].parameters["base_diffuse_roughness"].value == pytest.approx(0.1)
    assert load_materials(f, variants={"look": "soft"})[0].parameters["base_diffuse_roughness"].value == pytest.approx(
        0.9
    )
    with pytest.raises(ValueError, match="look=glossy"):
        load_materials(f, variants=["look=glossy"])
    with pytest.raises(ValueError, match="not on any prim"):
        load_materials(f, variants=["finish=matte"])
    assert f.read_bytes() == before


def test_bindings_and_purposes(tmp_path):
    from pxr import Sdf, UsdGeom, UsdShade

    st = _stage(tmp_path)
    full, sh1 = _material(st, "/Looks/Full")
    sh1.CreateInput("base_diffuse_roughness", Sdf.ValueTypeNames.Float).Set(0.75)
    prev, sh2 = _material(st, "/Looks/Prev", "UsdPreviewSurface", "surface", context=None)
    sh2.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).Set((0.3, 0.3, 0.3))
    parent = UsdGeom.Xform.Define(st, "/World")
    ball = UsdGeom.Sphere.Define(st, "/World/Ball")
    UsdShade.MaterialBindingAPI.Apply(ball.GetPrim()).Bind(full, materialPurpose=UsdShade.Tokens.full)
    UsdShade.MaterialBindingAPI.Apply(ball.GetPrim()).Bind(prev, materialPurpose=UsdShade.Tokens.preview)
    other = UsdGeom.Sphere.Define(st, "/World/Other")  # inherits the parent's all-purpose binding
    UsdShade.MaterialBindingAPI.Apply(parent.GetPrim()).Bind(prev)
    UsdGeom.Sphere.Define(st, "/Lonely")
    st.Save()
    f = tmp_path / "s.usda"
    assert [m.path for m in load_materials(f, material="/World/Ball")] == ["/Looks/Full"]
    assert [m.path for m in load_materials(f, material="/World/Ball", purpose="preview")] == ["/Looks/Prev"]
    assert [m.path for m in load_materials(f, material="/World/Other")] == ["/Looks/Prev"]
    assert [m.path for m in load_materials(f, material="Ball")] == ["/Looks/Full"]
    assert load_materials(f, material="/World/Ball")[0].parameters["base_diffuse_roughness"].value == 0.75
    with pytest.raises(ValueError, match="no bound material"):
        load_materials(f, material="/Lonely")
    with pytest.raises(ValueError, match="no material or prim"):
        load_materials(f, material="/Nope")


def _texture_stage(tmp_path, file, wrap="repeat", scale=None, bias=None, fallback=None, source="raw", st_value=None):
    from pxr import Sdf, UsdShade

    name = f"t{next(_COUNTER)}.usda"  # a new layer each time (USD's registry keeps open ones)
    st = _stage(tmp_path, name)
    _, sh = _material(st, "/M", "UsdPreviewSurface", "surface", context=None)
    tex = UsdShade.Shader.Define(st, "/M/Tex")
    tex.CreateIdAttr("UsdUVTexture")
    tex.CreateInput("file", Sdf.ValueTypeNames.Asset).Set(file)
    tex.CreateInput("wrapS", Sdf.ValueTypeNames.Token).Set(wrap)
    tex.CreateInput("wrapT", Sdf.ValueTypeNames.Token).Set(wrap)
    tex.CreateInput("sourceColorSpace", Sdf.ValueTypeNames.Token).Set(source)
    if scale is not None:
        tex.CreateInput("scale", Sdf.ValueTypeNames.Float4).Set(scale)
    if bias is not None:
        tex.CreateInput("bias", Sdf.ValueTypeNames.Float4).Set(bias)
    if fallback is not None:
        tex.CreateInput("fallback", Sdf.ValueTypeNames.Float4).Set(fallback)
    if st_value is None:
        reader = UsdShade.Shader.Define(st, "/M/UV")
        reader.CreateIdAttr("UsdPrimvarReader_float2")
        reader.CreateInput("varname", Sdf.ValueTypeNames.String).Set("st")
        tex.CreateInput("st", Sdf.ValueTypeNames.Float2).ConnectToSource(
            reader.CreateOutput("result", Sdf.ValueTypeNames.Float2)
        )
    rgb = tex.CreateOutput("rgb", Sdf.ValueTypeNames.Float3)
    r = tex.CreateOutput("r", Sdf.ValueTypeNames.Float)
    sh.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).ConnectToSource(rgb)
    sh.CreateInput("roughness", Sdf.ValueTypeNames.Float).ConnectToSource(r)
    from pxr import Usd

    Usd.ColorSpaceAPI.Apply(st.GetPrimAtPath("/M")).CreateColorSpaceNameAttr("lin_ap1_scene")
    st.Save()
    return tmp_path / name


def _centre(i, j):
    """uv of the centre of texel column i, row j (row 0 at the top)."""
    return ((i + 0.5) / 4.0, 1.0 - (j + 0.5) / 4.0)


def test_uv_texture_texel_centres_and_bilinear(tmp_path):
    a = _texels()
    _write_exr(tmp_path / "tex.exr", a)
    f = _texture_stage(tmp_path, "tex.exr")
    for i, j in ((0, 0), (3, 1), (2, 3)):
        (m,) = load_materials(f, uv=_centre(i, j))
        p = m.parameters["diffuseColor"]
        assert np.allclose(p.value, a[j, i], atol=1e-6), (i, j)
        assert "tex.exr" in p.provenance and p.kind == "texture"
        assert m.parameters["roughness"].value == pytest.approx(a[j, i, 0], abs=1e-6)
    # half-way between the centres of columns 1 and 2 on row 2: the mean of the two texels
    u, v = (_centre(1, 2)[0] + _centre(2, 2)[0]) / 2, _centre(1, 2)[1]
    (m,) = load_materials(f, uv=(u, v))
    assert np.allclose(m.parameters["diffuseColor"].value, (a[2, 1] + a[2, 2]) / 2, atol=1e-6)


@pytest.mark.parametrize("wrap, col", [("repeat", 0), ("clamp", 3), ("mirror", 3), ("black", None)])
def test_uv_texture_wrap_modes(tmp_path, wrap, col):
    a = _texels()
    _write_exr(tmp_path / "tex.exr", a)
    f = _texture_stage(tmp_path, "tex.exr", wrap=wrap)
    u = 1.0 + 0.125 if wrap != "clamp" else 1.7  # column 0 repeated / column 3 mirrored or clamped
    v = _centre(0, 1)[1]
    (m,) = load_materials(f, uv=(u, v))
    want = np.zeros(3) if col is None else a[1, col]
    assert np.allclose(m.parameters["diffuseColor"].value, want, atol=1e-6)


def test_uv_texture_scale_bias_and_fallback(tmp_path):
    a = _texels()
    _write_exr(tmp_path / "tex.exr", a)
    f = _texture_stage(tmp_path, "tex.exr", scale=(0.5, 0.5, 2.0, 1.0), bias=(0.1, 0.0, -0.5, 0.0))
    (m,) = load_materials(f, uv=_centre(1, 1))
    assert np.allclose(m.parameters["diffuseColor"].value, a[1, 1] * (0.5, 0.5, 2.0) + (0.1, 0.0, -0.5), atol=1e-6)
    f = _texture_stage(tmp_path, "missing.exr", fallback=(0.3, 0.2, 0.1, 1.0))
    (m,) = load_materials(f)
    assert np.allclose(m.parameters["diffuseColor"].value, (0.3, 0.2, 0.1), atol=1e-7)
    assert any("missing.exr" in w for w in m.warnings)


def test_uv_texture_srgb_png(tmp_path):
    import OpenImageIO as oiio

    px = np.zeros((2, 2, 3), dtype=np.uint8)
    px[...] = (200, 100, 30)
    buf = oiio.ImageBuf(oiio.ImageSpec(2, 2, 3, "uint8"))
    buf.set_pixels(oiio.ROI(0, 2, 0, 2), px)
    assert buf.write(str(tmp_path / "c.png"))
    # 8-bit with sourceColorSpace "auto" is sRGB-encoded: decode, then the scene's
    # colour space (here lin_rec709 via ColorSpaceAPI) -> ACEScg
    f = _texture_stage(tmp_path, "c.png", source="auto")
    from pxr import Usd

    st = Usd.Stage.Open(str(f))
    Usd.ColorSpaceAPI(st.GetPrimAtPath("/M")).GetColorSpaceNameAttr().Set("lin_rec709_scene")
    st.Save()
    (m,) = load_materials(f)
    lin = _srgb_decode(np.array([200, 100, 30]) / 255.0)
    assert np.allclose(m.parameters["diffuseColor"].value, _gf_convert(lin, "lin_rec709_scene"), atol=3e-6)
    # raw: no decoding, no conversion of the data
    f = _texture_stage(tmp_path, "c.png", source="raw")
    (m,) = load_materials(f)
    assert m.parameters["roughness"].value == pytest.approx(200 / 255.0, abs=1e-6)


def test_colour_spaces_usd(tmp_path):
    from pxr import Sdf, Usd

    st = _stage(tmp_path)
    _, sh = _material(st, "/Looks/A")
    sh.CreateInput("base_color", Sdf.ValueTypeNames.Color3f).Set((0.5, 0.25, 0.125))
    _, sh2 = _material(st, "/Looks/B")
    attr = sh2.CreateInput("base_color", Sdf.ValueTypeNames.Color3f)
    attr.Set((0.5, 0.25, 0.125))
    attr.GetAttr().SetColorSpace("lin_rec709_scene")
    _, sh3 = _material(st, "/Other/C")
    sh3.CreateInput("base_color", Sdf.ValueTypeNames.Color3f).Set((0.5, 0.25, 0.125))
    Usd.ColorSpaceAPI.Apply(st.GetPrimAtPath("/Looks")).CreateColorSpaceNameAttr("lin_ap1_scene")
    st.Save()
    by = {m.path: m for m in load_materials(tmp_path / "s.usda")}
    # ColorSpaceAPI on an ancestor: ACEScg = the working space, unchanged
    assert np.allclose(by["/Looks/A"].parameters["base_color"].value, (0.5, 0.25, 0.125), atol=1e-7)
    # the attribute's own colorSpace wins over the ancestor's
    want = _gf_convert((0.5, 0.25, 0.125), "lin_rec709_scene")
    assert np.allclose(by["/Looks/B"].parameters["base_color"].value, want, atol=2e-6)
    assert "lin_rec709 -> acescg" in by["/Looks/B"].parameters["base_color"].provenance
    # nothing authored: OpenPBR colours default to ACEScg
    assert np.allclose(by["/Other/C"].parameters["base_color"].value, (0.5, 0.25, 0.125), atol=1e-7)


def test_preview_surface_mapping(tmp_path):
    from pxr import Sdf

    st = _stage(tmp_path)
    _, sh = _material(st, "/P", "UsdPreviewSurface", "surface", context=None)
    sh.CreateInput("metallic", Sdf.ValueTypeNames.Float).Set(0.25)
    sh.CreateInput("roughness", Sdf.ValueTypeNames.Float).Set(0.4)
    sh.CreateInput("ior", Sdf.ValueTypeNames.Float).Set(1.33)
    st.Save()
    (m,) = load_materials(tmp_path / "s.usda")
    ni = {n: p.value for n, p in m.node_inputs.items()}
    assert m.shader_id == "UsdPreviewSurface" and m.diffuse_model == "lambert"
    assert ni["base_metalness"] == 0.25 and ni["specular_roughness"] == 0.4 and ni["specular_ior"] == 1.33
    assert m.parameters["diffuseColor"].value == (0.18, 0.18, 0.18)  # nodedef default, grey in any space
    assert ni["base_diffuse_roughness"] == 0.0


def test_unsupported_shader_listed_never_crashes(tmp_path):
    from pxr import Sdf

    st = _stage(tmp_path)
    _, sh = _material(st, "/X", "ND_disney_principled", "out")
    sh.CreateInput("base_color", Sdf.ValueTypeNames.Color3f).Set((1, 0, 0))
    _material(st, "/Y", "MyStudioShader_v3", "out")
    st.Save()
    mats = load_materials(tmp_path / "s.usda")
    assert [m.supported for m in mats] == [False, False]
    assert mats[0].shader_id == "ND_disney_principled" and "ND_disney_principled" in mats[0].unsupported[0]
    assert mats[1].node() is None and "MyStudioShader_v3" in mats[1].unsupported[0]


def test_out_of_range_clamped_with_warning(tmp_path):
    from pxr import Sdf

    st = _stage(tmp_path)
    _, sh = _material(st, "/M")
    sh.CreateInput("base_color", Sdf.ValueTypeNames.Color3f).Set((1.5, -0.25, 0.5))
    sh.CreateInput("base_diffuse_roughness", Sdf.ValueTypeNames.Float).Set(2.0)
    st.Save()
    (m,) = load_materials(tmp_path / "s.usda")
    assert m.parameters["base_color"].value == (1.5, -0.25, 0.5)  # as authored
    assert m.node_inputs["base_color"].value == (1.0, 0.0, 0.5)  # clamped to the nodedef range
    assert m.node_inputs["base_diffuse_roughness"].value == 1.0
    assert any("base_color" in w and "clamped" in w for w in m.warnings)
    assert any("base_diffuse_roughness" in w for w in m.warnings)
    assert m.node() is not None


def test_connection_cycle_is_an_error(tmp_path):
    from pxr import Sdf, UsdShade

    st = _stage(tmp_path)
    _, sh = _material(st, "/M")
    a = UsdShade.Shader.Define(st, "/M/A")
    a.CreateIdAttr("ND_multiply_float")
    b = UsdShade.Shader.Define(st, "/M/B")
    b.CreateIdAttr("ND_multiply_float")
    a.CreateInput("in1", Sdf.ValueTypeNames.Float).ConnectToSource(b.CreateOutput("out", Sdf.ValueTypeNames.Float))
    b.CreateInput("in1", Sdf.ValueTypeNames.Float).ConnectToSource(a.CreateOutput("out", Sdf.ValueTypeNames.Float))
    sh.CreateInput("base_weight", Sdf.ValueTypeNames.Float).ConnectToSource(a.GetOutput("out"))
    st.Save()
    (m,) = load_materials(tmp_path / "s.usda")  # the material fails, not the file
    assert not m.supported and re.search("connection cycle", m.error), m.error


def test_wrong_value_type_is_an_error(tmp_path):
    from pxr import Sdf

    st = _stage(tmp_path)
    _, sh = _material(st, "/M")
    sh.CreateInput("base_color", Sdf.ValueTypeNames.Float).Set(0.5)
    st.Save()
    (m,) = load_materials(tmp_path / "s.usda")  # the material fails, not the file
    assert not m.supported and re.search("base_color.*color3", m.error), m.error


# ----------------------------------------------------------------------------- MaterialX
MTLX = """<?xml version="1.0"?>
<materialx version="1.39" colorspace="{space}">
  <nodegraph name="NG">
    <input name="tint" type="color3" value="0.5, 1.0, 0.25" />
    <constant name="k" type="float"><input name="value" type="float" value="0.4" /></constant>
    <image name="img" type="color3">
      <input name="file" type="filename" value="tex.exr" colorspace="acescg" />
      <input name="uaddressmode" type="string" value="{umode}" />
      <input name="vaddressmode" type="string" value="periodic" />
      <input name="default" type="color3" value="0.9, 0.8, 0.7" />
    </image>
    <multiply name="mul" type="color3">
      <input name="in1" type="color3" nodename="img" />
      <input name="in2" type="color3" interfacename="tint" />
    </multiply>
    <tiledimage name="tiled" type="float">
      <input name="file" type="filename" value="tex.exr" />
      <input name="uvtiling" type="vector2" value="2.0, 1.0" />
    </tiledimage>
    <output name="colour_result" type="color3" nodename="mul" />
    <output name="k_out" type="float" nodename="k" />
    <output name="tiled_out" type="float" nodename="tiled" />
  </nodegraph>
  <open_pbr_surface name="S" type="surfaceshader">
    <input name="base_color" type="color3" nodegraph="NG" output="colour_result" />
    <input name="base_diffuse_roughness" type="float" nodegraph="NG" output="k_out" />
    <input name="specular_roughness" type="float" nodegraph="NG" output="tiled_out" />
    <input name="base_weight" type="float" value="0.75" />
  </open_pbr_surface>
  <surfacematerial name="Mat" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="S" />
  </surfacematerial>
</materialx>
"""


def test_materialx_nodegraph_interface_constant_image_tiledimage(tmp_path):
    a = _texels()
    _write_exr(tmp_path / "tex.exr", a)
    f = tmp_path / "m.mtlx"
    f.write_text(MTLX.format(space="acescg", umode="periodic"))
    uv = _centre(1, 2)
    (m,) = load_materials(f, uv=uv)
    assert np.allclose(m.parameters["base_color"].value, a[2, 1] * (0.5, 1.0, 0.25), atol=1e-6)
    assert "NG/tint" in m.parameters["base_color"].provenance and "tex.exr" in m.parameters["base_color"].provenance
    assert m.parameters["base_diffuse_roughness"].value == pytest.approx(0.4)
    assert m.parameters["base_weight"].value == 0.75
    # tiledimage: texcoord * (2, 1) -> u = 2 * 0.375 = 0.75, half-way between the centres of
    # columns 2 (0.625) and 3 (0.875): the bilinear mean of the two texels
    assert m.parameters["specular_roughness"].value == pytest.approx((a[2, 2, 0] + a[2, 3, 0]) / 2, abs=1e-6)
    (m,) = load_materials(f, uv=(0.4375 + 1.0, uv[1]))  # u' = 2.875: column 3 (periodic)
    assert m.parameters["specular_roughness"].value == pytest.approx(a[2, 3, 0], abs=1e-6)


def test_materialx_constant_address_mode_and_colour_space(tmp_path):
    a = _texels()
    _write_exr(tmp_path / "tex.exr", a)
    f = tmp_path / "m.mtlx"
    f.write_text(MTLX.format(space="lin_rec709", umode="constant"))
    (m,) = load_materials(f, uv=(1.25, 0.5))
    # outside [0, 1] with "constant": the image node's default (0.9, 0.8, 0.7), in the
    # document's lin_rec709, times the tint, also lin_rec709; both converted to ACEScg
    want = _gf_convert((0.9, 0.8, 0.7), "lin_rec709_scene") * _gf_convert((0.5, 1.0, 0.25), "lin_rec709_scene")
    assert np.allclose(m.parameters["base_color"].value, want, atol=3e-6)


def test_materialx_cycle_and_wrong_type(tmp_path):
    cyc = """<?xml version="1.0"?>
<materialx version="1.39">
  <multiply name="a" type="float"><input name="in1" type="float" nodename="b" /></multiply>
  <multiply name="b" type="float"><input name="in1" type="float" nodename="a" /></multiply>
  <open_pbr_surface name="S" type="surfaceshader">
    <input name="base_weight" type="float" nodename="a" />
  </open_pbr_surface>
  <surfacematerial name="M" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="S" />
  </surfacematerial>
</materialx>"""
    (tmp_path / "c.mtlx").write_text(cyc)
    (m,) = load_materials(tmp_path / "c.mtlx")  # the material fails, not the file
    assert not m.supported and re.search("connection cycle", m.error), m.error
    bad = cyc.replace(
        '<input name="base_weight" type="float" nodename="a" />', '<input name="base_color" type="float" value="0.5" />'
    )
    (tmp_path / "t.mtlx").write_text(bad)
    (m,) = load_materials(tmp_path / "t.mtlx")  # the material fails, not the file
    assert not m.supported and re.search("base_color.*color3", m.error), m.error


def test_materialx_bare_oren_nayar_and_standard_surface(tmp_path):
    doc = """<?xml version="1.0"?>
<materialx version="1.39" colorspace="acescg">
  <oren_nayar_diffuse_bsdf name="on" type="BSDF">
    <input name="color" type="color3" value="0.4, 0.5, 0.6" />
    <input name="roughness" type="float" value="0.3" />
  </oren_nayar_diffuse_bsdf>
</materialx>"""
    (tmp_path / "on.mtlx").write_text(doc)
    (m,) = load_materials(tmp_path / "on.mtlx")
    assert m.node_class == "OrenNayarDiffuseBSDF" and m.diffuse_model == "qon"
    node = m.node()
    assert np.allclose(node.color, (0.4, 0.5, 0.6)) and float(node.roughness) == 0.3
    ss = """<?xml version="1.0"?>
<materialx version="1.39" colorspace="acescg">
  <standard_surface name="ss" type="surfaceshader">
    <input name="base" type="float" value="0.6" />
    <input name="base_color" type="color3" value="0.2, 0.4, 0.6" />
    <input name="diffuse_roughness" type="float" value="0.7" />
    <input name="metalness" type="float" value="0.3" />
    <input name="specular" type="float" value="0.5" />
    <input name="specular_IOR" type="float" value="1.4" />
  </standard_surface>
  <surfacematerial name="M" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="ss" />
  </surfacematerial>
</materialx>"""
    (tmp_path / "ss.mtlx").write_text(ss)
    (m,) = load_materials(tmp_path / "ss.mtlx")
    ni = {n: p.value for n, p in m.node_inputs.items()}
    assert m.diffuse_model == "qon"
    assert ni["base_weight"] == 0.6 and ni["base_diffuse_roughness"] == 0.7 and ni["base_metalness"] == 0.3
    assert ni["specular_ior"] == 1.4
    # MaterialX's translation graph: metalness > 0 -> specular_weight 1 (OpenPBR's weight also scales metal)
    assert ni["specular_weight"] == 1.0
    assert np.allclose(ni["base_color"], (0.2, 0.4, 0.6))  # coat 0: no coat attenuation
    assert m.approximations


def test_pruned_standard_surface_translation_equals_the_full_graph():
    """The mapping evaluates only the translation outputs that depend on set inputs; the full
    evaluation of MaterialX's graph must give the same OpenPBR inputs."""
    from openpbr_diffuse.readers import BUNDLED_MATERIALS, mapping

    (m,) = load_materials(BUNDLED_MATERIALS / "felt_red_standard_surface.mtlx")
    full = mapping._translate(list(mapping._translation_dependencies()), m.parameters, m)
    for out, value in full.items():
        got = m.node_inputs[out[:-4]].value
        want = value
        if m.node_inputs[out[:-4]].kind != "default" and out[:-4] in (
            "base_color",
            "base_weight",
            "base_diffuse_roughness",
            "specular_weight",
        ):
            assert np.allclose(got, want), out
        if isinstance(want, (tuple, float)):
            assert np.allclose(np.asarray(got, dtype=float), np.asarray(want, dtype=float), atol=0), out
