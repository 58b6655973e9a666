"""Bad input gets a clear ValueError naming what was wrong and what was expected."""

import numpy as np
import pytest

from tensor_cosdi.operators import (
    Blur,
    BlurSum,
    Code,
    LightFieldLayout,
    ModeProduct,
    Pad,
    Replicate,
    Shear,
    Stack,
    SumAxis,
    Transpose,
    weighted_sum,
)
from tensor_cosdi.testing import registry


def sd(shape=(4, 5, 3)):
    shear = Shear(shape, 1)
    return SumAxis(shear.output_shape, 2) @ shear @ Code(np.ones(shape[:2]), shape)


def test_wrong_shape_names_both_shapes():
    op = sd()
    with pytest.raises(ValueError, match=r"input shape \(4, 5, 3\), got shape \(4, 5, 2\)"):
        op.forward(np.zeros((4, 5, 2)))
    with pytest.raises(ValueError, match=r"output shape \(4, 7\), got shape \(4, 5\)"):
        op.adjoint(np.zeros((4, 5)))
    with pytest.raises(ValueError, match=r"output shape \(4, 7\), got shape \(3, 7\)"):
        op.solve_dual(np.zeros((3, 7)), 1.0)
    with pytest.raises(ValueError, match=r"input shape \(4, 5, 3\)"):
        op.solve_normal(np.zeros((4, 5)), 1.0)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_inputs(bad):
    op = sd()
    x = np.ones(op.input_shape)
    x[1, 2, 0] = bad
    with pytest.raises(ValueError, match="NaN or inf"):
        op.forward(x)
    y = np.ones(op.output_shape)
    y[0, 0] = bad
    with pytest.raises(ValueError, match="NaN or inf"):
        op.adjoint(y)
    with pytest.raises(ValueError, match="NaN or inf"):
        Code(np.full((4, 5), bad), (4, 5, 3))
    with pytest.raises(ValueError, match="NaN or inf"):
        ModeProduct((3, 4), {0: np.full((2, 3), bad)})
    with pytest.raises(ValueError, match="NaN or inf"):
        Blur((4, 4), np.full((3, 3), bad))


def test_integer_and_complex_inputs_rejected():
    op = sd()
    with pytest.raises(ValueError, match="floating-point.*int64"):
        op.forward(np.ones(op.input_shape, dtype=np.int64))
    with pytest.raises(ValueError, match="real array"):
        Code(np.ones((4, 5), dtype=complex), (4, 5, 3))


@pytest.mark.parametrize(
    "shifts, message",
    [
        ([0, 2, 1], "monotone .*, but band 2 has shift 1 < 2 of band 1"),
        ([0, -1, 2], "≥ 0"),
        (-1, "≥ 0"),
        ([0, 1], "expected 3 per-band shifts"),
        ([0, np.nan, 2], "finite"),
        (np.inf, "finite"),
    ],
)
def test_bad_shifts(shifts, message):
    with pytest.raises(ValueError, match=message):
        Shear((4, 5, 3), shifts)


@pytest.mark.parametrize(
    "shape, message",
    [
        ((4, -5, 3), r"positive integers.*-5 ≤ 0"),
        ((4, 0, 3), r"0 ≤ 0"),
        ((4, 5.5, 3), r"5.5 is not an integer"),
        ((4, "5", 3), r"is not an integer"),
        ((), "at least one axis"),
        ((True, 2), "not an integer"),
    ],
)
def test_bad_sizes(shape, message):
    with pytest.raises(ValueError, match=message):
        SumAxis(shape, 0)


def test_integral_float_sizes_accepted():
    assert SumAxis((4.0, 5), 0).output_shape == (5,)


