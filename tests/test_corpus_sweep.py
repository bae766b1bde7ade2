"""The real-world corpus sweep (../shared/corpus/realworld: MaterialX's test suite and examples,
usd-wg/assets, kwokcb/materialxusd): every material file is read as a pipeline engineer would,
and checked against MaterialX's and usd-core's own reading, done here.

- no traceback; a file the reader refuses is one MaterialX (``readFromXmlFile``) or usd-core
  (``Usd.Stage.Open``) refuses too;
- every renderable element MaterialX's ``findRenderableElements`` finds (standard libraries
  loaded as MaterialX loads them) and every ``UsdShade.Material`` prim of a stage is listed,
  by its path;
- for a fixed sample of materials the base colour, diffuse roughness and weights (textures at
  two uv points) equal a reading done here with MaterialX / pxr / OpenImageIO calls: input
  values parsed by MaterialX or read by usd-core, nodedef / Sdr defaults, colours converted to
  ACEScg with ``pxr.Gf.ColorSpace``, texels read by ``OpenImageIO.ImageBuf`` and interpolated
  here;
- the totals in docs/guide/materials.md are the totals of this sweep.
"""

import functools
import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("OPENPBR_DIFFUSE_SHARED") or ROOT.parent / "shared")
REALWORLD = SHARED / "corpus" / "realworld"
HAS_CORPUS = REALWORLD.is_dir()
corpus = [pytest.mark.corpus, pytest.mark.skipif(not HAS_CORPUS, reason="../shared/corpus/realworld is absent")]


@functools.lru_cache(maxsize=1)
def _bench():
    spec = importlib.util.spec_from_file_location("bench_readers", ROOT / "tools" / "bench_readers.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


FILES = _bench().corpus_files(REALWORLD) if HAS_CORPUS else []


def _rel(p):
    return str(Path(p).relative_to(REALWORLD))


@functools.cache
def _record(path):
    return _bench().sweep_file(path)


@functools.lru_cache(maxsize=1)
def _stdlib():
    import MaterialX as mx

    lib = mx.createDocument()
    mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), lib)
    return lib


def _mx_doc(path):
    import MaterialX as mx

    doc = mx.createDocument()
    mx.readFromXmlFile(doc, str(path))
    doc.setDataLibrary(_stdlib())
    return doc


# ----------------------------------------------------------------------------- the sweep
def _refused_by_owner(path):
    """Whether MaterialX (.mtlx) or usd-core (.usd*) refuses the file itself."""
    try:
        if path.suffix.lower() == ".mtlx":
            _mx_doc(path)
        else:
            from pxr import Usd

            if Usd.Stage.Open(str(path)) is None:
                return True
    except Exception:
        return True
    return False


def _expected_paths(path):
    """What MaterialX / usd-core find in the file: renderable elements, UsdShade materials."""
    if path.suffix.lower() == ".mtlx":
        from MaterialX import PyMaterialXGenShader as gen

        doc = _mx_doc(path)
        return {e.getNamePath(): e for e in gen.findRenderableElements(doc)}
    from pxr import Usd, UsdShade

    stage = Usd.Stage.Open(str(path))
    it = stage.Traverse(Usd.TraverseInstanceProxies(Usd.PrimAllPrimsPredicate))
    return {str(p.GetPath()): p for p in it if p.IsA(UsdShade.Material)}


def _check_file(path):
    rec = _record(path)
    assert rec["traceback"] is None, rec["traceback"]
    if rec["rejected"] is not None:
        assert _refused_by_owner(path), (
            f"refused, but {'MaterialX' if path.suffix == '.mtlx' else 'usd-core'} reads it: {rec['rejected']}"
        )
        return
    listed = {m[0] for m in rec["materials"]}
    missed = sorted(set(_expected_paths(path)) - listed)
    assert not missed, f"not listed: {missed[:10]}"
    assert rec["finite"], "a supported material's BRDF is not finite"
    for mpath, sid, supported, error, _out in rec["materials"]:
        assert supported or error or sid is not None
        if error:  # a failed material names its reason
            assert len(error) > len(str(path)) + 2, (mpath, error)


@pytest.mark.corpus
@pytest.mark.skipif(not HAS_CORPUS, reason="../shared/corpus/realworld is absent")
@pytest.mark.parametrize("path", FILES, ids=_rel)
def test_file_is_read_and_every_material_listed(path):
    _check_file(path)


