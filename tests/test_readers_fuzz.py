"""Odd and malformed material files, written here: no traceback, and one material's problem is
that material's own.  Each file holds a material "Bad" (the oddity) next to a plain material
"Good": ``eval`` exits 0 when every material was read (an unsupported shader or a missing
connection is listed, with a warning, not an error), 1 when some material could not be
evaluated (named on stderr, its reason in the JSON ``error``), 2 only when the file itself is
unusable; "Good" is always evaluated, and no file changes a byte."""

import hashlib
import json

import numpy as np
import pytest

from openpbr_diffuse.cli.main import main

GOOD_MTLX = """  <open_pbr_surface name="SG" type="surfaceshader"><input name="base_color" type="color3" value="0.2, 0.4, 0.6" /></open_pbr_surface>
  <surfacematerial name="Good" type="material"><input name="surfaceshader" type="surfaceshader" nodename="SG" /></surfacematerial>
"""
BAD_MATERIAL = '  <surfacematerial name="Bad" type="material"><input name="surfaceshader" type="surfaceshader" nodename="SB" /></surfacematerial>\n'


def _sb(inputs: str, extra: str = "") -> str:
    return f'{extra}  <open_pbr_surface name="SB" type="surfaceshader">{inputs}</open_pbr_surface>\n'


#: case -> (Bad's elements, exit status, words the Bad material's error / warnings / unsupported must hold)
MTLX = {
    "node_without_nodedef": (
        _sb('<input name="base_color" type="color3" nodename="x" />', '  <foo_node name="x" type="color3" />\n'),
        0,
        ["x", "foo_node", "no nodedef"],
    ),
    "unknown_node_type": (
        _sb(
            '<input name="base_color" type="color3" nodename="c" />',
            '  <constant name="c" type="foo"><input name="value" type="foo" value="1" /></constant>\n',
        ),
        0,
        ["c", "no nodedef"],
    ),
    "cycle_in_a_nodegraph": (
        _sb(
            '<input name="base_color" type="color3" nodegraph="g" output="out" />',
            '  <nodegraph name="g"><add name="a" type="color3"><input name="in1" type="color3" '
            'nodename="b" /></add><add name="b" type="color3"><input name="in1" type="color3" '
            'nodename="a" /></add><output name="out" type="color3" nodename="a" /></nodegraph>\n',
        ),
        1,
        ["cycle", "g/a", "g/b"],
    ),
    "node_reading_itself": (
        _sb(
            '<input name="base_weight" type="float" nodename="a" />',
            '  <add name="a" type="float"><input name="in1" type="float" nodename="a" /></add>\n',
        ),
        1,
        ["cycle"],
    ),
    "unknown_input_type": (
        _sb('<input name="base_color" type="colour3" value="0.1, 0.2, 0.3" />'),
        1,
        ["base_color", "colour3"],
    ),
    "string_where_a_float_is": (
        _sb('<input name="base_weight" type="string" value="abc" />'),
        1,
        ["base_weight", "string"],
    ),
    "empty_value": (
        _sb('<input name="base_color" type="color3" value="" /><input name="base_weight" type="float" value="" />'),
        0,
        ["SB/base_color", "empty"],
    ),
    "too_few_components": (
        _sb('<input name="base_color" type="color3" value="0.5, 0.5" />'),
        1,
        ["base_color", "0.5, 0.5"],
    ),
    "too_many_components": (
        _sb('<input name="base_color" type="color3" value="0.5, 0.5, 0.5, 0.5" />'),
        1,
        ["base_color"],
    ),
    # MaterialX reads "1.0.0" as its leading number: read so, with a warning
    "malformed_float": (
        _sb('<input name="base_weight" type="float" value="1.0.0" />'),
        0,
        ["base_weight", "1.0.0", "read as 1"],
    ),
    "not_a_number": (_sb('<input name="base_weight" type="float" value="nan" />'), 1, ["base_weight", "nan"]),
    "infinite_component": (_sb('<input name="base_color" type="color3" value="inf, 0, 0" />'), 1, ["base_color"]),
    "unconnected_nodegraph_output": (
        _sb(
            '<input name="base_color" type="color3" nodegraph="g" output="out" />',
            '  <nodegraph name="g"><output name="out" type="color3" /></nodegraph>\n',
        ),
        0,
        ["g/out", "connected to nothing"],
    ),
    "input_to_a_missing_node": (
        _sb('<input name="base_color" type="color3" nodename="nope" />'),
        0,
        ["SB/base_color", "'nope'", "does not exist"],
    ),
    "input_to_a_missing_nodegraph": (
        _sb('<input name="base_color" type="color3" nodegraph="nog" output="out" />'),
        0,
        ["'nog'", "does not exist"],
    ),
    "input_to_a_missing_output": (
        _sb(
            '<input name="base_color" type="color3" nodegraph="g" output="nope" />',
            '  <nodegraph name="g"><constant name="c" type="color3"><input name="value" '
            'type="color3" value="1,0,0"/></constant><output name="out" type="color3" '
            'nodename="c" /></nodegraph>\n',
        ),
        0,
        ["'nope'", "'g'", "no output"],
    ),
    "nodegraph_output_to_a_missing_node": (
        _sb(
            '<input name="base_color" type="color3" nodegraph="g" output="out" />',
            '  <nodegraph name="g"><output name="out" type="color3" nodename="ghost" /></nodegraph>\n',
        ),
        0,
        ["g/out", "'ghost'", "does not exist"],
    ),
    "missing_interface_input": (
        _sb(
            '<input name="base_color" type="color3" nodegraph="g" output="out" />',
            '  <nodegraph name="g"><constant name="c" type="color3"><input name="value" '
            'type="color3" interfacename="nothere" /></constant><output name="out" '
            'type="color3" nodename="c" /></nodegraph>\n',
        ),
        0,
        ["nothere", "does not exist"],
    ),
    "connected_type_mismatch": (
        _sb(
            '<input name="base_color" type="color3" nodename="c" />',
            '  <constant name="c" type="float"><input name="value" type="float" value="0.5" /></constant>\n',
        ),
        0,
        ["SB/base_color", "float"],
    ),
    "material_without_shader": ('  <open_pbr_surface name="SX" type="surfaceshader" />\n', 0, ["no surface shader"]),
    "undefined_operation": (
        _sb(
            '<input name="base_weight" type="float" nodename="l" />',
            '  <ln name="l" type="float"><input name="in" type="float" value="-1" /></ln>\n',
        ),
        1,
        ["SB/base_weight", "not finite"],
    ),
}


