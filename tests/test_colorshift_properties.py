"""Properties of the spectral vs RGB colour-shift pipeline, against independent computations.

Independent references used here: colour-science's own ``sd_to_XYZ`` (both its ASTM E308
and Integration methods) of the measured ColorChecker spectra; the quadrature reference
tables of EON's albedo (``reference_albedo``, data/albedo_eon.csv) in place of the closed
form; OpenImageIO's OCIO colour conversion (Bradford) between working spaces; Lambert
(E = rho) where EON must reduce to it.
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import openpbr_diffuse as od  # noqa: E402
from openpbr_diffuse import spectral as sp  # noqa: E402
from openpbr_diffuse._colour import _colour  # noqa: E402

colour = _colour()  # colour-science through the package: NumPy's print options left as they were
from openpbr_diffuse.spectral import recovery  # noqa: E402

# colour-science notes every re-shaping of a distribution it aligns for sd_to_XYZ
pytestmark = pytest.mark.filterwarnings("ignore::colour.utilities.ColourRuntimeWarning")
WORKING_SPACES = ["lin_rec709", "acescg"]
MU = [0.05, 0.2, 0.5, 1.0]


@pytest.fixture(scope="module", params=WORKING_SPACES)
def cm(request):
    return sp.colorimetry("D65", request.param)


@pytest.fixture(scope="module")
def checker_result(cm):
    return sp.colour_shift(sp.checker(cm), np.linspace(0.0, 1.0, 41), MU, cm)


def xy(XYZ):
    return XYZ[..., :2] / XYZ.sum(axis=-1, keepdims=True)


def test_checker_XYZ_equals_colour_sd_to_XYZ(cm):
    """At r = 0 the pipeline's XYZ of every patch is colour-science's own sd_to_XYZ of it."""
    res = sp.colour_shift(sp.checker(cm), [0.0], [0.5], cm)
    sds = colour.SDS_COLOURCHECKERS["BabelColor Average"]
    XYZ = res.XYZ["spectral"][:, 0, 0]
    integration = np.array(
        [colour.sd_to_XYZ(sds[n], cm.cmfs, cm.illuminant_sd, method="Integration") for n in res.colours.names]
    )
    np.testing.assert_allclose(XYZ, integration, rtol=0, atol=1e-9)
    # the default (ASTM E308 weighting tables on the measured 10 nm data): a different
    # integration rule, so close but not identical
    astm = np.array([colour.sd_to_XYZ(sds[n], cm.cmfs, cm.illuminant_sd) for n in res.colours.names])
    np.testing.assert_allclose(XYZ, astm, rtol=0, atol=0.02)
    assert float(cm.delta_E(cm.XYZ_to_Lab(XYZ), cm.XYZ_to_Lab(astm)).max()) < 0.01
    # perfect reflector at Y = 100 and the illuminant's white as Lab reference white
    np.testing.assert_allclose(cm.XYZ_to_Lab(cm.white_XYZ), [100.0, 0.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(
        cm.white_XYZ,
        colour.sd_to_XYZ(colour.sd_ones(cm.colour_shape), cm.cmfs, cm.illuminant_sd, method="Integration"),
        atol=1e-9,
    )


def test_no_difference_at_zero_roughness(checker_result):
    """EON at r = 0 is Lambert (linear in rho): all three albedos equal rho_rgb, dE = 0."""
    res = checker_result
    inside = ~res.rho_rgb_clipped
    for name in ("albedo_spectral", "albedo_rgb", "albedo_white_tint"):
        np.testing.assert_allclose(
            getattr(res, name)[inside, 0],
            np.broadcast_to(res.rho_rgb[inside, None, :], (inside.sum(), len(MU), 3)),
            rtol=0,
            atol=1e-6,
        )
    assert res.delta_e_rgb_vs_spectral[inside, 0].max() < 1e-5
    assert res.delta_e_shift[:, 0].max() < 1e-5
    assert abs(res.rel_luminance_diff_shift[:, 0]).max() < 1e-6


def test_clipped_patches_are_flagged(cm, checker_result):
    """Only Rec.709 'cyan' (R < 0) is outside its working space; ACEScg holds all 24."""
    names = [n for n, c in zip(checker_result.colours.names, checker_result.rho_rgb_clipped) if c]
    assert names == (["cyan"] if cm.working_space == "lin_rec709" else [])


@pytest.mark.parametrize("value", [0.03, 0.2, 0.5, 0.9, 1.0])
def test_flat_spectrum_rgb_equals_spectral(cm, value):
    """A spectrally flat reflectance: RGB and spectral evaluation agree, and equal the
    quadrature-table albedo of the grey (independent of EON's closed form)."""
    S = np.full((1, cm.wavelengths.size), value)
    cs = sp.ColourSet(["flat"], S, cm.XYZ_to_RGB(cm.spectra_to_XYZ(S)), ["flat"], np.array([np.nan]))
    np.testing.assert_allclose(cs.rho_rgb, value, atol=1e-9)  # grey stays grey through Bradford
    r = np.array([0.0, 0.3, 0.7, 1.0])
    res = sp.colour_shift(cs, r, MU, cm)
    np.testing.assert_allclose(res.albedo_rgb, res.albedo_spectral, rtol=0, atol=1e-9)
    assert res.delta_e_rgb_vs_spectral.max() < 1e-6
    E = od.reference_albedo("eon", np.array(MU)[None, :], r[:, None], [value])[..., 0]
    np.testing.assert_allclose(res.albedo_spectral[0], np.repeat(E[..., None], 3, -1), rtol=0, atol=1e-5)


def test_white_tint_keeps_chromaticity_of_rho(checker_result):
    """rho * E(rho = 1) is a scalar multiple of rho: its xy is the patch's xy exactly."""
    res = checker_result
    sds = colour.SDS_COLOURCHECKERS["BabelColor Average"]
    cm = res.colorimetry
    ref = xy(
        np.array([colour.sd_to_XYZ(sds[n], cm.cmfs, cm.illuminant_sd, method="Integration") for n in res.colours.names])
    )
    got = xy(res.XYZ["white_tint"])
    np.testing.assert_allclose(got, np.broadcast_to(ref[:, None, None], got.shape), rtol=0, atol=1e-12)
    # ... while the reference colour mode moves away from it once r > 0
    assert np.abs(xy(res.XYZ["spectral"])[:, -1] - ref[:, None]).max() > 1e-3


def test_white_tint_equals_library_white_tint_mode(cm):
    """albedo_white_tint is directional_albedo(..., color_mode="white_tint") per wavelength."""
    cs = sp.checker(cm)
    r, mu = np.array([0.3, 1.0]), np.array([0.2, 1.0])
    res = sp.colour_shift(cs, r, mu, cm)
    E = od.directional_albedo(
        "eon", mu[None, None, :], r[None, :, None], cs.spectra[:, None, None, :], color_mode="white_tint"
    )
    np.testing.assert_allclose(res.albedo_white_tint, cm.XYZ_to_RGB(cm.spectra_to_XYZ(E)), rtol=0, atol=1e-12)


def test_shift_saturates_monotonically_with_roughness(checker_result):
    """For chromatic patches (C*ab > 2) and mu > 0, CIE saturation C*/L*, the distance of xy
    from the white point and the HSV saturation of albedo_rgb all grow strictly with r."""
    res = checker_result
    Lab = res.Lab["spectral"]
    C = np.hypot(Lab[..., 1], Lab[..., 2])
    chromatic = C[:, 0, 0] > 2.0
    assert chromatic.sum() == 19  # the 5 neutrals excluded
    sat = (C / Lab[..., 0])[chromatic]
    assert (np.diff(sat, axis=1) > 0).all()
    dist = np.linalg.norm(xy(res.XYZ["spectral"]) - res.colorimetry.white_xy, axis=-1)[chromatic]
    assert (np.diff(dist, axis=1) > 0).all()
    a = res.albedo_rgb[chromatic & ~res.rho_rgb_clipped]
    hsv = (a.max(-1) - a.min(-1)) / a.max(-1)
    assert (np.diff(hsv, axis=1) > 0).all()


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.floats(0.01, 1.0), min_size=3, max_size=3).filter(lambda c: max(c) - min(c) > 0.05),
    st.floats(0.01, 1.0),
)
def test_per_channel_saturation_grows_with_roughness(rgb, mu):
    """Per channel, E(rho)/rho = E_F + (rho_ms/rho)(1 - E_F) grows with rho (Eq. 18, 20), so the
    channels spread apart as r grows: HSV saturation of the RGB-evaluated albedo increases.
    Checked on the quadrature tables (reference_albedo), not the closed form."""
    r = np.linspace(0.0, 1.0, 11)
    E = od.reference_albedo("eon", mu, r, np.asarray(rgb))  # (11, 3)
    sat = (E.max(-1) - E.min(-1)) / E.max(-1)
    assert (np.diff(sat) > -1e-9).all() and sat[-1] > sat[0]


