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

__all__ = ["require_torch"]


def require_torch():
    """The ``torch`` module, or an ``ImportError`` saying how to install it."""
    try:
        import torch
    except ImportError:
        raise ImportError(
            "this feature needs PyTorch: pip install 'tensor_cosdi[torch]' (or pip install torch)"
        ) from None
    return torch