def test_corpus_is_whole():
    if not HAS_CORPUS:
        pytest.skip("../shared/corpus/realworld is absent")
    assert len(FILES) >= 390
    assert {_rel(f).split("/")[0] for f in FILES} == {"MaterialX", "usd-wg-assets", "materialxusd"}


@pytest.mark.corpus
@pytest.mark.skipif(not HAS_CORPUS, reason="../shared/corpus/realworld is absent")
def test_docs_totals_are_the_sweeps_totals():
    """docs/guide/materials.md holds the totals of this sweep (regenerate:
    ``python tools/bench_readers.py --corpus-totals --write docs/guide/materials.md``)."""
    b = _bench()
    t = b.totals([_record(p) for p in FILES])
    assert t["files"] == len(FILES) and not t["tracebacks"] and not t["rejected"]
    text = (ROOT / "docs" / "guide" / "materials.md").read_text()
    i, j = text.index(b.BEGIN), text.index(b.END) + len(b.END)
    assert text[i:j] == b.totals_markdown(t), (
        "regenerate: python tools/bench_readers.py --corpus-totals --write docs/guide/materials.md"
    )


EVAL_SAMPLE = (
    "MaterialX/resources/Materials/TestSuite/pbrlib/multioutput/multioutput.mtlx",
    "usd-wg-assets/full_assets/StandardShaderBall/layers/environment.usda",
    "usd-wg-assets/test_assets/RoughnessTest/RoughnessTest.usdz",
    "usd-wg-assets/test_assets/MaterialXTest/standard_surface_brass_tiled.mtlx",
    "MaterialX/resources/Materials/TestSuite/stdlib/color_management/color_management.mtlx",
)


@pytest.mark.corpus
@pytest.mark.skipif(not HAS_CORPUS, reason="../shared/corpus/realworld is absent")
@pytest.mark.parametrize("rel", EVAL_SAMPLE)
def test_cli_eval_exits_0_or_1_with_json(rel):
    proc = subprocess.run(
        [sys.executable, "-m", "openpbr_diffuse", "eval", str(REALWORLD / rel), "--json"],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=ROOT,
    )
    assert proc.returncode in (0, 1), proc.stderr
    assert "Traceback" not in proc.stderr
    doc = json.loads(proc.stdout)
    listed = {m["path"] for m in doc["materials"]}
    assert set(_expected_paths(REALWORLD / rel)) <= listed
    assert (proc.returncode == 1) == any(m["error"] for m in doc["materials"])


def test_renderable_outputs_of_a_nodegraph_are_listed(tmp_path):
    """A shader output, a material output and a colour output of one nodegraph: the first two
    are the same standard_surface (its colour as authored, converted to ACEScg), the colour
    output is listed unsupported with the reason."""
    from openpbr_diffuse.readers import load_materials

    f = tmp_path / "g.mtlx"
    f.write_text("""<?xml version="1.0"?>
<materialx version="1.39">
  <nodegraph name="g">
    <standard_surface name="s" type="surfaceshader">
      <input name="base_color" type="color3" value="0.2, 0.4, 0.6" />
    </standard_surface>
    <surfacematerial name="m" type="material">
      <input name="surfaceshader" type="surfaceshader" nodename="s" />
    </surfacematerial>
    <constant name="c" type="color3"><input name="value" type="color3" value="1, 0, 0" /></constant>
    <output name="shader_out" type="surfaceshader" nodename="s" />
    <output name="material_out" type="material" nodename="m" />
    <output name="colour_out" type="color3" nodename="c" />
  </nodegraph>
</materialx>
""")
    mats = {m.path: m for m in load_materials(f)}
    assert set(mats) == {"g/shader_out", "g/material_out", "g/colour_out"}
    want = _convert((0.2, 0.4, 0.6), "lin_rec709")
    for p in ("g/shader_out", "g/material_out"):
        assert mats[p].supported and mats[p].shader_id == "ND_standard_surface_surfaceshader"
        assert np.allclose(mats[p].parameters["base_color"].value, want, atol=1e-6)
    c = mats["g/colour_out"]
    assert not c.supported and not c.error and "color3 output, not a surface shader" in c.unsupported[0]