def test_metameric_spectrum_can_lose_saturation():
    """Not every spectrum gets more saturated: this smooth blue (found in 1742 random smooth
    chromatic spectra, 3 of which behave so) reflects most in the deep red, which EON's
    multiple scattering amplifies; spectrally its saturation C*/L* falls with r while the
    per-channel evaluation of the same colour says it rises."""
    cm = sp.colorimetry()
    wl = cm.wavelengths
    c, w, a = np.array([602.8, 687.5, 494.7]), np.array([32.8, 106.9, 99.5]), np.array([-0.773, 0.548, -0.396])
    S = np.clip((0.5 + (a[:, None] * np.exp(-0.5 * ((wl - c[:, None]) / w[:, None]) ** 2)).sum(0)) * 0.988, 0, 1)
    res = sp.colour_shift(sp.from_spectra([S], cm, ["blue metamer"]), np.linspace(0, 1, 11), [1.0], cm)
    Lab = res.Lab["spectral"][0, :, 0]
    sat = np.hypot(Lab[:, 1], Lab[:, 2]) / Lab[:, 0]
    assert (np.diff(sat) < 0).all()
    a_rgb = res.albedo_rgb[0, :, 0]
    hsv = (a_rgb.max(-1) - a_rgb.min(-1)) / a_rgb.max(-1)
    assert (np.diff(hsv) > 0).all()


