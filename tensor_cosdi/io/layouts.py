"""Sensor frames ↔ measurement tensors, per system (the documented frame order of a capture).

* SD-CASSI / DD-CASSI, one shot: 1 frame → ``(Nx, Ny + S)`` / ``(Nx, Ny)``;
  ``K`` shots: ``K`` frames in shot order → ``(…, K)``.
* Dual-camera CASSI: 2 frames, the CASSI frame then the ``(Nx, Ny)``
  panchromatic one → ``(Nx, Ny + S, 2)``, the panchromatic frame zero-padded
  on the right.
* CASSI-VSI, CASSDI-DFA: 1 frame → ``(Nx, Ny + S)``.
* Mu-CoSDI ``"lf"`` / ``"monocular"``: 1 frame → ``(H, W)``.
* CS2LI, Mu-CoSDI ``"sl"``: ``Nt`` frames in pattern order (frequency-major,
  as :func:`~tensor_cosdi.systems.fringe_cube`) → ``(Nx, Ny, Nt)``.
* C3SLFI: ``K`` raw lenslet frames (snapshot order) in the system's
  ``raw_layout`` → 3-D ``(Ñ1, Ñ2, K)``; 5-D ``(N1, N2, K, N4, N5)`` (views cut
  by the lenslet layout, Eq. 78/85).

Each system implements its own order (``frames_to_measurement`` /
``measurement_to_frames`` / ``frame_count`` of
:class:`~tensor_cosdi.systems.System`); these functions call it.
Both directions are exact (pure reshapes/permutations), so frames →
measurement → frames is the identity.
"""

from __future__ import annotations

import numpy as np

from ..validate import imager, real_array

__all__ = ["frames_to_measurement", "measurement_to_frames", "frame_count", "dual_camera_frames"]


def frame_count(system) -> int:
    """How many sensor frames one measurement of ``system`` takes (``system.frame_count``)."""
    return imager(system, "frame_count").frame_count


def frames_to_measurement(system, frames):
    """Stack of sensor frames → ``system``'s measurement tensor (NumPy), per the table above.

    ``system.frames_to_measurement``; raises ``ValueError`` naming the
    expected frame count and shape when they do not match.
    """
    return imager(system, "frame_count").frames_to_measurement(frames)


def measurement_to_frames(system, measurement) -> np.ndarray:
    """``system``'s measurement → the ``(H, W, N)`` stack of sensor frames (the inverse of
    :func:`frames_to_measurement`)."""
    return imager(system, "frame_count").measurement_to_frames(measurement)


def dual_camera_frames(cassi_frame, pan_frame) -> np.ndarray:
    """The two frames of a dual-camera CASSI as one ``(Nx, Ny + S, 2)`` stack (pan zero-padded)."""
    c = real_array("cassi_frame", cassi_frame)
    p = real_array("pan_frame", pan_frame)
    if c.ndim != 2 or p.ndim != 2 or p.shape[0] != c.shape[0] or p.shape[1] > c.shape[1]:
        raise ValueError(
            f"need a CASSI frame (Nx, Ny + S) and a panchromatic frame (Nx, Ny); got {c.shape}, "
            f"{p.shape}"
        )
    out = np.zeros(c.shape + (2,))
    out[..., 0] = c
    out[:, : p.shape[1], 1] = p
    return out