def test_a_multi_output_node_lists_each_output(tmp_path):
    from openpbr_diffuse.readers import load_materials

    f = tmp_path / "multi.mtlx"
    f.write_text("""<?xml version="1.0"?>
<materialx version="1.39">
  <nodedef name="ND_two" node="two">
    <output name="a" type="surfaceshader" /><output name="b" type="surfaceshader" />
  </nodedef>
  <two name="t" type="multioutput">
    <output name="a" type="surfaceshader" /><output name="b" type="surfaceshader" />
  </two>
  <output name="out_a" type="surfaceshader" nodename="t" output="a" />
  <output name="out_b" type="surfaceshader" nodename="t" output="b" />
</materialx>
""")
    mats = load_materials(f)
    assert {m.path for m in mats} >= {"out_a", "out_b"}
    assert all(not m.supported for m in mats)


# ----------------------------------------------------------------------------- independent reading
# colour-space names (MaterialX's, USD's tokens, UsdUVTexture's) -> pxr Gf.ColorSpace names
_GF = {
    "lin_rec709": "LinearRec709",
    "srgb_texture": "SRGBRec709",
    "acescg": "LinearAP1",
    "g22_rec709": "G22Rec709",
    "g18_rec709": "G18Rec709",
    "g24_rec709": "G24Rec709",
    "aces2065-1": "LinearAP0",
    "lin_adobergb": "LinearAdobeRGB",
    "adobergb": "G22AdobeRGB",
    "lin_displayp3": "LinearDisplayP3",
    "srgb_displayp3": "SRGBP3D65",
    "lin_rec2020": "LinearRec2020",
    "g22_ap1": "G22AP1",
    "srgb_ap1": "SRGBAP1",
    "sRGB": "SRGBRec709",
}
#: The colour space of colours whose document says none (the readers' documented convention:
#: OpenPBR's own default, ACEScg; the other shaders', linear Rec.709).
_UNMARKED = {"open_pbr": "acescg"}


def _convert(rgb, space):
    """``rgb`` from ``space`` to ACEScg through pxr's Gf.ColorSpace; raw / data unchanged."""
    from pxr import Gf

    if space in ("raw", "data", "Raw", "Data", "identity", "none"):
        return tuple(float(x) for x in rgb)
    name = _GF.get(space)
    token = getattr(Gf.ColorSpaceNames, name) if name else space  # a USD token such as lin_rec709_scene
    src = Gf.ColorSpace(token)
    out = Gf.Color(Gf.Color(Gf.Vec3f(*[float(x) for x in rgb]), src), Gf.ColorSpace(Gf.ColorSpaceNames.LinearAP1))
    return tuple(float(x) for x in out.GetRGB())


@functools.lru_cache(maxsize=1)
def _scratch():
    import atexit
    import shutil
    import tempfile

    d = tempfile.mkdtemp(prefix="corpus-sweep-")
    atexit.register(shutil.rmtree, d, True)
    return Path(d)


def _local(file):
    """A path OpenImageIO can open: a package member (``x.usdz[tex.png]``) is read as bytes
    through usd-core's asset resolver (Ar) and written to a scratch file."""
    text = str(file)
    if not text.endswith("]") or "[" not in text:
        return text
    from pxr import Ar

    asset = Ar.GetResolver().OpenAsset(Ar.ResolvedPath(text))
    assert asset is not None, text
    out = _scratch() / f"{abs(hash(text))}_{Path(text[text.rindex('[') + 1 : -1]).name}"
    out.write_bytes(asset.GetBuffer())
    return str(out)


@functools.cache
def _pixels(file):
    import OpenImageIO as oiio

    buf = oiio.ImageBuf(_local(file))
    px = np.asarray(buf.get_pixels(oiio.FLOAT), dtype=np.float64)
    assert buf.spec().width > 0, buf.geterror()
    spec = buf.spec()
    return px.reshape(spec.height, spec.width, spec.nchannels), spec.format.basetype


def _bilinear(file, u, v):
    """The texel values at (u, v) (v up), bilinear between texel centres, periodic wrap."""
    px, _ = _pixels(file)
    h, w, _ = px.shape
    x, y = u * w - 0.5, (1.0 - v) * h - 0.5
    x0, y0 = int(np.floor(x)), int(np.floor(y))
    fx, fy = x - x0, y - y0

    def at(i, j):
        return px[j % h, i % w]

    return (
        (1 - fx) * (1 - fy) * at(x0, y0)
        + fx * (1 - fy) * at(x0 + 1, y0)
        + (1 - fx) * fy * at(x0, y0 + 1)
        + fx * fy * at(x0 + 1, y0 + 1)
    )


