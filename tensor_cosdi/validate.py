"""One validator for numeric and boolean options, used by methods, systems, denoisers and the CLI.

Booleans and strings are not numbers (``tol=True``, ``alpha_t="0.5"`` are
errors, not ``1.0`` and ``0.5``); numbers are finite unless a range says
otherwise; a flag is ``True`` or ``False``, not ``"yes"`` or ``1``.  Every
error is one line naming the option, what it got and what it expects.

>>> from tensor_cosdi.validate import number, integer
>>> number("sigma", 0.1, low=0, low_open=True)
0.1
>>> integer("max_iter", True, low=1)
Traceback (most recent call last):
...
ValueError: max_iter must be an integer ≥ 1, got True
"""

from __future__ import annotations

import math
import numbers

import numpy as np

__all__ = [
    "number", "integer", "flag", "axis_index", "seed", "precision", "option_types", "real_array",
    "increasing", "output_folder", "imager",
]  # fmt: skip


def _range_text(low, high, low_open, high_open) -> str:
    parts = []
    if low is not None:
        parts.append(f"{'>' if low_open else '≥'} {low:g}")
    if high is not None:
        parts.append(f"{'<' if high_open else '≤'} {high:g}")
    return " and ".join(parts)


def _is_real(value) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))


def _scalar(value):
    """A 0-d array or tensor (NumPy, PyTorch, …) as the Python scalar it holds; anything else
    as it is."""
    if isinstance(value, np.ndarray) and value.ndim == 0:
        return value[()]
    if (
        getattr(value, "ndim", None) == 0
        and hasattr(value, "item")
        and not isinstance(value, (np.generic, np.ndarray))
    ):
        return value.item()  # a 0-d torch tensor, say (a bool one stays a bool)
    return value


def number(name: str, value, *, low=None, high=None, low_open=False, high_open=False) -> float:
    """``value`` as a finite ``float`` in the range, or a ``ValueError`` naming ``name``.

    ``low``/``high`` bound it (``low_open``/``high_open``: strictly).  Accepts
    Python and NumPy reals (0-d arrays and tensors too), never booleans or strings.
    """
    rng = _range_text(low, high, low_open, high_open)
    want = "a finite number" + (f" {rng}" if rng else "")
    value = _scalar(value)
    if not _is_real(value):
        raise ValueError(f"{name} must be {want}, got {value!r}")
    v = float(value)
    if not math.isfinite(v):
        raise ValueError(f"{name} must be {want}, got {value!r}")
    if low is not None and (v < low or (low_open and v == low)):
        raise ValueError(f"{name} must be {want}, got {value!r}")
    if high is not None and (v > high or (high_open and v == high)):
        raise ValueError(f"{name} must be {want}, got {value!r}")
    return v


def integer(name: str, value, *, low=None, high=None) -> int:
    """``value`` as an ``int`` in ``[low, high]``; booleans, floats and strings are errors."""
    rng = _range_text(low, high, False, False)
    want = "an integer" + (f" {rng}" if rng else "")
    value = _scalar(value)
    ok = isinstance(value, numbers.Integral) and not isinstance(value, (bool, np.bool_))
    if not ok or (low is not None and value < low) or (high is not None and value > high):
        raise ValueError(f"{name} must be {want}, got {value!r}")
    return int(value)


def flag(name: str, value) -> bool:
    """``value`` as a ``bool``: only ``True``/``False`` (NumPy's too), not ``1`` or ``"yes"``."""
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} must be True or False, got {value!r}")
    return bool(value)


def axis_index(name: str, value, ndim: int) -> int:
    """``value`` as an axis of an array of ``ndim`` axes, counted from 0 (a negative one from the
    end, as NumPy does), or a ``ValueError`` naming ``name``; booleans are not axes.

    >>> axis_index("band_axis", -1, 3)
    2
    >>> axis_index("axis", 3, 3)
    Traceback (most recent call last):
    ...
    ValueError: axis must be an integer in -3…2 (an axis of an array of 3 axes), got 3
    """
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value[()]
    ok = isinstance(value, numbers.Integral) and not isinstance(value, (bool, np.bool_))
    if not ok or not -ndim <= value < ndim:
        raise ValueError(
            f"{name} must be an integer in {-ndim}…{ndim - 1} (an axis of an array of {ndim} "
            f"axes), got {value!r}"
        )
    return int(value) % ndim


def seed(name: str, value):
    """``value`` if it can seed NumPy's generator: ``None``, an integer ≥ 0 (not a boolean), a
    sequence of them (NumPy's entropy list), a ``Generator``, ``BitGenerator`` or
    ``SeedSequence``; else a ``ValueError`` naming ``name`` (NumPy would take ``True`` as the
    seed 1 and fail deep inside on ``2.5`` or ``"7"``).
    """
    if value is None or isinstance(
        value, (np.random.Generator, np.random.BitGenerator, np.random.SeedSequence)
    ):
        return value
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value[()]

    def count(v) -> bool:
        return isinstance(v, numbers.Integral) and not isinstance(v, (bool, np.bool_)) and v >= 0

    if count(value):
        return int(value)
    if isinstance(value, (list, tuple, np.ndarray)) and len(value) and all(map(count, value)):
        return [int(v) for v in value]
    raise ValueError(
        f"{name} must be None, an integer ≥ 0 (or a sequence of them) or a "
        f"numpy.random.Generator, got {value!r}"[:300]
    )


