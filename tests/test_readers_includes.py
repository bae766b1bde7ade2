"""Relative file names in xi:include'd MaterialX documents resolve against the document that
holds them (after MaterialX's ``fileprefix``, applied once per element scope), never against
the working directory or the including document.  Expected values: MaterialX's own
``flattenFilenames`` on a copy of the document (which file), and the texel read with
OpenImageIO directly (which value)."""

import os
import textwrap
from pathlib import Path

import numpy as np
import pytest

from openpbr_diffuse.readers import load_materials

SHARED = Path(os.environ.get("OPENPBR_DIFFUSE_SHARED") or Path(__file__).resolve().parents[1].parent / "shared")
REAL = SHARED / "corpus" / "realworld"
BRASS_LOOK = REAL / "MaterialX/resources/Materials/Examples/StandardSurface/standard_surface_look_brass_tiled.mtlx"
BRASS_USDWG = REAL / "usd-wg-assets/test_assets/MaterialXTest/standard_surface_brass_tiled.mtlx"

MAIN = """
<?xml version="1.0"?>
<materialx version="1.39" xmlns:xi="http://www.w3.org/2001/XInclude">
  <xi:include href="parts/inc.mtlx" />
</materialx>
"""

INC = """
<?xml version="1.0"?>
<materialx version="1.39" fileprefix="img/">
  <image name="colour" type="color3">
    <input name="file" type="filename" value="tex.png" colorspace="acescg" />
  </image>
  <nodegraph name="G" fileprefix="rough/">
    <image name="r" type="float">
      <input name="file" type="filename" value="tex.png" />
    </image>
    <output name="out" type="float" nodename="r" />
  </nodegraph>
  <open_pbr_surface name="S" type="surfaceshader">
    <input name="base_color" type="color3" nodename="colour" />
    <input name="specular_roughness" type="float" nodegraph="G" output="out" />
  </open_pbr_surface>
  <surfacematerial name="M" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="S" />
  </surfacematerial>
</materialx>
"""


def _png(path, rgb):
    import OpenImageIO as oiio

    path.parent.mkdir(parents=True, exist_ok=True)
    a = np.tile(np.asarray(rgb, dtype=np.uint8), (2, 2, 1))
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), oiio.ImageSpec(2, 2, 3, "uint8"))
    assert out.write_image(a)
    out.close()


def _texel(path):
    import OpenImageIO as oiio

    return np.array(oiio.ImageBuf(str(path)).getpixel(0, 0))


def _flattened(doc_path):
    """{element name path: file name} after MaterialX's flattenFilenames (fileprefix applied)."""
    import MaterialX as mx

    doc = mx.createDocument()
    mx.readFromXmlFile(doc, str(doc_path))
    flat = doc.copy()
    mx.flattenFilenames(flat)
    return {
        e.getNamePath(): e.getValueString()
        for e in flat.traverseTree()
        if e.isA(mx.Input) and e.getType() == "filename"
    }


def _layout(tmp_path):
    looks = tmp_path / "looks"
    (looks / "parts").mkdir(parents=True)
    (looks / "main.mtlx").write_text(textwrap.dedent(MAIN).lstrip())
    (looks / "parts" / "inc.mtlx").write_text(textwrap.dedent(INC).lstrip())
    _png(looks / "parts" / "img" / "tex.png", (200, 100, 50))  # the included document's
    _png(looks / "parts" / "rough" / "tex.png", (64, 64, 64))
    _png(looks / "img" / "tex.png", (1, 2, 3))  # decoys: the including document's
    _png(tmp_path / "cwd" / "img" / "tex.png", (9, 9, 9))  # and the working directory's
    _png(looks / "rough" / "tex.png", (250, 250, 250))
    return looks / "main.mtlx"


def test_included_texture_resolves_against_its_own_document(tmp_path, monkeypatch):
    main = _layout(tmp_path)
    monkeypatch.chdir(tmp_path / "cwd")
    flat = _flattened(main)
    assert flat == {"colour/file": "img/tex.png", "G/r/file": "rough/tex.png"}  # MaterialX: prefix per scope
    folder = main.parent / "parts"
    (m,) = load_materials(main)
    assert m.error == "" and not [w for w in m.warnings if "does not exist" in w], m.warnings
    np.testing.assert_allclose(m.parameters["base_color"].value, _texel(folder / flat["colour/file"]), atol=1e-12)
    np.testing.assert_allclose(
        m.parameters["specular_roughness"].value, _texel(folder / flat["G/r/file"])[0], atol=1e-12
    )
    assert str(folder / "img" / "tex.png") in m.parameters["base_color"].provenance


