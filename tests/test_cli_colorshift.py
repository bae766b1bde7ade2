"""``openpbr-diffuse colorshift``: table, JSON schema, swatch image, colour inputs, errors."""

import json

import numpy as np
import pytest

from openpbr_diffuse._colour import _colour

colour = _colour()  # colour-science through the package: NumPy's print options left as they were

pytestmark = pytest.mark.filterwarnings("ignore::colour.utilities.ColourRuntimeWarning")

from openpbr_diffuse.cli.main import main  # noqa: E402

FIELDS = {
    "patch",
    "source",
    "roughness",
    "mu",
    "rho_rgb",
    "rho_rgb_clipped",
    "albedo_spectral",
    "albedo_rgb",
    "albedo_white_tint",
    "delta_e_rgb_vs_spectral",
    "rel_luminance_diff_rgb_vs_spectral",
    "chroma_diff_rgb_vs_spectral",
    "delta_e_shift",
    "rel_luminance_diff_shift",
    "chroma_diff_shift",
    "roundtrip_delta_e",
}


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_default_json_schema(capsys):
    code, out, err = run(capsys, "colorshift", "--json")
    assert code == 0
    doc = json.loads(out)
    s = doc["settings"]
    assert 1.0 in s["mu"]  # the default mu grid includes normal view
    assert s["illuminant"] == "D65" and s["working_space"] == "lin_rec709"
    assert s["observer"] == "CIE 1931 2 Degree Standard Observer"
    assert s["chromatic_adaptation"].startswith("Bradford")
    assert s["spectral_shape"] == {"start_nm": 380.0, "end_nm": 780.0, "interval_nm": 5.0, "samples": 81}
    rows = doc["rows"]
    assert len(rows) == 24 * len(s["roughness"]) * len(s["mu"])
    assert set(rows[0]) == FIELDS
    assert rows[0]["patch"] == "dark skin" and rows[0]["roundtrip_delta_e"] is None
    assert s["roundtrip_delta_e_max"] is None  # measured spectra: no upsampling
    # independent: rho_rgb of a patch is colour-science's own sd_to_XYZ -> XYZ_to_RGB (Bradford)
    sd = colour.SDS_COLOURCHECKERS["BabelColor Average"]["dark skin"]
    XYZ = (
        colour.sd_to_XYZ(
            sd,
            colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"],
            colour.SDS_ILLUMINANTS["D65"],
            method="Integration",
        )
        / 100
    )
    rgb = colour.XYZ_to_RGB(
        XYZ,
        "ITU-R BT.709",
        illuminant=colour.XYZ_to_xy(
            colour.sd_to_XYZ(
                colour.sd_ones(),
                colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"],
                colour.SDS_ILLUMINANTS["D65"],
                method="Integration",
            )
            / 100
        ),
        chromatic_adaptation_transform="Bradford",
    )
    np.testing.assert_allclose(rows[0]["rho_rgb"], rgb, atol=2e-4)  # 1 nm vs 5 nm sampling


def test_table_output_and_summary(capsys):
    code, out, err = run(capsys, "colorshift", "--roughness", "0", "1", "--mu", "1")
    assert code == 0 and not err
    assert "illuminant D65" in out and "380-780 nm / 5 nm" in out and "Bradford" in out
    assert "cyan*" in out  # out of the Rec.709 gamut, flagged
    assert "r = 1, mu = 1: dE rgb/spec max 2.8468 (cyan), in gamut 1.4845 (orange yellow)" in out
    assert out.count("\n") > 48


def test_rgb_colours_and_methods(capsys):
    code, out, _ = run(
        capsys,
        "colorshift",
        "--colors",
        "0.8,0.2,0.1",
        "0.5,0.5,0.5",
        "--roughness",
        "1",
        "--mu",
        "0.5",
        "--method",
        "otsu2018",
        "--json",
    )
    assert code == 0
    doc = json.loads(out)
    assert doc["settings"]["method"] == "Otsu 2018"
    assert doc["settings"]["roundtrip_delta_e_max"] == pytest.approx(max(r["roundtrip_delta_e"] for r in doc["rows"]))
    rows = doc["rows"]
    assert [r["patch"] for r in rows] == ["0.8,0.2,0.1", "0.5,0.5,0.5"]
    assert rows[0]["rho_rgb"] == [0.8, 0.2, 0.1]
    assert 0 <= rows[0]["roundtrip_delta_e"] < 0.05 and "Otsu 2018" in rows[0]["source"]
    # grey: spectrally flat up to the upsampling, so RGB and spectral agree closely
    assert rows[1]["delta_e_rgb_vs_spectral"] < 0.05
    assert rows[0]["delta_e_shift"] > 1.0


