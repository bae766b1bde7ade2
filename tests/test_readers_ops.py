"""MaterialX stdlib nodes upstream of a surface input: each is evaluated as MaterialX defines it
(expected values written here in closed form, with Python's math / colorsys / scipy, from the
MaterialX specification and its genglsl implementations), or listed unsupported naming the
node; never a traceback.  Every value-typed nodedef of the data library is tried once."""

import colorsys
import math

import numpy as np
import pytest

from openpbr_diffuse.readers import load_materials, mxlib

UV = (0.25, 0.75)


def _xml_inputs(inputs):
    out = []
    for name, t, v in inputs:
        if isinstance(v, tuple):
            v = ", ".join(repr(float(x)) for x in v)
        elif isinstance(v, bool):
            v = "true" if v else "false"
        out.append(f'<input name="{name}" type="{t}" value="{v}" />')
    return "".join(out)


def node(cat, name, t, *inputs, nodedef=None, extra=""):
    nd = f' nodedef="{nodedef}"' if nodedef else ""
    return f'  <{cat} name="{name}" type="{t}"{nd}>{_xml_inputs(inputs)}{extra}</{cat}>\n'


def _doc(body, out, out_type, output=None, shader="S", material="M"):
    """``out`` (of ``out_type``) feeds an OpenPBR surface: a float its base_diffuse_roughness, a
    colour or vector its base_color (through MaterialX's convert to color3)."""
    o = f' output="{output}"' if output else ""
    if out_type == "float":
        conn = f'<input name="base_diffuse_roughness" type="float" nodename="{out}"{o} />'
        pre = ""
    elif out_type == "color3":
        conn = f'<input name="base_color" type="color3" nodename="{out}"{o} />'
        pre = ""
    else:
        pre = (
            f'  <convert name="{shader}_c" type="color3"><input name="in" type="{out_type}" nodename="{out}"{o} />'
            f'</convert>\n'
        )
        conn = f'<input name="base_color" type="color3" nodename="{shader}_c" />'
    return (
        body + pre + f'  <open_pbr_surface name="{shader}" type="surfaceshader">{conn}</open_pbr_surface>\n'
        f'  <surfacematerial name="{material}" type="material"><input name="surfaceshader" type="surfaceshader" '
        f'nodename="{shader}" /></surfacematerial>\n'
    )


def _load(tmp_path, body, name="t.mtlx"):
    f = tmp_path / name
    f.write_text(f'<?xml version="1.0"?>\n<materialx version="1.39">\n{body}</materialx>\n')
    return load_materials(f, uv=UV)


def value(tmp_path, body, out, out_type, output=None):
    (m,) = _load(tmp_path, _doc(body, out, out_type, output))
    assert not m.error, m.error
    assert not m.unsupported, m.unsupported
    key = "base_diffuse_roughness" if out_type == "float" else "base_color"
    p = m.parameters[key]
    assert p.kind != "default", p.provenance
    return np.asarray(p.value, dtype=np.float64)


