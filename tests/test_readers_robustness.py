"""The readers on damaged and unusual files, each written here: bounded memory on corrupt USD
packages and crate files (checked by one child process, replaced when it dies), one outcome for a corrupt texture shared by several materials,
connections between outputs and inputs of different types, a MaterialX document as the root
of a .usdz, a float written as several numbers, leftovers of killed processes, and text
layers that are not UTF-8.

Expected values come from the formats' own definitions and libraries: the USDZ specification
(members stored, https://openusd.org/release/spec_usdz.html), the crate file's table of
contents as usd-core writes it, MaterialX's own value parsing (``createValueFromStrings``)
and its ``ND_convert_*`` nodegraphs, sRGB's closed form (IEC 61966-2-1) and USD's
``Gf.ColorSpace`` for the conversion to ACEScg.
"""

import json
import os
import resource
import signal
import struct
import subprocess
import sys
import textwrap
import time
import zipfile

import numpy as np
import pytest

from openpbr_diffuse.cli.main import main
from openpbr_diffuse.readers import load_materials, textures

MTLX_HEAD = '<?xml version="1.0"?>\n<materialx version="1.39">\n'


# ----------------------------------------------------------------------------- helpers
def _usdc(path):
    """A crate file holding one UsdPreviewSurface material, written by usd-core."""
    from pxr import Gf, Sdf, Usd, UsdShade

    stage = Usd.Stage.CreateNew(str(path))
    mat = UsdShade.Material.Define(stage, "/M")
    shader = UsdShade.Shader.Define(stage, "/M/S")
    shader.CreateIdAttr("UsdPreviewSurface")
    shader.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(0.5, 0.25, 0.125))
    mat.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), "surface")
    stage.Save()
    return path


def _sections(data):
    """{name: (start, size)} of a crate file's table of contents: "PXR-USDC", 8 version bytes,
    the TOC offset (int64); at the TOC a count (uint64) and 32-byte records (16-byte name,
    int64 start, int64 size)."""
    assert data[:8] == b"PXR-USDC"
    (toc,) = struct.unpack_from("<q", data, 16)
    (count,) = struct.unpack_from("<Q", data, toc)
    out = {}
    for k in range(count):
        name, start, size = struct.unpack_from("<16sqq", data, toc + 8 + 32 * k)
        out[name.rstrip(b"\0").decode()] = (start, size)
    return out


def _crafted_usdc(tmp_path, section, count=1 << 26):
    """A crate file whose ``section`` declares ``count`` elements (its first uint64) in a few
    bytes: usd-core allocates for them (2 GB for FIELDS or SPECS) before it finds the lie."""
    good = _usdc(tmp_path / "good.usdc").read_bytes()
    start, _ = _sections(good)[section]
    bad = bytearray(good)
    struct.pack_into("<Q", bad, start, count)
    out = tmp_path / f"crafted_{section.lower()}.usdc"
    out.write_bytes(bytes(bad))
    return out


def _usdz(path, members):
    """A package with usd-core's own writer (members in order, 64-byte aligned)."""
    from pxr import Sdf

    writer = Sdf.ZipFileWriter.CreateNew(str(path))
    for src, name in members:
        writer.AddFile(str(src), name)
    writer.Save()
    return path


_DRIVER = textwrap.dedent(
    """
    import contextlib, io, json, sys
    from openpbr_diffuse.cli.main import main
    from openpbr_diffuse.readers import guard
    budget, files = int(sys.argv[1]), sys.argv[2:]
    if budget:
        guard.STAGE_BUDGET_MB = budget
    out = []
    for f in files:
        err = io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            rc = main(["eval", f])
        out.append({"file": f, "rc": rc, "err": err.getvalue()})
    print(json.dumps(out))
    """
)

#: Address space of the measured process: a reader that lost its bound fails the test at this
#: size instead of taking the machine's memory.
SAFETY_AS = 6 << 30


