"""The exact edges are vectors: mu = 0 and 1, L.V = +-1, azimuth differences 0 and pi,
roughness 0 and its maximum, rho = 0 and 1.  A correct implementation (written again from
the spec in tests/_hand_eon.py, and the conforming GLSL / C++ subjects) conforms; one that
returns NaN only at mu = 0 exactly -- the unguarded (S/mu)(1 - S^3) of Eq. 13, or a horizon
test ``z < 0`` -- does not, and the row is named with its inputs and the finite value there.
"""

import json
import math
from pathlib import Path

import _hand_eon as he
import numpy as np
import pytest
from _system import requires

from openpbr_diffuse.cli.main import main
from openpbr_diffuse.conformance.grade import grade
from openpbr_diffuse.conformance.vectors import default_vectors, write_vectors

V = default_vectors()
EON = V.subset(V.model == "eon")
SUBJECTS = Path(__file__).parent / "subjects"


def test_edges_are_in_the_default_vectors_and_old_ids_are_kept():
    brdf = V.kind == "brdf"
    wi, wo = V.wi[brdf], V.wo[brdf]
    assert (wi[:, 2] == 0.0).any() and (wo[:, 2] == 0.0).any() and ((wi[:, 2] == 1.0) & (wo[:, 2] == 1.0)).any()
    ldotv = np.einsum("ij,ij->i", wi, wo)
    assert (ldotv == 1.0).any() and (ldotv == -1.0).any()
    # azimuth difference exactly 0 and pi: both in the xz-plane, on the same / opposite side
    xz = (wi[:, 1] == 0) & (wo[:, 1] == 0) & (wi[:, 2] > 0) & (wo[:, 2] > 0)
    assert (xz & (wi[:, 0] * wo[:, 0] > 0)).any() and (xz & (wi[:, 0] * wo[:, 0] < 0)).any()
    assert (V.rho == 0).all(axis=1).any() and (V.rho == 1).all(axis=1).any()
    assert {0.0, 1.0} <= set(V.mu[V.kind == "albedo"])
    assert {0.0, 1.0} <= set(EON.roughness) and {0.0, math.pi / 2} <= set(V.roughness[V.model == "qon"])
    # the rows before the edges keep their ids and inputs: 33 pairs x 4 roughness x 3 colours
    ids = list(EON.id)
    assert ids[:396] == [f"eon-brdf-{k:04d}" for k in range(396)]
    assert EON.subset(EON.id == "eon-brdf-0395").wi[0, 2] > 0  # the last random pair, as before
    assert "eon-brdf-0396" in ids and "eon-albedo-084" in ids  # the edges continue the numbering
    assert len(set(V.id)) == len(V)


def test_template_csv_has_the_edge_rows(tmp_path):
    path = tmp_path / "t.csv"
    assert main(["template", "csv", "--out", str(path)]) == 0
    text = path.read_text()
    assert "eon-brdf-0396,brdf,eon,1.0,0.0,0.0,0.6,0.0,0.8" in text
    assert "eon-albedo-084,albedo,eon,,,,,,,0.0," in text


def test_correct_implementation_conforms_at_the_edges():
    assert grade(EON, he.eon(EON)).passed
    # float32, as a shader computes it
    assert grade(EON, he.eon(EON).astype(np.float32)).passed


def test_albedo_at_mu_0_either_convention_conforms():
    out = he.eon(EON)
    zero = (EON.kind == "albedo") & (EON.mu == 0)
    assert np.allclose(out[zero], EON.rho[zero])  # the grazing limit E -> rho
    out[zero] = 0.0  # the single-sided convention
    assert grade(EON, out).passed
    out[zero] = 0.5 * EON.rho[zero] + 0.1  # neither
    assert not grade(EON, out).passed


def _nan_rows(g):
    return g.diagnosis, g.diagnosis_detail


def test_unguarded_albedo_nan_at_mu_0_is_named_with_its_inputs():
    out = he.eon(EON, guarded=False)
    bad = ~np.isfinite(out).all(axis=1)
    assert bad.any() and (EON.mu[bad] == 0).all()  # NaN at mu = 0 exactly, nowhere else
    g = grade(EON, out)
    assert not g.passed and g.n_nan == 3 * int(bad.sum())
    assert g.diagnosis == "non_finite_output", _nan_rows(g)
    d = g.diagnosis_detail
    first = str(EON.id[bad][0])
    assert first in d and "albedo at mu 0" in d and "roughness" in d and "rho" in d
    assert "E_F -> 1" in d and "(S/mu)(1 - S^3)" in d


