"""sRGB previews: white is white, ColorChecker patches have their colours, bad input is an error."""

import warnings

import numpy as np
import pytest

import tensor_cosdi as tc
from tensor_cosdi.colour import rgb_to_cube, to_srgb
from tensor_cosdi.scenes import colorchecker, default_wavelengths


def test_flat_reflectance_is_grey():
    wl = default_wavelengths(28)
    rgb = to_srgb(np.full((3, 4, 28), 0.5), wl)
    assert rgb.shape == (3, 4, 3)
    np.testing.assert_allclose(rgb, rgb[0, 0, 0], atol=1e-9)  # neutral
    assert 0.7 < rgb[0, 0, 0] < 0.76  # sRGB encoding of 0.5 linear ≈ 0.735


def test_colorchecker_patches_have_their_hues():
    wl = default_wavelengths(28)
    rgb = to_srgb(colorchecker((4, 6), wl), wl).reshape(24, 3)
    blue, green, red, yellow, white, black = rgb[12], rgb[13], rgb[14], rgb[15], rgb[18], rgb[23]
    assert blue.argmax() == 2 and green.argmax() == 1 and red.argmax() == 0
    assert min(yellow[:2]) > 2 * yellow[2]
    assert white.min() > 0.85 and black.max() < 0.3


def test_chromatic_patches_match_colour_sciences_rendering():
    """Our 450–650 nm preview vs colour-science's full-spectrum sRGB of the same 18 chromatic
    patches.

    Hue within 20° on every patch except "blue flower" (its violet lies below
    450 nm, outside the cube: 37°), median within 10° (measured: 4.8°); a
    swapped channel or a wrong white point moves hues by far more.
    """
    from matplotlib.colors import rgb_to_hsv

    wl = default_wavelengths(28)
    rgb = to_srgb(colorchecker((4, 6), wl), wl).reshape(24, 3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # colour's notes on aligning spectral shapes
        import colour

        chart = colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"]
        names = list(chart)
        refs = [
            np.clip(colour.XYZ_to_sRGB(colour.sd_to_XYZ(chart[n]) / 100), 0, 1) for n in names[:18]
        ]
    diffs = []
    for i, (name, ref) in enumerate(zip(names[:18], refs)):
        d = abs(rgb_to_hsv(rgb[i])[0] - rgb_to_hsv(ref)[0])
        diffs.append(360 * min(d, 1 - d))
        if name != "blue flower":
            assert diffs[-1] < 20, f"{name}: hue off by {diffs[-1]:.1f}°"
    assert np.median(diffs) < 10


def test_band_axis_and_errors():
    wl = [450, 550, 650]
    cube = np.random.default_rng(0).random((3, 2, 5))
    np.testing.assert_allclose(to_srgb(cube, wl, band_axis=0), to_srgb(np.moveaxis(cube, 0, 2), wl))
    with pytest.raises(ValueError, match="expected 3 wavelengths"):
        to_srgb(np.ones((2, 2, 3)), [450, 550])
    with pytest.raises(ValueError, match="360–830"):
        to_srgb(np.ones((2, 2, 2)), [300, 550])
    with pytest.raises(ValueError, match="illuminant"):
        to_srgb(np.ones((2, 2, 2)), [450, 550], illuminant="D99")
    with pytest.raises(ValueError, match="cube must hold real numbers, got dtype complex128"):
        to_srgb(np.ones((2, 2, 2)) + 1j, [450, 550])  # not cast, imaginary part dropped
    with pytest.raises(ValueError, match="wavelengths must be 1-D \\(one per band\\)"):
        to_srgb(np.ones((2, 2, 4)), [[450, 500], [550, 600]])  # not flattened
    with pytest.raises(ValueError, match="band_axis must be an integer ≥ -3 and ≤ 2, got 3"):
        to_srgb(np.ones((2, 2, 2)), [450, 550], band_axis=3)
    with pytest.raises(ValueError, match="rgb must hold real numbers, got dtype complex128"):
        rgb_to_cube(np.full((2, 3), 0.5) + 1j, [450, 550])
    with pytest.raises(ValueError, match="wavelengths must be 1-D \\(one per band\\)"):
        rgb_to_cube(np.full((2, 3), 0.5), [[450, 500], [550, 600]])
    with pytest.raises(ValueError, match="wavelengths must hold real numbers"):
        tc.scenes.scene_cube("coffee", (8, 8), np.array([450, 550]) + 1j)


def test_colour_science_leaves_numpys_print_options_alone():
    """colour-science's import switches NumPy to the 1.13 legacy print format for the whole
    process; the library's way in (`colour.colour_science`, used by previews and scenes) must
    not pass that on to the user.  A fresh interpreter: colour may be imported here already."""
    import subprocess
    import sys

    code = (
        "import numpy as np\n"
        "before = np.get_printoptions()\n"
        "import tensor_cosdi as tc\n"
        "tc.colour.to_srgb(np.ones((2, 2, 3)) * 0.5, [450.0, 550.0, 650.0])\n"
        "tc.scenes.colorchecker((6, 4), [450.0, 550.0, 650.0])\n"
        "assert np.get_printoptions() == before, np.get_printoptions()\n"
        "print(repr(np.array([3.0, 4.0])))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)  # fmt: skip
    assert done.returncode == 0, done.stderr[-1500:]
    assert done.stdout.strip() == "array([3., 4.])"


def test_radiance_is_reflectance_times_the_illuminant_scaled_to_one():
    import colour

    from tensor_cosdi.colour import radiance

    wl = default_wavelengths(28)
    refl = colorchecker((4, 6), wl)
    lit = radiance(refl, wl, "A")
    assert lit.shape == refl.shape and lit.max() == pytest.approx(1.0)
    spd = colour.SDS_ILLUMINANTS["A"]
    s = np.interp(wl, spd.wavelengths, spd.values)
    ratio = lit / (refl * s)  # one constant for every voxel
    np.testing.assert_allclose(ratio, ratio.flat[0], rtol=1e-9)
    # tungsten light: a white patch is far dimmer in the blue than in the red
    white = lit[3, 0]
    assert white[0] < 0.35 * white[-1]
    # the band axis is honoured
    moved = radiance(np.moveaxis(refl, 2, 0), wl, "A", band_axis=0)
    np.testing.assert_allclose(np.moveaxis(moved, 0, 2), lit, rtol=1e-12)


@pytest.mark.parametrize(
    "args, kwargs, match",
    [
        ((np.ones((2, 2, 3)), [450, 550, 650], "nope"), {}, "unknown illuminant"),
        ((np.ones((2, 2, 3)), [450, 550, 650], "a"), {}, "unknown illuminant"),
        ((np.ones((2, 2, 3)), [450, 550], "A"), {}, "expected 3 wavelengths"),
        ((np.ones((2, 2, 3)), [450, 650, 550], "A"), {}, "increase strictly"),
        ((np.ones((2, 2, 3)), [450, 550, 900], "A"), {}, "tabulated range"),
        ((-np.ones((2, 2, 3)), [450, 550, 650], "A"), {}, "non-negative"),
        ((np.zeros((2, 2, 3)), [450, 550, 650], "A"), {}, "all zero"),
        ((np.full((2, 2, 3), np.nan), [450, 550, 650], "A"), {}, "NaN"),
        ((np.ones((2, 2, 3)), [450, 550, 650], "A"), {"band_axis": 3}, "band_axis"),
        ((np.ones((2, 2, 3)), [450, 550, 650], "A"), {"band_axis": 1.5}, "band_axis"),
        ((np.float64(1.0), [450], "A"), {}, "band axis"),
        ((np.ones((2, 2, 0)), [], "A"), {}, "cube is empty"),
    ],
)
def test_radiance_refuses_bad_input(args, kwargs, match):
    from tensor_cosdi.colour import radiance

    with pytest.raises(ValueError, match=match):
        radiance(*args, **kwargs)


def test_a_cube_with_nan_has_no_colour_and_micrometres_are_named():
    cube = np.ones((2, 2, 5))
    cube[0, 0, 1] = np.nan
    with pytest.raises(ValueError, match="NaN or infinite"):
        to_srgb(cube, [450, 500, 550, 600, 650])
    with pytest.raises(ValueError, match="look like micrometres"):
        default_wavelengths(8, 0.45, 0.65)
    with pytest.raises(ValueError, match="start < stop"):
        default_wavelengths(8, 650.0, 450.0)
