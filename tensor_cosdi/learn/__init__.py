"""Learned priors (optional: ``pip install "tensor_cosdi[torch]"``).

* :mod:`~tensor_cosdi.learn.spectral_net` — a band-count-agnostic spectral
  denoiser (a small CNN on the eigen-images of the cube's spectral subspace)
  for plug-and-play reconstruction with every system; registered as the
  denoiser ``"spectral_net"`` and used by the method ``"pnp_gap"``.
* :mod:`~tensor_cosdi.learn.train` — its training on the tuning scenes
  (``tensor-cosdi train-denoiser``: progress bar, checkpoints, resume, CPU or
  CUDA).
* :mod:`~tensor_cosdi.learn.dcosnet` — D-CoSNet (thesis §7): unfolded ADMM
  whose sensing layers are the system's own operator, trained per system
  (``tensor-cosdi train-dcosnet``) and used by the method ``"dcosnet"``.

Importing this package does not import torch; the functions that need it
raise an ``ImportError`` naming the extra to install.
"""

from __future__ import annotations

__all__ = ["require_torch", "torch_device", "load_weights"]


def require_torch():
    """The ``torch`` module, or an ``ImportError`` saying how to install it."""
    try:
        import torch
    except ImportError:
        raise ImportError(
            "this feature needs PyTorch: pip install 'tensor_cosdi[torch]' (or pip install torch)"
        ) from None
    return torch


def torch_device(torch, device):
    """``device`` (``None``: CUDA when available, else the CPU) as a ``torch.device`` this
    PyTorch can run on, or a one-line ``ValueError`` naming what it has: ``"cpu"``, ``"cuda"``
    or ``"cuda:N"`` (a string or a ``torch.device``).

    >>> import torch
    >>> torch_device(torch, "cpu")
    device(type='cpu')
    >>> torch_device(torch, "tpu")
    Traceback (most recent call last):
    ...
    ValueError: device must be a PyTorch device such as 'cpu' or 'cuda', got 'tpu'
    """
    if device is None:
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    if not isinstance(device, (str, torch.device)):
        raise ValueError(f"device must be a PyTorch device such as 'cpu' or 'cuda', got {device!r}")
    try:
        dev = torch.device(device)
    except (RuntimeError, TypeError, ValueError):
        raise ValueError(
            f"device must be a PyTorch device such as 'cpu' or 'cuda', got {device!r}"
        ) from None
    if dev.type == "cuda":
        if not torch.cuda.is_available():
            raise ValueError(
                f"device {device!r}: this PyTorch ({torch.__version__}) sees no CUDA GPU; use "
                "--device cpu"
            )
        if dev.index is not None and dev.index >= torch.cuda.device_count():
            raise ValueError(
                f"device {device!r}: only {torch.cuda.device_count()} CUDA device(s) here"
            )
    elif dev.type != "cpu":
        raise ValueError(f"device must be 'cpu' or 'cuda' (or 'cuda:N'), got {device!r}")
    return dev


def _exception_text(exc: BaseException) -> str:
    """``"Kind: first line"`` (100 characters at most) of a loader's exception, for a one-line
    message; ``"Kind"`` alone when it says nothing."""
    first = (str(exc).splitlines() or [""])[0][:100]
    return f"{type(exc).__name__}: {first}" if first else type(exc).__name__


def load_weights(path, kind: str, command: str) -> dict:
    """A weights file read with ``torch.load(weights_only=True)`` (no code in a pickle can run).

    Parameters
    ----------
    path : path
    kind : str
        What the file should hold, for the message (``"D-CoSNet"``, …).
    command : str
        The ``tensor-cosdi`` command that writes such files, for the message.

    Returns
    -------
    dict
        The checkpoint, with at least ``config`` and ``model``.

    Raises
    ------
    FileNotFoundError
        No such file.
    ValueError
        An empty, truncated or foreign file (one line naming ``kind`` and
        ``command``), or one whose parameters hold NaN or inf.
    """
    from pathlib import Path

    torch = require_torch()
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{kind} weights not found: {path}")
    try:
        ckpt = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as exc:  # EOFError, a zip reader's RuntimeError, UnpicklingError, …
        raise ValueError(
            f"{path} is not a {kind} checkpoint of tensor-cosdi {command} ({_exception_text(exc)})"
        ) from None
    if not isinstance(ckpt, dict) or "config" not in ckpt or "model" not in ckpt:
        raise ValueError(
            f"{path} is not a {kind} checkpoint of tensor-cosdi {command} (no config and model)"
        )
    if not isinstance(ckpt["model"], dict):
        raise ValueError(
            f"{path} is not a {kind} checkpoint of tensor-cosdi {command} (its model is a "
            f"{type(ckpt['model']).__name__}, not a dict of parameters)"
        )
    for name, value in ckpt["model"].items():  # a diverged training's file runs, into NaN
        if isinstance(value, torch.Tensor) and value.is_floating_point():
            if not bool(torch.isfinite(value).all()):
                raise ValueError(
                    f"{path}: {kind} parameter {name!r} holds NaN or inf; expected the finite "
                    f"weights of a finished tensor-cosdi {command}"
                )
    return ckpt
