"""The one validator for numeric options: booleans and strings are not numbers, numbers are
finite, flags are True/False — at the method door, in systems, denoisers and plans."""

import numpy as np
import pytest

import tensor_cosdi as tc
from tensor_cosdi.io.triggers import AcquisitionPlan
from tensor_cosdi.learn import dcosnet_train
from tensor_cosdi.solvers import denoisers
from tensor_cosdi.validate import (
    axis_index,
    flag,
    increasing,
    integer,
    number,
    option_types,
    precision,
    real_array,
    seed,
)


@pytest.mark.parametrize("bad", [True, np.bool_(False), "0.5", None, float("inf"), np.nan, 1j])
def test_number_refuses_what_is_not_a_finite_real(bad):
    with pytest.raises(ValueError, match="x must be a finite number"):
        number("x", bad)


def test_precision_is_float32_or_float64():
    assert precision("dtype", "float32") == np.float32
    assert precision("dtype", np.float64) == np.float64
    for bad in ("float16", "int32", "x", 3, None, True, np.int8, object):
        with pytest.raises(ValueError, match="dtype must be 'float32' or 'float64', got"):
            precision("dtype", bad)


def test_number_ranges_and_numpy_scalars():
    assert number("x", np.float32(0.5), low=0, high=1) == 0.5
    assert number("x", np.array(2)) == 2.0
    with pytest.raises(ValueError, match="x must be a finite number > 0, got 0"):
        number("x", 0, low=0, low_open=True)
    with pytest.raises(ValueError, match="≤ 1, got 1.5"):
        number("x", 1.5, high=1)


def test_integer_and_flag():
    assert integer("n", np.int64(3), low=1) == 3
    for bad in (True, 2.0, "3", 0):
        with pytest.raises(ValueError, match="n must be an integer ≥ 1"):
            integer("n", bad, low=1)
    assert flag("f", np.bool_(True)) is True
    for bad in (1, "yes", None):
        with pytest.raises(ValueError, match="f must be True or False"):
            flag("f", bad)


def test_real_array_and_increasing():
    np.testing.assert_array_equal(real_array("a", [[1, 2]], finite=True), [[1.0, 2.0]])
    assert real_array("m", np.array([True, False])).dtype == np.float64  # a mask is numbers
    for bad, message in (
        (np.ones(2) + 1j, "a must hold real numbers, got dtype complex128"),
        (np.array(["1", "2"]), "a must hold real numbers, got dtype <U1"),
        ([[1, 2], [3]], "a must be an array of real numbers"),
        ([1.0, np.nan, np.inf], "a holds 2 NaN or infinite values; expected finite numbers"),
    ):
        with pytest.raises(ValueError, match=message):
            real_array("a", bad)
    assert np.isnan(real_array("a", [np.nan], finite=False)[0])
    np.testing.assert_array_equal(increasing("wl", [450, 500], size=2), [450.0, 500.0])
    for bad, message in (
        ([[450, 500]], "wl must be 1-D, got shape \\(1, 2\\)"),
        ([450, 500, 600], "wl must hold 2 values \\(one per band\\), got 3"),
        ([500, 450], "wl must be non-empty and strictly increasing, got \\[500.0, 450.0\\]"),
        ([450, 450], "strictly increasing"),
    ):
        with pytest.raises(ValueError, match=message):
            increasing("wl", bad, size=2)
    with pytest.raises(ValueError, match="non-empty"):
        increasing("wl", [])


def test_option_types_follows_the_defaults():
    defaults = {"tol": 1e-4, "max_iter": 10, "progress": False, "lam": "auto", "guard": 1.3}
    option_types("m", {"tol": 1e-3, "max_iter": 5, "lam": 0.1, "guard": None}, defaults)
    for bad, message in (
        ({"tol": True}, "m: option tol must be a finite number, got True"),
        ({"tol": float("inf")}, "option tol must be a finite number"),
        ({"max_iter": "5"}, "option max_iter must be an integer"),
        ({"progress": "yes"}, "option progress must be True or False"),
    ):
        with pytest.raises(ValueError, match=message):
            option_types("m", bad, defaults)


