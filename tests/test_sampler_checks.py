"""The measurements of ``grade_sampler``, called one by one on Python samplers.

A correct sampler (the library's EON sampler with its own pdf) passes every measurement; two
wrong ones fail exactly the measurement that sees their error: a pdf reported 10 % too high
everywhere (normalisation, claimed-strategy agreement and chi-square fail; the samples are
valid), and samples mirrored below the horizon at u.x = 0.5 (validity fails; the pdf is right).
"""

from dataclasses import replace

import numpy as np
import pytest

from openpbr_diffuse.graders.grading import (
    SAMPLER_CASES,
    SAMPLER_HORIZON_TOL,
    SAMPLER_MASS_TOL,
    SAMPLER_PDF_TOL,
    check_pdf_normalisation,
    check_pdf_reference,
    check_sample_chi2,
    check_sample_validity,
    reference_sampler_subject,
    run_sampler,
)

EON = reference_sampler_subject("eon")


def _below_horizon_sample(wo, r, u):
    """EON samples, mirrored below the horizon where u.x = 0.5 (the u corners hit it in every case)."""
    wi, p = EON.sample(wo, r, u)
    return np.where(u[:, :1] == 0.5, wi * [1.0, 1.0, -1.0], wi), p


SUBJECTS = {
    "correct": EON,
    "pdf_x1.1": reference_sampler_subject("eon", pdf_scale=1.1),
    "below_horizon": replace(EON, name="below", sample=_below_horizon_sample),
}


@pytest.fixture(scope="module")
def runs():
    return {name: run_sampler(s) for name, s in SUBJECTS.items()}


def test_correct_sampler_passes_every_measurement(runs):
    run = runs["correct"]
    norm = check_pdf_normalisation(run)
    assert norm.check["id"] == "sampler_pdf.normalisation" and norm.check["status"] == "pass"
    assert norm.check["measured"] < 1e-4 and norm.diagnosis is None and norm.where == ""
    ref = check_pdf_reference(run, "eon")
    assert ref.check["status"] == "pass" and ref.check["by_strategy"]["eon"] <= SAMPLER_PDF_TOL
    assert check_pdf_reference(run).check["status"] == "info"  # no claim: reported, not graded
    valid = check_sample_validity(run)
    assert valid.check["status"] == "pass" and valid.check["measured"] == 0 and valid.data["valid"].all()
    chi2 = check_sample_chi2(run, norm, valid)
    assert chi2.check["status"] == "pass" and chi2.check["measured"] >= chi2.check["threshold"]
    assert len(chi2.data["plot"]) == len(SAMPLER_CASES)


def test_pdf_ten_percent_high_fails_normalisation_reference_and_chi2(runs):
    run = runs["pdf_x1.1"]
    norm = check_pdf_normalisation(run)
    assert norm.check["status"] == "fail" and norm.diagnosis == "pdf_not_normalised"
    assert abs(norm.check["measured"] - 0.1) < 1e-3 and norm.check["threshold"] == SAMPLER_MASS_TOL
    assert norm.sentence.startswith("pdf integrates to 1.1 at ") and norm.where
    ref = check_pdf_reference(run, "eon")
    assert ref.check["status"] == "fail" and ref.diagnosis == "pdf_differs_from_eon"
    assert abs(ref.check["measured"] - 0.1) < 1e-3
    valid = check_sample_validity(run)
    assert valid.check["status"] == "pass"  # the samples themselves are fine
    chi2 = check_sample_chi2(run, norm, valid)
    assert chi2.check["status"] == "fail" and chi2.diagnosis == "samples_do_not_follow_pdf"
    assert "the pdf integrates to 1.1 there (against it rescaled to 1: p = " in chi2.sentence


def test_samples_below_the_horizon_fail_validity_only(runs):
    run = runs["below_horizon"]
    assert check_pdf_normalisation(run).check["status"] == "pass"
    valid = check_sample_validity(run)
    counts = valid.check["counts"]
    assert valid.check["id"] == "sampler_chi2.valid" and valid.check["status"] == "fail"
    assert valid.diagnosis == "samples_below_horizon"
    # the corners (0.5, 0), (0.5, 0.5), (0.5, 1 - 2^-24) in every case
    assert counts["below_horizon"] >= 3 * len(SAMPLER_CASES) and counts["nan"] == 0
    assert valid.check["measured"] == counts["below_horizon"]
    assert f"below the horizon (z < -{SAMPLER_HORIZON_TOL:g})" in valid.sentence
    assert "u = (0.5, " in valid.where
    assert (~valid.data["valid"]).sum() == counts["below_horizon"]