def _run(path, capfd):
    before = hashlib.sha256(path.read_bytes()).hexdigest() if path.is_file() else None
    rc = main(["eval", str(path), "--json"])
    out, err = capfd.readouterr()
    assert "Traceback" not in err and "Traceback" not in out
    if path.is_file():
        assert hashlib.sha256(path.read_bytes()).hexdigest() == before, "the file changed"
    return rc, out, err


def _check(path, capfd, rc_want, words, good_value):
    rc, out, err = _run(path, capfd)
    assert rc == rc_want, (rc, err)
    doc = json.loads(out)
    mats = {m["name"]: m for m in doc["materials"]}
    assert {"Good", "Bad"} <= set(mats), list(mats)
    good = mats["Good"]
    assert good["supported"] and not good["error"], good
    assert np.allclose(
        good["evaluation"]["albedo"] if False else good["parameters"][good_value[0]]["value"], good_value[1], atol=1e-5
    )
    bad = mats["Bad"]
    said = " ".join([bad["error"] or ""] + bad.get("warnings", []) + bad.get("unsupported", []))
    for w in words:
        assert w in said, (w, said)
    if rc_want == 1:
        assert bad["error"] and str(path) in bad["error"] and not bad["supported"]
        assert "Bad" in err  # stderr names the failed material
    else:
        assert not bad["error"], bad["error"]
    return mats


@pytest.mark.parametrize("case", sorted(MTLX))
def test_materialx_oddity_is_its_materials_own(tmp_path, capfd, case):
    body, rc_want, words = MTLX[case]
    f = tmp_path / f"{case}.mtlx"
    f.write_text(
        '<?xml version="1.0"?>\n<materialx version="1.39">\n' + GOOD_MTLX + body + BAD_MATERIAL + "</materialx>\n"
    )
    _check(f, capfd, rc_want, words, ("base_color", [0.2, 0.4, 0.6]))


GOOD_USD = """def Material "Good"
{
    token outputs:surface.connect = </Good/S.outputs:surface>
    def Shader "S"
    {
        uniform token info:id = "UsdPreviewSurface"
        color3f inputs:diffuseColor = (0.2, 0.4, 0.6) ( colorSpace = "lin_ap1_scene" )
        token outputs:surface
    }
}
"""