def _uv_points(file):
    """Two texel centres (u, v) of ``file`` (a quarter and three quarters across)."""
    px, _ = _pixels(file)
    h, w, _ = px.shape
    return [((w // 4 + 0.5) / w, 1 - (h // 3 + 0.5) / h), (((3 * w) // 4 + 0.5) / w, 1 - ((2 * h) // 3 + 0.5) / h)]


class _Texture:
    """An input read from an image at uv: what to compute once the uv is known."""

    def __init__(self, file, fn):
        self.file, self.fn = file, fn


# MaterialX ------------------------------------------------------------------
def _mx_shader(doc, path):
    import MaterialX as mx

    e = doc.getDescendant(path)
    node = e.getConnectedNode() if e.isA(mx.Output) else e
    if node.getType() == "material":
        node = node.getInput("surfaceshader").getConnectedNode()
    if node.getCategory() == "surface":  # ND_surface: its BSDF is what is evaluated
        node = node.getInput("bsdf").getConnectedNode()
    return node


def _mx_input(node, name, unmarked, folder):
    inp = node.getInput(name)
    if inp is None:
        return node.getNodeDef().getActiveInput(name).getValue(), unmarked
    up = inp.getConnectedNode()
    if up is None:
        src = inp.getInterfaceInput() if inp.hasInterfaceName() else inp
        value = src.getValue() if src.getValue() is not None else node.getNodeDef().getActiveInput(name).getValue()
        return value, src.getActiveColorSpace() or unmarked
    assert up.getCategory() == "image" and up.getInput("texcoord") is None, f"sample: {up.getNamePath()}"
    fin = up.getInput("file")
    file = Path(folder) / fin.getResolvedValueString()
    space = fin.getActiveColorSpace() or unmarked
    n = {"float": 1, "color3": 3, "vector3": 3, "color4": 4}[up.getType()]

    def fn(u, v):
        t = _bilinear(file, u, v)
        vals = tuple(t[:n]) if t.size >= n else tuple(t[:1]) * n
        return vals

    return _Texture(file, fn), space


def _mx_expected(path, mpath, names):
    doc = _mx_doc(path)
    node = _mx_shader(doc, mpath)
    unmarked = _UNMARKED.get(node.getCategory(), "lin_rec709")
    return {n: _mx_input(node, n, unmarked, path.parent) for n in names}, node.getNodeDef().getName()


# USD ------------------------------------------------------------------------
def _sdr_default(sid, name):
    if sid.startswith("ND_"):
        return _stdlib().getNodeDef(sid).getActiveInput(name).getValue()
    from pxr import Sdr

    return Sdr.Registry().GetShaderNodeByIdentifier(sid).GetShaderInput(name).GetDefaultValue()


def _usd_expected(path, mpath, names):
    from pxr import Usd, UsdShade

    stage = Usd.Stage.Open(str(path))
    mat = UsdShade.Material(stage.GetPrimAtPath(mpath))
    shader = mat.ComputeSurfaceSource("mtlx")[0]
    sid = str(shader.GetIdAttr().Get())
    if sid == "ND_surface":
        shader = UsdShade.Shader(shader.GetInput("bsdf").GetConnectedSources()[0][0].source.GetPrim())
        sid = str(shader.GetIdAttr().Get())
    unmarked = _UNMARKED.get("open_pbr" if "open_pbr" in sid else sid, "lin_rec709")
    out = {}
    for name in names:
        inp = shader.GetInput(name)
        attrs = inp.GetValueProducingAttributes() if inp else []
        if not attrs:
            out[name] = (_sdr_default(sid, name), unmarked)
            continue
        a = attrs[0]
        if UsdShade.Input.IsInput(a):
            out[name] = (a.Get(), a.GetColorSpace() or unmarked)
            continue
        tex = UsdShade.Shader(a.GetPrim())
        tid = str(tex.GetIdAttr().Get())
        if tid.startswith("ND_image_"):  # a MaterialX image node in USD
            tc = tex.GetInput("texcoord")
            if tc:  # only the default uv set (an ND_texcoord_vector2 of index 0)
                src = UsdShade.Shader(tc.GetConnectedSources()[0][0].source.GetPrim())
                index = src.GetInput("index")
                assert str(src.GetIdAttr().Get()) == "ND_texcoord_vector2" and (
                    not index or index.Get() in (None, 0)
                ), f"sample: {a.GetPath()}"
            fin = tex.GetInput("file")
            fattrs = fin.GetValueProducingAttributes() if fin else []
            if not fattrs or not fattrs[0].Get() or not fattrs[0].Get().path:  # no file: the node's default
                d = tex.GetInput("default")
                out[name] = (d.Get() if d and d.Get() is not None else _sdr_default(tid, "default"), unmarked)
                continue
            fattr = fattrs[0]
            n = {"float": 1, "color3": 3, "vector3": 3, "color4": 4}[tid[len("ND_image_") :]]
            file = fattr.Get().resolvedPath
            out[name] = (
                _Texture(file, lambda u, v, file=file, n=n: tuple(_bilinear(file, u, v)[:n])),
                fattr.GetColorSpace() or unmarked,
            )
            continue
        assert tid == "UsdUVTexture", f"sample: {a.GetPath()}"
        out[name] = _usd_texture(tex, a.GetBaseName())
    return out, sid


def _usd_texture(tex, channel):
    def val(n, default):
        i = tex.GetInput(n)
        attrs = i.GetValueProducingAttributes() if i else []
        v = attrs[0].Get() if attrs else None
        return default if v is None else v

    file = val("file", None).resolvedPath  # a str: a package member keeps its brackets
    scale, bias = np.array(val("scale", (1, 1, 1, 1)), float), np.array(val("bias", (0, 0, 0, 0)), float)
    cs = str(val("sourceColorSpace", "auto"))
    px, fmt = _pixels(file)
    nch = px.shape[2]
    import OpenImageIO as oiio
    from pxr import Gf

    srgb = cs == "sRGB" or (cs == "auto" and fmt in (oiio.UINT8, oiio.INT8) and nch in (3, 4))

    def fn(u, v):
        t = _bilinear(file, u, v)
        rgba = {1: [t[0], t[0], t[0], 1.0], 2: [t[0], t[0], t[0], t[1]], 3: [*t[:3], 1.0]}.get(nch, list(t[:4]))
        if srgb:  # decoded to linear, same primaries
            c = Gf.Color(Gf.Vec3f(*rgba[:3]), Gf.ColorSpace(Gf.ColorSpaceNames.SRGBRec709))
            rgba[:3] = Gf.Color(c, Gf.ColorSpace(Gf.ColorSpaceNames.LinearRec709)).GetRGB()
        rgba = np.array(rgba, float) * scale + bias
        pick = {"rgb": rgba[:3], "r": rgba[:1], "g": rgba[1:2], "b": rgba[2:3], "a": rgba[3:4]}[channel]
        return tuple(pick)

    return _Texture(file, fn), "lin_rec709" if channel == "rgb" else "raw"


# ----------------------------------------------------------------------------- the fixed sample
_NAMES = {
    "ND_open_pbr_surface_surfaceshader": ("base_color", "base_diffuse_roughness", "base_weight"),
    "ND_standard_surface_surfaceshader": ("base_color", "diffuse_roughness", "base"),
    "UsdPreviewSurface": ("diffuseColor", "roughness", "metallic"),
    "ND_UsdPreviewSurface_surfaceshader": ("diffuseColor", "roughness", "metallic"),
    "ND_gltf_pbr_surfaceshader": ("base_color", "roughness", "metallic"),
    "ND_oren_nayar_diffuse_bsdf": ("color", "roughness", "weight"),
}
_MX, _WG, _MU = "MaterialX/resources/Materials/", "usd-wg-assets/", "materialxusd/tests/"
SAMPLE = [
    # (file relative to the corpus, material path, reason of a known failure or None)
    *[
        (_MX + f"Examples/StandardSurface/standard_surface_{n}.mtlx", m, None)
        for n, m in [
            ("chrome", "Chrome"),
            ("copper", "Copper"),
            ("gold", "Gold"),
            ("jade", "Jade"),
            ("plastic", "Plastic"),
            ("velvet", "Velvet"),
            ("default", "Default"),
            ("glass", "Glass"),
            ("carpaint", "Car_Paint"),
            ("greysphere", "Greysphere"),
            ("metal_brushed", "Metal_Brushed"),
        ]
    ],
    *[
        (_MX + f"Examples/UsdPreviewSurface/usd_preview_surface_{n}.mtlx", m, None)
        for n, m in [
            ("gold", "USD_Gold"),
            ("plastic", "USD_Plastic"),
            ("default", "USD_Default"),
            ("glass", "USD_Glass"),
        ]
    ],
    *[
        (_MX + f"Examples/GltfPbr/gltf_pbr_{n}.mtlx", m, None)
        for n, m in [("gold", "PBR_Gold"), ("plastic", "PBR_Plastic"), ("default", "Default")]
    ],
    *[(_MX + "TestSuite/pbrlib/bsdf/oren_nayar_diffuse.mtlx", f"oren_nayar_diffuse/out{i}", None) for i in (1, 2, 5)],
    (_MX + "TestSuite/pbrlib/surfaceshader/transparency_hints.mtlx", "geom_hint", None),
    *[
        (_WG + "test_assets/TextureCoordinateTest/TextureCoordinateTest.mtlx", m, None)
        for m in ("BottomLeftMat", "TopRightMat", "BackPlaneMat")
    ],
    *[
        (
            _WG + "test_assets/TextureCoordinateTest/TextureCoordinateTest.usda",
            f"/Asset/Materials/UsdPreviewSurface/Materials/{m}",
            None,
        )
        for m in ("BottomLeftMat", "TopRightMat")
    ],
    *[
        (_WG + f"test_assets/TextureFileFormatTests/{n}.usda", "/Scene/Looks/MainMaterial", None)
        for n in ("png_rgb_8-bit", "png_rgb_16-bit", "png_grayscale_8-bit", "png_grayscale_16-bit", "jpeg_rgb_8-bit")
    ],
    (
        _WG + "test_assets/AlphaBlendModeTest/AlphaBlendModeTest.usd",
        "/AlphaBlendModeTest/Materials/Mat_Opaque__165642",
        None,
    ),
    (_WG + "full_assets/McUsd/McUsd.usda", "/McUsd/Looks/fern", None),
    (
        _WG + "full_assets/StandardShaderBall/layers/environment.usda",
        "/standard_shader_ball_scene/materials/box_base",
        None,
    ),
    (_WG + "test_assets/USDZ/AnimatedCube/AnimatedCube.usdz", None, None),
    (_WG + "test_assets/USDZ/CesiumMan/CesiumMan.usdz", "/CesiumMan/Materials/Cesium_Man_effect", None),
    (_WG + "test_assets/RoughnessTest/RoughnessTest.usdz", "/Roughness/Materials/Tex033", None),
    (_WG + "test_assets/RoughnessTest/RoughnessTest.usdz", "/Roughness/Materials/Const066", None),
    (
        _WG + "test_assets/USDZ/InterpolationTest/InterpolationTest.usdz",
        "/InterpolationTest/Materials/Material_001",
        None,
    ),
    (_WG + "test_assets/USDZ/BoxAnimated/BoxAnimated.usdz", "/BoxAnimated/Materials/outer", None),
    *[
        (_MU + f"resources/Materials/Examples/OpenPbr/{n}.usda", f"/MaterialX/Materials/{n}", None)
        for n in ("Aluminum_Brushed", "Car_Paint", "Default", "Honey", "Pearl", "Velvet")
    ],
    *[
        (_MU + f"resources/Materials/Examples/StandardSurface/{n}.usda", f"/MaterialX/Materials/{n}", None)
        for n in ("Chrome", "Copper", "Jade", "Plastic")
    ],
    (_MU + "resources/Materials/Examples/UsdPreviewSurface/USD_Default.usda", "/MaterialX/Materials/USD_Default", None),
    *[
        (_MU + f"resources/Materials/Examples/GltfPbr/{n}.usda", f"/MaterialX/Materials/{n}", None)
        for n in ("PBR_Gold", "PBR_Plastic")
    ],
    *[
        (_MU + "physically_based/Brick_OPBR_MAT_PBM.usda", f"/MaterialX/Materials/{n}_OPBR_MAT_PBM", None)
        for n in ("Aluminum", "Banana", "Brick", "Charcoal")
    ],
]


def _sample_params():
    out = []
    for rel, mpath, xfail in SAMPLE:
        marks = [pytest.mark.xfail(strict=True, reason=xfail)] if xfail else []
        out.append(pytest.param(rel, mpath, marks=marks, id=f"{rel}:{mpath or ''}"))
    return out


def _first_material(path):
    """The first UsdShade material of a stage (for a sample entry without a path)."""
    from pxr import Usd, UsdShade

    stage = Usd.Stage.Open(str(path))
    return next(str(p.GetPath()) for p in stage.Traverse() if p.IsA(UsdShade.Material))


def test_sample_is_large_and_spread():
    if not HAS_CORPUS:
        pytest.skip("../shared/corpus/realworld is absent")
    assert len(SAMPLE) >= 40
    assert {rel.split("/")[0] for rel, _, _ in SAMPLE} == {"MaterialX", "usd-wg-assets", "materialxusd"}


@pytest.mark.corpus
@pytest.mark.skipif(not HAS_CORPUS, reason="../shared/corpus/realworld is absent")
@pytest.mark.parametrize("rel,mpath", _sample_params())
def test_sample_values_equal_an_independent_reading(rel, mpath):
    from openpbr_diffuse.readers import load_materials

    path = REALWORLD / rel
    mpath = mpath or _first_material(path)
    if path.suffix == ".mtlx":
        doc = _mx_doc(path)
        sid = _mx_shader(doc, mpath).getNodeDef().getName()
        expected, _ = _mx_expected(path, mpath, _NAMES[sid])
    else:
        from pxr import Usd, UsdShade

        stage = Usd.Stage.Open(str(path))
        shader = UsdShade.Material(stage.GetPrimAtPath(mpath)).ComputeSurfaceSource("mtlx")[0]
        sid0 = str(shader.GetIdAttr().Get())
        sid = "ND_oren_nayar_diffuse_bsdf" if sid0 == "ND_surface" else sid0
        expected, _ = _usd_expected(path, mpath, _NAMES[sid])
    textures = [v for v, _ in expected.values() if isinstance(v, _Texture)]
    uvs = _uv_points(textures[0].file) if textures else [(0.5, 0.5)]
    for uv in uvs:
        mats = load_materials(path, material=mpath, uv=uv)
        assert len(mats) == 1, [m.path for m in mats]
        m = mats[0]
        assert not m.error and m.supported, (m.error, m.unsupported)
        for name, (value, space) in expected.items():
            if isinstance(value, _Texture):
                value = value.fn(*uv)
            want = np.atleast_1d(np.array(value if not hasattr(value, "__len__") else tuple(value), float))
            if want.size == 3 and space not in (None, "raw"):
                want = np.array(_convert(want, space))
            got = np.atleast_1d(np.asarray(m.parameters[name].value, float))
            # Gf works in float32; OpenColorIO's sRGB curve and Gf's differ by up to ~1.5e-5
            # (a texel step of an 8-bit texture is 4e-3)
            tol = 5e-5 if m.parameters[name].kind == "texture" else 2e-6
            assert np.allclose(got, want, rtol=0, atol=tol), (name, uv, got, want, m.parameters[name].provenance)


def test_a_nodedef_implementation_graph_reads_the_nodedef_interface(tmp_path):
    """A nodegraph implementing a nodedef (rendered by MaterialX on its own): an interfacename
    refers to the nodedef's input, whose value is the default."""
    from openpbr_diffuse.readers import load_materials

    f = tmp_path / "impl.mtlx"
    f.write_text("""<?xml version="1.0"?>
<materialx version="1.39" colorspace="acescg">
  <nodedef name="ND_metalish" node="metalish">
    <input name="tint" type="color3" value="0.25, 0.5, 0.75" />
    <input name="rough" type="float" value="0.375" />
    <output name="out" type="surfaceshader" />
  </nodedef>
  <nodegraph name="NG_metalish" nodedef="ND_metalish">
    <standard_surface name="s" type="surfaceshader">
      <input name="base_color" type="color3" interfacename="tint" />
      <input name="diffuse_roughness" type="float" interfacename="rough" />
    </standard_surface>
    <output name="out" type="surfaceshader" nodename="s" />
  </nodegraph>
</materialx>
""")
    (m,) = load_materials(f)
    assert m.path == "NG_metalish/out" and m.supported and not m.warnings, m.warnings
    assert m.parameters["base_color"].value == (0.25, 0.5, 0.75)
    assert m.parameters["diffuse_roughness"].value == 0.375