def test_acescg_and_illuminant(capsys):
    code, out, _ = run(
        capsys,
        "colorshift",
        "--colors",
        "checker",
        "--working-space",
        "acescg",
        "--illuminant",
        "D50",
        "--roughness",
        "0.5",
        "--mu",
        "1",
        "--json",
    )
    assert code == 0
    doc = json.loads(out)
    assert doc["settings"]["working_space"] == "acescg" and doc["settings"]["illuminant"] == "D50"
    assert doc["settings"]["method_resolved"] == "Otsu 2018"
    assert not any(r["rho_rgb_clipped"] for r in doc["rows"])


def test_spectra_csv(tmp_path, capsys):
    wl = np.arange(400, 701, 10)
    lines = ["wavelength,flat,ramp"] + [f"{w},0.4,{(w - 400) / 300 * 0.8 + 0.1:.4f}" for w in wl]
    path = tmp_path / "spectra.csv"
    path.write_text("# measured\n" + "\n".join(lines) + "\n")
    code, out, _ = run(capsys, "colorshift", "--colors", str(path), "--roughness", "1", "--mu", "1", "--json")
    assert code == 0
    rows = json.loads(out)["rows"]
    assert [r["patch"] for r in rows] == ["flat", "ramp"]
    assert rows[0]["delta_e_rgb_vs_spectral"] < 1e-6  # flat spectrum: no RGB/spectral difference
    assert rows[1]["delta_e_rgb_vs_spectral"] > 1e-3


def test_image(tmp_path, capsys):
    import OpenImageIO as oiio

    path = tmp_path / "sw.png"
    code, out, _ = run(
        capsys, "colorshift", "--colors", "checker", "--roughness", "0", "1", "--mu", "1", "--image", str(path)
    )
    assert code == 0 and path.exists()
    buf = oiio.ImageBuf(str(path))
    spec = buf.spec()
    assert spec.nchannels == 3 and spec.height > 24 * 28 and spec.width > 2 * 4 * 28
    px = buf.get_pixels(oiio.FLOAT)
    from openpbr_diffuse.spectral import swatches

    # the L swatch of the white patch (row 18) at r = 0 is its sRGB-encoded rho_rgb
    y = swatches.HEAD_H + 18 * (swatches.SWATCH + 4) + swatches.SWATCH // 2
    x = swatches.LABEL_W + 2
    white = colour.cctf_encoding(np.clip(json.loads(main_json(capsys))["rows"][18 * 2]["rho_rgb"], 0, 1))
    np.testing.assert_allclose(px[y, x], white, atol=2.5 / 255)
    # labels were drawn: the label column is not uniform
    assert px[:, : swatches.LABEL_W].std() > 0.01


def main_json(capsys):
    main(["colorshift", "--colors", "checker", "--roughness", "0", "1", "--mu", "1", "--json"])
    return capsys.readouterr()[0]


def test_material_files_need_the_readers_or_work(tmp_path, capsys):
    """Material files go through openpbr_diffuse.readers.load_materials."""
    path = tmp_path / "m.mtlx"
    path.write_text("""<?xml version="1.0"?>
<materialx version="1.39">
  <open_pbr_surface name="red_clay" type="surfaceshader">
    <input name="base_color" type="color3" value="0.6, 0.2, 0.1" />
    <input name="base_diffuse_roughness" type="float" value="0.8" />
  </open_pbr_surface>
  <surfacematerial name="M_red_clay" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="red_clay" />
  </surfacematerial>
</materialx>
""")
    before = path.read_bytes()
    code, out, err = run(
        capsys,
        "colorshift",
        "--colors",
        str(path),
        "--working-space",
        "acescg",
        "--roughness",
        "1",
        "--mu",
        "1",
        "--json",
    )
    assert path.read_bytes() == before  # never modified
    try:
        import openpbr_diffuse.readers  # noqa: F401
    except ImportError:
        assert code == 2 and "readers" in err and err.count("\n") == 1
        return
    assert code == 0
    rows = json.loads(out)["rows"]
    assert len(rows) == 1 and rows[0]["rho_rgb"] == pytest.approx([0.6, 0.2, 0.1])
    assert rows[0]["material_diffuse_roughness"] == pytest.approx(0.8)


@pytest.mark.parametrize(
    "argv,match",
    [
        (["--colors", "0.5,0.5"], "R,G,B"),
        (["--colors", "0.5,x,0.5"], "R,G,B"),
        (["--colors", "1.5,0.5,0.5"], "[0, 1]"),
        (["--colors", "nosuchfile.usda"], "existing file"),
        (["--roughness", "2"], "roughness"),
        (["--mu", "-0.5"], "mu"),
        (["--method", "smits"], "--method"),
        (["--illuminant", "D66"], "illuminant"),
        (["--working-space", "srgb"], "working_space"),
        (["--colors", "0.9,0.05,0.05", "--working-space", "acescg", "--method", "mallett2019"], "gamut"),
    ],
)
def test_bad_input_one_line_exit_2(capsys, argv, match):
    code, out, err = run(capsys, "colorshift", *argv)
    assert code == 2 and not out
    assert err.count("\n") == 1 and match in err