def _eval_measured(files, budget=0):
    """``eval`` of each file in one child process: ([{file, rc, err}], the peak resident
    memory in bytes of that process and every process it started, from ``wait4``)."""

    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (SAFETY_AS, SAFETY_AS))

    proc = subprocess.Popen(
        [sys.executable, "-c", _DRIVER, str(budget), *map(str, files)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        preexec_fn=limit,
    )
    out = proc.stdout.read()
    err = proc.stderr.read()
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    assert proc.returncode == 0, err.decode()[-2000:]
    return json.loads(out), usage.ru_maxrss * 1024


# ----------------------------------------------------------------------------- bounded memory
def test_corrupt_packages_and_crate_files_read_in_bounded_memory(tmp_path):
    good = _usdc(tmp_path / "scene.usdc")
    pkg = _usdz(tmp_path / "good.usdz", [(good, "scene.usdc")])
    data = pkg.read_bytes()
    truncated = tmp_path / "truncated.usdz"
    truncated.write_bytes(data[: len(data) // 2])
    huge = tmp_path / "huge_member.usdz"  # the local header declares 10^9 bytes (usd-core reads it)
    b = bytearray(data)
    struct.pack_into("<II", b, 18, 10**9, 10**9)
    huge.write_bytes(bytes(b))
    fields = _crafted_usdc(tmp_path, "FIELDS")
    specs = _crafted_usdc(tmp_path, "SPECS")
    inside = _usdz(tmp_path / "crafted_inside.usdz", [(specs, "scene.usdc")])
    text_root = tmp_path / "text_root.usda"  # a small text layer whose sublayer is the crafted file
    text_root.write_text(f'#usda 1.0\n(\n    subLayers = [@{specs.name}@]\n)\ndef Material "M" {{}}\n')
    files = [truncated, huge, fields, specs, inside, text_root]

    results, peak = _eval_measured(files)
    assert peak < 1 << 30, f"peak resident memory {peak / 2**20:.0f} MB"
    for r in results:
        assert r["rc"] == 2, r
        lines = r["err"].strip().splitlines()
        assert len(lines) == 1 and r["file"] in lines[0] and "Traceback" not in r["err"], r
    said = {os.path.basename(r["file"]): r["err"] for r in results}
    assert "beyond the end of the file" in said["truncated.usdz"]
    assert "1000000000 bytes" in said["huge_member.usdz"]
    for name in ("crafted_fields.usdc", "crafted_specs.usdc", "crafted_inside.usdz", "text_root.usda"):
        assert "memory" in said[name], said[name]


def test_self_multiplying_text_layer_is_refused_within_the_budget(tmp_path):
    # each level holds two references to the level below: 2^24 prims from 30 lines
    lines = ["#usda 1.0\n", 'def "A0"\n{\n    def Material "M" {}\n}\n']
    for k in range(1, 25):
        lines.append(
            f'def "A{k}"\n{{\n    def "x" (references = </A{k - 1}>) {{}}\n'
            f'    def "y" (references = </A{k - 1}>) {{}}\n}}\n'
        )
    f = tmp_path / "doubling.usda"
    f.write_text("".join(lines))
    (r,), peak = _eval_measured([f], budget=64)
    assert r["rc"] == 2 and str(f) in r["err"] and "64 MB of memory" in r["err"], r
    assert peak < 1 << 30


def test_a_good_package_still_reads(tmp_path):
    pkg = _usdz(tmp_path / "good.usdz", [(_usdc(tmp_path / "scene.usdc"), "scene.usdc")])
    (m,) = load_materials(pkg)
    assert m.error == "" and m.supported
    np.testing.assert_allclose(m.parameters["diffuseColor"].authored, (0.5, 0.25, 0.125))


def test_compressed_package_member_is_refused_naming_it(tmp_path, capfd):
    src = _usdc(tmp_path / "scene.usdc")
    pkg = tmp_path / "deflated.usdz"
    with zipfile.ZipFile(pkg, "w", zipfile.ZIP_DEFLATED) as z:
        z.write(src, "scene.usdc")
    assert main(["eval", str(pkg)]) == 2
    err = capfd.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(pkg) in err[0] and "'scene.usdc' is compressed" in err[0]


# ----------------------------------------------------------------------------- one checking child
def _children(script):
    """Pids of this process's children running ``script`` (from /proc, not from the guard)."""
    me, found = os.getpid(), set()
    for name in os.listdir("/proc"):
        if not name.isdigit():
            continue
        try:
            with open(f"/proc/{name}/stat", "rb") as f:
                stat = f.read()
            with open(f"/proc/{name}/cmdline", "rb") as f:
                cmd = f.read()
        except OSError:
            continue
        fields = stat[stat.rfind(b")") + 2 :].split()
        if int(fields[1]) == me and fields[0] != b"Z" and script.encode() in cmd:
            found.add(int(name))
    return found


def _gone(pid, seconds=5.0):
    """Whether ``pid`` has ended (gone, or a zombie nobody reaped) within ``seconds``."""
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        try:
            with open(f"/proc/{pid}/stat", "rb") as f:
                stat = f.read()
        except OSError:
            return True
        if stat[stat.rfind(b")") + 2 :].split()[0] == b"Z":
            return True
        time.sleep(0.05)
    return False


def _referencing(path):
    """A text layer with a composition arc (checked in the child) holding one material."""
    path.write_text(f'#usda 1.0\ndef "A" (references = @{path.name}@</M>) {{}}\ndef Material "M" {{}}\n')
    return path


@pytest.fixture
def checker(monkeypatch):
    from openpbr_diffuse.readers import guard

    guard.CHECKER.stop()  # the process's own child, from the tests before: not counted here
    fresh = guard.StageChecker()
    monkeypatch.setattr(guard, "CHECKER", fresh)
    yield fresh
    fresh.stop()


def test_twenty_stages_are_checked_by_one_child(tmp_path, checker):
    from openpbr_diffuse.readers import guard

    files = [_referencing(tmp_path / f"s{k}.usda") for k in range(10)]
    files += [_usdc(tmp_path / f"s{k}.usdc") for k in range(10)]
    seen = set()
    t0 = time.monotonic()
    for f in files:
        assert guard.needs_child(str(f))
        guard.check_stage(str(f))
        seen |= _children("_usd_child.py")
    assert len(seen) == 1, seen  # one Python start and import of usd-core for all 20
    assert time.monotonic() - t0 < 15


def test_a_stage_that_kills_the_child_fails_alone_and_the_next_gets_a_fresh_child(tmp_path, checker):
    from openpbr_diffuse.readers import guard

    good = _usdc(tmp_path / "good.usdc")
    guard.check_stage(str(good))
    (first,) = _children("_usd_child.py")
    with pytest.raises(ValueError, match="needs more than 512 MB of memory"):
        guard.check_stage(str(_crafted_usdc(tmp_path, "FIELDS")))
    assert _gone(first)
    other = _usdc(tmp_path / "other.usdc")
    guard.check_stage(str(other))  # not blamed for its predecessor
    (second,) = _children("_usd_child.py")
    assert second != first


def test_a_child_killed_between_stages_is_replaced_without_blaming_the_next(tmp_path, checker):
    from openpbr_diffuse.readers import guard

    guard.check_stage(str(_referencing(tmp_path / "a.usda")))
    (first,) = _children("_usd_child.py")
    os.kill(first, signal.SIGKILL)
    assert _gone(first)
    guard.check_stage(str(_referencing(tmp_path / "b.usda")))
    (second,) = _children("_usd_child.py")
    assert second != first


def test_the_child_outlives_a_thread_that_started_it(tmp_path, checker):
    """PR_SET_PDEATHSIG fires when the thread that forked a child ends: the child must not."""
    import threading

    from openpbr_diffuse.readers import guard

    t = threading.Thread(target=guard.check_stage, args=(str(_referencing(tmp_path / "a.usda")),))
    t.start()
    t.join()
    (first,) = _children("_usd_child.py") or {None}
    time.sleep(0.3)
    guard.check_stage(str(_referencing(tmp_path / "b.usda")))
    assert _children("_usd_child.py") == {first}


def test_the_child_dies_with_its_parent(tmp_path):
    f = _referencing(tmp_path / "a.usda")
    code = (
        "import sys, time\nfrom openpbr_diffuse.readers import guard\n"
        f"guard.check_stage({str(f)!r})\nprint(guard.CHECKER.proc.pid, flush=True)\ntime.sleep(60)\n"
    )
    parent = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    try:
        child = int(parent.stdout.readline())
        assert not _gone(child, 0.2)
    finally:
        parent.kill()
        parent.wait()
    assert _gone(child)


# A stand-in for ``_usd_child.py`` (its protocol: "+" on receipt, then one JSON line): its
# stages named *.slow take a minute, those named *.grow leave it 100 MB larger.
_FAKE_CHILD = """
import json, sys, time
out = sys.stdout.buffer
for line in iter(sys.stdin.buffer.readline, b""):
    path = json.loads(line)["path"]
    out.write(b"+")
    out.flush()
    if path.endswith(".slow"):
        open(path + ".started", "w").close()
        time.sleep(60)
    vm = 100 << 20 if path.endswith(".grow") else 0
    out.write(json.dumps({"status": 0, "base": 0, "warm": 0, "vm": vm, "rss": 0, "layers": 0}).encode() + b"\\n")
    out.flush()
"""


@pytest.fixture
def fake(tmp_path):
    from openpbr_diffuse.readers import guard

    script = tmp_path / "fake_child.py"
    script.write_text(_FAKE_CHILD)
    c = guard.StageChecker([sys.executable, str(script)])
    yield c
    c.stop(kill=True)


def test_a_child_killed_during_a_stage_fails_that_stage_and_is_replaced(tmp_path, fake):
    import threading

    slow = tmp_path / "x.slow"
    out = []
    t = threading.Thread(target=lambda: out.append(fake.check(str(slow))))
    t.start()
    deadline = time.monotonic() + 10
    while not (tmp_path / "x.slow.started").exists() and time.monotonic() < deadline:
        time.sleep(0.02)
    (first,) = _children("fake_child.py")
    os.kill(first, signal.SIGKILL)
    t.join(10)
    assert out == [("died", -signal.SIGKILL)]
    assert fake.check(str(tmp_path / "next.usda")) == ("ok", 0)
    assert _children("fake_child.py") - {first}


def test_a_stage_past_the_time_limit_is_refused_and_its_child_killed(tmp_path, fake):
    t0 = time.monotonic()
    assert fake.check(str(tmp_path / "x.slow"), timeout=0.5) == ("timeout", 0)
    assert time.monotonic() - t0 < 5
    assert not _children("fake_child.py")
    assert fake.check(str(tmp_path / "next.usda")) == ("ok", 0)


def test_a_timeout_is_one_line_naming_the_file(tmp_path, fake, monkeypatch):
    from openpbr_diffuse.readers import guard

    f = _referencing(tmp_path / "a.usda")
    monkeypatch.setattr(guard, "CHECKER", fake)
    monkeypatch.setattr(guard, "STAGE_TIMEOUT", 0.5)
    monkeypatch.setattr(fake, "check", lambda *a, **k: ("timeout", 0))
    with pytest.raises(ValueError, match=r"not read: usd-core did not finish opening it within 0.5 s") as e:
        guard.check_stage(str(f))
    assert str(f) in str(e.value) and "\n" not in str(e.value)


def test_the_child_is_replaced_after_its_quota_of_stages_and_when_it_grew(tmp_path, fake, monkeypatch):
    from openpbr_diffuse.readers import guard

    monkeypatch.setattr(guard, "CHILD_FILES", 3)
    pids = []
    for k in range(7):
        assert fake.check(str(tmp_path / f"{k}.usda")) == ("ok", 0)
        pids.append(_children("fake_child.py"))
    assert [len(p) for p in pids] == [1, 1, 0, 1, 1, 0, 1]  # stopped after the 3rd and 6th stage
    assert fake.check(str(tmp_path / "a.grow")) == ("ok", 0)  # 100 MB > CHILD_GROWTH_MB
    assert not _children("fake_child.py")


# ----------------------------------------------------------------------------- shared corrupt texture
def _corrupt_png(path):
    """A 64 x 64 PNG whose compressed pixel data is damaged (the header still reads)."""
    import OpenImageIO as oiio

    px = (np.arange(64 * 64 * 3) % 251).astype(np.uint8).reshape(64, 64, 3)
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), oiio.ImageSpec(64, 64, 3, "uint8"))
    assert out.write_image(px)
    out.close()
    data = bytearray(path.read_bytes())
    idat = data.index(b"IDAT") + 8
    for i in range(idat + 20, idat + 60):
        data[i] ^= 0x55
    path.write_bytes(bytes(data))
    return path


def _three_mtlx(folder):
    body = "".join(
        f'  <image name="img{k}" type="color3"><input name="file" type="filename" value="bad.png" />'
        f'<input name="default" type="color3" value="0.1, 0.2, 0.3" /></image>\n'
        f'  <open_pbr_surface name="S{k}" type="surfaceshader"><input name="base_color" type="color3" '
        f'nodename="img{k}" /></open_pbr_surface>\n'
        f'  <surfacematerial name="M{k}" type="material"><input name="surfaceshader" type="surfaceshader" '
        f'nodename="S{k}" /></surfacematerial>\n'
        for k in range(3)
    )
    f = folder / "three.mtlx"
    f.write_text(MTLX_HEAD + body + "</materialx>\n")
    return f, "base_color", (0.1, 0.2, 0.3)


def _three_usda(folder):
    body = "".join(
        f"""
def Material "M{k}"
{{
    token outputs:surface.connect = </M{k}/S.outputs:surface>
    def Shader "S"
    {{
        uniform token info:id = "UsdPreviewSurface"
        color3f inputs:diffuseColor.connect = </M{k}/T.outputs:rgb>
        token outputs:surface
    }}
    def Shader "T"
    {{
        uniform token info:id = "UsdUVTexture"
        asset inputs:file = @bad.png@
        float4 inputs:fallback = (0.1, 0.2, 0.3, 1)
        float3 outputs:rgb
    }}
}}
"""
        for k in range(3)
    )
    f = folder / "three.usda"
    f.write_text("#usda 1.0\n" + body)
    return f, "diffuseColor", (0.1, 0.2, 0.3)


@pytest.mark.parametrize("make", [_three_mtlx, _three_usda], ids=["mtlx", "usda"])
def test_corrupt_texture_shared_by_three_materials_falls_back_alike(tmp_path, capfd, make):
    _corrupt_png(tmp_path / "bad.png")
    f, name, fallback = make(tmp_path)
    mats = load_materials(f)
    assert len(mats) == 3
    for m in mats:
        assert m.error == "" and m.supported, m.error
        np.testing.assert_allclose(m.parameters[name].value, fallback)
        said = [w for w in m.warnings if "bad.png" in w]
        assert len(said) == 1 and "IDAT" in said[0], m.warnings
    assert "libpng" not in capfd.readouterr().err
    assert main(["eval", str(f)]) == 0
    assert "libpng" not in capfd.readouterr().err


# ----------------------------------------------------------------------------- connection types
def test_colour_input_on_a_uv_output_is_converted_as_materialx_converts(tmp_path, capfd):
    import MaterialX as mx

    # MaterialX's own ND_convert_vector2_color3 graph: combine3(x, y, 0)
    lib = mx.createDocument()
    mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), lib)
    graph = lib.getNodeGraph("NG_convert_vector2_color3")
    combine = graph.getNode("combine")
    assert combine.getCategory() == "combine3" and combine.getInput("in3").getValue() == 0.0

    f = tmp_path / "uv.mtlx"
    f.write_text(
        MTLX_HEAD + '  <texcoord name="tc" type="vector2" />\n'
        '  <open_pbr_surface name="S1" type="surfaceshader"><input name="base_color" type="color3" nodename="tc" />'
        "</open_pbr_surface>\n"
        '  <surfacematerial name="M1" type="material"><input name="surfaceshader" type="surfaceshader" '
        'nodename="S1" /></surfacematerial>\n'
        '  <open_pbr_surface name="S2" type="surfaceshader"><input name="base_weight" type="float" nodename="tc" />'
        "</open_pbr_surface>\n"
        '  <surfacematerial name="M2" type="material"><input name="surfaceshader" type="surfaceshader" '
        'nodename="S2" /></surfacematerial>\n'
        '  <open_pbr_surface name="S3" type="surfaceshader"><input name="base_color" type="color3" '
        'value="0.5, 0.5, 0.5" /></open_pbr_surface>\n'
        '  <surfacematerial name="M3" type="material"><input name="surfaceshader" type="surfaceshader" '
        'nodename="S3" /></surfacematerial>\n'
        "</materialx>\n"
    )
    m1, m2, m3 = load_materials(f, uv=(0.25, 0.75))
    assert m1.error == "" and m1.supported
    np.testing.assert_allclose(m1.parameters["base_color"].value, (0.25, 0.75, 0.0))
    assert any("ND_convert_vector2_color3" in w for w in m1.warnings)
    # MaterialX has no vector2 -> float conversion: that material fails, naming file and input
    assert not m2.supported and str(f) in m2.error and "S2/base_weight" in m2.error
    assert m3.error == "" and m3.supported
    assert main(["eval", str(f)]) == 1
    err = capfd.readouterr().err
    assert "M2" in err and "M1" not in err and "Traceback" not in err


