"""The depth channel of a reconstructed cube, per system (what ``Result.depth`` holds)."""

from __future__ import annotations

__all__ = ["depth_from_cube"]


def depth_from_cube(system, cube, *, n_steps: int = 4, max_disparity: float = 2.0):
    """Depth estimate from a cube of ``system``'s ``cube_shape``, or ``None`` for spectral-only
    systems.

    The system knows its depth channel (``system.depth_from_cube``, kind
    ``system.depth_kind``):

    * CASSDI-DFA (``"planes"``): index of the depth plane holding most of
      each pixel's energy, ``argmax_z Σ_λ F[:, :, λ, z]`` (float).
    * CS2LI, Mu-CoSDI ``"sl"`` (``"phase"``): wrapped fringe phase per
      frequency ``(Nx, Ny, Nt / K)`` of the band sums by the N-step PSA
      (``K = n_steps`` when it divides ``Nt``, else all ``Nt`` patterns as one
      sequence); unwrap and convert to height with :mod:`tensor_cosdi.depth`.
    * C3SLFI (with views), Mu-CoSDI ``"lf"`` (``"disparity"``): disparity (px
      per view step) of the centre view, :func:`disparity_from_views` over all bands.
    * Mu-CoSDI ``"monocular"``: the system's ``depth_estimator`` if it has one.
    """
    return system.depth_from_cube(cube, n_steps=n_steps, max_disparity=max_disparity)
