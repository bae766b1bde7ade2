"""Input checks do what their messages say."""

import math

import numpy as np
import pytest

import openpbr_diffuse as od
from openpbr_diffuse import _arrays as ar


def test_unit_tolerance_is_on_the_length():
    """|w| = 1 +- UNIT_TOL is accepted, as the message states; beyond it is refused."""
    for length in (1.0 + 0.9 * ar.UNIT_TOL, 1.0 - 0.9 * ar.UNIT_TOL):  # |w|^2 - 1 ~ 1.8e-4
        assert od.evaluate("eon", [0.0, 0.0, length], [0.0, 0.0, 1.0], 0.5).shape == (1,)
    for length in (1.0 + 1.1 * ar.UNIT_TOL, 1.0 - 1.1 * ar.UNIT_TOL):
        with pytest.raises(ValueError, match=r"\|w\| = 1 within 0\.0001"):
            od.evaluate("eon", [0.0, 0.0, length], [0.0, 0.0, 1.0], 0.5)
    # the fused kernel check and the NumPy check agree (large arrays take the kernel path)
    w = np.tile([0.0, 0.0, 1.0 + 0.9 * ar.UNIT_TOL], (2 * ar._PARALLEL_MIN, 1))
    assert ar.directions("wi", w, np.dtype(np.float64)) is w
    assert od.evaluate("eon", w, w, 0.5).shape == (len(w), 1)


def test_float16_unit_vectors_are_accepted_and_bad_ones_named_with_their_dtype():
    rng = np.random.default_rng(0)
    v = rng.normal(size=(1000, 3))
    v[:, 2] = np.abs(v[:, 2])
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    f = od.evaluate("eon", v.astype(np.float16), np.array([0.0, 0.0, 1.0], np.float16), np.float16(0.5))
    assert f.dtype == np.float32
    np.testing.assert_allclose(f, od.evaluate("eon", v, [0.0, 0.0, 1.0], 0.5), rtol=5e-3)
    with pytest.raises(ValueError, match="float16"):
        od.evaluate("eon", np.array([0.6, 0.0, 0.9], np.float16), [0.0, 0.0, 1.0], 0.5)


@pytest.mark.parametrize(
    "value,dtype,shown",
    [
        (1.0000001, np.float32, "1.0000001"),
        (1.0 + 2.0**-52, np.float64, "1.0000000000000002"),
    ],
)
def test_out_of_range_values_are_printed_in_full(value, dtype, shown):
    with pytest.raises(ValueError) as info:
        od.evaluate("eon", [0.0, 0.0, 1.0], [0.0, 0.0, 1.0], np.array(value, dtype))
    assert f"got {shown}" in str(info.value)


def test_sigma_bound_and_value_are_distinguishable():
    above = np.nextafter(math.pi / 2, 4.0)
    with pytest.raises(ValueError) as info:
        od.evaluate("qon", [0.0, 0.0, 1.0], [0.0, 0.0, 1.0], above)
    msg = str(info.value)
    assert repr(math.pi / 2) in msg and repr(float(above)) in msg


def test_one_dimensional_direction_has_no_empty_index():
    with pytest.raises(ValueError) as info:
        od.evaluate("eon", [0.0, 0.0, 2.0], [0.0, 0.0, 1.0], 0.5)
    assert "wi[]" not in str(info.value) and str(info.value).startswith("wi = [0, 0, 2]")
    with pytest.raises(ValueError, match=r"^wi\[1\] = "):
        od.evaluate("eon", [[0.0, 0.0, 1.0], [0.0, 0.0, 2.0]], [0.0, 0.0, 1.0], 0.5)


def test_masked_values_are_refused_not_dropped():
    wi = np.ma.masked_array([[0.0, 0.0, 1.0], [0.0, 0.0, 7.0]], mask=[[0, 0, 0], [1, 1, 1]])
    with pytest.raises(ValueError, match="wi is a masked array"):
        od.evaluate("eon", wi, [0.0, 0.0, 1.0], 0.5)
    rho = np.ma.masked_array([0.5, 0.2], mask=[0, 1])
    with pytest.raises(ValueError, match="rho is a masked array"):
        od.directional_albedo("eon", 0.5, 0.5, rho)
    # an empty mask is just the data
    clean = np.ma.masked_array([[0.0, 0.0, 1.0]])
    np.testing.assert_array_equal(
        od.evaluate("eon", clean, [0.0, 0.0, 1.0], 0.5), od.evaluate("eon", [[0.0, 0.0, 1.0]], [0.0, 0.0, 1.0], 0.5)
    )


@pytest.mark.parametrize(
    "kwargs,exc,needle",
    [
        ({"rng": "seed"}, TypeError, "rng"),
        ({"rng": -1}, ValueError, "rng"),
        ({"rng": 1.5}, TypeError, "rng"),
        ({"rng": 0, "shape": (-3,)}, ValueError, "shape"),
        ({"rng": 0, "shape": (2.5,)}, ValueError, "shape"),
        ({"rng": 0, "shape": "ab"}, ValueError, "shape"),
    ],
)
def test_sample_rng_arguments_are_checked_before_numpy(kwargs, exc, needle):
    with pytest.raises(exc, match=needle):
        od.sample_rng("eon", [0.0, 0.0, 1.0], 0.5, **kwargs)


def test_sample_rng_accepts_an_int_shape():
    wi, p = od.sample_rng("eon", [0.0, 0.0, 1.0], 0.5, rng=1, shape=4)
    assert wi.shape == (4, 3) and p.shape == (4,)


def test_messages_do_not_depend_on_numpy_print_options():
    """colour-science sets np.set_printoptions(legacy="1.13") on import; messages stay exact."""
    saved = np.get_printoptions()
    try:
        np.set_printoptions(legacy="1.13")
        with pytest.raises(ValueError, match=r"got 1\.0000001\b"):
            od.evaluate("eon", [0.0, 0.0, 1.0], [0.0, 0.0, 1.0], np.array(1.0000001, np.float32))
    finally:
        np.set_printoptions(**saved)
