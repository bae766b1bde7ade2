"""``OpenPBRSurface.lobes_and_eval``: a material's lobes and its BSDF from one compiled pass.

Checked against the two verbs it stands for, ``lobes(wo)`` and ``eval(wi, wo)`` (each
verified on its own against quadrature in ``test_surface_stack`` / ``test_openpbr_surface``):
the same formulas compiled into another driver, so equal to a few ulp (numba compiles for
the host CPU; two drivers may vectorise a row differently), on every lobe set and diffuse
model, one material or a material per row, one row or many (a partial last block).
"""

import numpy as np
import pytest
from test_surface_stack import STACKS

from openpbr_diffuse.nodes import OpenPBRSurface
from openpbr_diffuse.readers.evaluate import brdf_and_lobes

#: the base surface, a metal, and the layered stacks of ``test_surface_stack``
MATERIALS = {
    "base": dict(base_color=(0.8, 0.5, 0.3), base_diffuse_roughness=0.7, specular_roughness=0.4),
    "metal": dict(base_color=(0.9, 0.6, 0.2), base_metalness=0.6, specular_roughness=0.3),
    **STACKS,
}


def _directions(n, seed):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(2, n, 3))
    v[1, :, 2] = np.abs(v[1, :, 2])  # wo above; wi on the whole sphere
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _agree(a, b, ulps=8):
    a, b = np.asarray(a), np.asarray(b)
    scale = np.maximum(np.abs(a), np.abs(b))
    assert np.all(np.abs(a - b) <= ulps * np.spacing(np.maximum(scale, 1e-300))), np.max(np.abs(a - b))


#: every lobe set with EON, and each other diffuse model once (each pair compiles a driver)
CASES = [(name, "eon") for name in sorted(MATERIALS)] + [("base", "qon"), ("everything", "lambert")]


@pytest.mark.cpu_portable
@pytest.mark.parametrize("name, model", CASES)
@pytest.mark.parametrize("n", [1, 67])
def test_lobes_and_eval_is_lobes_and_eval(name, model, n):
    s = OpenPBRSurface(**MATERIALS[name], diffuse_model=model)
    wi, wo = _directions(n, seed=n)
    if n == 1:
        wi, wo = wi[0], wo[0]
    lobes, f = s.lobes_and_eval(wi, wo)
    _agree(f, s.eval(wi, wo))
    alone = s.lobes(wo)
    assert [lb.name for lb in lobes] == [lb.name for lb in alone]
    for a, b in zip(lobes, alone):
        for field in ("weight", "albedo", "probability"):
            _agree(getattr(a, field), getattr(b, field))


def test_a_material_per_row():
    rng = np.random.default_rng(3)
    n = 70  # one whole block of 64 rows and a partial one
    s = OpenPBRSurface(
        base_color=rng.uniform(0.1, 0.9, (n, 3)),
        base_diffuse_roughness=rng.uniform(0.0, 1.0, n),
        coat_weight=rng.uniform(0.0, 1.0, n),
        fuzz_weight=rng.uniform(0.0, 1.0, n),
    )
    wi, wo = _directions(n, seed=4)
    lobes, f = s.lobes_and_eval(wi, wo)
    _agree(f, s.eval(wi, wo))
    for a, b in zip(lobes, s.lobes(wo)):
        _agree(a.weight, b.weight)
        _agree(a.albedo, b.albedo)
        _agree(a.probability, b.probability)


def test_the_readers_albedo_is_the_surfaces_albedo():
    """``brdf_and_lobes`` reports sum_k w_k E_k as the albedo: ``albedo(wo)`` to rounding."""
    s = OpenPBRSurface(**MATERIALS["everything"])
    wi, wo = _directions(40, seed=5)
    brdf, albedo, diffuse, listing = brdf_and_lobes(s, wi, wo)
    np.testing.assert_allclose(albedo, s.albedo(wo), rtol=1e-13, atol=1e-15)
    _agree(brdf, s.eval(wi, wo))
    assert abs(sum(np.asarray(x["probability"]) for x in listing) - 1.0).max() < 1e-12
    assert {x["name"] for x in listing} >= {"diffuse", "coat", "fuzz"}
    assert np.asarray(diffuse["weight"]).shape == (40, 3)


def test_bad_directions_are_named():
    s = OpenPBRSurface()
    with pytest.raises(ValueError, match="wi"):
        s.lobes_and_eval([0.0, 0.0, 2.0], [0.0, 0.0, 1.0])
    with pytest.raises(ValueError, match="wo"):
        s.lobes_and_eval([0.0, 0.0, 1.0], [np.nan, 0.0, 1.0])
