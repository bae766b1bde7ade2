"""Conformance grading: the reference and float32 implementations pass, each known deviation
fails with the right diagnosis, unusable files exit 2.

The "implementations" are ``tests/_hand_impl.py`` (formulas typed from the paper in plain
NumPy, independent of the library and of ``conformance.deviations``).
"""

import json
import math

import _hand_impl as hand
import numpy as np
import pytest

from openpbr_diffuse.cli.main import main
from openpbr_diffuse.conformance.deviations import DEVIATIONS, reference
from openpbr_diffuse.conformance.grade import grade
from openpbr_diffuse.conformance.vectors import (
    COLUMNS,
    OUT_COLUMNS,
    default_vectors,
    read_results,
    write_vectors,
)

V = default_vectors()


@pytest.fixture(scope="module")
def vectors():
    return V


def _check(tmp_path, out, name="results.csv", extra=()):
    path = tmp_path / name
    write_vectors(V, path, out=out)
    return path, main(["check", str(path), "--json", *extra])


def test_vector_set_covers_the_edges(vectors):
    brdf = vectors.kind == "brdf"
    wi, wo = vectors.wi[brdf], vectors.wo[brdf]
    ldotv = np.einsum("ij,ij->i", wi, wo)
    s = ldotv - wi[:, 2] * wo[:, 2]
    assert (np.minimum(wi[:, 2], wo[:, 2]) < 0.002).any() and (wi[:, 2] < 0).any() and (wo[:, 2] < 0).any()
    assert (np.abs(wi - wo).max(axis=1) < 1e-12).sum() >= 4  # backscatter
    assert (np.abs(s) < 1e-12).any() and (ldotv < -0.4).any()  # s = 0, L.V < 0
    assert {0.0, 1.0} <= set(vectors.roughness[vectors.model == "eon"])  # r = 0 and 1
    mus = set(vectors.mu[vectors.kind == "albedo"])
    assert 0.001 in mus and 0.0 in mus  # grazing, and mu = 0 exactly (either convention is accepted there)
    assert set(vectors.model) >= {"eon", "qon", "fon", "lambert", "eon_approx"}
    assert len(set(vectors.id)) == len(vectors) and vectors.version


def test_reference_agrees_with_the_hand_implementation(vectors):
    """The library's reference against formulas typed independently from the paper."""
    g = grade(vectors, hand.answer(vectors, np.float64))
    assert g.passed, g.worst[:3]
    assert g.max_normalised_error < 0.05


def test_reference_and_float32_pass(tmp_path, vectors):
    ref = reference(vectors)
    assert grade(vectors, ref).passed and grade(vectors, ref).max_abs_error == 0.0
    assert grade(vectors, ref.astype(np.float32)).passed
    # a float32 implementation computing every step in float32 (a shader)
    g32 = grade(vectors, hand.answer(vectors, np.float32))
    assert g32.passed, g32.worst[:3]
    path, status = _check(tmp_path, ref.astype(np.float32))
    assert status == 0


DEVIATION_IMPLEMENTATIONS = {
    "no_energy_compensation_qon": dict(energy="qon"),
    "no_energy_compensation_fon": dict(energy="fon"),
    "rho_ms_extra_inv_pi": dict(ms_scale="inv_pi"),
    "rho_ms_extra_rho": dict(ms_scale="rho"),
    "ldotv_clamped": dict(clamp_ldotv=True),
    "white_tint": dict(white_tint=True),
    "times_cos_theta_i": dict(times_cos=True),
    "roughness_sigma_vs_r": dict(roughness="sigma_vs_r"),
    "roughness_squared": dict(roughness="squared"),
    "no_energy_compensation_lambert": dict(energy="lambert"),
    "eq14_fit_for_exact": dict(ef_fit=True),
    "constant_factor": dict(scale=math.pi),
    "ms_missing_inv_pi": dict(ms_scale="times_pi"),
    "divided_by_cos_theta_i": dict(divide_cos=True),
    "roughness_degrees": dict(roughness="degrees"),
    "rho_srgb_encoded": dict(rho_srgb="encode"),
    "mu_floor": dict(mu_floor=0.01),
}


def test_every_known_deviation_has_an_implementation():
    from test_conformance_new_deviations import NEW_DEVIATIONS  # implemented in tests/_hand_eon.py

    assert set(DEVIATION_IMPLEMENTATIONS) | set(NEW_DEVIATIONS) == set(DEVIATIONS)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("name", sorted(DEVIATION_IMPLEMENTATIONS))
