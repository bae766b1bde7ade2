"""OpenPBRSurface(diffuse_model=...): the diffuse lobe is EON, QON or Lambert.

Reference: the lobe models' own ``evaluate`` / ``directional_albedo`` (a pure-diffuse
surface, specular_weight = 0, must equal base_weight * f_model(base_color)), and the
samplers named by the model (EON sampler for "eon", cosine otherwise).
"""

import numpy as np
import pytest

import openpbr_diffuse as od
from openpbr_diffuse import OpenPBRSurface

WO = np.array([[0.6, 0.0, 0.8], [0.0, 0.995, 0.0998749217771909]])
WI = np.array([[0.0, 0.6, 0.8], [-0.3, 0.1, 0.9486832980505138]])


@pytest.mark.parametrize(
    "model, lobe, strategy", [("eon", "eon", "eon"), ("qon", "qon", "cosine"), ("lambert", "lambert", "cosine")]
)
def test_pure_diffuse_surface_is_the_named_model(model, lobe, strategy):
    color, r, weight = np.array([0.9, 0.5, 0.2]), 0.7, 0.8
    s = OpenPBRSurface(
        base_color=color, base_diffuse_roughness=r, base_weight=weight, specular_weight=0.0, diffuse_model=model
    )
    assert np.allclose(s.eval(WI, WO), weight * od.evaluate(lobe, WI, WO, r, color), rtol=1e-12, atol=1e-15)
    assert np.allclose(s.albedo(WO), weight * od.directional_albedo(lobe, WO[:, 2], r, color), rtol=1e-12)
    assert np.allclose(s.pdf(WO, WI), od.pdf(strategy, WO, WI, r if strategy == "eon" else 0.0), rtol=1e-12)


def test_qon_uses_sigma_in_radians_and_differs_from_eon():
    a = OpenPBRSurface(base_diffuse_roughness=1.0, diffuse_model="qon").albedo(WO)
    b = OpenPBRSurface(base_diffuse_roughness=1.0, diffuse_model="eon").albedo(WO)
    assert np.all(np.abs(a - b) > 1e-3)


def test_unknown_diffuse_model_is_rejected():
    with pytest.raises(ValueError, match="diffuse_model"):
        OpenPBRSurface(diffuse_model="oren_nayar")