def test_no_shift_at_grazing_limit(cm):
    """E_F(mu = 0) = 1 for every r, so E = rho there: no colour shift at mu = 0."""
    res = sp.colour_shift(sp.checker(cm), [0.5, 1.0], [0.0], cm)
    assert res.delta_e_shift.max() < 1e-4


def test_white_furnace_per_wavelength(cm):
    """rho(lambda) = 1: the albedo is 1 at every wavelength, the colour is the illuminant white."""
    S = np.ones((1, cm.wavelengths.size))
    r, mu = np.linspace(0, 1, 11)[:, None], np.linspace(0, 1, 9)[None, :]
    E = od.directional_albedo("eon", mu, r, S[0])
    np.testing.assert_allclose(E, 1.0, rtol=0, atol=1e-6)
    cs = sp.ColourSet(["white"], S, np.ones((1, 3)), ["white"], np.array([np.nan]))
    res = sp.colour_shift(cs, r[:, 0], mu[0], cm)
    np.testing.assert_allclose(res.Lab["spectral"][0], np.broadcast_to([100.0, 0, 0], (11, 9, 3)), atol=1e-4)
    np.testing.assert_allclose(res.albedo_spectral, 1.0, atol=1e-6)
    assert res.delta_e_shift.max() < 1e-4 and res.delta_e_rgb_vs_spectral.max() < 1e-4


def test_albedo_matches_quadrature_tables(cm):
    """The spectral albedo per wavelength matches the quadrature tables for measured spectra."""
    cs = sp.checker(cm)
    r, mu = np.array([0.25, 0.6, 1.0]), np.array([0.1, 0.7, 1.0])
    res = sp.colour_shift(cs, r, mu, cm)
    E = od.reference_albedo("eon", mu[None, None, :], r[None, :, None], cs.spectra[:, None, None, :])
    np.testing.assert_allclose(res.albedo_spectral, cm.XYZ_to_RGB(cm.spectra_to_XYZ(E)), rtol=0, atol=1e-6)