def test_usd_colour_input_on_a_primvar_uv_is_converted(tmp_path):
    f = tmp_path / "uv.usda"
    f.write_text(
        textwrap.dedent(
            """\
            #usda 1.0
            def Material "M1"
            {
                token outputs:surface.connect = </M1/S.outputs:surface>
                def Shader "S"
                {
                    uniform token info:id = "UsdPreviewSurface"
                    color3f inputs:diffuseColor.connect = </M1/uv.outputs:result>
                    token outputs:surface
                }
                def Shader "uv"
                {
                    uniform token info:id = "UsdPrimvarReader_float2"
                    string inputs:varname = "st"
                    float2 outputs:result
                }
            }
            def Material "M2"
            {
                token outputs:surface.connect = </M2/S.outputs:surface>
                def Shader "S"
                {
                    uniform token info:id = "UsdPreviewSurface"
                    color3f inputs:diffuseColor = (0.5, 0.5, 0.5)
                    token outputs:surface
                }
            }
            """
        )
    )
    m1, m2 = load_materials(f, uv=(0.25, 0.75))
    assert m1.error == "" and m1.supported and m2.error == "" and m2.supported
    np.testing.assert_allclose(m1.parameters["diffuseColor"].value, (0.25, 0.75, 0.0))
    assert main(["eval", str(f)]) == 0


