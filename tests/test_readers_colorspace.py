"""Colour spaces: every name MaterialX knows (its cmlib library, its default colour-management
system's remapped names, the OpenColorIO ACES configuration's scene-referred spaces and their
aliases) converts to ACEScg as independent references convert it: OpenColorIO (through
OpenImageIO), USD's Gf.ColorSpace, colour-science's RGB_to_RGB, and closed forms (gamma 2.2 of
0.5 is 0.5 ** 2.2).  The stored table is what colour-science computes today."""

import numpy as np
import pytest

from openpbr_diffuse.readers import colorspace, load_materials

MX_LIB = None
VALUES = np.array(
    [
        [0.5, 0.5, 0.5],
        [0.2, 0.4, 0.6],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.03, 0.7, 0.95],
        [1.0, 1.0, 1.0],
    ]
)


def _colour():
    from openpbr_diffuse.spectral.colorimetry import _colour

    return _colour()


def _ocio(values, src):
    """OpenColorIO's conversion (OpenImageIO's built-in ACES configuration) to ACEScg."""
    import OpenImageIO as oiio

    a = np.ascontiguousarray(np.asarray(values, dtype=np.float32).reshape(-1, 1, 3))
    out = oiio.ImageBufAlgo.colorconvert(oiio.ImageBuf(a), src, "ACEScg")
    assert not out.has_error, out.geterror()
    return np.asarray(out.get_pixels(oiio.FLOAT), dtype=np.float64).reshape(-1, 3)


def _gf(values, token):
    from pxr import Gf

    src, dst = Gf.ColorSpace(token), Gf.ColorSpace(Gf.ColorSpaceNames.LinearAP1)
    return np.array([list(Gf.Color(Gf.Color(Gf.Vec3f(*map(float, v)), src), dst).GetRGB()) for v in values])


def _cmlib_names():
    """The source colour spaces of MaterialX's cmlib (ND_<space>_to_lin_rec709_color3)."""
    import MaterialX as mx

    lib = mx.createDocument()
    mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), lib)
    names = {
        nd.getName()[3 : -len("_to_lin_rec709_color3")]
        for nd in lib.getNodeDefs()
        if nd.getName().endswith("_to_lin_rec709_color3")
    }
    return sorted(names)


def test_the_stored_table_is_colour_sciences():
    built = colorspace.build_table()
    from openpbr_diffuse.readers import _colorspace_table as table

    assert built["aliases"] == table.ALIASES and built["display"] == table.DISPLAY
    assert set(built["spaces"]) == set(table.SPACES)
    for name, spec in built["spaces"].items():
        assert spec["decoding"] == table.SPACES[name]["decoding"], name
        assert np.allclose(spec["matrix"], table.SPACES[name]["matrix"], rtol=0, atol=1e-15), name


def test_every_cmlib_space_and_remapped_name_is_known():
    names = _cmlib_names()
    assert {
        "srgb_texture",
        "g22_rec709",
        "g18_rec709",
        "rec709_display",
        "acescg",
        "g22_ap1",
        "adobergb",
        "lin_adobergb",
        "lin_displayp3",
        "srgb_displayp3",
    } <= set(names)
    for n in names + ["lin_rec709", "gamma18", "gamma22", "gamma24", "lin_ap1"]:
        colorspace.canonical(n)  # no ValueError
    # MaterialX's DefaultColorManagementSystem remap
    assert colorspace.canonical("gamma18") == colorspace.canonical("g18_rec709")
    assert colorspace.canonical("gamma22") == colorspace.canonical("g22_rec709")
    assert colorspace.canonical("gamma24") == colorspace.canonical("rec709_display")
    assert colorspace.canonical("lin_ap1") == "acescg"


