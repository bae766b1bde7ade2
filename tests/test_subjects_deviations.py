"""The common bugs, named in code: the conforming EON subjects (tests/subjects/eon_conforming.glsl
and .cpp, written from the paper's equations) conform, and each mutant of them
(tests/_subject_mutants.py: a 1/pi dropped, the cosine folded in, the roughness squared, ...) is
graded through ``check --glsl/--cpp`` -- or, for the whole matrix, through the library API that
``check`` uses (``graders.grading.grade_subject``), every mutant in one shader / one compiled
harness -- and named as the bug written into it.  A mutant that matches no known deviation says
so, with no "closest".

The expected names come from what was written into the code, not from the library: the albedo
of a mutant whose albedo is unchanged must conform; where the tolerance cannot resolve a
deviation (the Eq. 14 fit of the albedo on llvmpipe) the expectation is decided by the
independent NumPy implementation of ``_hand_impl`` at that tolerance.
"""

import dataclasses
import json

import _hand_impl as hand
import _subject_mutants as sm
import numpy as np
import pytest
from _system import requires

from openpbr_diffuse.cli.main import main
from openpbr_diffuse.conformance.grade import NOT_EXPLAINED
from openpbr_diffuse.conformance.vectors import default_vectors

needs_gl = requires("gl")
needs_cxx = requires("glm")
LANGUAGES = [pytest.param("glsl", marks=needs_gl), pytest.param("cpp", marks=needs_cxx)]


def check(capsys, *args):
    status = main(["check", *args, "--json"])
    out = capsys.readouterr().out
    return status, (json.loads(out) if out.strip() else None)


def by_quantity(result):
    """{quantity: dict} of a check --json result or an ImplementationGrade."""
    if isinstance(result, dict):
        return {q["quantity"]: q for q in result["quantities"]}
    return {q.quantity: dataclasses.asdict(q) for q in result.quantities}


def _tolerance(language):
    from openpbr_diffuse.conformance.grade import ABS_TOL, REL_TOL
    from openpbr_diffuse.graders.glsl import TOLERANCE

    return TOLERANCE if language == "glsl" else (REL_TOL, ABS_TOL)


def expected_albedo(mutant, language):
    """The albedo verdict expected: the mutant's, unless its albedo deviation is below the
    language's tolerance on every row (then it must conform) -- decided by _hand_impl."""
    if mutant.name != "eq14":
        return mutant.albedo
    v = default_vectors()
    rows = v.subset((v.kind == "albedo") & (v.model == "eon"))
    right, fit = hand.answer(rows, np.float64), hand.answer(rows, np.float64, ef_fit=True)
    rel, ab = _tolerance(language)
    return mutant.albedo if np.max(np.abs(fit - right) / (ab + rel * np.abs(right))) > 1.0 else None


def assert_named(q, mutant, language):
    brdf, albedo = q["brdf"], q["albedo"]
    assert not brdf["passed"], brdf
    if mutant.brdf == sm.NOT_EXPLAINED:
        assert brdf["diagnosis"] is None and brdf["detail"].startswith(NOT_EXPLAINED), brdf["detail"]
        assert brdf.get("closest") is None and "closest named deviation" not in brdf["detail"]
    else:
        assert brdf["diagnosis"] == mutant.brdf, brdf["detail"]
        assert mutant.fragment in brdf["detail"], brdf["detail"]
    want = expected_albedo(mutant, language)
    if want is None:
        assert albedo["passed"], albedo["detail"]
    elif mutant.name == "lambert":
        # E = rho for Lambert, and for white_tint as well (rho E_EON(rho = 1) = rho: EON's white
        # furnace), so the albedo rows alone cannot tell the two apart: either name is right.
        v = default_vectors()
        rows = v.subset((v.kind == "albedo") & (v.model == "eon"))
        np.testing.assert_allclose(
            hand.answer(rows, np.float64, energy="lambert"),
            hand.answer(rows, np.float64, white_tint=True),
            rtol=1e-6,
            atol=1e-7,
        )
        assert not albedo["passed"] and albedo["diagnosis"] in (want, "white_tint"), albedo["detail"]
    else:
        # albedo rows alone may not tell two deviations apart (white tint and Lambert both give
        # rho): then the other is named and the finding says it cannot tell them apart
        detail = albedo["detail"]
        assert not albedo["passed"], detail
        assert albedo["diagnosis"] == want or f"cannot tell it from: {want}" in detail, detail


