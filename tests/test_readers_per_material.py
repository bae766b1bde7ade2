"""Real-world file shapes that must read per material, never as a traceback or a lost file:
a document's own nodedefs, explicit texcoord nodes, float3 colours, space-separated values,
and one bad value failing only its own material.  Each file is small and written here; the
expected values come from a second, plain spelling of the same material (read by the same
public API), so a wrong reading of either spelling fails."""

import textwrap

import numpy as np
import pytest

from openpbr_diffuse.readers import load_materials


def _write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(textwrap.dedent(text).lstrip())
    return p


def _by_name(mats):
    return {m.name: m for m in mats}


OPENPBR_DOC = """
<?xml version="1.0"?>
<materialx version="1.39" colorspace="lin_rec709">
  {extra}
  <open_pbr_surface name="S" type="surfaceshader">
    {shader_inputs}
  </open_pbr_surface>
  <surfacematerial name="M" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="S" />
  </surfacematerial>
</materialx>
"""


def _openpbr(tmp_path, name, shader_inputs, extra=""):
    return _write(tmp_path, name, OPENPBR_DOC.format(extra=extra, shader_inputs=shader_inputs))


def _base_color(path, **kw):
    (m,) = load_materials(path, **kw)
    assert m.error == "", m.error
    return np.asarray(m.parameters["base_color"].value)


# --------------------------------------------------------------- document-local nodedefs
LOCAL_NODEDEF = """
  <nodedef name="ND_halve_color3" node="halve">
    <input name="in" type="color3" value="1, 1, 1" />
    <output name="out" type="color3" />
  </nodedef>
  <nodegraph name="NG_halve_color3" nodedef="ND_halve_color3">
    <multiply name="m" type="color3">
      <input name="in1" type="color3" interfacename="in" />
      <input name="in2" type="float" value="0.5" />
    </multiply>
    <output name="out" type="color3" nodename="m" />
  </nodegraph>
  <halve name="h" type="color3">
    <input name="in" type="color3" value="0.8, 0.4, 0.2" />
  </halve>
"""


def test_document_local_nodedef_is_evaluated(tmp_path):
    local = _openpbr(tmp_path, "local.mtlx", '<input name="base_color" type="color3" nodename="h" />', LOCAL_NODEDEF)
    plain = _openpbr(tmp_path, "plain.mtlx", '<input name="base_color" type="color3" value="0.4, 0.2, 0.1" />')
    np.testing.assert_allclose(_base_color(local), _base_color(plain), rtol=1e-12)


def test_document_local_nodedef_default_is_used(tmp_path):
    extra = LOCAL_NODEDEF.replace('<input name="in" type="color3" value="0.8, 0.4, 0.2" />', "")
    local = _openpbr(tmp_path, "local.mtlx", '<input name="base_color" type="color3" nodename="h" />', extra)
    plain = _openpbr(tmp_path, "plain.mtlx", '<input name="base_color" type="color3" value="0.5, 0.5, 0.5" />')
    # grey is grey in every RGB space: the default's colour space cannot matter beyond round-off
    np.testing.assert_allclose(_base_color(local), _base_color(plain), rtol=1e-6)


# --------------------------------------------------------------- explicit texcoord nodes
def _texture(tmp_path):
    """A 2x2 float RGB texture, distinct texels (written with OpenImageIO)."""
    import OpenImageIO as oiio

    path = str(tmp_path / "t.exr")
    pix = np.array([[[0.1, 0.2, 0.3], [0.4, 0.5, 0.6]], [[0.7, 0.8, 0.9], [0.25, 0.5, 0.75]]], dtype=np.float32)
    out = oiio.ImageOutput.create(path)
    out.open(path, oiio.ImageSpec(2, 2, 3, "float"))
    out.write_image(pix)
    out.close()
    return path


