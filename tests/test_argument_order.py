"""One convention for the direction arguments of the public verbs (docs/guide/sampling.md).

Every verb that takes directions names them ``wi`` (towards the light) and ``wo`` (towards
the viewer) and accepts them as keywords.  Positionally, the BRDF verbs take
``(wi, wo)`` (``evaluate``, the nodes' ``eval``) and the sampling verbs take ``wo`` first
(``sample(strategy, wo, ...)``, ``pdf(strategy, wo, wi, ...)``, the nodes' ``pdf(wo, wi)``):
the sampled direction comes second.  These tests fail if a verb's arguments are swapped
inside (a keyword bound to the other direction) or its positional order changes.
"""

import inspect

import numpy as np
import pytest

import openpbr_diffuse as od

#: Two unit directions whose roles cannot be exchanged without changing every pdf but
#: "uniform"'s: different heights and azimuths.
A = np.array([0.48, 0.36, 0.8])  # |A| = 1
B = np.array([-0.28, 0.0, 0.96])  # |B| = 1
R = 0.7


@pytest.mark.parametrize(
    ("verb", "order"),
    [
        (od.evaluate, ("model", "wi", "wo", "roughness", "rho")),
        (od.pdf, ("strategy", "wo", "wi", "roughness")),
        (od.sample, ("strategy", "wo", "roughness", "u")),
        (od.sample_rng, ("strategy", "wo", "roughness")),
        (od.directional_albedo, ("model", "mu", "roughness", "rho")),
        (od.OrenNayarDiffuseBSDF.eval, ("self", "wi", "wo")),
        (od.OrenNayarDiffuseBSDF.pdf, ("self", "wo", "wi")),
        (od.OrenNayarDiffuseBSDF.sample, ("self", "wo", "u")),
        (od.OrenNayarDiffuseBSDF.albedo, ("self", "wo")),
        (od.OpenPBRSurface.eval, ("self", "wi", "wo")),
        (od.OpenPBRSurface.pdf, ("self", "wo", "wi")),
        (od.OpenPBRSurface.sample, ("self", "wo", "u")),
        (od.OpenPBRSurface.albedo, ("self", "wo")),
    ],
    ids=lambda v: getattr(v, "__qualname__", None),
)
def test_documented_positional_order(verb, order):
    """The positional order of each verb, as documented; every name usable as a keyword."""
    params = list(inspect.signature(verb).parameters.values())
    assert tuple(p.name for p in params[: len(order)]) == order
    assert all(p.kind is inspect.Parameter.POSITIONAL_OR_KEYWORD for p in params[: len(order)])


@pytest.mark.parametrize("strategy", od.STRATEGIES)
def test_pdf_keywords_bind_by_name(strategy):
    by_name = od.pdf(strategy, wi=A, wo=B, roughness=R)
    assert by_name == od.pdf(strategy, B, A, R)  # positional: wo first
    assert by_name == od.pdf(strategy, roughness=R, wo=B, wi=A)
    if strategy != "uniform":  # 1/(2 pi) for any pair above the horizon
        assert by_name != od.pdf(strategy, A, B, R)


def test_pdf_cosine_is_a_density_of_wi():
    """An independent closed form: "cosine" has pdf = wi.z / pi whatever wo is."""
    assert od.pdf("cosine", wi=A, wo=B, roughness=R) == pytest.approx(A[2] / np.pi, rel=1e-12)
    assert od.pdf("cosine", B, A, R) == pytest.approx(A[2] / np.pi, rel=1e-12)


@pytest.mark.parametrize("model", od.MODELS)
def test_evaluate_keywords_equal_positional(model):
    rho = [0.8, 0.5, 0.2]
    positional = od.evaluate(model, A, B, R, rho)
    np.testing.assert_array_equal(od.evaluate(model, wi=A, wo=B, roughness=R, rho=rho), positional)
    np.testing.assert_array_equal(od.evaluate(model, wo=B, wi=A, rho=rho, roughness=R), positional)


@pytest.mark.parametrize(
    "call",
    [
        lambda bad, good: od.evaluate("eon", wi=bad, wo=good, roughness=R),
        lambda bad, good: od.evaluate("eon", bad, good, R),
        lambda bad, good: od.pdf("eon", wi=bad, wo=good, roughness=R),
        lambda bad, good: od.pdf("eon", good, bad, R),
        lambda bad, good: od.OrenNayarDiffuseBSDF(roughness=R).eval(wi=bad, wo=good),
        lambda bad, good: od.OrenNayarDiffuseBSDF(roughness=R).pdf(wo=good, wi=bad),
        lambda bad, good: od.OrenNayarDiffuseBSDF(roughness=R).pdf(good, bad),
    ],
)
def test_errors_name_the_direction_given(call):
    """Even where values are symmetric (reciprocal BRDFs), a bad wi is reported as wi."""
    with pytest.raises(ValueError, match=r"^wi\b"):
        call(np.array([0.0, 0.0, 2.0]), A)


@pytest.mark.parametrize("strategy", od.STRATEGIES)
def test_sample_keywords_and_its_pdf(strategy):
    u = np.array([[0.3, 0.6], [0.8, 0.1]])
    wi, p = od.sample(strategy, wo=B, roughness=R, u=u)
    wi2, p2 = od.sample(strategy, B, R, u)
    np.testing.assert_array_equal(wi, wi2)
    np.testing.assert_array_equal(p, p2)
    np.testing.assert_allclose(od.pdf(strategy, wi=wi, wo=B, roughness=R), p, rtol=1e-12)


def test_node_verbs_follow_the_convention():
    node = od.OrenNayarDiffuseBSDF(color=(0.8, 0.5, 0.2), roughness=R, energy_compensation=True)
    np.testing.assert_array_equal(node.eval(wi=A, wo=B), node.eval(A, B))
    np.testing.assert_array_equal(node.eval(wo=B, wi=A), od.evaluate("eon", A, B, R, [0.8, 0.5, 0.2]))
    assert node.pdf(wi=A, wo=B) == node.pdf(B, A)
    assert node.pdf(wi=A, wo=B) == od.pdf("eon", wi=A, wo=B, roughness=R)
    assert node.pdf(wi=A, wo=B) != node.pdf(A, B)
    np.testing.assert_array_equal(node.albedo(wo=B), node.albedo(B))
    surface = od.OpenPBRSurface(base_diffuse_roughness=R, specular_weight=0.0)
    np.testing.assert_array_equal(surface.eval(wi=A, wo=B), surface.eval(A, B))
    assert surface.pdf(wi=A, wo=B) == surface.pdf(B, A)
    assert surface.pdf(wi=A, wo=B) != surface.pdf(A, B)