def test_horizon_test_below_zero_nan_names_mu_i_0():
    out = he.eon(EON, guarded=False, horizon="<")
    g = grade(EON.subset(EON.kind == "brdf"), out[EON.kind == "brdf"])
    assert not g.passed and g.n_nan > 0
    assert g.diagnosis == "non_finite_output"
    assert "mu_i 0," in g.diagnosis_detail or "mu_o 0," in g.diagnosis_detail
    assert "f = 0" in g.diagnosis_detail and "z <= 0" in g.diagnosis_detail


def test_nan_does_not_mask_another_bug():
    out = he.eon(EON, guarded=False, rough=lambda r: r * r)
    g = grade(EON, out)
    assert g.diagnosis == "non_finite_output & roughness_squared", _nan_rows(g)


def test_check_csv_nan_at_mu_0(tmp_path, capsys):
    out = np.full((len(V), 3), np.nan)
    eon = V.model == "eon"
    out[eon] = he.eon(EON, guarded=False)
    path = write_vectors(V.subset(eon), tmp_path / "r.csv", out=out[eon])
    assert main(["check", str(path), "--json"]) == 1
    d = json.loads(capsys.readouterr().out)
    assert not d["passed"] and d["diagnosis"] == "non_finite_output"
    assert "albedo at mu 0" in d["diagnosis_detail"]
    assert main(["check", str(path)]) == 1
    text = capsys.readouterr().out
    assert "DOES NOT CONFORM" in text and "non_finite_output" in text and "eon-albedo-0" in text


def _mutate(text, old, new):
    assert old in text
    return text.replace(old, new)


#: The conforming subjects' guarded E_F, turned back into Eq. 13 as printed, with a `< 0`
#: horizon test: NaN at mu = 0 exactly (BRDF and albedo rows), right everywhere else.
_GLSL_EF = "(2.0 / 3.0) * (S * mu * (1.0 + S + S * S) / (1.0 + S) - S)"
_CPP_EF = "(2.0f / 3.0f) * (S * mu * (1.0f + S + S * S) / (1.0f + S) - S)"


def _nan_subject(language, tmp_path):
    src = (SUBJECTS / f"eon_conforming.{language}").read_text()
    if language == "glsl":
        src = _mutate(src, _GLSL_EF, "(2.0 / 3.0) * ((S / mu) * (1.0 - S * S * S) - S)")
        src = _mutate(src, "if (wi.z <= 0.0 || wo.z <= 0.0)", "if (wi.z < 0.0 || wo.z < 0.0)")
    else:
        src = _mutate(src, _CPP_EF, "(2.0f / 3.0f) * ((S / mu) * (1.0f - S * S * S) - S)")
        src = _mutate(src, "if (wi.z <= 0.0f || wo.z <= 0.0f)", "if (wi.z < 0.0f || wo.z < 0.0f)")
    path = tmp_path / f"eon_nan_at_0.{language}"
    path.write_text(src)
    return path


@pytest.mark.parametrize(
    "language", [pytest.param("glsl", marks=requires("gl")), pytest.param("cpp", marks=requires("glm"))]
)
def test_code_nan_at_mu_0_does_not_conform(language, tmp_path, capsys):
    path = _nan_subject(language, tmp_path)
    status = main(["check", f"--{language}", str(path), "--function", "f", "--albedo-function", "albedo", "--json"])
    d = json.loads(capsys.readouterr().out)
    assert status == 1 and not d["passed"], d
    q = {x["quantity"]: x for x in d["quantities"]}
    for kind in ("brdf", "albedo"):
        assert not q[kind]["passed"], q[kind]
        text = json.dumps(q[kind])
        assert "non_finite_output" in text and "NaN" in text and "roughness" in text, text
    assert "albedo at mu 0" in json.dumps(q["albedo"])
    assert "mu_i 0," in json.dumps(q["brdf"]) or "mu_o 0," in json.dumps(q["brdf"])


@pytest.mark.parametrize(
    "language", [pytest.param("glsl", marks=requires("gl")), pytest.param("cpp", marks=requires("glm"))]
)
def test_conforming_code_conforms_at_the_edges(language, capsys):
    path = SUBJECTS / f"eon_conforming.{language}"
    status = main(["check", f"--{language}", str(path), "--function", "f", "--albedo-function", "albedo", "--json"])
    d = json.loads(capsys.readouterr().out)
    assert status == 0 and d["passed"], d