@pytest.mark.parametrize(
    "name, want",
    [
        ("lin_rec709", "lin_rec709"),
        ("Linear Rec.709 (sRGB)", "lin_rec709"),
        ("Utility - Linear - sRGB", "lin_rec709"),
        ("lin_srgb", "lin_rec709"),
        ("lin_rec709_scene", "lin_rec709"),
        ("srgb_texture", "srgb_texture"),
        ("sRGB - Texture", "srgb_texture"),
        ("Utility - sRGB - Texture", "srgb_texture"),
        ("sRGB", "srgb_texture"),
        ("ACEScg", "acescg"),
        ("lin_ap1", "acescg"),
        ("lin_ap1_scene", "acescg"),
        ("ACES - ACEScg", "acescg"),
        ("ACES2065-1", "aces2065-1"),
        ("lin_ap0", "aces2065-1"),
        ("lin_ap0_scene", "aces2065-1"),
        ("CIE XYZ-D65 - Scene-referred", "lin_ciexyzd65"),
        ("lin_ciexyzd65_scene", "lin_ciexyzd65"),
        ("lin_displayp3", "lin_displayp3"),
        ("srgb_displayp3", "srgb_displayp3"),
        ("adobergb", "adobergb"),
        ("lin_adobergb", "lin_adobergb"),
        ("rec709_display", "g24_rec709"),
        ("g18_rec709", "g18_rec709"),
        ("g22_rec709", "g22_rec709"),
        ("g22_ap1", "g22_ap1"),
        ("Raw", "raw"),
        ("raw", "raw"),
        ("Utility - Raw", "raw"),
        ("  GAMMA22 ", "g22_rec709"),
    ],
)
def test_names(name, want):
    assert colorspace.canonical(name) == want


@pytest.mark.parametrize("name", ["gamma99", "lin_rec710", "sRGB - Display", "not a space"])
def test_unknown_and_display_names_are_refused_by_name(name):
    with pytest.raises(ValueError, match=repr(name).replace("(", r"\(").replace(")", r"\)")):
        colorspace.canonical(name)


def test_display_referred_is_said():
    with pytest.raises(ValueError, match="display-referred"):
        colorspace.canonical("sRGB - Display")


@pytest.mark.parametrize(
    "name, gamma", [("gamma18", 1.8), ("gamma22", 2.2), ("gamma24", 2.4), ("g22_ap1", 2.2), ("adobergb", 563 / 256)]
)
def test_gamma_decoding_is_the_power(name, gamma):
    v = np.array([0.0, 0.1, 0.5, 0.8, 1.0])
    assert np.allclose(colorspace.decode(v, name), v**gamma, rtol=1e-15, atol=0)
    assert colorspace.decode([-0.5], name)[0] == 0.0  # MaterialX's cmlib clamps at 0


def test_srgb_decoding_is_iec_61966_2_1():
    v = np.array([-0.2, 0.0, 0.02, 0.04045, 0.5, 1.0])
    want = [-0.2 / 12.92, 0.0, 0.02 / 12.92, 0.04045 / 12.92, ((0.5 + 0.055) / 1.055) ** 2.4, 1.0]
    assert np.allclose(colorspace.decode(v, "srgb_texture"), want, rtol=1e-15, atol=0)
    assert colorspace.decode([1.0], "srgb_texture")[0] == 1.0


def _supported():
    from openpbr_diffuse.readers import _colorspace_table as table

    return sorted(table.SPACES)


@pytest.mark.parametrize("space", _supported())
def test_each_space_agrees_with_colour_science(space):
    colour = _colour()
    spec = colorspace.SPECS[space]
    got = colorspace.to_working(VALUES, space)
    derived = {}
    for name in (spec[1], "ACEScg"):  # matrices from the primaries and white point, as OpenColorIO's
        derived[name] = colour.RGB_COLOURSPACES[name].copy()
        derived[name].use_derived_transformation_matrices(True)
    if space == "lin_ciexyzd65":
        d65 = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"]
        want = colour.XYZ_to_RGB(VALUES, derived["ACEScg"], d65, "Bradford")
    elif spec[2]:  # a decoding named apart from the primaries (Gamma 2.4 on Rec.709)
        want = colour.RGB_to_RGB(
            colour.cctf_decoding(VALUES, function=spec[2]),
            derived[spec[1]],
            derived["ACEScg"],
            chromatic_adaptation_transform="Bradford",
        )
    else:
        want = colour.RGB_to_RGB(
            VALUES,
            derived[spec[1]],
            derived["ACEScg"],
            chromatic_adaptation_transform="Bradford",
            apply_cctf_decoding=True,
        )
    assert np.allclose(got, want, rtol=0, atol=1e-12), space


@pytest.mark.parametrize("space", _supported())
def test_each_space_agrees_with_opencolorio(space):
    """OpenColorIO evaluates in single precision and approximates powers (2e-4 relative) and
    the ACEScc / ACEScct logarithms (2e-3)."""
    ocio = colorspace.SPECS[space][0]
    log = space in ("acescc", "acescct")
    values = 0.2 + 0.4 * VALUES if log else VALUES  # log encodings: linear 0.003 to 6, not 222
    got = colorspace.to_working(values, space)
    want = _ocio(values, ocio)
    rtol = 2e-3 if log else 2e-4
    assert np.allclose(got, want, rtol=rtol, atol=2e-5), (space, got, want)