def test_unwritable_image(capsys, tmp_path):
    code, _, err = run(
        capsys, "colorshift", "--roughness", "1", "--mu", "1", "--image", str(tmp_path / "no" / "dir" / "x.png")
    )
    assert code == 2 and err.count("\n") == 1


def test_bundled_materials_colours(capsys):
    """Every supported bundled material becomes a row; its rho_rgb is the reader's ACEScg colour
    converted to lin_rec709 (checked with OpenImageIO's OCIO conversion, Bradford)."""
    import OpenImageIO as oiio

    from openpbr_diffuse import readers

    path = readers.BUNDLED_MATERIALS / "clay_rough.mtlx"
    mats = [m for m in readers.load_materials(path) if m.supported]
    code, out, _ = run(capsys, "colorshift", "--colors", str(path), "--roughness", "0.5", "--mu", "1", "--json")
    assert code == 0
    rows = json.loads(out)["rows"]
    assert [r["patch"] for r in rows] == [m.name for m in mats]
    aces = np.array([m.node_inputs["base_color"].value for m in mats], np.float32)
    buf = oiio.ImageBufAlgo.colorconvert(
        oiio.ImageBuf(np.ascontiguousarray(aces[None])), "ACEScg", "Linear Rec.709 (sRGB)"
    )
    np.testing.assert_allclose([r["rho_rgb"] for r in rows], np.clip(buf.get_pixels(oiio.FLOAT)[0], 0, 1), atol=2e-4)
    assert rows[0]["material_diffuse_model"] == "eon" and rows[0]["material_diffuse_roughness"] is not None


def test_black_and_white_colours_give_finite_json(capsys):
    code, out, _ = run(
        capsys, "colorshift", "--colors", "0,0,0", "1,1,1", "--roughness", "0", "1", "--mu", "0", "1", "--json"
    )
    assert code == 0
    assert "NaN" not in out and "Infinity" not in out
    rows = json.loads(out)["rows"]
    black = [r for r in rows if r["patch"] == "0,0,0"]
    assert all(r["rel_luminance_diff_shift"] == 0 and r["delta_e_shift"] < 1e-6 for r in black)
    white = [r for r in rows if r["patch"] == "1,1,1"]
    assert all(abs(r["rel_luminance_diff_shift"]) < 1e-6 for r in white)  # white furnace


@pytest.mark.parametrize(
    "name,text,match",
    [
        ("colours.txt", "0.5,0.5,0.5\n", ".csv"),
        ("bad.csv", "wavelength,a\n400,0.5\n410,0.5\n", "at least 6"),
        ("bad2.csv", "wavelength,a\n" + "".join(f"{400 + 10 * i},0.5\n" for i in range(6)) + "470,x\n", "numbers"),
        ("bad3.csv", "wavelength,a\n" + "".join(f"{400 + 10 * i},0.5\n" for i in range(6)) + "470,1.5\n", "[0, 1]"),
        (
            "bad5.csv",
            "wavelength,a\n" + "".join(f"{400 + 10 * i},0.5\n" for i in range(6)) + "470,0.5,0.2\n",
            "columns",
        ),
        ("bad4.csv", "wavelength,a\n" + "".join(f"{480 - 10 * i},0.5\n" for i in range(7)), "increase"),
    ],
)
def test_bad_files_one_line_exit_2(tmp_path, capsys, name, text, match):
    path = tmp_path / name
    path.write_text(text)
    code, out, err = run(capsys, "colorshift", "--colors", str(path), "--roughness", "1", "--mu", "1")
    assert code == 2 and not out and err.count("\n") == 1 and match in err


def test_image_exr_keeps_linear_working_space_values(tmp_path, capsys):
    import OpenImageIO as oiio

    from openpbr_diffuse.spectral import swatches

    path = tmp_path / "sw.exr"
    code, _, _ = run(
        capsys,
        "colorshift",
        "--colors",
        "0.8,0.3,0.1",
        "--working-space",
        "acescg",
        "--roughness",
        "1",
        "--mu",
        "1",
        "--image",
        str(path),
    )
    assert code == 0
    doc = json.loads(
        main_json_args(capsys, "--colors", "0.8,0.3,0.1", "--working-space", "acescg", "--roughness", "1", "--mu", "1")
    )
    row = doc["rows"][0]
    buf = oiio.ImageBuf(str(path))
    assert buf.spec().get_string_attribute("oiio:ColorSpace") in ("ACEScg", "lin_ap1_scene")  # OIIO normalises
    px = buf.get_pixels(oiio.FLOAT)
    y = swatches.HEAD_H + swatches.SWATCH // 2
    for j, name in enumerate(("rho_rgb", "albedo_rgb", "albedo_spectral", "albedo_white_tint")):
        x = swatches.LABEL_W + j * swatches.SWATCH + swatches.SWATCH // 2
        np.testing.assert_allclose(px[y, x], row[name], rtol=2e-3, atol=1e-4)


def main_json_args(capsys, *argv):
    main(["colorshift", *argv, "--json"])
    return capsys.readouterr()[0]