def test_bradford_adaptation_matches_openimageio():
    """ACEScg rho_rgb equals OpenImageIO's (OCIO, Bradford) conversion of the Rec.709 one."""
    import OpenImageIO as oiio

    a = sp.checker(sp.colorimetry("D65", "lin_rec709")).rho_rgb
    b = sp.checker(sp.colorimetry("D65", "acescg")).rho_rgb
    buf = oiio.ImageBuf(np.ascontiguousarray(a[None].astype(np.float32)))
    conv = oiio.ImageBufAlgo.colorconvert(buf, "Linear Rec.709 (sRGB)", "ACEScg")
    np.testing.assert_allclose(conv.get_pixels(oiio.FLOAT)[0], b, rtol=0, atol=2e-4)


def test_other_illuminant_uses_its_own_white():
    """Under illuminant A the perfect reflector is Lab (100, 0, 0) and RGB (1, 1, 1)."""
    cm = sp.colorimetry("A", "lin_rec709")
    xyA = colour.XYZ_to_xy(
        colour.sd_to_XYZ(colour.sd_ones(cm.colour_shape), cm.cmfs, cm.illuminant_sd, method="Integration") / 100
    )
    np.testing.assert_allclose(cm.white_xy, xyA, atol=1e-12)
    np.testing.assert_allclose(cm.XYZ_to_RGB(cm.white_XYZ), 1.0, atol=1e-9)
    assert cm.describe()["illuminant"] == "A"


# ColorChecker at r = 1, D65: per working space and mu, per field:
# (max, max patch, max over in-gamut patches, its patch, median, median patches).
# The numbers the documentation quotes; print them with
#   openpbr-diffuse colorshift --roughness 1 --mu 1 0.5 [--working-space acescg]
HEADLINE = {
    ("lin_rec709", 1.0): {
        "delta_e_rgb_vs_spectral": (2.8468, "cyan", 1.4845, "orange yellow", 0.1081, "purplish blue / purple"),
        "delta_e_shift": (4.4218, "neutral 5 (.70 D)", 4.4218, "neutral 5 (.70 D)", 3.3723, "dark skin / orange"),
    },
    ("lin_rec709", 0.5): {
        "delta_e_rgb_vs_spectral": (2.5150, "cyan", 0.8630, "orange yellow", 0.0611, "purplish blue / purple"),
        "delta_e_shift": (2.6052, "neutral 5 (.70 D)", 2.6052, "neutral 5 (.70 D)", 1.9812, "dark skin / orange"),
    },
    ("acescg", 1.0): {
        "delta_e_rgb_vs_spectral": (0.7167, "red", 0.7167, "red", 0.1261, "blue flower / purple"),
        "delta_e_shift": (4.4218, "neutral 5 (.70 D)", 4.4218, "neutral 5 (.70 D)", 3.3723, "dark skin / orange"),
    },
}


@pytest.mark.parametrize("working_space,mu", list(HEADLINE))
def test_checker_headline_numbers(working_space, mu):
    cm = sp.colorimetry("D65", working_space)
    s = sp.colour_shift(sp.checker(cm), [1.0], [mu], cm).summary(1.0)[mu]
    for name, (largest, patch, largest_in, patch_in, median, median_patches) in HEADLINE[working_space, mu].items():
        assert s[name]["max"][1] == patch and s[name]["max"][0] == pytest.approx(largest, abs=1e-4)
        assert s[name]["max_in_gamut"][1] == patch_in
        assert s[name]["max_in_gamut"][0] == pytest.approx(largest_in, abs=1e-4)
        assert s[name]["median"][1] == median_patches
        assert s[name]["median"][0] == pytest.approx(median, abs=1e-4)


def test_shipped_tables_regression():
    """The shipped ColorChecker tables are reproduced (colour-science version permitting)."""
    from openpbr_diffuse.spectral import reference as ref

    for ws in ref.TABLE_WORKING_SPACES:
        header, cols = ref.load_table(ws)
        assert header["regenerate"] == "python tools/make_colorshift_table.py"
        cm = sp.colorimetry(ref.TABLE_ILLUMINANT, ws)
        res = sp.colour_shift(sp.checker(cm), ref.TABLE_ROUGHNESS, ref.TABLE_MU, cm)
        new = ref.table_lines(res)
        _, fresh = ref.load_table(ws, path=_write(new))
        assert fresh["patch"] == cols["patch"]
        for name in cols:
            if name != "patch":
                np.testing.assert_allclose(fresh[name], cols[name], rtol=0, atol=1e-8, err_msg=f"{ws} {name}")


