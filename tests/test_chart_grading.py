"""Grading rendered chart images (``check --image``): images built here from chart.json with
the library's ``evaluate`` for the OTHER models (never from the grader's own predictions),
written with OpenImageIO and graded through the command line."""

from __future__ import annotations

import json
import math

import numpy as np
import OpenImageIO as oiio
import pytest

from openpbr_diffuse.chart.layout import build_scene
from openpbr_diffuse.cli.main import main
from openpbr_diffuse.models import evaluate

RES = 256


@pytest.fixture(scope="module", params=[35.0, 110.0], ids=["LdotV>0", "LdotV<0"])
def scene(request, tmp_path_factory):
    d = tmp_path_factory.mktemp("chart")
    s = build_scene(request.param, "distant", RES, 1)
    path = d / "chart.json"
    path.write_text(json.dumps(s))
    return s, path


def _image(scene, brdf):
    """Every tile filled with brdf(wi, wo, r, rho) mu_i E (a distant light)."""
    E = scene["light"]["irradiance"]
    img = np.zeros((scene["height"], scene["width"], 3))
    for t in scene["tiles"]:
        wi, wo = np.array(t["wi"]), np.array(t["wo"])
        f = np.asarray(brdf(wi, wo, t["roughness"], np.array(t["rho"])), float).reshape(3)
        x0, y0, x1, y1 = t["rect"]
        img[y0:y1, x0:x1] = f * wi[2] * E
    return img


def _eon(wi, wo, r, rho):
    return evaluate("eon", wi, wo, r, rho)


def _write(path, img, fmt=oiio.FLOAT):
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), oiio.ImageSpec(img.shape[1], img.shape[0], 3, fmt))
    assert out.write_image(np.ascontiguousarray(img, np.float32))
    out.close()
    return path


def _check(tmp_path, capsys, scene, img, *extra, name="render.exr", fmt=oiio.FLOAT):
    p = _write(tmp_path / name, img, fmt)
    code = main(["check", "--image", str(p), "--chart", str(scene[1]), "--json", *extra])
    out = capsys.readouterr().out
    return code, json.loads(out)


def test_the_reference_conforms(scene, tmp_path, capsys):
    code, d = _check(tmp_path, capsys, scene, _image(scene[0], _eon))
    assert code == 0 and d["passed"] and d["non_linear"] is None
    assert abs(d["exposure"] - 1.0) < 1e-5


def test_noise_of_one_percent_per_pixel_conforms(scene, tmp_path, capsys):
    # each tile's mean has a standard error of 1 % / sqrt(n pixels); 4 of them are allowed
    rng = np.random.default_rng(7)
    img = _image(scene[0], _eon)
    img = img * (1.0 + 0.01 * rng.standard_normal(img.shape))
    code, d = _check(tmp_path, capsys, scene, img)
    assert code == 0 and d["passed"], d["diagnosis_detail"]
    assert d["image_tolerance"]["relative"] > 5e-3  # widened by the measured noise (~4 x 1 %/7)
    # without the standard-error band the same image fails: the band is what lets it pass
    from openpbr_diffuse.chart.grading import grade_image

    assert not grade_image(img, scene[0], k_sigma=0.0).passed


def test_exposure_times_two_conforms_and_reports_the_factor(scene, tmp_path, capsys):
    code, d = _check(tmp_path, capsys, scene, 2.0 * _image(scene[0], _eon))
    assert code == 0 and d["passed"]
    assert abs(d["exposure"] - 2.0) <= 0.02
    code, d = _check(tmp_path, capsys, scene, 2.0 * _image(scene[0], _eon), "--absolute", name="abs.exr")
    assert code == 1 and not d["passed"]


def test_srgb_encoded_exr_is_reported_as_non_linear_output(scene, tmp_path, capsys):
    lin = _image(scene[0], _eon)
    enc = np.where(lin <= 0.0031308, 12.92 * lin, 1.055 * np.maximum(lin, 0) ** (1 / 2.4) - 0.055)
    code, d = _check(tmp_path, capsys, scene, enc)
    assert code == 1 and not d["passed"]
    assert d["non_linear"].startswith("sRGB-encoded")
    assert d["brdf_passed"]  # linearised, the BRDF itself is right: not named a BRDF deviation
    assert d["diagnosis"] is None


def test_text_output_names_the_non_linear_output(scene, tmp_path, capsys):
    lin = _image(scene[0], _eon)
    p = _write(tmp_path / "g.exr", lin ** (1 / 2.2))
    assert main(["check", "--image", str(p), "--chart", str(scene[1])]) == 1
    out = capsys.readouterr().out
    assert "non-linear output: gamma ~ 2.2" in out


def test_an_8_bit_srgb_png_of_the_reference_conforms(scene, tmp_path, capsys):
    lin = _image(scene[0], _eon)
    enc = np.where(lin <= 0.0031308, 12.92 * lin, 1.055 * np.maximum(lin, 0) ** (1 / 2.4) - 0.055)
    code, d = _check(tmp_path, capsys, scene, np.clip(enc, 0, 1), name="r.png", fmt=oiio.UINT8)
    assert code == 0 and d["passed"], d["diagnosis_detail"]


