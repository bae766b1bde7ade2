"""The deviations beyond the common bugs, named: each wrong implementation is computed here
from the spec's formulas (tests/_hand_eon.py, plain NumPy, no call into the library or its
deviation predictors), graded through ``grade()`` and, for one, as a CSV through ``check``.
Pairs of deviations are named as the pair; rounding noise is called precision.
"""

import json
import math

import _hand_eon as he
import numpy as np
import pytest

from openpbr_diffuse.cli.main import main
from openpbr_diffuse.conformance.deviations import DEVIATIONS
from openpbr_diffuse.conformance.grade import NOT_EXPLAINED, grade
from openpbr_diffuse.conformance.vectors import default_vectors, write_vectors

V = default_vectors()
EON = V.subset(V.model == "eon")
QON = V.subset(V.model == "qon")
FUJII = default_vectors(["qon_fujii"])

#: the deviations this file implements (the others: tests/_hand_impl.py)
NEW_DEVIATIONS = (
    "roughness_sigma_over_sqrt2",
    "qon_fujii_constants",
    "rho_ms_from_scalar_rho",
    "ms_missing_mu_i_factor",
    "avg_albedo_constant",
    "roughness_floor",
    "nonzero_below_horizon",
)


def test_new_deviations_are_in_the_catalogue():
    assert set(NEW_DEVIATIONS) <= set(DEVIATIONS)
    for name in NEW_DEVIATIONS:  # each says what to fix
        assert any(w in DEVIATIONS[name].description for w in ("use", "pass", "return", "compute", "multiply"))


def _named(vectors, out, name, fragment=""):
    g = grade(vectors, out)
    assert not g.passed
    assert g.diagnosis == name, (g.diagnosis, g.diagnosis_detail)
    assert fragment in g.diagnosis_detail, g.diagnosis_detail
    return g


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_sigma_over_sqrt2(dtype):
    _named(EON, he.eon(EON, rough=lambda r: r / math.sqrt(2.0)).astype(dtype), "roughness_sigma_over_sqrt2", "sqrt(2)")


def test_qon_with_fujii_constants_and_the_fujii_target(capsys, tmp_path):
    _named(QON, he.qon(QON, fujii=True), "qon_fujii_constants", "Fujii")
    # Fujii's model graded as its own target conforms; plain QON there is named
    assert grade(FUJII, he.qon(FUJII, fujii=True)).passed
    _named(FUJII, he.qon(FUJII), "qon_fujii_constants")
    path = write_vectors(FUJII, tmp_path / "fujii.csv", out=he.qon(FUJII, fujii=True))
    assert main(["check", str(path), "--model", "qon_fujii", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["models"] == ["qon_fujii"]


def test_vectors_cli_writes_the_fujii_rows(tmp_path, capsys):
    path = tmp_path / "v.csv"
    assert main(["vectors", "--out", str(path), "--model", "qon_fujii"]) == 0
    body = [ln for ln in path.read_text().splitlines() if ln and not ln.startswith(("#", "id,"))]
    assert len(body) == len(FUJII) and all(",qon_fujii," in ln for ln in body)


@pytest.mark.parametrize("which, weights", [("luminance", (0.2126, 0.7152, 0.0722)), ("mean", (1 / 3, 1 / 3, 1 / 3))])
def test_rho_ms_from_a_grey_rho(which, weights):
    _named(EON, he.eon(EON, rho_ms_of=he.rho_ms_grey(weights)), "rho_ms_from_scalar_rho", which)


def test_f_ms_without_its_mu_i_factor():
    _named(EON, he.eon(EON, drop_mu_i=True), "ms_missing_mu_i_factor", "1 - E_F(mu_i)")


@pytest.mark.parametrize("c2", [10 * he.C2, 0.05, 0.0])
def test_average_albedo_constant_is_fitted(c2):
    g = _named(EON, he.eon(EON, c2=c2), "avg_albedo_constant")
    stated = float(g.diagnosis_detail.split("c = ")[1].split(" ")[0])
    assert abs(stated - c2) <= 1e-3 * max(abs(c2), 0.1), g.diagnosis_detail


@pytest.mark.parametrize("floor", [0.05, 0.01])
def test_roughness_floor_is_fitted(floor):
    g = _named(EON, he.eon(EON, rough=lambda r: np.maximum(r, floor)), "roughness_floor")
    stated = float(g.diagnosis_detail.split("max(x, ")[1].split(")")[0])
    assert abs(stated - floor) <= 2e-3 * floor, g.diagnosis_detail


def test_two_sided_lobe_is_named_alone():
    _named(EON, he.eon(EON, horizon="none"), "nonzero_below_horizon", "wi.z <= 0")


def test_below_the_horizon_does_not_mask_another_bug():
    out = he.eon(EON, horizon="none", rough=lambda r: r * r)
    g = _named(EON, out, "nonzero_below_horizon & roughness_squared", "above the horizon are graded on their own")
    assert "roughness squared" in g.diagnosis_detail


@pytest.mark.parametrize(
    "kwargs, scale, pair",
    [
        (dict(rough=lambda r: r * r), math.pi, "constant_factor & roughness_squared"),
        (dict(drop_mu_i=True, rough=lambda r: r / math.sqrt(2.0)), 1.0, None),
    ],
)
def test_two_deviations_are_named_as_the_pair(kwargs, scale, pair):
    g = grade(EON, scale * he.eon(EON, **kwargs))
    assert not g.passed
    if pair is None:  # two input changes: named as a pair or honestly not explained
        assert g.diagnosis is None or " & " in g.diagnosis, g.diagnosis
        return
    assert g.diagnosis == pair, (g.diagnosis, g.diagnosis_detail)
    assert "two deviations at once" in g.diagnosis_detail and "1/pi forgotten" in g.diagnosis_detail


def test_pair_through_check_csv(tmp_path, capsys):
    out = math.pi * he.eon(EON, rough=lambda r: r * r)
    path = write_vectors(EON, tmp_path / "r.csv", out=out)
    assert main(["check", str(path), "--json"]) == 1
    d = json.loads(capsys.readouterr().out)
    assert d["diagnosis"] == "constant_factor & roughness_squared"


def test_rounding_noise_is_called_precision():
    out = he.eon(EON, digits=3)  # every intermediate rounded to 3 significant digits
    g = grade(EON, out)
    assert not g.passed
    assert g.diagnosis == "precision", (g.diagnosis, g.diagnosis_detail)
    assert "not a formula bug" in g.diagnosis_detail and "precision ~ " in g.diagnosis_detail
    level = float(g.diagnosis_detail.split("precision ~ ")[1].split(" ")[0])
    assert 1e-4 <= level <= 5e-3


def test_a_one_signed_bias_is_not_precision():
    out = he.eon(EON)
    g = grade(EON, out + 3e-3 * np.abs(out))  # every value 0.3 % too large: a factor
    assert g.diagnosis == "constant_factor"
    g = grade(EON, he.eon(EON, c2=0.3) * (1 + 1e-3))
    assert g.diagnosis != "precision"


def test_correct_code_still_conforms_and_nonsense_is_unexplained():
    assert grade(EON, he.eon(EON)).passed
    rng = np.random.default_rng(3)
    g = grade(EON, he.eon(EON) * rng.uniform(0.3, 3.0, (len(EON), 1)))
    assert g.diagnosis is None and g.diagnosis_detail.startswith(NOT_EXPLAINED)