_GF = {
    "lin_rec709": "LinearRec709",
    "srgb_texture": "SRGBRec709",
    "g18_rec709": "G18Rec709",
    "g22_rec709": "G22Rec709",
    "g24_rec709": "G24Rec709",
    "aces2065-1": "LinearAP0",
    "g22_ap1": "G22AP1",
    "srgb_ap1": "SRGBAP1",
    "lin_adobergb": "LinearAdobeRGB",
    "adobergb": "G22AdobeRGB",
    "lin_displayp3": "LinearP3D65",
    "srgb_displayp3": "SRGBP3D65",
    "lin_rec2020": "LinearRec2020",
    "lin_ciexyzd65": "LinearCIEXYZD65",
}


@pytest.mark.parametrize("space", sorted(_GF))
def test_each_space_agrees_with_usd(space):
    from pxr import Gf

    want = _gf(VALUES, getattr(Gf.ColorSpaceNames, _GF[space]))
    assert np.allclose(colorspace.to_working(VALUES, space), want, rtol=1e-5, atol=1e-6), space


def test_gamma22_value_is_decoded_then_converted():
    """0.5 in gamma 2.2 Rec.709: 0.5 ** 2.2 in linear Rec.709, white-preserving to ACEScg."""
    got = colorspace.to_working([0.5, 0.5, 0.5], "gamma22")
    assert np.allclose(got, [0.5**2.2] * 3, rtol=1e-12)


def test_matrix_only_for_linear_spaces():
    assert np.allclose(colorspace.matrix("lin_ap0") @ [1, 1, 1], [1, 1, 1], atol=1e-12)
    with pytest.raises(ValueError, match="not a linear"):
        colorspace.matrix("gamma22")


def test_log_spaces_decode_through_colour_science():
    colour = _colour()
    v = np.array([[0.4, 0.5, 0.6]])
    for space, fn in (("acescc", "ACEScc"), ("acescct", "ACEScct")):
        assert np.allclose(colorspace.to_working(v, space), colour.cctf_decoding(v, function=fn), rtol=1e-12)


@pytest.mark.parametrize("space, gamma", [("gamma18", 1.8), ("gamma22", 2.2), ("gamma24", 2.4)])
def test_materialx_document_in_a_legacy_gamma_space(tmp_path, space, gamma):
    """A Standard Surface base colour in MaterialX's legacy gamma names is read (not failed):
    decoded by the power, then linear Rec.709 -> ACEScg (Gf.ColorSpace's conversion)."""
    from pxr import Gf

    f = tmp_path / "g.mtlx"
    f.write_text(f"""<?xml version="1.0"?>
<materialx version="1.39" colorspace="{space}">
  <standard_surface name="S" type="surfaceshader">
    <input name="base_color" type="color3" value="0.2, 0.4, 0.6" />
  </standard_surface>
  <surfacematerial name="M" type="material"><input name="surfaceshader" type="surfaceshader" nodename="S" /></surfacematerial>
</materialx>
""")
    before = f.read_bytes()
    (m,) = load_materials(f)
    assert m.supported and not m.error
    lin = np.array([0.2, 0.4, 0.6]) ** gamma
    want = _gf([lin], Gf.ColorSpaceNames.LinearRec709)[0]
    assert np.allclose(m.parameters["base_color"].value, want, rtol=1e-5)
    assert f.read_bytes() == before


def test_usd_colour_in_cie_xyz(tmp_path):
    from pxr import Gf

    f = tmp_path / "x.usda"
    f.write_text("""#usda 1.0
def Material "M" {
    token outputs:surface.connect = </M/S.outputs:surface>
    def Shader "S" {
        uniform token info:id = "UsdPreviewSurface"
        color3f inputs:diffuseColor = (0.3, 0.35, 0.2) ( colorSpace = "CIE XYZ-D65 - Scene-referred" )
        token outputs:surface
    }
}
""")
    (m,) = load_materials(f)
    assert m.supported and not m.error, m.error
    want = _gf([[0.3, 0.35, 0.2]], Gf.ColorSpaceNames.LinearCIEXYZD65)[0]
    assert np.allclose(m.parameters["diffuseColor"].value, want, rtol=1e-5)