def _qon_sigma_r(wi, wo, r, rho):  # MaterialX OSL: oren_nayar_diffuse_bsdf with sigma = r
    return evaluate("qon", wi, wo, r, rho)


def _lambert(wi, wo, r, rho):
    return rho / math.pi


def _cycles(wi, wo, r, rho):  # f_ss + rho f_ms (Blender Cycles)
    fon = evaluate("fon", wi, wo, r, rho)
    return fon + rho * (evaluate("eon", wi, wo, r, rho) - fon)


@pytest.mark.parametrize(
    "brdf, name",
    [
        (_lambert, "no_energy_compensation_lambert"),
        (_qon_sigma_r, "no_energy_compensation_qon"),
        (_cycles, "rho_ms_extra_rho"),
    ],
)
def test_a_deviation_is_named_from_the_image_alone(scene, tmp_path, capsys, brdf, name):
    code, d = _check(tmp_path, capsys, scene, _image(scene[0], brdf))
    assert code == 1 and not d["passed"]
    assert d["diagnosis"] == name, d["diagnosis_detail"]
    assert abs(d["exposure"] - 1.0) < 1e-3  # the ramp is Lambert in every model


def test_unusable_inputs_exit_2(scene, tmp_path, capsys):
    small = _write(tmp_path / "small.exr", np.zeros((16, 16, 3)))
    assert main(["check", "--image", str(small), "--chart", str(scene[1])]) == 2
    assert main(["check", "--image", str(tmp_path / "missing.exr"), "--chart", str(scene[1])]) == 2
    assert main(["check", "--image", str(small)]) == 2
    bad = tmp_path / "bad.json"
    bad.write_text('{"schema": "openpbr-diffuse-chart/1", "width": 16}')
    assert main(["check", "--image", str(small), "--chart", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 4 and all(e.startswith("openpbr-diffuse check: error: ") for e in err)


def test_junit_and_expected_image_round_trip(scene, tmp_path, capsys):
    exp = tmp_path / "expected.exr"
    assert main(["chart", "--expected-image", str(exp), "--chart", str(scene[1])]) == 0
    junit = tmp_path / "junit.xml"
    assert main(["check", "--image", str(exp), "--chart", str(scene[1]), "--junit", str(junit)]) == 0
    assert "<failure" not in junit.read_text()
    # the expected image is the reference computed independently here
    buf = oiio.ImageBuf(str(exp))
    got = buf.get_pixels(oiio.FLOAT).reshape(scene[0]["height"], scene[0]["width"], -1)[..., :3]
    np.testing.assert_allclose(got, _image(scene[0], _eon), rtol=1e-5, atol=1e-7)
    assert main(["chart", "--expected-image", str(exp), "--chart", str(scene[1])]) == 2  # never replaced


@pytest.mark.slow
def test_blender_cycles_renders_the_chart_and_is_graded(tmp_path, capsys):
    """End to end: the chart's Blender script rendered by Cycles (CPU, 256^2, 16 samples per
    pixel, a couple of seconds) and graded from the image: Cycles' Principled BSDF diffuse
    roughness is EON with the extra rho on its multiple-scattering term."""
    import os
    import subprocess

    from _system import need

    need("bpy")
    from openpbr_diffuse.graders.cycles import bpy_python

    out = tmp_path / "chart"
    assert main(["chart", "--format", "blender", "--out", str(out), "--resolution", str(RES)]) == 0
    capsys.readouterr()
    scene = out / "scene_01"
    exr = tmp_path / "cycles.exr"
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    run = subprocess.run(
        [bpy_python(), str(scene / "render_blender.py"), str(exr), "16"],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
        check=False,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    code = main(["check", "--image", str(exr), "--chart", str(scene / "chart.json"), "--json"])
    d = json.loads(capsys.readouterr().out)
    assert code == 1 and not d["passed"]
    assert d["non_linear"] is None and abs(d["exposure"] - 1.0) < 1e-3  # Sun strength E: irradiance E
    assert d["diagnosis"] == "rho_ms_extra_rho", d["diagnosis_detail"]


def _per_tile_error(scene, img, size, rng, roles=("test",)):
    """Each tile of ``roles`` multiplied by (1 + u), u uniform in [-size, size]: a rasteriser's
    structured error (flat within a tile, different from tile to tile), not pixel noise."""
    img = img.copy()
    for t in scene["tiles"]:
        if t["role"] in roles:
            x0, y0, x1, y1 = t["rect"]
            img[y0:y1, x0:x1] *= 1.0 + size * rng.uniform(-1.0, 1.0)
    return img


def test_lambert_with_rasteriser_error_is_named_as_the_closest_deviation(scene, tmp_path, capsys):
    img = _per_tile_error(scene[0], _image(scene[0], _lambert), 0.02, np.random.default_rng(11))
    code, d = _check(tmp_path, capsys, scene, img)
    assert code == 1 and not d["passed"] and d["diagnosis"] is None
    c = d["closest"]
    assert c["deviation"] == "no_energy_compensation_lambert", d["diagnosis_detail"]
    assert 0.01 < c["residual_max_rel"] <= 0.021  # the 2 % put in, stated
    assert c["improvement"] >= 5
    assert "closest named deviation: no_energy_compensation_lambert" in d["diagnosis_detail"]
    # the same image with EON's values: the error alone is not a deviation (no closest one)
    img = _per_tile_error(scene[0], _image(scene[0], _eon), 0.02, np.random.default_rng(11))
    code, d = _check(tmp_path, capsys, scene, img, name="eon.exr")
    assert code == 1 and d["diagnosis"] != "no_energy_compensation_lambert" and "closest" not in d


def test_the_ramp_scatter_is_a_stated_floor_and_not_a_curve(scene, tmp_path, capsys):
    """A rasteriser's error on the ramp too: not flagged as non-linear (a gamma of ~1 within
    the scatter), measured as the renderer's floor and added to the tolerance -- with it, the
    Lambert lobe is named outright."""
    rng = np.random.default_rng(5)
    img = _per_tile_error(scene[0], _image(scene[0], _lambert), 0.01, rng, roles=("test", "ramp", "white"))
    code, d = _check(tmp_path, capsys, scene, img)
    assert d["non_linear"] is None
    floor = d["image_tolerance"]["renderer_floor"]
    assert 2e-3 < floor < 0.01 and "renderer's own error" in d["image_tolerance"]["rule"]
    # named (with the ramp's 0.25 % exposure error as a factor) or the closest
    name = d["diagnosis"] or d.get("closest", {}).get("deviation", "")
    assert name.endswith("no_energy_compensation_lambert"), d["diagnosis_detail"]
    # a clean ramp has no floor
    code, d = _check(tmp_path, capsys, scene, _image(scene[0], _lambert), name="clean.exr")
    assert d["image_tolerance"]["renderer_floor"] == 0.0


def test_an_image_with_most_tiles_missing_does_not_conform(scene, tmp_path, capsys):
    """Only a few tiles rendered (the rest black, one ramp tile too): the ramp's scatter is
    no renderer floor to widen the tolerance with -- capped, and the image does not conform."""
    img = _image(scene[0], _eon)
    tests = [t for t in scene[0]["tiles"] if t["role"] == "test"]
    ramp = [t for t in scene[0]["tiles"] if t["role"] == "ramp"]
    for t in tests[3:] + ramp[:1]:
        x0, y0, x1, y1 = t["rect"]
        img[y0:y1, x0:x1] = 0.0
    code, d = _check(tmp_path, capsys, scene, img)
    assert code == 1 and not d["passed"]
    tol = d["image_tolerance"]
    assert tol["renderer_floor"] <= 0.02 < tol["renderer_floor_measured"]
    assert "capped" in tol["rule"]


def test_a_ramp_off_by_a_third_of_a_percent_is_linear_but_gamma_1_05_is_not(scene, tmp_path, capsys):
    img = _image(scene[0], _eon)
    ramp = [t for t in scene[0]["tiles"] if t["role"] == "ramp"]
    x0, y0, x1, y1 = min(ramp, key=lambda t: t["rho"][0])["rect"]
    img[y0:y1, x0:x1] *= 1.0 - 3.5e-3  # the darkest ramp tile 0.35 % low (EEVEE's, a gamma of 1.001)
    code, d = _check(tmp_path, capsys, scene, img)
    assert d["non_linear"] is None, d["non_linear"]
    from openpbr_diffuse.chart.grading import grade_image

    assert grade_image(img, scene[0]).ramp_residual > 2e-3  # beyond the ramp's band: the scatter test decides
    code, d = _check(tmp_path, capsys, scene, _image(scene[0], _eon) ** 1.05, name="g105.exr")
    assert d["non_linear"] is not None and d["non_linear"].startswith("gamma ~ 0.95")


def test_code_with_precision_noise_around_lambert_gets_the_closest_deviation():
    """The same tier for code graded on the vectors: Lambert answered with 1 % structured
    error per row; EON's own values with that error have no closest deviation."""
    from openpbr_diffuse.conformance.grade import grade
    from openpbr_diffuse.conformance.vectors import default_vectors

    v = default_vectors()
    v = v.subset((v.model == "eon") & (v.kind == "brdf") & (v.wi[:, 2] > 0) & (v.wo[:, 2] > 0))
    rng = np.random.default_rng(3)
    err = 1.0 + 0.01 * rng.uniform(-1.0, 1.0, (len(v), 1))
    g = grade(v, v.rho / math.pi * err)
    assert g.diagnosis is None and g.closest["deviation"] == "no_energy_compensation_lambert"
    assert "closest named deviation" in g.diagnosis_detail and g.to_dict()["closest"]["residual_max_rel"] <= 0.0101
    eon = np.array([evaluate("eon", a, b, r, rho) for a, b, r, rho in zip(v.wi, v.wo, v.roughness, v.rho)])
    g = grade(v, eon * err)
    assert g.closest is None and "closest" not in g.to_dict()