# ----------------------------------------------------------------------------- MaterialX root of a package
def _srgb_decode(c):
    c = np.asarray(c, dtype=np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def _rec709_to_acescg(rgb):
    from pxr import Gf

    src, dst = Gf.ColorSpace(Gf.ColorSpaceNames.LinearRec709), Gf.ColorSpace(Gf.ColorSpaceNames.LinearAP1)
    return np.array(dst.Convert(src, Gf.Vec3f(*map(float, rgb))).GetRGB())


def test_usdz_whose_root_is_a_materialx_document(tmp_path, monkeypatch):
    import OpenImageIO as oiio

    texels = np.array([[[200, 100, 50], [10, 20, 30]], [[0, 0, 0], [255, 255, 255]]], dtype=np.uint8)
    png = tmp_path / "a.png"
    out = oiio.ImageOutput.create(str(png))
    assert out.open(str(png), oiio.ImageSpec(2, 2, 3, "uint8"))
    assert out.write_image(texels)
    out.close()
    (tmp_path / "outside.mtlx").write_text(MTLX_HEAD + '  <constant name="outside" type="float" />\n</materialx>\n')
    doc = (
        MTLX_HEAD.replace("<materialx ", '<materialx xmlns:xi="http://www.w3.org/2001/XInclude" ')
        + '  <xi:include href="outside.mtlx" />\n'
        '  <image name="img" type="color3"><input name="file" type="filename" value="textures/a.png" '
        'colorspace="srgb_texture" /></image>\n'
        '  <open_pbr_surface name="S" type="surfaceshader"><input name="base_color" type="color3" nodename="img" />'
        "</open_pbr_surface>\n"
        '  <surfacematerial name="M" type="material"><input name="surfaceshader" type="surfaceshader" '
        'nodename="S" /></surfacematerial>\n'
        "</materialx>\n"
    )
    pkg = tmp_path / "pkg" / "look.usdz"
    pkg.parent.mkdir()
    with zipfile.ZipFile(pkg, "w", zipfile.ZIP_STORED) as z:
        z.writestr("look.mtlx", doc)
        z.write(png, "textures/a.png")
    png.unlink()
    monkeypatch.chdir(tmp_path)  # outside.mtlx would be found here if the include were read
    (m,) = load_materials(pkg, uv=(0.25, 0.75))
    assert m.error == "" and m.supported and m.file == str(pkg)
    want = _rec709_to_acescg(_srgb_decode(texels[0, 0] / 255.0))
    np.testing.assert_allclose(m.parameters["base_color"].value, want, atol=5e-6)
    assert f"{pkg}[textures/a.png]" in m.parameters["base_color"].provenance
    assert any("outside.mtlx" in w and "not read" in w for w in m.warnings), m.warnings


# ----------------------------------------------------------------------------- a float written as several numbers
def test_float_written_as_three_numbers_reads_as_materialx_does(tmp_path):
    import MaterialX as mx

    text = "0.482,0.169,0.109"
    f = tmp_path / "f.mtlx"
    f.write_text(
        MTLX_HEAD + f'  <open_pbr_surface name="S" type="surfaceshader"><input name="coat_roughness" type="float" '
        f'value="{text}" /><input name="base_color" type="color3" value="0.2, 0.4, 0.6" /></open_pbr_surface>\n'
        '  <surfacematerial name="M" type="material"><input name="surfaceshader" type="surfaceshader" '
        'nodename="S" /></surfacematerial>\n</materialx>\n'
    )
    (m,) = load_materials(f)
    assert m.error == "" and m.supported
    theirs = mx.createValueFromStrings(text, "float")  # MaterialX's own reading (float32)
    assert np.float32(m.parameters["coat_roughness"].value) == np.float32(theirs)
    said = [w for w in m.warnings if text in w]
    assert len(said) == 1 and str(f) in said[0] and "material M" in said[0] and "S/coat_roughness" in said[0]


# ----------------------------------------------------------------------------- leftovers of killed processes
def _dead_pid():
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


def _stamped(folder, pid, start=""):
    folder.mkdir()
    (folder / textures.STAMP).write_text(f"{pid} {start}\n")
    (folder / "member.png").write_bytes(b"x")
    return folder


def test_leftover_folders_of_dead_owners_are_removed_and_nothing_else(tmp_path):
    base = tmp_path / "tmp"
    base.mkdir()
    dead = _stamped(base / f"{textures.PREFIX}dead", _dead_pid())
    live_proc = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        live = _stamped(base / f"{textures.PREFIX}live", live_proc.pid)
        # the pid runs, but it is another process than the one that wrote the stamp (Linux
        # /proc/PID/stat field 22, the start time, differs): a reused pid
        reused = _stamped(base / f"{textures.PREFIX}reused", live_proc.pid, "1")
        unstamped = base / f"{textures.PREFIX}nostamp"
        unstamped.mkdir()
        other = _stamped(base / "someone_else", _dead_pid())
        target = _stamped(tmp_path / "target", _dead_pid())  # reached only through a link
        link = base / f"{textures.PREFIX}link"
        link.symlink_to(target, target_is_directory=True)
        removed = textures.remove_leftovers(str(base))
        gone = [dead, reused] if os.path.exists(f"/proc/{live_proc.pid}/stat") else [dead]
        assert sorted(removed) == sorted(map(str, gone))
        assert not any(g.exists() for g in gone)
        for kept in (live, unstamped, other, target, target / "member.png"):
            assert kept.exists(), kept
        assert link.is_symlink()
    finally:
        live_proc.kill()
        live_proc.wait()


def test_folder_of_a_killed_reader_is_removed_by_the_next(tmp_path):
    env = dict(os.environ, TMPDIR=str(tmp_path))
    code = (
        "import sys, time\nfrom openpbr_diffuse.readers import textures\n"
        "print(textures._private_dir(), flush=True)\ntime.sleep(60)\n"
    )
    first = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, env=env, text=True)
    try:
        folder = first.stdout.readline().strip()
    finally:
        first.send_signal(signal.SIGKILL)  # no exit handler runs
        first.wait()
    assert os.path.isdir(folder) and os.path.dirname(folder) == str(tmp_path)
    second = subprocess.run(
        [sys.executable, "-c", "from openpbr_diffuse.readers import textures\nprint(textures._private_dir())"],
        capture_output=True,
        text=True,
        env=env,
        check=True,
    )
    deadline = time.monotonic() + 5
    while os.path.exists(folder) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not os.path.exists(folder)
    assert not os.path.exists(second.stdout.strip())  # the second one removed its own at exit


# ----------------------------------------------------------------------------- text that is not UTF-8
def test_usda_that_is_not_utf8_is_one_line_naming_file_and_position(tmp_path, capfd):
    f = tmp_path / "latin1.usda"
    f.write_bytes(b'#usda 1.0\n# caf\xe9\ndef Material "M"\n{\n}\n')
    assert main(["eval", str(f)]) == 2
    err = capfd.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(f) in err[0], err
    assert "byte 0xe9 at line 2, column 6" in err[0], err