def test_every_method_door_refuses_a_boolean_for_a_number():
    p = tc.studies.make_problem("sd_cassi", "colorchecker", shape=(8, 8), n_bands=4)
    checked = 0
    for name in tc.solvers.methods(p.system):  # the imager check comes first
        if tc.solvers.METHODS[name].needs:
            continue  # a missing needed option is named first
        numeric = [
            k for k, v in tc.solvers.METHODS[name].defaults.items()
            if isinstance(v, float) and not isinstance(v, bool)
        ]  # fmt: skip
        if not numeric:
            continue
        with pytest.raises(ValueError, match=f"method '{name}': option {numeric[0]} must be"):
            tc.reconstruct(p.system, p.measurement, name, **{numeric[0]: True})
        checked += 1
    assert checked >= 6  # every method for SD-CASSI with a float option


def test_denoisers_and_plans_validate_too():
    with pytest.raises(ValueError, match="tv: sigma must be a finite number > 0, got -1"):
        denoisers.tv(np.ones((4, 4, 2)), -1)
    with pytest.raises(ValueError, match="wavelet: sigma must be a finite number ≥ 0"):
        denoisers.wavelet(np.ones((4, 4, 2)), float("nan"))
    with pytest.raises(ValueError, match="frames in a plan must be an integer ≥ 1 and ≤ 100000"):
        AcquisitionPlan.snapshots(10**8)


_Z = np.random.default_rng(0).random((8, 8, 4)) + 0.5j
_WL = np.linspace(450, 650, 4)


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: tc.bases.svd_basis(_Z[..., 0]), "matrix"),
        (lambda: tc.bases.tucker_bases(_Z), "tucker_bases: the tensor"),
        (lambda: tc.colour.reflectance(_Z, _Z.real), "cube"),
        (lambda: tc.colour.radiance(_Z, _WL), "cube"),
        (lambda: tc.noise.snr_db(_Z.real, _Z), "noisy"),
        (lambda: tc.noise.estimate_snr_db(_Z[..., 0]), "measurement"),
        (lambda: tc.depth.wrapped_phase(_Z), "frames"),
        (lambda: tc.depth.guided_filter(_Z[..., 0], _Z[..., 0].real), "guide"),
        (lambda: tc.depth.focus_measure(_Z[..., 0]), "image"),
        (lambda: tc.depth.disparity_from_views(_Z), "views"),
        (lambda: tc.io.bin_frame(_Z[..., 0], 2), "frame"),
        (lambda: tc.optics.psf_width(_Z[..., 0]), "the PSF"),
        (lambda: tc.optics.phase_shift_patterns(_Z[..., 0]), "phase"),
        (lambda: tc.scenes.light_field(_Z, 0.5), "cube"),
        (lambda: tc.scenes.depth_planes(_Z[..., 0], 3), "depth"),
        (lambda: tc.solvers.train_dictionary([_Z], patch=4), "a training cube"),
        (
            lambda: tc.systems.SDCASSI(np.ones((8, 8)), n_bands=4, wavelengths=_WL + 1j),
            "wavelengths",
        ),
    ],  # fmt: skip
)
def test_a_complex_array_is_refused_not_cast_to_its_real_part(call, name):
    with pytest.raises(ValueError, match=f"^{name} must hold real numbers, got dtype complex128$"):
        call()


