"""Bad input to the readers and the eval/render commands: one clear line on stderr and exit
status 2 (or a warning and a defined result), never a traceback; files never modified."""

import json
import re

import pytest

from openpbr_diffuse.cli.main import main
from openpbr_diffuse.readers import BUNDLED_MATERIALS, load_materials

CYCLE = """<?xml version="1.0"?>
<materialx version="1.39">
  <add name="a" type="float"><input name="in1" type="float" nodename="b" /></add>
  <add name="b" type="float"><input name="in1" type="float" nodename="a" /></add>
  <open_pbr_surface name="S" type="surfaceshader"><input name="base_weight" type="float" nodename="a" /></open_pbr_surface>
  <surfacematerial name="M" type="material"><input name="surfaceshader" type="surfaceshader" nodename="S" /></surfacematerial>
</materialx>"""

WRONG_TYPE = """#usda 1.0
def Material "M"
{
    token outputs:mtlx:surface.connect = </M/S.outputs:out>
    def Shader "S"
    {
        uniform token info:id = "ND_open_pbr_surface_surfaceshader"
        string inputs:base_diffuse_roughness = "rough"
        token outputs:out
    }
}
"""

OUT_OF_RANGE = """<?xml version="1.0"?>
<materialx version="1.39" colorspace="acescg">
  <open_pbr_surface name="S" type="surfaceshader">
    <input name="base_color" type="color3" value="1.2, 0.5, -0.1" />
    <input name="base_weight" type="float" value="1.5" />
  </open_pbr_surface>
  <surfacematerial name="M" type="material"><input name="surfaceshader" type="surfaceshader" nodename="S" /></surfacematerial>
</materialx>"""

MISSING_TEXTURE = """<?xml version="1.0"?>
<materialx version="1.39" colorspace="acescg">
  <image name="img" type="color3">
    <input name="file" type="filename" value="no_such_texture.png" />
    <input name="default" type="color3" value="0.25, 0.5, 0.75" />
  </image>
  <open_pbr_surface name="S" type="surfaceshader"><input name="base_color" type="color3" nodename="img" /></open_pbr_surface>
  <surfacematerial name="M" type="material"><input name="surfaceshader" type="surfaceshader" nodename="S" /></surfacematerial>
</materialx>"""


def _run(capfd, *argv):
    rc = main(list(argv))
    out, err = capfd.readouterr()
    return rc, out, err


def _one_error_line(err):
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, err
    # "openpbr-diffuse eval: error: ..." (the program and sub-command, as argparse names them)
    assert "Traceback" not in err and re.match(r"openpbr-diffuse (eval|render): error: ", lines[0]), lines[0]
    return lines[0]


def _files(tmp_path):
    f = {
        "cycle.mtlx": CYCLE,
        "wrong.usda": WRONG_TYPE,
        "range.mtlx": OUT_OF_RANGE,
        "tex.mtlx": MISSING_TEXTURE,
        "bad.mtlx": "<materialx version='1.39'><open_pbr_surface name='S' </materialx>",
        "bad.usda": "#usda 1.0\ndef Material \"M\" {{{ nonsense\n",
        "empty.usda": "",
        "notes.txt": "not a material",
    }
    for name, text in f.items():
        (tmp_path / name).write_text(text)
    return tmp_path


@pytest.mark.parametrize(
    "args, needle",
    [
        (["missing.usda"], "no such file"),
        (["missing.mtlx"], "no such file"),
        (["."], "directory"),
        (["notes.txt"], "unknown file type"),
        (["bad.mtlx"], "not a readable MaterialX document"),
        (["bad.usda"], "not a readable USD stage"),
        (["range.mtlx", "--material", "Nope"], "no material or prim 'Nope'"),
        (["wrong.usda", "--variant", "finish=matte"], "variant set 'finish'"),
        (["range.mtlx", "--variant", "a=b"], "variants apply to USD"),
        (["range.mtlx", "--variant", "nonsense"], "SET=VALUE"),
        (["range.mtlx", "--theta-i", "120"], "theta_i"),
        (["range.mtlx", "--theta-i", "10", "20", "--theta-o", "1", "2", "3"], "same number"),
        (["range.mtlx", "--uv", "nan", "0"], "uv must be finite"),
    ],
)
def test_eval_bad_input_one_line_exit_2(tmp_path, monkeypatch, capfd, args, needle):
    monkeypatch.chdir(_files(tmp_path))
    rc, out, err = _run(capfd, "eval", *args)
    assert rc == 2
    assert needle in _one_error_line(err)


