"""D-CoSNet as a reconstruction method (``method="dcosnet"``; needs the ``torch`` extra).

The network and its training live in :mod:`tensor_cosdi.learn.dcosnet`.
"""

from __future__ import annotations

import time

import tensorly as tl

from ._base import register_method, relative_residual

__all__ = ["dcosnet"]

_LOADED: dict = {}


def dcosnet(system, measurement, *, weights=None, start="auto", device=None, nonneg: bool = True):
    """One pass of a trained D-CoSNet (thesis §7.2).  Registered as ``"dcosnet"``.

    ``weights``: a file written by ``tensor-cosdi train-dcosnet`` (default:
    the shipped weights for the system's kind — SD-CASSI, 28 bands, 2 px per
    band).  The weights must match the system's kind, channel count and
    shift (a ``ValueError`` says what to train otherwise).  ``start``: where the
    unfolded ADMM begins, as the weights were trained (``"auto"``: the file's own, or for
    the shipped weights :data:`~tensor_cosdi.learn.dcosnet.DEFAULT_START`): ``"fast"`` from
    the first-stage cube ``pnp_fast`` starts from on clean data
    (:func:`~tensor_cosdi.solvers.otd.fast_start`, about 2 s of the call at 256×256×28 on 2
    cores), ``"adaptive"`` from ``pnp_fast``'s start on any data (the same, with 10 ADMM
    iterations more where the estimated SNR reads noisy; the shipped
    ``dcosnet_adaptive_sd_cassi.pt`` also reads that SNR), ``"zero"`` from 0 as in the
    thesis (the shipped ``dcosnet_sd_cassi.pt``).  ``device``:
    ``"cpu"``, ``"cuda"``… (default CUDA when available).  ``nonneg`` (on: a
    cube of light) clips the network's output at 0.  Not iterative: the
    history has one entry.
    """
    if not isinstance(nonneg, bool):
        raise ValueError(f"nonneg must be True or False, got {nonneg!r}")
    from ..learn import require_torch

    require_torch()
    from ..learn.dcosnet import DEFAULT_START, STARTS, DCoSNet, read_config

    if not (isinstance(start, str) and start in ("auto", *STARTS)):
        raise ValueError(f"start must be one of {('auto', *STARTS)}, got {start!r}")
    pick = DEFAULT_START if start == "auto" else start
    key = (None if weights is None else str(weights), device, pick)
    if key not in _LOADED:
        if weights is not None and start != "auto":  # read once, with the network
            own = read_config(weights).get("start", "zero")
            if own != start:
                raise ValueError(
                    f"start={start!r}, but {weights} were trained from start {own!r}: pass "
                    f"start='auto' (or {own!r}) with them"
                )
        _LOADED.clear()  # keep one network in memory
        _LOADED[key] = DCoSNet(weights, device=device, start=pick)
    t0 = time.perf_counter()
    cube = _LOADED[key](system, measurement)
    if nonneg:
        cube = tl.clip(cube, 0, None)
    res = relative_residual(system, cube, measurement)
    history = {
        "objective": [0.5 * (res * float(tl.norm(measurement))) ** 2],
        "residual": [res],
        "change": [1.0],
        "seconds": [time.perf_counter() - t0],
    }
    return cube, history, True


register_method(
    "dcosnet",
    dcosnet,
    summary="D-CoSNet: unfolded ADMM with the Woodbury x-step and a U-Net (thesis §7; torch)",
    requires=("torch",),
)