def _bad_usd(material_body: str, shaders: str = "") -> str:
    return f'def Material "Bad"\n{{\n{material_body}\n{shaders}}}\n'


def _shader(name: str, lines: str) -> str:
    return f'    def Shader "{name}"\n    {{\n{lines}\n    }}\n'


_PREVIEW = '        uniform token info:id = "UsdPreviewSurface"\n'
_TEXTURED = _shader(
    "S", _PREVIEW + '        color3f inputs:diffuseColor.connect = </Bad/T.outputs:rgb>\n        token outputs:surface'
) + _shader(
    "T",
    '        uniform token info:id = "UsdUVTexture"\n        asset inputs:file = @{asset}@\n'
    '        float4 inputs:fallback = (0.1, 0.2, 0.3, 1)\n        float3 outputs:rgb',
)

USD = {
    "surface_connected_to_a_missing_prim": (
        _bad_usd('    token outputs:surface.connect = </Nowhere/S.outputs:surface>'),
        0,
        ["/Nowhere/S"],
    ),
    "shader_without_info_id": (
        _bad_usd(
            '    token outputs:surface.connect = </Bad/S.outputs:surface>',
            _shader("S", '        color3f inputs:diffuseColor = (1, 0, 0)\n        token outputs:surface'),
        ),
        0,
        ["no info:id"],
    ),
    "sdr_source_asset_shader": (
        _bad_usd(
            '    token outputs:surface.connect = </Bad/S.outputs:surface>',
            _shader(
                "S",
                '        uniform token info:implementationSource = "sourceAsset"\n'
                '        uniform asset info:glslfx:sourceAsset = @./shader.glslfx@\n'
                '        token outputs:surface',
            ),
        ),
        0,
        ["sourceAsset", "shader.glslfx"],
    ),
    "sdr_source_code_shader": (
        _bad_usd(
            '    token outputs:surface.connect = </Bad/S.outputs:surface>',
            _shader(
                "S",
                '        uniform token info:implementationSource = "sourceCode"\n'
                '        uniform string info:osl:sourceCode = "shader x() {}"\n'
                '        token outputs:surface',
            ),
        ),
        0,
        ["sourceCode"],
    ),
    "unknown_shader_id": (
        _bad_usd(
            '    token outputs:surface.connect = </Bad/S.outputs:surface>',
            _shader("S", '        uniform token info:id = "MyFancySurface"\n        token outputs:surface'),
        ),
        0,
        ["MyFancySurface"],
    ),
    "texture_url": (
        _bad_usd(
            '    token outputs:surface.connect = </Bad/S.outputs:surface>',
            _TEXTURED.replace("{asset}", "http://example.invalid/tex.png"),
        ),
        0,
        ["tex.png"],
    ),
    "texture_path_under_a_file": (
        _bad_usd(
            '    token outputs:surface.connect = </Bad/S.outputs:surface>',
            _TEXTURED.replace("{asset}", "/dev/null/x.png"),
        ),
        0,
        ["x.png"],
    ),
    "texture_missing": (
        _bad_usd(
            '    token outputs:surface.connect = </Bad/S.outputs:surface>',
            _TEXTURED.replace("{asset}", "./textures/missing.png"),
        ),
        0,
        ["missing.png", "does not exist"],
    ),
    "only_displacement": (
        _bad_usd(
            '    token outputs:displacement.connect = </Bad/D.outputs:displacement>',
            _shader("D", _PREVIEW + '        token outputs:displacement'),
        ),
        0,
        ["no surface shader"],
    ),
    "surface_to_a_missing_output": (
        _bad_usd(
            '    token outputs:surface.connect = </Bad/S.outputs:nothere>',
            _shader("S", _PREVIEW + '        token outputs:surface'),
        ),
        0,
        [],
    ),
    "connection_cycle": (
        _bad_usd(
            '    token outputs:surface.connect = </Bad/S.outputs:surface>',
            _shader(
                "S",
                _PREVIEW + '        float inputs:roughness.connect = </Bad/A.outputs:out>\n'
                '        token outputs:surface',
            )
            + _shader(
                "A",
                '        uniform token info:id = "ND_add_float"\n'
                '        float inputs:in1.connect = </Bad/B.outputs:out>\n'
                '        float outputs:out',
            )
            + _shader(
                "B",
                '        uniform token info:id = "ND_add_float"\n'
                '        float inputs:in1.connect = </Bad/A.outputs:out>\n'
                '        float outputs:out',
            ),
        ),
        1,
        ["cycle"],
    ),
    "interface_input_reading_itself": (
        _bad_usd(
            '    float inputs:r.connect = </Bad.inputs:r>\n'
            '    token outputs:surface.connect = </Bad/S.outputs:surface>',
            _shader(
                "S",
                _PREVIEW + '        float inputs:roughness.connect = </Bad.inputs:r>\n        token outputs:surface',
            ),
        ),
        1,
        ["cycle"],
    ),
    "string_where_a_float_is": (
        _bad_usd(
            '    token outputs:surface.connect = </Bad/S.outputs:surface>',
            _shader("S", _PREVIEW + '        string inputs:roughness = "abc"\n        token outputs:surface'),
        ),
        1,
        ["roughness"],
    ),
    "not_a_number": (
        _bad_usd(
            '    token outputs:surface.connect = </Bad/S.outputs:surface>',
            _shader("S", _PREVIEW + '        float inputs:roughness = nan\n        token outputs:surface'),
        ),
        1,
        ["roughness", "finite"],
    ),
    "material_output_to_itself": (_bad_usd('    token outputs:surface.connect = </Bad.outputs:surface>'), 0, []),
    "unknown_colour_space": (
        _bad_usd(
            '    token outputs:surface.connect = </Bad/S.outputs:surface>',
            _shader(
                "S",
                _PREVIEW + '        color3f inputs:diffuseColor = (0.2, 0.4, 0.6) '
                '( colorSpace = "gamma99" )\n'
                '        token outputs:surface',
            ),
        ),
        1,
        ["gamma99"],
    ),
}