def test_deviation_is_failed_and_diagnosed(name, dtype, vectors):
    out = hand.answer(vectors, dtype, **DEVIATION_IMPLEMENTATIONS[name])
    g = grade(vectors, out)
    assert not g.passed
    assert g.diagnosis == name, (g.diagnosis, g.diagnosis_detail)


@pytest.mark.parametrize("name", sorted(DEVIATION_IMPLEMENTATIONS))
def test_deviation_diagnosed_from_eon_rows_only(name, vectors):
    """An EON-only implementation submits only the eon rows (check --model eon)."""
    eon = vectors.subset(vectors.model == "eon")
    g = grade(eon, hand.answer(eon, np.float32, **DEVIATION_IMPLEMENTATIONS[name]))
    assert not g.passed and g.diagnosis == name, g.diagnosis_detail


def test_deviation_also_in_albedo_rows_is_diagnosed(vectors):
    """times cos applied to the albedo queries as well (E mu) is still the same deviation."""
    out = hand.answer(vectors, np.float64, times_cos=True)
    alb = vectors.kind == "albedo"
    out[alb] *= vectors.mu[alb, None]
    assert grade(vectors, out).diagnosis == "times_cos_theta_i"


@pytest.mark.parametrize("name", ["rho_ms_extra_rho", "ldotv_clamped", "times_cos_theta_i"])
def test_check_cli_diagnoses(tmp_path, capsys, name, vectors):
    out = hand.answer(vectors, np.float32, **DEVIATION_IMPLEMENTATIONS[name])
    path, status = _check(tmp_path, out)
    assert status == 1
    d = json.loads(capsys.readouterr().out)
    assert d["passed"] is False and d["diagnosis"] == name and d["worst"]
    assert set(d) >= {"max_abs_error", "rms_error", "tolerance", "tolerance_reason", "candidates"}


def test_model_filter_and_json_format(tmp_path, capsys, vectors):
    """--model grades only that model's rows; a JSON results file reads like the CSV."""
    out = hand.answer(vectors, np.float64, ms_scale="rho")
    lam = vectors.model == "lambert"
    path = tmp_path / "lambert.json"
    write_vectors(vectors.subset(lam), path, out=out[lam])
    assert main(["check", str(path), "--model", "lambert"]) == 0
    path2, status = _check(tmp_path, out, name="all.json", extra=("--model", "eon"))
    assert status == 1 and json.loads(capsys.readouterr().out.splitlines()[-1])["models"] == ["eon"]


def test_unrelated_error_gets_no_diagnosis(vectors):
    out = reference(vectors) * 1.01 + 0.003
    g = grade(vectors, out)
    assert not g.passed and g.diagnosis is None and g.diagnosis_detail.startswith("no known deviation explains this")


def test_nan_output_fails(vectors):
    out = reference(vectors)
    out[5, 1] = math.nan
    g = grade(vectors, out)
    assert not g.passed and g.worst[0]["id"] == vectors.id[5]


def _edit_csv(path, fn):
    lines = path.read_text().splitlines()
    body = [ln for ln in lines if not ln.startswith("#")]
    path.write_text("\n".join(fn(body)) + "\n")


@pytest.mark.parametrize(
    "case", ["missing_column", "non_numeric", "wrong_input", "unknown_id", "duplicate", "blank_out", "empty"]
)
def test_unusable_file_exits_2(tmp_path, capsys, case, vectors):
    path = tmp_path / "r.csv"
    write_vectors(vectors, path, out=reference(vectors))

    def edit(body):
        head = body[0].split(",")
        if case == "missing_column":
            k = head.index("out_g")
            return [",".join(c for j, c in enumerate(row.split(",")) if j != k) for row in body]
        if case == "empty":
            return body[:1]
        row = body[7].split(",")
        if case == "non_numeric":
            row[head.index("out_r")] = "abc"
        elif case == "wrong_input":
            row[head.index("wi_x")] = "0.123"
        elif case == "unknown_id":
            row[0] = "eon-brdf-9999"
        elif case == "blank_out":
            row[head.index("out_b")] = ""
        elif case == "duplicate":
            return body + [body[7]]
        return body[:7] + [",".join(row)] + body[8:]

    _edit_csv(path, edit)
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    with pytest.raises(ValueError):
        read_results(path)


