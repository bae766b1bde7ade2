"""The common bugs, named: each deviation written independently (``tests/_hand_impl.py``,
formulas typed from the EON paper in plain NumPy) is diagnosed by name through the public
``grade()`` API and as the rows of a filled CSV template through ``check FILE``; mutants that
match no known deviation say so, with no "closest".  (The same bugs written as GLSL and C++
code: tests/test_subjects_deviations.py.)
"""

import json
import math

import _hand_impl as hand
import numpy as np
import pytest

from openpbr_diffuse.cli.main import main
from openpbr_diffuse.conformance.grade import NOT_EXPLAINED, grade
from openpbr_diffuse.conformance.vectors import default_vectors, write_vectors

V = default_vectors()

#: diagnosis -> the hand implementation's switches (and a fragment the detail must hold)
COMMON_BUGS = {
    "pi_forgotten": ("constant_factor", dict(scale=math.pi), "x 3.1416 (1/pi forgotten)"),
    "extra_inv_pi": ("constant_factor", dict(scale=1 / math.pi), "an extra 1/pi"),
    "times_two": ("constant_factor", dict(scale=2.0), "x 2"),
    "any_scale": ("constant_factor", dict(scale=0.731), "x 0.731"),
    "pi_forgotten_brdf_only": ("constant_factor", dict(scale=math.pi, scale_brdf_only=True), "BRDF"),
    "ms_missing_inv_pi": ("ms_missing_inv_pi", dict(ms_scale="times_pi"), "f_ms"),
    "ms_extra_inv_pi": ("rho_ms_extra_inv_pi", dict(ms_scale="inv_pi"), "f_ms"),
    "cos_included": ("times_cos_theta_i", dict(times_cos=True), "mu_i"),
    "cos_divided_out": ("divided_by_cos_theta_i", dict(divide_cos=True), "mu_i"),
    "cos_of_wo": ("times_cos_theta_i+wi_wo_swapped", dict(cos_wo=True), "swapped"),
    "sigma_vs_r": ("roughness_sigma_vs_r", dict(roughness="sigma_vs_r"), ""),
    "r_squared": ("roughness_squared", dict(roughness="squared"), ""),
    "degrees": ("roughness_degrees", dict(roughness="degrees"), "pi/180"),
    "srgb_encoded": ("rho_srgb_encoded", dict(rho_srgb="encode"), "srgb_encode"),
    "srgb_decoded_twice": ("rho_srgb_encoded", dict(rho_srgb="decode"), "srgb_decode"),
    "mu_floor_0.01": ("mu_floor", dict(mu_floor=0.01), "max(mu, 0.01)"),
    "mu_floor_0.05": ("mu_floor", dict(mu_floor=0.05), "max(mu, 0.05)"),
    "eq14": ("eq14_fit_for_exact", dict(ef_fit=True), "--model eon_approx"),
    "qon": ("no_energy_compensation_qon", dict(energy="qon"), ""),
    "fon": ("no_energy_compensation_fon", dict(energy="fon"), ""),
    "lambert": ("no_energy_compensation_lambert", dict(energy="lambert"), ""),
}


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("case", sorted(COMMON_BUGS))
def test_common_bug_is_named(case, dtype):
    name, switches, fragment = COMMON_BUGS[case]
    g = grade(V, hand.answer(V, dtype, **switches))
    assert not g.passed
    assert g.diagnosis == name, (g.diagnosis, g.diagnosis_detail)
    assert fragment in g.diagnosis_detail
    assert "closest" not in g.diagnosis_detail


@pytest.mark.parametrize("case", ["pi_forgotten", "ms_missing_inv_pi", "mu_floor_0.01", "eq14", "lambert"])
def test_common_bug_named_from_eon_rows_only(case):
    name, switches, _ = COMMON_BUGS[case]
    eon = V.subset(V.model == "eon")
    g = grade(eon, hand.answer(eon, np.float32, **switches))
    assert g.diagnosis == name, g.diagnosis_detail


def _mutants():
    rng = np.random.default_rng(7)
    ref = hand.answer(V, np.float64)
    yield "random_perturbation", ref * (1.0 + 0.05 * rng.standard_normal(ref.shape))
    yield "wrong_A_coefficient", hand.answer(V, np.float64, c1=0.33)
    yield "offset", ref + 0.01
    both = hand.answer(V, np.float64, scale=math.pi, mu_floor=0.02)  # two bugs at once: neither alone
    yield "two_bugs", both
    wavy = ref.copy()  # f x (1 + 0.3 sin(7 mu_i)): like no known bug
    brdf = V.kind == "brdf"
    wavy[brdf] *= (1.0 + 0.3 * np.sin(7.0 * np.maximum(V.wi[brdf, 2], 0.0)))[:, None]
    yield "sin_mu_i", wavy