def test_mtlx_image_with_explicit_texcoord_node(tmp_path):
    tex = _texture(tmp_path)
    img = (
        '<image name="img" type="color3"><input name="file" type="filename" value="{f}" colorspace="lin_rec709" />'
        '{tc}</image>'
    )
    explicit = _openpbr(
        tmp_path,
        "explicit.mtlx",
        '<input name="base_color" type="color3" nodename="img" />',
        '<texcoord name="tc" type="vector2" />'
        + img.format(f=tex, tc='<input name="texcoord" type="vector2" nodename="tc" />'),
    )
    implicit = _openpbr(
        tmp_path, "implicit.mtlx", '<input name="base_color" type="color3" nodename="img" />', img.format(f=tex, tc="")
    )
    for uv in ((0.25, 0.25), (0.75, 0.75)):
        a, b = _base_color(explicit, uv=uv), _base_color(implicit, uv=uv)
        np.testing.assert_allclose(a, b, rtol=1e-12)
    assert not np.allclose(_base_color(explicit, uv=(0.25, 0.25)), _base_color(explicit, uv=(0.75, 0.75)))


USD_IMAGE = """
#usda 1.0
def Material "M"
{{
    token outputs:mtlx:surface.connect = </M/S.outputs:surface>
    def Shader "S"
    {{
        uniform token info:id = "ND_open_pbr_surface_surfaceshader"
        color3f inputs:base_color.connect = </M/img.outputs:out>
        token outputs:surface
    }}
    def Shader "img"
    {{
        uniform token info:id = "ND_image_color3"
        asset inputs:file = @{tex}@ ( colorSpace = "lin_rec709" )
        {texcoord}
        color3f outputs:out
    }}
    def Shader "tc"
    {{
        uniform token info:id = "ND_texcoord_vector2"
        float2 outputs:out
    }}
}}
"""


def test_usd_image_with_explicit_texcoord_node(tmp_path):
    tex = _texture(tmp_path)
    explicit = _write(
        tmp_path,
        "explicit.usda",
        USD_IMAGE.format(tex=tex, texcoord="float2 inputs:texcoord.connect = </M/tc.outputs:out>"),
    )
    implicit = _write(tmp_path, "implicit.usda", USD_IMAGE.format(tex=tex, texcoord=""))
    for uv in ((0.25, 0.25), (0.75, 0.75)):
        np.testing.assert_allclose(_base_color(explicit, uv=uv), _base_color(implicit, uv=uv), rtol=1e-12)
    assert not np.allclose(_base_color(explicit, uv=(0.25, 0.25)), _base_color(explicit, uv=(0.75, 0.75)))


# --------------------------------------------------------------- float3 colours (USD)
PREVIEW = """
#usda 1.0
def Material "M"
{{
    token outputs:surface.connect = </M/S.outputs:surface>
    def Shader "S"
    {{
        uniform token info:id = "UsdPreviewSurface"
        {decl} inputs:diffuseColor = (0.2, 0.4, 0.6)
        token outputs:surface
    }}
}}
def Material "Other"
{{
    token outputs:surface.connect = </Other/S.outputs:surface>
    def Shader "S"
    {{
        uniform token info:id = "UsdPreviewSurface"
        float inputs:roughness = 0.3
        token outputs:surface
    }}
}}
"""


def test_usd_float3_colour_is_a_colour(tmp_path):
    f3 = _write(tmp_path, "f3.usda", PREVIEW.format(decl="float3"))
    c3 = _write(tmp_path, "c3.usda", PREVIEW.format(decl="color3f"))
    a, b = _by_name(load_materials(f3)), _by_name(load_materials(c3))
    assert set(a) == {"M", "Other"}
    assert a["M"].error == "" and a["M"].supported
    np.testing.assert_allclose(
        a["M"].parameters["diffuseColor"].value, b["M"].parameters["diffuseColor"].value, rtol=1e-12
    )


# --------------------------------------------------------------- values separated by spaces
def test_space_separated_values_parse_as_materialx_does(tmp_path):
    spaced = _openpbr(tmp_path, "spaced.mtlx", '<input name="base_color" type="color3" value="0.2 0.4 0.6" />')
    commas = _openpbr(tmp_path, "commas.mtlx", '<input name="base_color" type="color3" value="0.2, 0.4, 0.6" />')
    np.testing.assert_allclose(_base_color(spaced), _base_color(commas), rtol=1e-12)