def precision(name: str, value) -> np.dtype:
    """``value`` as the NumPy dtype ``float32`` or ``float64`` (a name or a dtype-like), or a
    ``ValueError`` naming ``name``: the float precision a study or a measurement runs in."""
    try:
        dt = np.dtype(value) if isinstance(value, (str, type, np.dtype)) else None
    except TypeError:
        dt = None
    if dt is None or dt not in (np.dtype(np.float32), np.dtype(np.float64)):
        raise ValueError(f"{name} must be 'float32' or 'float64', got {value!r}")
    return dt


def option_types(where: str, options: dict, defaults: dict) -> None:
    """Check each option's *kind* against its default's: a number where the default is a number
    (not a boolean, not a string, finite), a flag where it is a flag.

    ``None`` is left to the method (some take it as "off"), except for a flag, which is only
    ``True`` or ``False``; options whose default is ``None``, a string (``"auto"`` and the
    like) or a container are left to the method, which knows their meaning.  ``where`` names
    the method or system in the message.
    """
    for key, value in options.items():
        if key not in defaults:
            continue
        default = defaults[key]
        label = f"{where}: option {key}"
        if value is None and not isinstance(default, (bool, np.bool_)):
            continue  # None: "off", where the method allows it; a flag is True or False
        if isinstance(default, (bool, np.bool_)):
            flag(label, value)
        elif isinstance(default, numbers.Integral):
            if isinstance(value, (bool, np.bool_, str, bytes, numbers.Real)):
                integer(label, value)  # a count: not a float, a flag or a string
            # another object (a random Generator for a seed, say) is the method's to judge
        elif isinstance(default, numbers.Real):
            number(label, value)


def real_array(name: str, value, *, finite: bool = True) -> np.ndarray:
    """``value`` as a float64 ndarray of real numbers, or a ``ValueError`` naming ``name``.

    Complex, text and object arrays are errors (a cast would drop the imaginary part or fail
    deep inside NumPy); with ``finite`` (default) so are NaN and ±inf, counted in the message.
    Booleans and integers are numbers here (a mask, raw counts).
    """
    try:
        a = np.asarray(value)
    except (ValueError, TypeError) as e:  # ragged nested lists
        raise ValueError(f"{name} must be an array of real numbers: {e}") from None
    if a.dtype.kind not in "biuf":
        raise ValueError(f"{name} must hold real numbers, got dtype {a.dtype}")
    a = a.astype(np.float64, copy=False)
    if finite:
        bad = a.size - int(np.count_nonzero(np.isfinite(a)))
        if bad:
            raise ValueError(f"{name} holds {bad} NaN or infinite values; expected finite numbers")
    return a


def increasing(name: str, value, *, size: int | None = None) -> np.ndarray:
    """``value`` as a 1-D float64 array of finite, strictly increasing numbers (of ``size``
    entries when given) — band centres, candidate depths — or a ``ValueError`` naming ``name``.
    """
    a = real_array(name, value)
    if a.ndim != 1:
        raise ValueError(f"{name} must be 1-D, got shape {a.shape}")
    if size is not None and a.size != size:
        raise ValueError(f"{name} must hold {size} values (one per band), got {a.size}")
    if a.size == 0 or (np.diff(a) <= 0).any():
        raise ValueError(f"{name} must be non-empty and strictly increasing, got {a.tolist()}")
    return a


def imager(system, *attributes: str):
    """``system`` if it has what an imager of :mod:`tensor_cosdi.systems` has (``operator``,
    ``cube_shape``, ``measurement_shape`` and every name in ``attributes``), else a one-line
    ``ValueError``: an entry that takes an imager says so before it touches one.

    >>> imager("sd_cassi")
    Traceback (most recent call last):
    ...
    ValueError: system: expected an imager (tensor_cosdi.systems), got str
    """
    needs = ("operator", "cube_shape", "measurement_shape", *attributes)
    if not all(hasattr(system, a) for a in needs):
        raise ValueError(
            f"system: expected an imager (tensor_cosdi.systems), got {type(system).__name__}"
        )
    return system


def output_folder(path, what: str = "output folder") -> None:
    """A ``FileNotFoundError`` unless the folder that the file ``path`` goes into exists and is a
    folder (checked before any work, so that a typo there does not cost a reconstruction).

    >>> output_folder("/no/such/folder/cube.h5")
    Traceback (most recent call last):
    ...
    FileNotFoundError: output folder /no/such/folder does not exist
    """
    from pathlib import Path

    folder = Path(path).parent
    if not folder.is_dir():
        state = "is not a folder" if folder.exists() else "does not exist"
        raise FileNotFoundError(f"{what} {folder} {state}")
