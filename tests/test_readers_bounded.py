"""Bounded work on hostile graphs: shared nodes evaluated once, long chains evaluated or
failed per material (never a RecursionError), FIFOs refused by type before opening."""

import os

import pytest

from openpbr_diffuse.cli.main import main
from openpbr_diffuse.readers import load_materials, ops
from openpbr_diffuse.readers.graph import MAX_CHAIN

HEAD = '<?xml version="1.0"?>\n<materialx version="1.39">\n'
TAIL = """  <open_pbr_surface name="S" type="surfaceshader">
    <input name="base_diffuse_roughness" type="float" nodename="n{last}" />
  </open_pbr_surface>
  <surfacematerial name="M" type="material"><input name="surfaceshader" type="surfaceshader" nodename="S" /></surfacematerial>
</materialx>
"""


def _doubling(tmp_path, n):
    """n add nodes, each reading the previous one twice: n_k = 2 n_(k-1), n_0 = 2^-n."""
    lines = [f'  <constant name="n0" type="float"><input name="value" type="float" value="{2.0**-n!r}" /></constant>\n']
    for k in range(1, n + 1):
        lines.append(
            f'  <add name="n{k}" type="float"><input name="in1" type="float" nodename="n{k - 1}" />'
            f'<input name="in2" type="float" nodename="n{k - 1}" /></add>\n'
        )
    f = tmp_path / f"doubling{n}.mtlx"
    f.write_text(HEAD + "".join(lines) + TAIL.format(last=n))
    return f


def _chain(tmp_path, n, step=0.001):
    """n add nodes in a chain, each adding ``step``: the end is n * step."""
    lines = ['  <constant name="n0" type="float"><input name="value" type="float" value="0" /></constant>\n']
    for k in range(1, n + 1):
        lines.append(
            f'  <add name="n{k}" type="float"><input name="in1" type="float" nodename="n{k - 1}" />'
            f'<input name="in2" type="float" value="{step!r}" /></add>\n'
        )
    f = tmp_path / f"chain{n}.mtlx"
    f.write_text(HEAD + "".join(lines) + TAIL.format(last=n))
    return f


def test_shared_nodes_are_evaluated_once(tmp_path, monkeypatch):
    calls = []
    real = ops.apply
    monkeypatch.setattr(ops, "apply", lambda cat, *a, **k: calls.append(cat) or real(cat, *a, **k))
    (m,) = load_materials(_doubling(tmp_path, 12))
    assert m.error == ""
    # 12 add nodes + 1 constant, once each (2^13 - 1 evaluations without memoisation)
    assert calls.count("add") == 12
    assert m.parameters["base_diffuse_roughness"].value == 1.0


def test_26_nodes_each_read_twice(tmp_path):
    (m,) = load_materials(_doubling(tmp_path, 26))
    assert m.error == "" and m.parameters["base_diffuse_roughness"].value == 1.0  # 2^26 * 2^-26


def test_600_node_chain_is_evaluated(tmp_path):
    (m,) = load_materials(_chain(tmp_path, 600))
    assert m.error == ""
    assert m.parameters["base_diffuse_roughness"].value == pytest.approx(0.6, rel=1e-12)


def test_chain_beyond_the_documented_depth_fails_its_material(tmp_path):
    (m,) = load_materials(_chain(tmp_path, MAX_CHAIN + 50, step=1e-4))
    assert not m.supported and f"deeper than {MAX_CHAIN}" in m.error


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this platform")
def test_fifo_is_refused_before_opening(tmp_path, capfd):
    fifo = tmp_path / "pipe.mtlx"
    os.mkfifo(fifo)  # opening it for reading would block forever
    with pytest.raises(ValueError, match="is a FIFO"):
        load_materials(fifo)
    assert main(["eval", str(fifo)]) == 2
    err = [ln for ln in capfd.readouterr().err.splitlines() if ln.strip()]
    assert len(err) == 1 and "is a FIFO" in err[0]


def test_device_is_refused(capfd):
    if not os.path.exists("/dev/null"):
        pytest.skip("no /dev/null")
    assert main(["eval", "/dev/null"]) == 2
    assert "is a device" in capfd.readouterr().err


def test_usd_shared_shaders_are_evaluated_once(tmp_path, monkeypatch):
    from pxr import Sdf, Usd, UsdShade

    st = Usd.Stage.CreateNew(str(tmp_path / "d.usda"))
    mat = UsdShade.Material.Define(st, "/M")
    sh = UsdShade.Shader.Define(st, "/M/S")
    sh.CreateIdAttr("ND_open_pbr_surface_surfaceshader")
    mat.CreateSurfaceOutput("mtlx").ConnectToSource(sh.CreateOutput("out", Sdf.ValueTypeNames.Token))
    n = 24
    prev = UsdShade.Shader.Define(st, "/M/n0")
    prev.CreateIdAttr("ND_constant_float")
    prev.CreateInput("value", Sdf.ValueTypeNames.Float).Set(2.0**-n)
    for k in range(1, n + 1):
        s = UsdShade.Shader.Define(st, f"/M/n{k}")
        s.CreateIdAttr("ND_add_float")
        out = prev.CreateOutput("out", Sdf.ValueTypeNames.Float)
        s.CreateInput("in1", Sdf.ValueTypeNames.Float).ConnectToSource(out)
        s.CreateInput("in2", Sdf.ValueTypeNames.Float).ConnectToSource(out)
        prev = s
    sh.CreateInput("base_diffuse_roughness", Sdf.ValueTypeNames.Float).ConnectToSource(
        prev.CreateOutput("out", Sdf.ValueTypeNames.Float)
    )
    st.GetRootLayer().Save()
    calls = []
    real = ops.apply
    monkeypatch.setattr(ops, "apply", lambda cat, *a, **k: calls.append(cat) or real(cat, *a, **k))
    (m,) = load_materials(tmp_path / "d.usda")
    assert m.error == "" and calls.count("add") == n
    assert m.parameters["base_diffuse_roughness"].value == pytest.approx(1.0, rel=1e-6)  # float32 2^-24 * 2^24


def test_pathologically_nested_usd_layer_is_refused_before_usd_core(tmp_path):
    """~10^5 nested prims crash usd-core (segfault); the reader refuses the layer with one line."""
    import subprocess
    import sys
    from pathlib import Path

    depth = 100_000
    text = "#usda 1.0\n" + "".join(f'def Xform "p{i}" {{\n' for i in range(depth)) + "}\n" * depth
    f = tmp_path / "nested.usda"
    f.write_text(text)
    root = Path(__file__).resolve().parents[1]
    p = subprocess.run(
        [sys.executable, "-m", "openpbr_diffuse", "eval", str(f)],
        capture_output=True,
        text=True,
        env={"PYTHONPATH": str(root), "PATH": "/usr/bin:/bin"},
        timeout=120,
    )
    assert p.returncode == 2, (p.returncode, p.stderr[-500:])
    assert "nested 100000 levels deep" in p.stderr and len(p.stderr.strip().splitlines()) == 1
