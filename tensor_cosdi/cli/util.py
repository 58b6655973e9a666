"""Small argument helpers shared by the ``tensor-cosdi`` sub-commands."""

from __future__ import annotations

import argparse


class LazyHelp(str):
    """An option's help text made by ``make()`` only when argparse shows it (that sub-command's
    ``--help``): building the parser then imports no registry, and ``tensor-cosdi --help``
    stays light.  (argparse fills a help text in with ``help % params``.)"""

    def __new__(cls, make):
        self = super().__new__(cls, "(listed by the sub-command's --help)")
        self._make = make
        return self

    def __mod__(self, params):
        return self._make().replace("%", "%%") % params


def _option_value(text: str):
    import json

    if "=" not in text:
        raise argparse.ArgumentTypeError(f"expected key=value, got {text!r}")
    key, value = text.split("=", 1)
    if not key.isidentifier():
        raise argparse.ArgumentTypeError(
            f"expected key=value with an option name before '=', got {text!r}"
        )
    try:
        return key, json.loads(value)
    except RecursionError:
        raise argparse.ArgumentTypeError(f"{key}: the value is nested too deeply") from None
    except ValueError:
        return key, value


def option_dict(pairs, flag: str) -> dict:
    """``{key: value}`` of repeated ``FLAG key=value`` arguments; a key given twice is an error
    (which of the two was meant is not guessed)."""
    out = {}
    for key, value in pairs or []:
        if key in out:
            raise ValueError(
                f"{flag} {key}= is given twice ({out[key]!r} and {value!r}); give it once"
            )
        out[key] = value
    return out


def check_output(out, force: bool) -> None:
    """Before any work: ``out`` must not be a folder, must not exist without ``--force``, and its
    folder must exist (a typo there would otherwise surface only after the reconstruction)."""
    from pathlib import Path

    from ..validate import output_folder

    out = Path(out)
    if out.is_dir():
        raise IsADirectoryError(f"--out {out} is a folder; give a file name")
    if out.exists() and not force:
        raise FileExistsError(f"{out} exists; pass --force to replace it")
    output_folder(out, f"--out {out}: the output folder")


def _method_defaults(name):
    from ..solvers import METHODS

    return METHODS[name].defaults  # an unknown name is an error listing the registered ones


def _jsonable(v) -> bool:
    import json

    try:
        json.dumps(v)
        return True
    except (TypeError, ValueError):
        return False


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {value}")
    return value


def run_metadata(args, res, seconds, **extra) -> dict:
    """What a reconstruction bundle records about the run (method, options, time, …)."""
    return {
        "method": args.method,
        "options": {k: v for k, v in res.options.items() if _jsonable(v)},
        "seconds": seconds,
        "iterations": res.iterations,
        **extra,
    }


def done_line(system, method: str, res, seconds: float, out) -> str:
    """The line ``reconstruct`` prints when it has written its bundle."""
    return (
        f"{type(system).__name__} {tuple(system.cube_shape)} reconstructed with {method} in "
        f"{seconds:.1f} s ({res.iterations} iterations, residual "
        f"{res.history['residual'][-1]:.3g}); written to {out}"
    )
