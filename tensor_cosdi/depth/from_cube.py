"""The depth channel of a reconstructed cube, per system (what ``Result.depth`` holds)."""

from __future__ import annotations

import numpy as np

from .. import _backend as B

__all__ = ["depth_from_cube"]


def depth_from_cube(system, cube, *, n_steps: int = 4, max_disparity: float = 2.0):
    """Depth estimate from a cube of ``system``'s ``cube_shape``, or ``None`` for spectral-only systems.

    * CASSDI-DFA: index of the depth plane holding most of each pixel's
      energy, ``argmax_z Σ_λ F[:, :, λ, z]`` (float).
    * CS2LI, Mu-CoSDI ``"sl"``: wrapped fringe phase per frequency
      ``(Nx, Ny, Nt / K)`` of the band sums by the N-step PSA
      (``K = n_steps`` when it divides ``Nt``, else all ``Nt`` patterns as one
      sequence); unwrap and convert to height with :mod:`tensor_cosdi.depth`.
    * C3SLFI (with views), Mu-CoSDI ``"lf"``: disparity (px per view step)
      of the centre view, :func:`disparity_from_views` over all bands.
    * Mu-CoSDI ``"monocular"``: the system's ``depth_estimator`` if it has one.
    """
    from ..systems import C3SLFI, CASSDIDFA, CS2LI, MuCoSDI
    from .light_field import disparity_from_views
    from .structured_light import wrapped_phase

    x = np.asarray(B.to_numpy(cube), dtype=np.float64)
    if isinstance(system, CASSDIDFA):
        return np.argmax(x.sum(axis=2), axis=2).astype(np.float64)
    if isinstance(system, CS2LI) or (isinstance(system, MuCoSDI) and system.modality == "sl"):
        z = x.sum(axis=2)
        nt = z.shape[2]
        K = n_steps if nt % n_steps == 0 and n_steps >= 3 else nt
        if K < 3:
            return None
        return np.stack([wrapped_phase(z[..., i * K:(i + 1) * K]) for i in range(nt // K)], axis=-1)
    if isinstance(system, C3SLFI):
        if system.layout == "3d" and system.views is None:
            return None
        lf = np.asarray(B.to_numpy(system.to_5d(cube)))  # (N1, N2, N3, N4, N5)
        return disparity_from_views(np.moveaxis(lf, (3, 4), (0, 1)), max_disparity=max_disparity)
    if isinstance(system, MuCoSDI) and system.modality == "lf":
        lf = np.asarray(B.to_numpy(system.to_views(cube)))
        return disparity_from_views(np.moveaxis(lf, (3, 4), (0, 1)), max_disparity=max_disparity)
    if isinstance(system, MuCoSDI) and system.modality == "monocular" and system.depth_estimator is not None:
        return system.estimate_depth(cube)
    return None