def test_space_separated_vector2_in_a_graph(tmp_path):
    graph = (
        '<constant name="k" type="vector2"><input name="value" type="vector2" value="{v}" /></constant>'
        '<extract name="x" type="float"><input name="in" type="vector2" nodename="k" />'
        '<input name="index" type="integer" value="1" /></extract>'
    )
    inputs = '<input name="base_diffuse_roughness" type="float" nodename="x" />'
    spaced = _openpbr(tmp_path, "spaced.mtlx", inputs, graph.format(v="0.25 0.75"))
    (m,) = load_materials(spaced)
    assert m.error == "", m.error
    assert m.parameters["base_diffuse_roughness"].value == pytest.approx(0.75)


# --------------------------------------------------------------- one bad value, one material
TWO = """
<?xml version="1.0"?>
<materialx version="1.39">
  <open_pbr_surface name="Sbad" type="surfaceshader">
    {bad}
  </open_pbr_surface>
  <surfacematerial name="Bad" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="Sbad" />
  </surfacematerial>
  <open_pbr_surface name="Sgood" type="surfaceshader">
    <input name="base_diffuse_roughness" type="float" value="0.6" />
  </open_pbr_surface>
  <surfacematerial name="Good" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="Sgood" />
  </surfacematerial>
</materialx>
"""


@pytest.mark.parametrize(
    "bad, words",
    [
        ('<input name="base_color" type="color3" value="0.5, 0.5, 0.5" colorspace="gamma99" />', "gamma99"),
        ('<input name="base_diffuse_roughness" type="float" value="rough" />', "rough"),
    ],
)
def test_one_bad_value_fails_only_its_material(tmp_path, bad, words):
    f = _write(tmp_path, "two.mtlx", TWO.format(bad=bad))
    mats = _by_name(load_materials(f))
    assert set(mats) == {"Bad", "Good"}
    assert not mats["Bad"].supported and words in mats["Bad"].error and str(f) in mats["Bad"].error
    assert mats["Good"].error == "" and mats["Good"].supported
    assert mats["Good"].parameters["base_diffuse_roughness"].value == pytest.approx(0.6)


def test_usd_unknown_colour_space_fails_only_its_material(tmp_path):
    text = PREVIEW.format(decl="color3f").replace(
        "inputs:diffuseColor = (0.2, 0.4, 0.6)", 'inputs:diffuseColor = (0.2, 0.4, 0.6) ( colorSpace = "gamma99" )'
    )
    mats = _by_name(load_materials(_write(tmp_path, "cs.usda", text)))
    assert "gamma99" in mats["M"].error and not mats["M"].supported
    assert mats["Other"].error == "" and mats["Other"].supported


# --------------------------------------------------------------- shaders inside nodegraphs
GRAPH_SHADERS = """
<?xml version="1.0"?>
<materialx version="1.39">
  <nodegraph name="G">
    <oren_nayar_diffuse_bsdf name="d1" type="BSDF">
      <input name="color" type="color3" value="0.6, 0.5, 0.4" />
      <input name="roughness" type="float" value="0.25" />
      <input name="energy_compensation" type="boolean" value="true" />
    </oren_nayar_diffuse_bsdf>
    <surface name="s1" type="surfaceshader"><input name="bsdf" type="BSDF" nodename="d1" /></surface>
    <output name="out1" type="surfaceshader" nodename="s1" />
    <oren_nayar_diffuse_bsdf name="d2" type="BSDF">
      <input name="roughness" type="float" value="0.75" />
    </oren_nayar_diffuse_bsdf>
    <surface name="s2" type="surfaceshader"><input name="bsdf" type="BSDF" nodename="d2" /></surface>
    <output name="out2" type="surfaceshader" nodename="s2" />
  </nodegraph>
  <open_pbr_surface name="S" type="surfaceshader" />
  <surfacematerial name="M" type="material"><input name="surfaceshader" type="surfaceshader" nodename="S" /></surfacematerial>
</materialx>
"""