def test_every_mutant_edit_applies_and_changes_the_code():
    for name in sm.MUTANTS:
        for language in ("glsl", "cpp"):
            assert sm.mutant_source(name, language) != sm.conforming(language)


@pytest.mark.parametrize("language", LANGUAGES)
def test_conforming_subject_conforms(language, capsys):
    path = sm.GLSL_FILE if language == "glsl" else sm.CPP_FILE
    status, result = check(capsys, f"--{language}", str(path), "--function", "f", "--albedo-function", "albedo")
    q = by_quantity(result)
    assert status == 0 and result["passed"], result
    # 396 + 32 edge rows (mu = 0 exactly, L.V = +-1, rho = 0) + 52 swapped pairs, 84 + 8 (the albedo at mu = 0, 1)
    assert q["brdf"]["n"] == 480 and q["albedo"]["n"] == 92
    assert q["brdf"]["max_abs_error"] < 5e-5 and q["albedo"]["max_abs_error"] < 5e-5


#: a handful in the default run, through the command line; the whole matrix is below (slow)
DEFAULT = [
    ("glsl", "pi_forgotten"),
    ("glsl", "eq14"),
    ("glsl", "sin_mu_i"),
    ("cpp", "ms_missing_inv_pi"),
    ("cpp", "cos_of_wo"),
    ("cpp", "srgb_encoded"),
]


@pytest.mark.parametrize(
    "language,name", [pytest.param(lang, n, marks=needs_gl if lang == "glsl" else needs_cxx) for lang, n in DEFAULT]
)
def test_mutant_is_named_by_check(language, name, tmp_path, capsys):
    mutant = sm.MUTANTS[name]
    path = sm.write_mutant(name, language, tmp_path)
    status, result = check(capsys, f"--{language}", str(path), "--function", "f", "--albedo-function", "albedo")
    # the Eq. 14 fit where exact EON is claimed: "conforms with warnings" (exit 0), still named
    assert status == (0 if name == "eq14" else 1) and not result["passed"]
    assert result["tier"] == ("conforms with warnings" if name == "eq14" else "does not conform")
    assert_named(by_quantity(result), mutant, language)


@needs_gl
def test_eq14_mutant_conforms_as_eon_approx(tmp_path, capsys):
    """The suggestion of the eq14 diagnosis, followed: graded as eon_approx, it conforms."""
    path = sm.write_mutant("eq14", "glsl", tmp_path)
    status, result = check(
        capsys, "--glsl", str(path), "--function", "f", "--albedo-function", "albedo", "--model", "eon_approx"
    )
    assert status == 0 and result["passed"] and result["model"] == "eon_approx", result


@pytest.mark.slow
@pytest.mark.parametrize("language", LANGUAGES)
def test_every_mutant_is_named(language, tmp_path):
    """All mutants and the conforming code in one shader / one harness, each graded by
    grade_subject (the grading of check --glsl/--cpp)."""
    from openpbr_diffuse.graders.grading import grade_subject

    subjects = sm.batch_subjects(["conforming", *sm.MUTANTS], language, tmp_path)
    assert grade_subject(subjects.pop("conforming"), quantities=("brdf", "albedo")).passed
    for name, subject in subjects.items():
        q = by_quantity(grade_subject(subject, quantities=("brdf", "albedo")))
        assert_named(q, sm.MUTANTS[name], language)
    eq14 = dataclasses.replace(subjects["eq14"], model="eon_approx")
    assert grade_subject(eq14, quantities=("brdf", "albedo")).passed
