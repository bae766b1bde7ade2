"""Real implementations installed by packages, run from their own code, graded with the verdicts
measured here.

The expected verdicts and diagnoses are what the graders measured on this machine (see the docs
page "Graded implementations"), each backed by a reason in the code under test:

- MaterialX GLSL clamps L.V to [M_FLOAT_EPS, 1] (mx_oren_nayar_diffuse_bsdf.glsl) -> ldotv_clamped;
  its albedo conforms.  With energy_compensation = false it is QON, and its albedo is
  MaterialX's rational fit.
- Cycles multiplies f_ms by rho once more -> rho_ms_extra_rho (slow: renders).

Code that no package installs is graded with --glsl / --cpp (tests/test_graders_adapters.py,
tests/test_subjects_deviations.py).
"""

import numpy as np
import pytest
from _system import requires

from openpbr_diffuse.graders import grade_implementation, load

needs_gl = requires("gl")


def quantities(result):
    return {q.quantity: q for q in result.quantities}


@pytest.fixture(scope="module")
def graded():
    cache = {}

    def get(name):
        if name not in cache:
            cache[name] = grade_implementation(name, quick=True)
        return cache[name]

    return get


@needs_gl
def test_materialx_glsl_clamps_ldotv(graded):
    r = graded("materialx-glsl")
    q = quantities(r)
    assert r.version["materialx"] and len(r.version["sha256"]) == 64
    assert "pbrlib/genglsl/mx_oren_nayar_diffuse_bsdf.glsl" in r.version["files"]
    # and, at wo.z = 0 exactly (an edge row), a non-zero f: MaterialX clamps N.V instead of returning 0
    assert not q["brdf"].passed and q["brdf"].diagnosis == "nonzero_below_horizon & ldotv_clamped"
    assert q["brdf"].max_abs_error > 0.1  # the s <= 0 branch: L.V < 0 rows
    assert q["albedo"].passed and q["albedo"].max_abs_error < 5e-5
    assert not r.passed


@pytest.mark.slow
@requires("bpy")
def test_cycles_has_an_extra_rho_on_f_ms():
    from openpbr_diffuse.conformance.deviations import DEVIATIONS, reference
    from openpbr_diffuse.conformance.vectors import default_vectors
    from openpbr_diffuse.graders.grading import grade_subject

    subject = load("cycles")
    r = grade_subject(subject, quantities=("brdf", "albedo"))
    q = quantities(r)
    assert r.version["blender"].startswith("5.") and len(r.version["sha256"]) == 64
    assert not q["brdf"].passed and q["brdf"].diagnosis == "rho_ms_extra_rho"
    assert not q["albedo"].passed and q["albedo"].diagnosis == "rho_ms_extra_rho"
    # the render budget separates the two formulas by more than 10x the measured noise
    v = default_vectors()
    rows = v.subset((v.kind == "albedo") & (v.model == "eon") & (v.mu >= 0.05))
    gap = np.abs(reference(rows) - DEVIATIONS["rho_ms_extra_rho"](rows))
    se = subject.noise["albedo_stderr"]
    differ = gap > 1e-3
    assert differ.sum() >= 20
    assert np.min(gap[differ] / np.maximum(se[differ], 1e-12)) > 10.0


def test_unknown_implementation_is_a_value_error():
    with pytest.raises(ValueError, match="implementation"):
        load("renderman")


@needs_gl
def test_materialx_glsl_qon_mode(graded):
    """energy_compensation = false: QON f conforms; its albedo is MaterialX's rational fit."""
    r = graded("materialx-glsl-qon")
    q = quantities(r)
    assert r.model == "qon"
    # f conforms above the horizon; at wo.z = 0 exactly (V on the horizon) it is not 0
    assert (
        q["brdf"].diagnosis == "nonzero_below_horizon" and "3 of 480 rows" in q["brdf"].detail
    )  # 428 + 52 swapped pairs
    assert not q["albedo"].passed and q["albedo"].diagnosis is None
    assert 0.03 < q["albedo"].max_abs_error < 0.1