def test_nan_result_in_file_does_not_conform(tmp_path, capsys, vectors):
    out = reference(vectors)
    out[3, 0] = math.nan
    path, status = _check(tmp_path, out)
    assert status == 1
    d = json.loads(capsys.readouterr().out)
    assert d["passed"] is False and d["worst"][0]["id"] == vectors.id[3]


def test_missing_file_exits_2(tmp_path):
    assert main(["check", str(tmp_path / "nope.csv")]) == 2


def test_vectors_cli_writes_csv_columns_in_order(tmp_path):
    path = tmp_path / "v.csv"
    assert main(["vectors", "--out", str(path)]) == 0
    header = [ln for ln in path.read_text().splitlines() if not ln.startswith("#")][0]
    assert header.split(",") == list(COLUMNS + OUT_COLUMNS)
    assert main(["vectors", "--out", str(tmp_path / "v.json")]) == 0
    doc = json.loads((tmp_path / "v.json").read_text())
    assert doc["columns"] == list(COLUMNS + OUT_COLUMNS) and len(doc["rows"]) == len(V) and doc["version"] == V.version
    assert main(["vectors", "--out", str(path)]) == 2  # never overwritten without --force
    # an implementer fills the empty out columns of the CSV written by `vectors`
    lines = path.read_text().splitlines()
    ref = reference(V)
    k = 0
    new = []
    for ln in lines:
        if ln.startswith("#") or ln.startswith("id,"):
            new.append(ln)
        else:
            assert ln.endswith(",,,")
            new.append(ln[:-3] + "," + ",".join(f"{x:.9g}" for x in ref[k]))
            k += 1
    path.write_text("\n".join(new) + "\n")
    assert main(["check", str(path)]) == 0


def test_cli_as_a_module_exits_2_without_traceback(tmp_path):
    """`python -m openpbr_diffuse.cli.main check` (how the CLI runs from a worktree)."""
    import subprocess
    import sys

    for argv in (["check"], ["check", str(tmp_path / "missing.csv")]):
        p = subprocess.run([sys.executable, "-m", "openpbr_diffuse.cli.main", *argv], capture_output=True, text=True)
        assert p.returncode == 2 and "Traceback" not in p.stderr and p.stderr.count("\n") == 1


@pytest.mark.parametrize("floor", [0.002, 0.0047, 0.01])
def test_mu_floor_fit_recovers_the_floor(floor, vectors):
    """The fitted floor of an implementation that clamps mu (typed independently in
    ``_hand_impl``) is the floor it used, to the 4 digits the diagnosis states."""
    g = grade(vectors, hand.answer(vectors, np.float64, mu_floor=floor))
    assert g.diagnosis == "mu_floor", g.diagnosis_detail
    assert f"mu' = max(mu, {floor:.4g})" in g.diagnosis_detail, g.diagnosis_detail


def test_remembered_predictions_give_the_grades_of_fresh_ones(vectors, monkeypatch):
    """The fixed deviations' predictions are remembered per rows' contents: grading several
    implementations on the same rows, on a subset, or on rows changed in place gives what
    predicting afresh gives, and the same rows are predicted once."""
    from openpbr_diffuse.conformance import grade as g

    outs = [hand.answer(vectors, np.float32, **DEVIATION_IMPLEMENTATIONS[n]) for n in ("white_tint", "ldotv_clamped")]
    sub = vectors.subset(vectors.model == "eon")

    def summary(r):
        return r.diagnosis, r.diagnosis_detail, sorted(r.candidates.items())

    g._PREDICTIONS.clear()
    first = [summary(grade(vectors, o)) for o in outs] + [summary(grade(sub, outs[0][vectors.model == "eon"]))]
    n_kept = len(g._PREDICTIONS)
    again = [summary(grade(vectors, o)) for o in outs] + [summary(grade(sub, outs[0][vectors.model == "eon"]))]
    assert len(g._PREDICTIONS) == n_kept  # nothing predicted twice
    monkeypatch.setattr(g, "_PREDICTIONS_KEPT", 0)  # nothing remembered
    fresh = [summary(grade(vectors, o)) for o in outs] + [summary(grade(sub, outs[0][vectors.model == "eon"]))]
    assert first == again == fresh
    assert first[0][0] == "white_tint" and first[1][0] == "ldotv_clamped"
    # rows with other contents (a rougher copy) are predicted for themselves
    rough = vectors.subset(np.arange(len(vectors)))
    rough.roughness[:] = np.where(np.isnan(rough.roughness), np.nan, np.minimum(rough.roughness * 1.5, 1.0))
    assert g._rows_key(rough) != g._rows_key(vectors)
