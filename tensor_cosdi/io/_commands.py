"""Checks on what reaches the trigger device and the capture folder (the line protocol of
:mod:`tensor_cosdi.io.triggers`)."""

from __future__ import annotations

import numpy as np

#: Largest deformable-mirror Zernike amplitude (waves) a command may ask for; the device's declared
#: range.  Larger, NaN or infinite values never reach the hardware.
DM_MAX_WAVES = 10.0

#: The longest command line sent to the device (a plan's longest, ``DM`` with many pairs, is far
#: shorter); a longer one is refused before it is echoed in a message or written to the port.
MAX_COMMAND_CHARS = 1024


def check_command(c):
    """``c`` stripped, or a ``ValueError``: one line, a known verb, arguments of the right kind and
    range (``DMD``/``PROJ``/``TRIG``: one integer ≥ 0; ``DM``: ``j:a`` pairs, Noll ``j ≥ 1``,
    finite ``|a| ≤`` :data:`DM_MAX_WAVES`; ``PING``: none)."""
    if isinstance(c, str) and len(c) > MAX_COMMAND_CHARS:
        raise ValueError(
            f"a command is at most {MAX_COMMAND_CHARS} characters, got {len(c)} starting {c[:40]!r}"
        )
    if not isinstance(c, str) or not c.strip() or "\n" in c or "\r" in c:
        raise ValueError(f"a command is one non-empty line of text, got {c!r}")
    verb, *args = c.split()
    if verb not in ("PING", "DMD", "DM", "PROJ", "TRIG"):
        raise ValueError(
            f"unknown command verb {verb!r} in {c!r}; the protocol knows PING, DMD, DM, PROJ, TRIG"
        )
    if verb == "PING" and args:
        raise ValueError(f"PING takes no arguments, got {c!r}")
    if verb in ("DMD", "PROJ", "TRIG"):
        if len(args) != 1 or not args[0].isdigit():
            raise ValueError(f"{verb} takes one integer ≥ 0, got {c!r}")
    if verb == "DM":
        if not args:
            raise ValueError(f"DM needs at least one j:a pair, got {c!r}")
        for pair in args:
            j, sep, a = pair.partition(":")
            try:
                amp = float(a)
            except ValueError:
                amp = None
            if not sep or not j.isdigit() or int(j) < 1 or amp is None:
                raise ValueError(f"DM takes j:a pairs (Noll j ≥ 1, amplitude a), got {pair!r}")
            if not np.isfinite(amp) or abs(amp) > DM_MAX_WAVES:
                raise ValueError(
                    f"DM amplitude {a} for Zernike {j} is not a finite value within "
                    f"±{DM_MAX_WAVES:g} waves (DM_MAX_WAVES); not sent"
                )
    return c.strip()


def _check_frame_name(name):
    """A plan's frame name must be a plain file name: it is joined to the capture folder."""
    size = len(name.encode("utf-8", "surrogatepass")) if isinstance(name, str) else 0
    if size > 255:
        raise ValueError(
            f"a frame name is at most 255 bytes (a file name), got {size} starting {name[:40]!r}"
        )
    if (
        not isinstance(name, str)
        or not name
        or name in (".", "..")
        or "/" in name
        or "\\" in name
        or "\0" in name
        or name.startswith(".")
    ):
        raise ValueError(
            f"frame names must be plain file names (no folders, '..', leading dots or absolute "
            f"paths), got {name!r}"
        )
    return name