def test_constructor_consistency_errors():
    with pytest.raises(
        ValueError, match=r"code shape \(4, 6\) does not match input shape \(4, 5, 3\)"
    ):
        Code(np.ones((4, 6)), (4, 5, 3))
    with pytest.raises(ValueError, match="expected 1 to 3 axes"):
        Code(np.ones((4, 5, 3, 2)), (4, 5, 3))
    with pytest.raises(ValueError, match=r"matrix for mode 1 must have shape \(rows, 5\)"):
        ModeProduct((4, 5), {1: np.ones((2, 4))})
    with pytest.raises(ValueError, match="distinct"):
        ModeProduct((4, 5), [np.ones((2, 4)), np.ones((2, 4))], modes=[0, 0])
    with pytest.raises(ValueError, match="axis and band_axis must differ"):
        Shear((4, 5, 3), 1, axis=2, band_axis=2)
    with pytest.raises(ValueError, match="out of range"):
        SumAxis((4, 5), 2)
    with pytest.raises(ValueError, match="permutation"):
        Transpose((2, 3, 4), (0, 0, 1))
    with pytest.raises(ValueError, match="before must be an integer ≥ 0"):
        Pad((3, 4), axis=1, before=-1)
    with pytest.raises(ValueError, match="layout must be one of"):
        LightFieldLayout((2, 2, 3, 2, 2), "diagonal")
    with pytest.raises(ValueError, match="at least 4 axes"):
        LightFieldLayout((2, 2, 3), "tiled")
    with pytest.raises(ValueError, match=r"psfs shape .* does not match"):
        Blur((4, 4, 3), np.ones((3, 3, 2)))
    with pytest.raises(ValueError, match="must not be a spatial axis"):
        BlurSum((4, 4, 2, 3), np.ones((3, 3, 2, 3, 2)), sum_axis=1)
    with pytest.raises(ValueError, match=r"psfs must have shape \(h, w, \*rest, K\)"):
        BlurSum((4, 4, 2, 3), np.ones((3, 3, 2, 3)), sum_axis=3)
    with pytest.raises(ValueError, match="sum_axis must be an integer"):
        BlurSum((4, 4, 2, 3), np.ones((3, 3, 2, 3, 2)), sum_axis=True)
    with pytest.raises(ValueError, match="at least 3 axes"):
        BlurSum((4, 4), np.ones((3, 3, 2)), sum_axis=1)
    with pytest.raises(ValueError, match="axes must be two distinct axes"):
        BlurSum((4, 4, 2, 3), np.ones((3, 3, 2, 3, 2)), sum_axis=3, axes=0)
    with pytest.raises(ValueError, match="n must contain positive integers"):
        Replicate((3, 4), 0, 0)


def test_combination_errors():
    a = sd((4, 5, 3))
    b = sd((4, 6, 3))
    with pytest.raises(
        ValueError,
        match=r"output shape \(4, 8\) differs from the outer operator's input shape \(4, 5, 3\)",
    ):
        a @ b
    with pytest.raises(ValueError, match="different shapes"):
        a + b
    with pytest.raises(ValueError, match="equal shapes"):
        Stack([a, b])
    with pytest.raises(ValueError, match="one weight per operator"):
        weighted_sum([a], [0.5, 0.5])
    with pytest.raises(ValueError, match="divide an operator by zero"):
        a / 0
    with pytest.raises(ValueError, match="finite real"):
        float("nan") * a


@pytest.mark.parametrize("mu", [0, -1.0, float("nan"), float("inf"), "1"])
def test_bad_mu(mu):
    op = registry()["sd_cassi"](np.random.default_rng(0))
    with pytest.raises(ValueError, match="mu must be a finite positive number"):
        op.solve_normal(np.ones(op.input_shape), mu)


def test_nan_in_discarded_entries_and_overflow():
    """Compressive maps scan their (smaller) result: a NaN that cannot reach the
    result is ignored, one that can is reported as the argument's; overflow of
    finite input is named as such."""
    shear = Shear((3, 4, 3), 1)
    y = np.ones(shear.output_shape)
    y[0, 0, 2] = np.nan  # band 2 starts at column 2: column 0 is cropped away
    clean = y.copy()
    clean[0, 0, 2] = 0.0
    np.testing.assert_array_equal(shear.adjoint(y), shear.adjoint(clean))
    y[0, 3, 2] = np.inf  # this one lands in the result
    with pytest.raises(ValueError, match=r"argument of shape \(3, 6, 3\) contains NaN or inf"):
        shear.adjoint(y)
    op = sd((2, 2, 3))
    big = np.full(op.input_shape, 3e38, dtype=np.float32)
    with pytest.raises(ValueError, match="overflowed to inf for a finite argument"):
        op.forward(big)