@pytest.mark.parametrize("case", sorted(USD))
def test_usd_oddity_is_its_materials_own(tmp_path, capfd, case):
    bad, rc_want, words = USD[case]
    f = tmp_path / f"{case}.usda"
    f.write_text("#usda 1.0\n" + GOOD_USD + bad)
    _check(f, capfd, rc_want, words, ("diffuseColor", [0.2, 0.4, 0.6]))


def test_missing_sublayer_is_a_warning(tmp_path, capfd):
    f = tmp_path / "root.usda"
    f.write_text('#usda 1.0\n(\n    subLayers = [@./does_not_exist.usda@]\n)\n' + GOOD_USD)
    rc, out, err = _run(f, capfd)
    assert rc == 0, err
    (good,) = json.loads(out)["materials"]
    assert good["supported"] and not good["error"]
    assert any("does_not_exist.usda" in w for w in good["warnings"]), good["warnings"]


def test_usdz_with_a_missing_texture(tmp_path, capfd):
    """A packaged texture that is not in the package: a warning and the fallback, the package's
    other material read."""
    from pxr import Sdf

    inner = tmp_path / "inner.usda"
    inner.write_text("#usda 1.0\n" + GOOD_USD + USD["texture_missing"][0])
    pkg = tmp_path / "pkg.usdz"
    w = Sdf.ZipFileWriter.CreateNew(str(pkg))
    w.AddFile(str(inner), "inner.usda")
    w.Save()
    inner.unlink()
    mats = _check(pkg, capfd, 0, ["missing.png"], ("diffuseColor", [0.2, 0.4, 0.6]))
    assert np.allclose(mats["Bad"]["parameters"]["diffuseColor"]["value"], [0.1, 0.2, 0.3], atol=1e-6)


UNUSABLE = {
    "not_xml.mtlx": b"not xml at all <<<",
    "truncated.mtlx": b'<?xml version="1.0"?>\n<materialx version="1.39">\n<nodegraph name="g">',
    "empty.mtlx": b"",
    "syntax.usda": b'#usda 1.0\ndef Material "X" {\n',
    "garbage.usdc": b"PXR-USDC garbage",
    "empty.usdz": b"",
    "not_a_zip.usdz": b"PK\x03\x04 this is not a zip",
    "binary.usda": bytes(range(256)),
}


@pytest.mark.parametrize("name", sorted(UNUSABLE))
def test_unusable_file_exit_2_one_line(tmp_path, capfd, name):
    f = tmp_path / name
    f.write_bytes(UNUSABLE[name])
    rc, out, err = _run(f, capfd)
    assert rc == 2
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and name in lines[0], lines


def test_a_directory_named_like_a_material_file(tmp_path, capfd):
    d = tmp_path / "looks.mtlx"
    d.mkdir()
    rc, out, err = _run(d, capfd)
    assert rc == 2 and len([ln for ln in err.splitlines() if ln.strip()]) == 1
