"""Wrong implementations that differ from the named common bugs: a factor 1/2 or 1/(2 pi) is
reported with its value, f_ms with rho in place of rho_ms and a clamped L.V are named, a
compound (f mu_i pi) is named as the pair of its two deviations, and an altered FON
coefficient is honestly left unexplained, never "closest".
(The subjects are ``tests/_hand_impl.py``: formulas typed from the EON paper in plain NumPy.)
"""

import math

import _hand_impl as hand
import pytest

from openpbr_diffuse.conformance.grade import grade
from openpbr_diffuse.conformance.vectors import default_vectors

V = default_vectors()


@pytest.fixture(scope="module")
def base():
    return hand.answer(V)


@pytest.mark.parametrize("factor, text", [(0.5, "x 0.5 (x 1/2)"), (1 / (2 * math.pi), "1/(2 pi)")])
def test_unseen_constant_factor_reported_with_value(base, factor, text):
    g = grade(V, base * factor)
    assert not g.passed
    assert g.diagnosis == "constant_factor"
    assert text in g.diagnosis_detail


@pytest.mark.parametrize(
    "switches, name",
    [
        (dict(ms_scale="rho"), "rho_ms_extra_rho"),
        (dict(clamp_ldotv=True), "ldotv_clamped"),
        (dict(white_tint=True), "white_tint"),
    ],
)
def test_unseen_bug_named(switches, name):
    g = grade(V, hand.answer(V, **switches))
    assert not g.passed
    assert g.diagnosis == name, (g.diagnosis, g.diagnosis_detail)


def test_compound_is_named_as_the_pair():
    g = grade(V, hand.answer(V, times_cos=True, scale=math.pi))
    assert not g.passed
    assert g.diagnosis == "constant_factor & times_cos_theta_i", (g.diagnosis, g.diagnosis_detail)
    assert "two deviations at once" in g.diagnosis_detail and "1/pi forgotten" in g.diagnosis_detail


@pytest.mark.parametrize("switches", [dict(c1=0.6)])
def test_unseen_unexplained_is_said_so(switches):
    g = grade(V, hand.answer(V, **switches))
    assert not g.passed
    assert g.diagnosis is None
    assert g.diagnosis_detail.startswith("no known deviation explains this")
    assert "closest" not in g.diagnosis_detail