def test_nested_include_follows_materialx_source_uri(tmp_path, monkeypatch):
    import MaterialX as mx

    main = _layout(tmp_path)
    # parts/inc.mtlx now only includes deeper/inner.mtlx (relative to parts/), which holds the material
    inner = main.parent / "parts" / "deeper" / "inner.mtlx"
    inner.parent.mkdir()
    inner.write_text(textwrap.dedent(INC).lstrip())
    (main.parent / "parts" / "inc.mtlx").write_text(
        textwrap.dedent(MAIN).replace("parts/inc.mtlx", "deeper/inner.mtlx").lstrip()
    )
    _png(inner.parent / "img" / "tex.png", (30, 60, 90))
    monkeypatch.chdir(tmp_path / "cwd")
    # MaterialX (1.39) gives a nested include's elements the source URI of the outermost included
    # document; the readers resolve against the document MaterialX names
    doc = mx.createDocument()
    mx.readFromXmlFile(doc, str(main))
    uri = doc.getDescendant("colour/file").getActiveSourceUri()
    want = _texel((main.parent / uri).parent / _flattened(main)["colour/file"])
    (m,) = load_materials(main)
    assert m.error == "", m.error
    np.testing.assert_allclose(m.parameters["base_color"].value, want, atol=1e-12)


@pytest.mark.corpus
@pytest.mark.skipif(not BRASS_LOOK.is_file(), reason="../shared/corpus is absent")
def test_brass_look_greysphere_from_another_directory(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (m,) = load_materials(BRASS_LOOK, material="Greysphere_Calibration")
    assert not [w for w in m.warnings if "does not exist" in w], m.warnings
    prov = m.parameters["base_color"].provenance
    want = BRASS_LOOK.parent / "../../../Images/greysphere_calibration.png"
    assert os.path.normpath(want) in prov, prov
    assert max(m.parameters["base_color"].value) > 0.1


@pytest.mark.corpus
@pytest.mark.skipif(not BRASS_USDWG.is_file(), reason="../shared/corpus is absent")
def test_brass_doubled_prefix_is_what_materialx_resolves(tmp_path, monkeypatch):
    # fileprefix="./textures/" over value="./textures/brass_color.jpg": MaterialX itself resolves
    # ./textures/./textures/brass_color.jpg; the readers name that same file (missing from the asset)
    monkeypatch.chdir(tmp_path)
    flat = _flattened(BRASS_USDWG)
    (m,) = load_materials(BRASS_USDWG)
    missing = [w for w in m.warnings if "does not exist" in w]
    for value in {v for v in flat.values()}:
        want = os.path.normpath(BRASS_USDWG.parent / value)
        assert any(want in w for w in missing), (want, missing)


PLAIN = """
<?xml version="1.0"?>
<materialx version="1.39">
  <image name="colour" type="color3">
    <input name="file" type="filename" value="img/tex.png" colorspace="acescg" />
  </image>
  <open_pbr_surface name="S" type="surfaceshader">
    <input name="base_color" type="color3" nodename="colour" />
  </open_pbr_surface>
  <surfacematerial name="M" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="S" />
  </surfacematerial>
</materialx>
"""


@pytest.mark.parametrize("which", ["plain", "include"])
def test_document_named_by_a_relative_path_resolves_like_its_absolute_path(tmp_path, monkeypatch, which):
    """A document named relative to the working directory (``eval looks/main.mtlx``) carries that
    relative name as its elements' source URI; its textures resolve next to it, as with the
    absolute name, and the texel is OpenImageIO's."""
    main = _layout(tmp_path)
    if which == "plain":
        main = main.parent / "plain.mtlx"
        main.write_text(textwrap.dedent(PLAIN).lstrip())
        want = _texel(main.parent / "img" / "tex.png")
    else:
        want = _texel(main.parent / "parts" / "img" / "tex.png")
    monkeypatch.chdir(tmp_path)
    relative = os.path.relpath(main, tmp_path)
    (a,) = load_materials(main)
    (r,) = load_materials(relative)
    for m in (a, r):
        assert m.error == "" and not [w for w in m.warnings if "does not exist" in w], m.warnings
        np.testing.assert_allclose(m.parameters["base_color"].value, want, atol=1e-12)