def test_surface_shaders_inside_nodegraphs_are_listed(tmp_path):
    import MaterialX as mx
    from MaterialX import PyMaterialXGenShader as gen

    def renderable(f):
        doc = mx.createDocument()
        mx.readFromXmlFile(doc, str(f))
        return {e.getNamePath() for e in gen.findRenderableElements(doc)}

    # what MaterialX's findRenderableElements finds, eval lists: with a material node, the
    # material; without one, the nodegraph's surface-shader outputs
    with_material = _write(tmp_path, "m.mtlx", GRAPH_SHADERS)
    assert set(_by_name(load_materials(with_material))) == renderable(with_material) == {"M"}
    f = _write(
        tmp_path,
        "g.mtlx",
        GRAPH_SHADERS.replace(
            '<surfacematerial name="M" type="material"><input name="surfaceshader" type="surfaceshader" '
            'nodename="S" /></surfacematerial>',
            "",
        ),
    )
    mats = _by_name(load_materials(f))
    assert renderable(f) >= {"G/out1", "G/out2"}
    assert {"G/out1", "G/out2"} <= set(mats) and set(mats) <= renderable(f) | {"S"}
    a, b = mats["G/out1"], mats["G/out2"]
    assert a.error == "" and a.node_class == "OrenNayarDiffuseBSDF" and a.diffuse_model == "eon"
    assert a.parameters["roughness"].value == 0.25 and a.node_inputs["roughness"].value == 0.25
    # d2 takes the nodedef defaults of MaterialX's library (read there, not here)
    lib = mx.createDocument()
    mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), lib)
    nd = lib.getNodeDef("ND_oren_nayar_diffuse_bsdf")
    assert b.parameters["color"].value == pytest.approx(tuple(nd.getInput("color").getValue()))
    assert b.parameters["energy_compensation"].value == nd.getInput("energy_compensation").getValue()


# --------------------------------------------------------------- sourceColorSpace "auto"
UVTEX = """
#usda 1.0
def Material "M"
{{
    token outputs:surface.connect = </M/S.outputs:surface>
    def Shader "S"
    {{
        uniform token info:id = "UsdPreviewSurface"
        float inputs:roughness.connect = </M/T.outputs:r>
        token outputs:surface
    }}
    def Shader "T"
    {{
        uniform token info:id = "UsdUVTexture"
        asset inputs:file = @{tex}@
        token inputs:sourceColorSpace = "{cs}"
        float outputs:r
    }}
}}
"""


@pytest.mark.parametrize(
    "channels, cs, decoded",
    [
        (1, "auto", False),
        (2, "auto", False),
        (3, "auto", True),
        (4, "auto", True),
        (1, "sRGB", True),
        (3, "raw", False),
    ],
)
def test_auto_source_colour_space_decodes_only_colour_textures(tmp_path, channels, cs, decoded):
    import OpenImageIO as oiio

    tex = str(tmp_path / f"t{channels}.png")
    pix = np.full((4, 4, channels), 216, dtype=np.uint8)
    out = oiio.ImageOutput.create(tex)
    out.open(tex, oiio.ImageSpec(4, 4, channels, "uint8"))
    out.write_image(pix)
    out.close()
    (m,) = load_materials(_write(tmp_path, "t.usda", UVTEX.format(tex=tex, cs=cs)))
    assert m.error == "", m.error
    c = 216 / 255
    srgb = ((c + 0.055) / 1.055) ** 2.4  # IEC 61966-2-1 decoding
    want = srgb if decoded else c
    # (the decoding runs through OpenColorIO, whose CPU path approximates the power to ~2e-5)
    assert m.parameters["roughness"].value == pytest.approx(want, abs=5e-5)


# --------------------------------------------------------------- clamp warnings and round-off
def test_no_clamp_warning_for_colour_space_round_off(tmp_path):
    white = _openpbr(tmp_path, "w.mtlx", '<input name="base_color" type="color3" value="1, 1, 1" />')
    (m,) = load_materials(white)
    authored = np.asarray(m.parameters["base_color"].value)
    assert np.all(np.abs(authored - 1.0) < 1e-6)  # lin_rec709 white in ACEScg, up to round-off
    assert not [w for w in m.warnings if "base_color" in w]
    assert all(0.0 <= x <= 1.0 for x in m.node_inputs["base_color"].value)
    over = _openpbr(tmp_path, "o.mtlx", '<input name="base_color" type="color3" value="1.001, 1, 1" />')
    (m,) = load_materials(over)
    assert [w for w in m.warnings if "base_color" in w and "clamped" in w]  # a real overshoot still warns