def _write(lines):
    import tempfile

    with tempfile.NamedTemporaryFile("w", suffix=".csv", delete=False, encoding="utf-8") as f:
        f.write("\n".join(lines) + "\n")
    return f.name


@pytest.mark.parametrize("method,tol", [("Mallett 2019", 0.005), ("Otsu 2018", 0.05)])
def test_recovery_roundtrip(method, tol):
    cm = sp.colorimetry()
    rgb = np.random.default_rng(11).uniform(0.02, 0.95, (12, 3))
    spectra, de = sp.rgb_to_spectra(rgb, cm, method)
    assert spectra.shape == (12, cm.wavelengths.size)
    assert spectra.min() >= 0 and spectra.max() <= 1
    # the reported round trip is the dE2000 of the spectrum's colour, recomputed here with
    # colour-science's own sd_to_XYZ
    XYZ = np.array(
        [
            colour.sd_to_XYZ(
                colour.SpectralDistribution(s, cm.colour_shape), cm.cmfs, cm.illuminant_sd, method="Integration"
            )
            for s in spectra
        ]
    )
    np.testing.assert_allclose(de, cm.delta_E(cm.XYZ_to_Lab(cm.RGB_to_XYZ(rgb)), cm.XYZ_to_Lab(XYZ)), atol=1e-9)
    assert de.max() < tol


def test_recovery_jakob2019_per_colour_optimisation():
    cm = sp.colorimetry()
    spectra, de = sp.rgb_to_spectra([[0.6, 0.3, 0.1]], cm, "Jakob 2019")
    assert de[0] < 0.05 and 0 < spectra.min() and spectra.max() < 1


def test_names_are_case_insensitive_with_aliases():
    assert sp.colorimetry("d65", "ACEScg").describe()["illuminant"] == "D65"
    assert sp.colorimetry("D65", "lin_ap1_scene").working_space == "acescg"
    assert sp.colorimetry("D65", "Rec709").working_space == "lin_rec709"
    assert sp.colorimetry("fl2").illuminant == "FL2"


def test_auto_method_and_method_table():
    assert set(recovery.RECOVERY_METHODS) == {"Mallett 2019", "Otsu 2018", "Jakob 2019"}
    assert recovery.resolve_method("auto", sp.colorimetry()) == "Mallett 2019"
    assert recovery.resolve_method("auto", sp.colorimetry("D65", "acescg")) == "Otsu 2018"


def test_user_rgb_at_zero_roughness_differs_only_by_roundtrip():
    cm = sp.colorimetry()
    cs = sp.from_rgb([[0.7, 0.2, 0.1], [0.1, 0.4, 0.6]], cm, "auto")
    res = sp.colour_shift(cs, [0.0, 1.0], [1.0], cm)
    np.testing.assert_allclose(res.delta_e_rgb_vs_spectral[:, 0, 0], cs.roundtrip_delta_e, atol=1e-9)
    assert (res.delta_e_shift[:, 1] > 0.5).all()


@pytest.mark.parametrize(
    "call,match",
    [
        (lambda: sp.colorimetry("D66"), "illuminant"),
        (lambda: sp.colorimetry("D65", "srgb"), "working_space"),
        (lambda: sp.colorimetry(65), "illuminant"),
        (lambda: sp.rgb_to_spectra([[0.5, 1.2, 0.1]], sp.colorimetry()), "rgb"),
        (lambda: sp.rgb_to_spectra([[0.5, 0.2]], sp.colorimetry()), "rgb"),
        (lambda: sp.rgb_to_spectra([[0.5, 0.2, 0.1]], sp.colorimetry(), "Smits"), "method"),
        (lambda: sp.rgb_to_spectra([[0.8, 0.1, 0.05]], sp.colorimetry("D65", "acescg"), "Mallett 2019"), "gamut"),
        (lambda: sp.colour_shift(sp.checker(sp.colorimetry()), [1.5], [1.0]), "roughness"),
        (lambda: sp.colour_shift(sp.checker(sp.colorimetry()), [0.5], [-0.1]), "mu"),
        (lambda: sp.colour_shift(sp.checker(sp.colorimetry()), [0.5], [float("nan")]), "mu"),
    ],
)
def test_bad_input_raises(call, match):
    with pytest.raises((ValueError, TypeError), match=match):
        call()
