"""OpenPBRSurface construction and ``lobes(wo)``: the fast paths equal the general ones.

Plain Python numbers and 3-tuples are converted without NumPy's array checks, and one
material at one direction calls the serial lobes driver directly; both must give bit for
bit what the general path (NumPy inputs, batches of directions) gives, with the same errors
and warnings.
"""

import warnings

import numpy as np
import pytest

from openpbr_diffuse.nodes import OpenPBRSurface

WO = np.array([0.6, 0.0, 0.8])
PLAIN = {
    "stack": dict(
        base_color=(0.8, 0.5, 0.3),
        base_diffuse_roughness=0.7,
        base_metalness=0.3,
        specular_roughness=0.4,
        coat_weight=0.6,
        fuzz_weight=0.4,
    ),
    "ints and lists": dict(
        base_color=[1, 0, 1], base_weight=1, specular_ior=2, coat_weight=1, coat_color=[0.5, 1, 0.25]
    ),
    "everything": dict(
        base_weight=0.9,
        base_color=(0.7, 0.6, 0.5),
        base_diffuse_roughness=0.3,
        base_metalness=0.2,
        specular_weight=0.8,
        specular_color=(1.2, 0.9, 1.0),
        specular_roughness=0.35,
        specular_ior=1.7,
        transmission_weight=0.3,
        transmission_color=(0.9, 0.8, 0.7),
        subsurface_weight=0.4,
        subsurface_color=(0.6, 0.5, 0.4),
        subsurface_scatter_anisotropy=-0.3,
        coat_weight=0.5,
        coat_color=(0.9, 0.95, 1.0),
        coat_roughness=0.2,
        coat_ior=1.4,
        coat_darkening=0.5,
        fuzz_weight=0.3,
        fuzz_color=(0.8, 0.8, 0.9),
        fuzz_roughness=0.6,
        geometry_thin_walled=True,
    ),
}


def _as_numpy(kwargs):
    """The same inputs as NumPy values (0-d and (3,) arrays): the general conversion path."""
    return {n: v if isinstance(v, bool) else np.asarray(v, dtype=np.float64) for n, v in kwargs.items()}


def _lobes(s, wo):
    return [(lobe.name, lobe.weight, lobe.albedo, lobe.probability) for lobe in s.lobes(wo)]


def _same_lobes(a, b):
    assert [x[0] for x in a] == [x[0] for x in b]
    for x, y in zip(a, b):
        for u, v in zip(x[1:], y[1:]):
            assert type(u) is type(v) and u.shape == v.shape and np.array_equal(u, v)


@pytest.mark.parametrize("name", PLAIN)
def test_plain_inputs_equal_numpy_inputs(name):
    plain, arrays = OpenPBRSurface(**PLAIN[name]), OpenPBRSurface(**_as_numpy(PLAIN[name]))
    assert plain.params.tobytes() == arrays.params.tobytes()
    assert plain.active == arrays.active
    for n, v in plain.inputs.items():
        assert v is arrays.inputs[n] if v is None else np.array_equal(v, arrays.inputs[n])
    _same_lobes(_lobes(plain, WO), _lobes(arrays, WO))


@pytest.mark.parametrize("name", PLAIN)
def test_one_direction_equals_a_batch_of_one(name):
    s = OpenPBRSurface(**PLAIN[name])
    one, batch = _lobes(s, WO), _lobes(s, WO[None])
    _same_lobes(one, [(n, w[0], e[0], p[0, ...]) for n, w, e, p in batch])
    for lobe in s.lobes(WO):
        assert lobe.weight.shape == lobe.albedo.shape == (3,)
        assert isinstance(lobe.probability, np.ndarray) and lobe.probability.shape == ()
    assert np.isclose(sum(float(p) for *_, p in one), 1.0)


def test_one_direction_of_any_layout():
    s = OpenPBRSurface(**PLAIN["stack"])
    ref = _lobes(s, WO)
    strided = np.array([0.6, 9.0, 0.0, 9.0, 0.8])[::2]
    read_only = WO.copy()
    read_only.flags.writeable = False
    for wo in (strided, read_only, list(WO)):
        _same_lobes(_lobes(s, wo), ref)
    s.lobes(WO)
    assert WO.flags.writeable  # the caller's array is left as it was


@pytest.mark.parametrize(
    "kwargs, exc, needle",
    [
        (dict(base_weight=1.5), ValueError, "base_weight must lie in [0, 1]"),
        (dict(base_weight=float("nan")), ValueError, "base_weight must be finite"),
        (dict(specular_ior=float("inf")), ValueError, "specular_ior must be finite"),
        (dict(base_color=(0.5, 1.5, 0.5)), ValueError, "base_color must lie in [0, 1] (component 1)"),
        (dict(base_color=(0.5, -0.5, 0.5)), ValueError, "base_color must lie in [0, 1] (component 1)"),
        (dict(base_color=(0.5, 0.5)), ValueError, "base_color must have shape (..., 3)"),
        (dict(base_weight=True), TypeError, "base_weight must be a real number"),
        (dict(base_color=(True, 0.5, 0.5)), None, None),  # a bool component goes the general way: accepted
    ],
)
def test_plain_inputs_fail_as_the_general_path_does(kwargs, exc, needle):
    if exc is None:
        assert OpenPBRSurface(**kwargs).params.tobytes() == OpenPBRSurface(base_color=(1.0, 0.5, 0.5)).params.tobytes()
        return
    with pytest.raises(exc) as err:
        OpenPBRSurface(**kwargs)
    assert needle in str(err.value)


def test_warnings_are_those_of_the_general_path():
    for kwargs in (
        dict(specular_ior=0.8),
        dict(thin_film_weight=0.5, coat_weight=0.5),
        dict(base_metalness=1.0, base_color=(0.05, 0.05, 0.05), specular_color=(0.0, 0.0, 0.0)),
    ):
        seen = []
        for k in (kwargs, _as_numpy(kwargs)):
            with warnings.catch_warnings(record=True) as ws:
                warnings.simplefilter("always")
                OpenPBRSurface(**k)
            seen.append([(w.category, str(w.message), w.filename) for w in ws])
        assert seen[0] == seen[1] and seen[0] and all(f == __file__ for *_, f in seen[0])