F, C3, V3 = "float", "color3", "vector3"
CASES = {
    "modulo_float": (node("modulo", "n", F, ("in1", F, -0.25), ("in2", F, 1.0)), F, -0.25 % 1.0),
    "modulo_vector3": (
        node("modulo", "n", V3, ("in1", V3, (1.5, -0.5, 2.25)), ("in2", V3, (1.0, 0.3, 2.0))),
        V3,
        [1.5 % 1.0, -0.5 % 0.3, 2.25 % 2.0],
    ),
    "modulo_color3FA": (
        node("modulo", "n", C3, ("in1", C3, (1.5, -0.5, 0.25)), ("in2", F, 0.4)),
        C3,
        [1.5 % 0.4, -0.5 % 0.4, 0.25 % 0.4],
    ),
    "fract": (node("fract", "n", F, ("in", F, -1.25)), F, -1.25 - math.floor(-1.25)),
    "floor": (node("floor", "n", C3, ("in", C3, (-1.5, 0.2, 2.7))), C3, [-2.0, 0.0, 2.0]),
    "ceil": (node("ceil", "n", C3, ("in", C3, (-1.5, 0.2, 2.7))), C3, [-1.0, 1.0, 3.0]),
    "round_half_up": (node("round", "n", F, ("in", F, 2.5)), F, 3.0),
    "round_half_down": (node("round", "n", F, ("in", F, -2.5)), F, -3.0),
    "sign": (node("sign", "n", C3, ("in", C3, (-0.3, 0.0, 2.0))), C3, [-1.0, 0.0, 1.0]),
    "sqrt": (node("sqrt", "n", F, ("in", F, 0.25)), F, 0.5),
    "exp": (node("exp", "n", F, ("in", F, 0.5)), F, math.exp(0.5)),
    "ln": (node("ln", "n", F, ("in", F, 2.0)), F, math.log(2.0)),
    "sin": (node("sin", "n", F, ("in", F, 0.7)), F, math.sin(0.7)),
    "cos": (node("cos", "n", V3, ("in", V3, (0.1, 0.2, 0.3))), V3, [math.cos(x) for x in (0.1, 0.2, 0.3)]),
    "tan": (node("tan", "n", F, ("in", F, 0.3)), F, math.tan(0.3)),
    "asin": (node("asin", "n", F, ("in", F, 0.3)), F, math.asin(0.3)),
    "acos": (node("acos", "n", F, ("in", F, 0.3)), F, math.acos(0.3)),
    "atan2": (node("atan2", "n", F, ("iny", F, 1.0), ("inx", F, -1.0)), F, math.atan2(1.0, -1.0)),
    "power": (node("power", "n", C3, ("in1", C3, (0.5, 0.25, 2.0)), ("in2", F, 2.0)), C3, [0.25, 0.0625, 4.0]),
    "absval": (node("absval", "n", F, ("in", F, -0.4)), F, 0.4),
    "min": (node("min", "n", F, ("in1", F, 0.3), ("in2", F, 0.2)), F, 0.2),
    "max": (node("max", "n", F, ("in1", F, 0.3), ("in2", F, 0.2)), F, 0.3),
    "clamp": (
        node("clamp", "n", C3, ("in", C3, (-1.0, 0.5, 2.0)), ("low", F, 0.0), ("high", F, 1.0)),
        C3,
        [0.0, 0.5, 1.0],
    ),
    "mix": (node("mix", "n", F, ("fg", F, 1.0), ("bg", F, 0.2), ("mix", F, 0.25)), F, 0.4),
    "remap": (
        node(
            "remap",
            "n",
            F,
            ("in", F, 0.25),
            ("inlow", F, 0.0),
            ("inhigh", F, 0.5),
            ("outlow", F, 1.0),
            ("outhigh", F, 3.0),
        ),
        F,
        2.0,
    ),
    "smoothstep_float": (
        node("smoothstep", "n", F, ("in", F, 0.25), ("low", F, 0.0), ("high", F, 1.0)),
        F,
        3 * 0.25**2 - 2 * 0.25**3,
    ),
    "smoothstep_vector3": (
        node(
            "smoothstep",
            "n",
            V3,
            ("in", V3, (0.25, -1.0, 2.0)),
            ("low", V3, (0.0, 0.0, 0.0)),
            ("high", V3, (1.0, 1.0, 1.0)),
        ),
        V3,
        [3 * 0.25**2 - 2 * 0.25**3, 0.0, 1.0],
    ),
    "magnitude": (node("magnitude", "n", F, ("in", V3, (3.0, 4.0, 12.0))), F, 13.0),
    "normalize": (node("normalize", "n", V3, ("in", V3, (3.0, 4.0, 0.0))), V3, [0.6, 0.8, 0.0]),
    "crossproduct": (
        node("crossproduct", "n", V3, ("in1", V3, (1.0, 0.0, 0.0)), ("in2", V3, (0.0, 1.0, 0.0))),
        V3,
        [0.0, 0.0, 1.0],
    ),
    "dotproduct": (node("dotproduct", "n", F, ("in1", V3, (1.0, 2.0, 3.0)), ("in2", V3, (4.0, 5.0, 6.0))), F, 32.0),
    "luminance": (
        node("luminance", "n", C3, ("in", C3, (0.2, 0.4, 0.6))),
        C3,
        [0.2722287 * 0.2 + 0.6740818 * 0.4 + 0.0536895 * 0.6] * 3,
    ),
    "rgbtohsv": (node("rgbtohsv", "n", C3, ("in", C3, (0.2, 0.4, 0.6))), C3, list(colorsys.rgb_to_hsv(0.2, 0.4, 0.6))),
    "hsvtorgb": (node("hsvtorgb", "n", C3, ("in", C3, (0.7, 0.5, 0.8))), C3, list(colorsys.hsv_to_rgb(0.7, 0.5, 0.8))),
    "hsvtorgb_wraps_hue": (
        node("hsvtorgb", "n", C3, ("in", C3, (1.2, 0.5, 0.8))),
        C3,
        list(colorsys.hsv_to_rgb(0.2, 0.5, 0.8)),
    ),
    # uv = (0.25, 0.75): ramps mix by the clamped coordinate, splits step at center
    "ramplr": (node("ramplr", "n", F, ("valuel", F, 0.0), ("valuer", F, 1.0)), F, 0.25),
    "ramptb": (node("ramptb", "n", F, ("valuet", F, 1.0), ("valueb", F, 0.0)), F, 0.75),
    "splitlr": (node("splitlr", "n", F, ("valuel", F, 0.1), ("valuer", F, 0.9), ("center", F, 0.5)), F, 0.1),
    "splittb": (node("splittb", "n", F, ("valuet", F, 0.9), ("valueb", F, 0.1), ("center", F, 0.5)), F, 0.9),
    "ramp4": (
        node("ramp4", "n", F, ("valuetl", F, 1.0), ("valuetr", F, 2.0), ("valuebl", F, 3.0), ("valuebr", F, 4.0)),
        F,
        (3 + 0.25) * 0.25 + (1 + 0.25) * 0.75,
    ),
    "contrast": (node("contrast", "n", F, ("in", F, 0.7), ("amount", F, 2.0), ("pivot", F, 0.5)), F, 0.9),
    "range_gamma": (
        node(
            "range",
            "n",
            F,
            ("in", F, 0.25),
            ("inlow", F, 0.0),
            ("inhigh", F, 1.0),
            ("gamma", F, 2.0),
            ("outlow", F, 0.0),
            ("outhigh", F, 1.0),
        ),
        F,
        0.5,
    ),
    "invert": (node("invert", "n", F, ("in", F, 0.3)), F, 0.7),
    "switch_which_1": (
        node("switch", "n", F, ("in1", F, 0.1), ("in2", F, 0.2), ("in3", F, 0.3), ("which", F, 1.0)),
        F,
        0.2,
    ),
    "switch_which_floored": (
        node("switch", "n", F, ("in1", F, 0.1), ("in2", F, 0.2), ("in3", F, 0.3), ("which", F, 2.7)),
        F,
        0.3,
    ),
    "switch_integer_which": (
        node(
            "switch",
            "n",
            C3,
            ("in1", C3, (0.1, 0.1, 0.1)),
            ("in2", C3, (0.2, 0.3, 0.4)),
            ("which", "integer", 1),
            nodedef="ND_switch_color3I",
        ),
        C3,
        [0.2, 0.3, 0.4],
    ),
    "extract": (
        node("extract", "n", F, ("in", V3, (0.1, 0.2, 0.3)), ("index", "integer", 2), nodedef="ND_extract_vector3"),
        F,
        0.3,
    ),
    "combine2": (node("combine2", "n", "vector2", ("in1", F, 0.1), ("in2", F, 0.2)), "vector2", [0.1, 0.2, 0.0]),
    "combine3": (node("combine3", "n", C3, ("in1", F, 0.1), ("in2", F, 0.2), ("in3", F, 0.3)), C3, [0.1, 0.2, 0.3]),
    "combine4": (
        node("combine4", "n", "vector4", ("in1", F, 0.1), ("in2", F, 0.2), ("in3", F, 0.3), ("in4", F, 0.4)),
        "vector4",
        [0.1, 0.2, 0.3],
    ),
    "plus": (node("plus", "n", F, ("fg", F, 0.3), ("bg", F, 0.6)), F, 0.9),
    "minus": (node("minus", "n", F, ("fg", F, 0.3), ("bg", F, 0.6)), F, 0.3),
    "difference": (node("difference", "n", F, ("fg", F, 0.8), ("bg", F, 0.6)), F, 0.2),
    "screen": (node("screen", "n", F, ("fg", F, 0.3), ("bg", F, 0.6)), F, 1 - 0.7 * 0.4),
    "burn": (node("burn", "n", F, ("fg", F, 0.8), ("bg", F, 0.6)), F, 1 - 0.4 / 0.8),
    "dodge": (node("dodge", "n", F, ("fg", F, 0.3), ("bg", F, 0.6)), F, 0.6 / 0.7),
    "overlay": (node("overlay", "n", F, ("fg", F, 0.3), ("bg", F, 0.6)), F, 1 - 2 * 0.7 * 0.4),
    "inside": (node("inside", "n", F, ("in", F, 0.5), ("mask", F, 0.4)), F, 0.2),
    "outside": (node("outside", "n", F, ("in", F, 0.5), ("mask", F, 0.4)), F, 0.3),
    "over": (
        node("over", "n", "color4", ("fg", "color4", (0.5, 0.0, 0.0, 0.5)), ("bg", "color4", (0.0, 0.0, 1.0, 1.0))),
        "color4",
        [0.5, 0.0, 0.5],
    ),
    "premult": (node("premult", "n", "color4", ("in", "color4", (0.5, 0.4, 0.2, 0.5))), "color4", [0.25, 0.2, 0.1]),
    "rotate2d": (
        node("rotate2d", "n", "vector2", ("in", "vector2", (1.0, 0.0)), ("amount", F, 90.0)),
        "vector2",
        [0.0, -1.0, 0.0],
    ),
    "dot": (node("dot", "n", F, ("in", F, 0.35)), F, 0.35),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_node_value(tmp_path, case):
    body, t, want = CASES[case]
    got = value(tmp_path, body, "n", t)
    assert np.allclose(got, want, rtol=1e-12, atol=1e-12), (got, want)


def test_rotate3d_turns_as_rotate2d(tmp_path):
    """rotate3d about +z by 90 degrees takes +x to -y (clockwise, as rotate2d; MaterialX writes
    v' = v M): scipy's rotation by -90 degrees."""
    from scipy.spatial.transform import Rotation

    body = node("rotate3d", "n", V3, ("in", V3, (1.0, 0.2, 0.3)), ("amount", F, 90.0), ("axis", V3, (0.0, 0.0, 2.0)))
    want = Rotation.from_rotvec([0.0, 0.0, -math.pi / 2]).apply([1.0, 0.2, 0.3])
    assert np.allclose(value(tmp_path, body, "n", V3), want, atol=1e-12)


def test_convert_vector3_to_vector4_is_materialxs_graph(tmp_path):
    """MaterialX's NG_convert_vector3_vector4 sets w = 1 (not 0)."""
    body = (
        node("constant", "v", V3, ("value", V3, (0.1, 0.2, 0.3)))
        + '  <convert name="c4" type="vector4"><input name="in" type="vector3" nodename="v" /></convert>\n'
        + '  <extract name="n" type="float" nodedef="ND_extract_vector4"><input name="in" type="vector4" '
        'nodename="c4" /><input name="index" type="integer" value="3" /></extract>\n'
    )
    assert value(tmp_path, body, "n", F) == 1.0


def test_switch_beyond_its_inputs_is_zero(tmp_path):
    body = node("switch", "n", F, ("in1", F, 0.1), ("in2", F, 0.2), ("which", F, 30.0))
    assert value(tmp_path, body, "n", F) == 0.0


def test_separate3_output(tmp_path):
    body = node("separate3", "n", "multioutput", ("in", C3, (0.1, 0.2, 0.3)), nodedef="ND_separate3_color3")
    assert value(tmp_path, body, "n", F, output="outg") == 0.2


def test_place2d_offset(tmp_path):
    body = node("place2d", "n", "vector2", ("texcoord", "vector2", (0.3, 0.4)), ("offset", "vector2", (0.1, 0.25)))
    assert np.allclose(value(tmp_path, body, "n", "vector2"), [0.2, 0.15, 0.0], atol=1e-12)


def test_ramplr_reads_the_uv(tmp_path):
    """Without a texcoord input, a ramp reads the surface point's uv (UV0)."""
    (m,) = _load(
        tmp_path,
        _doc(node("ramplr", "n", C3, ("valuel", C3, (0.0, 0.0, 0.0)), ("valuer", C3, (1.0, 0.5, 0.0))), "n", C3),
    )
    assert np.allclose(m.parameters["base_color"].value, [0.25, 0.125, 0.0])


UNSUPPORTED = {
    "noise2d": node("noise2d", "n", F),
    "noise3d": node("noise3d", "n", F),
    "fractal3d": node("fractal3d", "n", F),
    "cellnoise2d": node("cellnoise2d", "n", F),
    "cellnoise3d": node("cellnoise3d", "n", F),
    "worleynoise2d": node("worleynoise2d", "n", F),
    "worleynoise3d": node("worleynoise3d", "n", F),
    "position": node("position", "n", V3),
    "time": node("time", "n", F),
    "normalmap": node("normalmap", "n", V3),
    "geompropvalue": node("geompropvalue", "n", F, ("geomprop", "string", "foo")),
}


@pytest.mark.parametrize("case", sorted(UNSUPPORTED))
def test_unsupported_node_is_named(tmp_path, case):
    t = F if 'type="float"' in UNSUPPORTED[case] else V3
    (m,) = _load(tmp_path, _doc(UNSUPPORTED[case], "n", t))
    assert not m.error, m.error
    assert any(u.startswith("node n ") for u in m.unsupported), m.unsupported
    if t == F:  # connected directly: the input takes its default (through a convert: the convert's)
        assert m.parameters["base_diffuse_roughness"].kind == "default"


def test_undefined_value_fails_its_material_only(tmp_path):
    """ln(0) is -inf: that material fails naming the input; the file's other material is read."""
    body = _doc(node("ln", "a", F, ("in", F, 0.0)), "a", F, shader="S1", material="M1") + _doc(
        node("ln", "b", F, ("in", F, 1.0)), "b", F, shader="S2", material="M2"
    )
    mats = {m.name: m for m in _load(tmp_path, body)}
    assert "not finite" in mats["M1"].error and "S1" in mats["M1"].error and not mats["M1"].supported
    assert not mats["M2"].error and mats["M2"].parameters["base_diffuse_roughness"].value == 0.0


def test_undefined_value_in_an_unselected_branch_is_harmless(tmp_path):
    """GLSL computes both branches of an ifgreater: a NaN in the one not taken does not matter."""
    body = (
        node("sqrt", "bad", F, ("in", F, -1.0))
        + '  <ifgreater name="n" type="float"><input name="value1" type="float" value="1" />'
        '<input name="value2" type="float" value="0" /><input name="in1" type="float" value="0.3" />'
        '<input name="in2" type="float" nodename="bad" /></ifgreater>\n'
    )
    assert value(tmp_path, body, "n", F) == 0.3


_VALUE_OUT = ("float", "color3", "color4", "vector2", "vector3", "vector4")


def _library_value_nodedefs():
    lib = mxlib.library()
    out = []
    for nd in lib.getNodeDefs():
        outs = nd.getActiveOutputs()
        if len(outs) != 1 or outs[0].getType() not in _VALUE_OUT:
            continue
        if any(
            i.getType() not in _VALUE_OUT + ("integer", "boolean", "string", "filename", "matrix33", "matrix44")
            for i in nd.getActiveInputs()
        ):
            continue  # closures in (BSDF -> value nodes do not exist in the stdlib)
        out.append((nd.getName(), nd.getNodeString(), outs[0].getType()))
    return sorted(out)


def test_every_library_value_node_is_evaluated_or_named(tmp_path):
    """One material per value-typed nodedef of MaterialX's data library (its defaults as
    inputs), all in one file: the file is read, every material listed; each one is evaluated
    with a finite value, or lists its node as unsupported, or fails with a reason naming it."""
    defs = _library_value_nodedefs()
    assert len(defs) > 300
    body = []
    for k, (ndname, cat, t) in enumerate(defs):
        body.append(
            _doc(
                f'  <{cat} name="n{k}" type="{t}" nodedef="{ndname}" />\n', f"n{k}", t, shader=f"S{k}", material=f"M{k}"
            )
        )
    f = tmp_path / "library.mtlx"
    f.write_text('<?xml version="1.0"?>\n<materialx version="1.39">\n' + "".join(body) + "</materialx>\n")
    before = f.read_bytes()
    mats = {m.name: m for m in load_materials(f, uv=UV)}
    assert f.read_bytes() == before
    assert set(mats) == {f"M{k}" for k in range(len(defs))}
    evaluated = 0
    for k, (ndname, _cat, t) in enumerate(defs):
        m = mats[f"M{k}"]
        if m.error:
            assert str(f) in m.error and (f"S{k}" in m.error or f"n{k}" in m.error), (ndname, m.error)
            continue
        key = "base_diffuse_roughness" if t == "float" else "base_color"
        p = m.parameters[key]
        if p.kind == "default":
            assert any(f"n{k}" in u for u in m.unsupported), (ndname, m.unsupported, p.provenance)
        else:
            assert np.all(np.isfinite(np.asarray(p.value, dtype=np.float64))), (ndname, p.value)
            evaluated += 1
    assert evaluated > 0.6 * len(defs), evaluated