def test_system_wavelengths_must_be_one_dimensional():
    with pytest.raises(ValueError, match="wavelengths must be 1-D \\(one per band\\), got shape"):
        tc.systems.SDCASSI(np.ones((8, 8)), n_bands=4, wavelengths=_WL.reshape(2, 2))


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: tc.codes.random_binary(np.zeros((0, 8))), "shape must have at least one axis"),
        (lambda: tc.codes.random_binary(()), "shape must have at least one axis"),
        (lambda: tc.testing.random_tensor(()), "shape must have at least one axis"),
        (lambda: tc.operators.vec_index(()), "shape must have at least one axis"),
        (lambda: tc.bases.tucker_bases(np.zeros((0, 4, 3))), "the tensor has no entries"),
        (lambda: tc.plot.white_point(np.zeros((0, 4, 3))), "the cube is empty"),
        (lambda: tc.io.frame_count(np.zeros(3)), "expected an imager"),
        (lambda: tc.studies.conditioning(np.zeros(3)), "expected an imager"),
        (lambda: tc.studies.compare(np.zeros(3)), "compare needs a Problem"),
        (lambda: tc.operators.sensing_gain(np.zeros(3)), "expected a TensorOperator"),
        (lambda: tc.operators.gram_eigenvalues(np.zeros(3)), "expected a structured A Aᵀ"),
        (lambda: tc.testing.dot_test(np.zeros(3)), "dot_test needs a TensorOperator"),
        (lambda: tc.datasets.data_file(3), "data_file takes a path inside"),
        (lambda: tc.solvers.otd.lam_schedule(np.zeros(3)), "expected an imager"),
        (lambda: tc.solvers.subspace.has_many_bands("sd_cassi"), "expected an imager"),
        (lambda: dcosnet_train.training_data({"n_bands": 28}), "needs a DCoSNetConfig, got dict"),
    ],
)
def test_empty_shapes_and_objects_of_the_wrong_kind_are_named(call, message):
    with pytest.raises(ValueError, match=message):
        call()


@pytest.mark.parametrize("path", ["/etc/passwd", "../secret.mat", "masks/../../x.mat", ""])
def test_data_file_stays_inside_the_research_data(path):
    """An absolute path or one climbing out with ``..`` would read any file on the machine."""
    with pytest.raises(ValueError, match="data_file takes a relative path inside"):
        tc.datasets.data_file(path)


def test_wavelengths_with_nan_say_so():
    """An ENVI header's ``wavelength = {400, nan}`` once read as "got 400–400"."""
    from tensor_cosdi._units import check_wavelengths_nm

    with pytest.raises(ValueError, match="got 400–400 and 1 NaN or infinite$"):
        check_wavelengths_nm([400.0, np.nan])
    with pytest.raises(ValueError, match="got no finite values and 2 NaN or infinite$"):
        check_wavelengths_nm([np.nan, np.inf])


def test_axis_index_counts_from_either_end_and_refuses_the_rest():
    assert axis_index("axis", -1, 3) == 2 and axis_index("axis", np.int64(1), 3) == 1
    assert axis_index("axis", np.array(0), 1) == 0
    for bad in (3, -4, True, 1.0, "1", None):
        with pytest.raises(ValueError, match=r"band_axis must be an integer in -3…2"):
            axis_index("band_axis", bad, 3)


def test_seed_is_none_a_count_or_a_generator():
    g = np.random.default_rng(3)
    assert seed("rng", None) is None and seed("rng", 7) == 7 and seed("rng", g) is g
    assert seed("rng", np.uint32(5)) == 5 and seed("rng", (3, 4)) == [3, 4]
    for bad in (True, -1, 2.5, "7", [1, True], [], [-1]):
        with pytest.raises(ValueError, match="rng must be None, an integer ≥ 0"):
            seed("rng", bad)
    # every seeded entry goes through it: a boolean seed is not the seed 1
    with pytest.raises(ValueError, match="rng must be"):
        tc.codes.random_binary((4, 4), rng=True)
    assert np.array_equal(
        tc.codes.random_binary((4, 4), rng=1), tc.codes.random_binary((4, 4), rng=1)
    )


def test_a_zero_dimensional_tensor_is_the_number_it_holds():
    torch = pytest.importorskip("torch")
    assert number("sigma", torch.tensor(0.25)) == 0.25
    assert integer("n", torch.tensor(3), low=1) == 3
    for bad in (torch.tensor(True), torch.tensor([0.1]), torch.tensor(float("nan"))):
        with pytest.raises(ValueError, match="sigma must be a finite number"):
            number("sigma", bad)