@pytest.mark.parametrize("case,out", list(_mutants()), ids=lambda x: x if isinstance(x, str) else "")
def test_mutant_is_not_explained(tmp_path, capsys, case, out):
    g = grade(V, out)
    assert not g.passed and g.diagnosis is None
    assert g.diagnosis_detail.startswith(NOT_EXPLAINED)
    assert "closest" not in g.diagnosis_detail
    path = tmp_path / "r.csv"
    write_vectors(V, path, out=out)
    assert main(["check", str(path)]) == 1
    text = capsys.readouterr().out
    assert NOT_EXPLAINED in text and "closest" not in text.lower()
    assert main(["check", str(path), "--json"]) == 1
    d = json.loads(capsys.readouterr().out)
    assert d["diagnosis"] is None and "closest" not in json.dumps(d).lower()


def test_regions_and_nonfinite_counts():
    out = hand.answer(V, np.float64)
    low = np.minimum(V.wi[:, 2], V.wo[:, 2])
    graz_brdf = (V.kind == "brdf") & (low > 0) & (low < 0.1)
    graz = graz_brdf | ((V.kind == "albedo") & (V.mu < 0.1))
    k = np.flatnonzero(graz_brdf)
    out[k[0], 0] = math.nan
    out[k[1], 2] = math.inf
    out[k[2]] *= 1.5
    g = grade(V, out)
    assert (g.n_nan, g.n_inf) == (1, 1)
    reg = {r["region"]: r for r in g.regions}
    assert reg["grazing (mu < 0.1)"]["n_failed"] == 3 and reg["grazing (mu < 0.1)"]["n"] == int(graz.sum())
    assert reg["all"]["n_failed"] == 3
    statuses = {w["status"] for w in g.worst}
    assert {"nan", "inf", "fail"} <= statuses
    w = g.worst[0]
    assert {"wi", "wo", "mu_i", "mu_o", "ldotv", "roughness", "rho", "model", "expected", "got"} <= set(w)


def test_check_text_names_nan_and_shows_inputs(tmp_path, capsys):
    out = hand.answer(V, np.float64)
    out[5, 1] = math.nan
    out[40, 0] = math.inf
    path = tmp_path / "r.csv"
    write_vectors(V, path, out=out)
    assert main(["check", str(path)]) == 1
    text = capsys.readouterr().out
    assert "NaN output" in text and "Inf output" in text and "infx" not in text
    assert "1 NaN values, 1 Inf values" in text
    assert "mu_i" in text and "L.V" in text and "by region" in text and "grazing (mu < 0.1)" in text


def _fill_template(template, out, rows):
    """The CSV template as a user fills it: out_r, out_g, out_b written on ``rows`` only."""
    lines, k = [], 0
    for line in template.read_text().splitlines():
        if not line.startswith("#") and not line.startswith("id,"):
            if rows[k]:
                line = line[: -len(",,")] + ",".join(repr(float(x)) for x in out[k])
            k += 1
        lines.append(line)
    assert k == len(V)
    return "\n".join(lines) + "\n"


@pytest.fixture(scope="module")
def csv_template(tmp_path_factory):
    path = tmp_path_factory.mktemp("template") / "vectors.csv"
    assert main(["template", "csv", "--out", str(path)]) == 0
    return path


@pytest.mark.parametrize("case", sorted(COMMON_BUGS))
def test_common_bug_named_from_the_filled_csv_template(case, csv_template, tmp_path, capsys):
    """Only the EON rows of the template filled (float32 values, as a shader writes them):
    check FILE skips the blank rows and names the bug."""
    name, switches, fragment = COMMON_BUGS[case]
    eon = V.model == "eon"
    path = tmp_path / "filled.csv"
    path.write_text(_fill_template(csv_template, hand.answer(V, np.float32, **switches), eon))
    capsys.readouterr()
    # the Eq. 14 fit where exact EON is claimed is a bounded deviation: "conforms with warnings", exit 0
    bounded = name == "eq14_fit_for_exact"
    assert main(["check", str(path), "--json"]) == (0 if bounded else 1)
    d = json.loads(capsys.readouterr().out)
    assert d["tier"] == ("conforms with warnings" if bounded else "does not conform")
    assert d["diagnosis"] == name and fragment in d["diagnosis_detail"], d["diagnosis_detail"]
    assert d["n_rows"] == int(eon.sum()) and d["n_skipped"] == len(V) - int(eon.sum())
    assert "closest" not in d["diagnosis_detail"]
