"""Every bad argument of ``tensor_cosdi.testing.hostile_arguments`` is refused with a one-line
``ValueError``/``TypeError`` that names it (NaN, ±inf, booleans and strings for numbers, numbers
too large to compute with, axes that do not exist, objects of the wrong kind)."""

import warnings

import pytest

from tensor_cosdi.testing import hostile_arguments

CASES = hostile_arguments()


@pytest.mark.parametrize("case", CASES, ids=[f"{m}: {label}" for m, label, _, _ in CASES])
def test_bad_argument_is_refused_by_name(case):
    module, label, call, words = case
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a warning is not the error that is due
        with pytest.raises((ValueError, TypeError)) as info:
            call()
    message = str(info.value)
    assert "\n" not in message, f"{label}: a multi-line message"
    assert any(w in message.lower() for w in words), f"{label}: {message!r} names none of {words}"


def test_the_catalogue_covers_every_module_it_names():
    modules = {m for m, _, _, _ in CASES}
    assert {"codes", "colour", "metrics", "noise", "scenes", "depth", "optics", "bases",
            "io.lenslet", "io.calibration", "operators", "systems"} <= modules  # fmt: skip
    assert len(CASES) >= 200