@pytest.mark.parametrize("name, needle", [("cycle.mtlx", "connection cycle"), ("wrong.usda", "base_diffuse_roughness")])
def test_eval_material_that_cannot_be_evaluated_exit_1(tmp_path, monkeypatch, capfd, name, needle):
    """The material is listed with its path and reason; exit 1; no traceback."""
    monkeypatch.chdir(_files(tmp_path))
    rc, out, err = _run(capfd, "eval", name)
    assert rc == 1 and "Traceback" not in err
    assert "# M  [not evaluated]" in out or "# /M  [not evaluated]" in out, out
    assert needle in out and "could not be evaluated: " in err
    rc, out, err = _run(capfd, "eval", name, "--json")
    (m,) = json.loads(out)["materials"]
    assert rc == 1 and needle in m["error"] and m["supported"] is False


def test_malformed_usd_diagnostics_do_not_leak(tmp_path, monkeypatch, capfd):
    monkeypatch.chdir(_files(tmp_path))
    rc, _, err = _run(capfd, "eval", "bad.usda")
    assert rc == 2 and len(err.strip().splitlines()) == 1


def test_out_of_range_values_clamped_with_warning(tmp_path, monkeypatch, capfd):
    monkeypatch.chdir(_files(tmp_path))
    rc, out, err = _run(capfd, "eval", "range.mtlx", "--json")
    assert rc == 0
    (m,) = json.loads(out)["materials"]
    assert m["node_inputs"]["base_color"]["value"] == [1.0, 0.5, 0.0]
    assert m["node_inputs"]["base_weight"]["value"] == 1.0
    assert m["parameters"]["base_weight"]["value"] == 1.5
    assert sum("clamped" in w for w in m["warnings"]) == 2
    assert m["evaluation"]["brdf"] is not None


def test_missing_texture_warns_and_uses_default(tmp_path, monkeypatch, capfd):
    monkeypatch.chdir(_files(tmp_path))
    (m,) = load_materials("tex.mtlx")
    assert m.parameters["base_color"].value == (0.25, 0.5, 0.75)
    assert any("no_such_texture.png" in w for w in m.warnings)
    rc, out, _ = _run(capfd, "eval", "tex.mtlx")
    assert rc == 0 and "no_such_texture.png" in out


def test_render_bad_input(tmp_path, monkeypatch, capfd):
    monkeypatch.chdir(_files(tmp_path))
    rc, _, err = _run(capfd, "render", str(BUNDLED_MATERIALS / "clay_rough.mtlx"), "--out", "x.bmpx")
    assert rc == 2 and ".exr or .png" in _one_error_line(err)
    rc, _, err = _run(capfd, "render", str(BUNDLED_MATERIALS / "terracotta_bound.usda"), "--out", "x.png")
    assert rc == 2 and "choose one with --material" in _one_error_line(err)
    rc, _, err = _run(capfd, "render", str(BUNDLED_MATERIALS / "clay_rough.mtlx"), "--out", "x.png", "--size", "2")
    assert rc == 2 and "size" in _one_error_line(err)


def test_unsupported_material_is_listed_not_an_error(tmp_path, capfd):
    f = tmp_path / "g.mtlx"
    f.write_text("""<?xml version="1.0"?>
<materialx version="1.39">
  <disney_principled name="G" type="surfaceshader"><input name="base_color" type="color3" value="1, 0, 0" /></disney_principled>
  <surfacematerial name="M" type="material"><input name="surfaceshader" type="surfaceshader" nodename="G" /></surfacematerial>
</materialx>""")
    rc, out, _ = _run(capfd, "eval", str(f))
    assert rc == 0 and "ND_disney_principled" in out and "not supported" in out


def test_files_are_never_modified(tmp_path, capfd):
    """Every bundled file and every bad file: bytes identical after load, eval and render."""
    files = sorted(p for p in BUNDLED_MATERIALS.rglob("*") if p.is_file())
    before = {p: p.read_bytes() for p in files}
    for p in files:
        if p.suffix in (".usda", ".mtlx"):
            for m in load_materials(p, variants=["finish=gloss"] if p.name == "paint_variants.usda" else None):
                m.node()
            assert main(["eval", str(p), "--json"]) == 0
    assert (
        main(
            [
                "render",
                str(BUNDLED_MATERIALS / "paint_variants.usda"),
                "--variant",
                "finish=gloss",
                "--out",
                str(tmp_path / "p.png"),
                "--size",
                "16",
            ]
        )
        == 0
    )
    capfd.readouterr()
    assert {p: p.read_bytes() for p in files} == before
    assert not any(p.name.endswith((".usda~", ".bak")) for p in BUNDLED_MATERIALS.rglob("*"))
