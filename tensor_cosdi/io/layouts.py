"""Sensor frames ↔ measurement tensors, per system (the documented frame order of a capture).

=====================================  =========================  ==========================================
system                                 frames (each ``(H, W)``)   measurement
=====================================  =========================  ==========================================
SDCASSI / DDCASSI, one shot            1                          ``(Nx, Ny + S)`` / ``(Nx, Ny)``
SDCASSI / DDCASSI, ``K`` shots         ``K``, shot order          ``(…, K)``
DualCameraCASSI                        2: CASSI frame, then the   ``(Nx, Ny + S, 2)``, the panchromatic
                                       ``(Nx, Ny)`` panchromatic  frame zero-padded on the right
CASSIVSI, CASSDIDFA                    1                          ``(Nx, Ny + S)``
Mu-CoSDI ``"lf"`` / ``"monocular"``    1                          ``(H, W)``
CS2LI, Mu-CoSDI ``"sl"``               ``Nt``, pattern order      ``(Nx, Ny, Nt)`` (frequency-major, as
                                       (frequency-major)          :func:`~tensor_cosdi.systems.fringe_cube`)
C3SLFI                                 ``K`` raw lenslet frames   3-D: ``(Ñ1, Ñ2, K)``; 5-D:
                                       (snapshot order) in the    ``(N1, N2, K, N4, N5)`` (views cut by the
                                       system's ``raw_layout``    lenslet layout, Eq. 78/85)
=====================================  =========================  ==========================================

Both directions are exact (pure reshapes/permutations), so frames →
measurement → frames is the identity.
"""

from __future__ import annotations

import numpy as np

from .. import _backend as B

__all__ = ["frames_to_measurement", "measurement_to_frames", "frame_count", "dual_camera_frames"]


def _stack(frames) -> np.ndarray:
    if isinstance(frames, (list, tuple)):
        if not frames:
            raise ValueError("no frames given")
        shapes = {np.shape(f) for f in frames}
        if len(shapes) != 1:
            raise ValueError(f"frames of different shapes: {sorted(shapes)}")
        a = np.stack([np.asarray(f, dtype=np.float64) for f in frames], axis=-1)
    else:
        a = np.asarray(B.to_numpy(frames), dtype=np.float64)
        if a.ndim == 2:
            a = a[..., None]
    if a.ndim != 3:
        raise ValueError(f"frames must be a (H, W, N) stack or a list of 2-D frames, got shape {a.shape}")
    return a


def frame_count(system) -> int:
    """How many sensor frames one measurement of ``system`` takes."""
    from ..systems import C3SLFI, DualCameraCASSI

    shape = system.measurement_shape
    if isinstance(system, DualCameraCASSI):
        return 2
    if isinstance(system, C3SLFI):
        return system.n_snapshots
    return shape[2] if len(shape) == 3 else 1


def frames_to_measurement(system, frames):
    """Stack of sensor frames → ``system``'s measurement tensor (NumPy), per the table above.

    Raises ``ValueError`` naming the expected frame count and shape when
    they do not match.
    """
    from ..systems import C3SLFI, DualCameraCASSI

    a = _stack(frames)
    n = frame_count(system)
    if a.shape[2] != n:
        raise ValueError(f"{type(system).__name__} takes {n} frame(s) per measurement, got {a.shape[2]}")
    shape = tuple(system.measurement_shape)
    if isinstance(system, DualCameraCASSI):
        nx, w = shape[:2]
        ny = system.cube_shape[1]
        if a.shape[:2] == (nx, w):  # panchromatic frame already padded
            g = a.copy()
        else:
            raise ValueError(f"DualCameraCASSI frames must be {nx}×{w} (CASSI) and {nx}×{ny} (panchromatic, "
                             f"give it zero-padded to {nx}×{w} or use dual_camera_frames); got {a.shape[:2]}")
        if np.any(g[:, ny:, 1] != 0):
            raise ValueError(f"the panchromatic frame has non-zero columns beyond {ny}: not a {nx}×{ny} image")
        return g
    if isinstance(system, C3SLFI):
        if system.layout == "3d":
            if a.shape != shape:
                raise ValueError(f"C3SLFI frames: expected {shape[2]} frames of {shape[:2]}, got {a.shape}")
            return a
        g3_shape = (shape[0] * shape[3], shape[1] * shape[4], shape[2])
        if a.shape != g3_shape:
            raise ValueError(f"C3SLFI frames: expected {g3_shape[2]} lenslet frames of {g3_shape[:2]}, got {a.shape}")
        return np.asarray(system._layout(system.n_snapshots).adjoint(a))
    target = shape if len(shape) == 3 else shape + (1,)
    if a.shape != target:
        raise ValueError(f"{type(system).__name__}: expected {target[2]} frame(s) of {target[:2]}, got {a.shape}")
    return a if len(shape) == 3 else a[..., 0]


def measurement_to_frames(system, measurement) -> np.ndarray:
    """``system``'s measurement → the ``(H, W, N)`` stack of sensor frames (the inverse of :func:`frames_to_measurement`)."""
    from ..systems import C3SLFI

    g = np.asarray(B.to_numpy(measurement), dtype=np.float64)
    if g.shape != tuple(system.measurement_shape):
        raise ValueError(f"measurement shape {g.shape} does not match the system's {tuple(system.measurement_shape)}")
    if isinstance(system, C3SLFI) and system.layout == "5d":
        return np.asarray(system.measurement_to_3d(g))
    return g if g.ndim == 3 else g[..., None]


def dual_camera_frames(cassi_frame, pan_frame) -> np.ndarray:
    """The two frames of a dual-camera CASSI as one ``(Nx, Ny + S, 2)`` stack (pan zero-padded)."""
    c = np.asarray(cassi_frame, dtype=np.float64)
    p = np.asarray(pan_frame, dtype=np.float64)
    if c.ndim != 2 or p.ndim != 2 or p.shape[0] != c.shape[0] or p.shape[1] > c.shape[1]:
        raise ValueError(f"need a CASSI frame (Nx, Ny + S) and a panchromatic frame (Nx, Ny); got {c.shape}, {p.shape}")
    out = np.zeros(c.shape + (2,))
    out[..., 0] = c
    out[:, : p.shape[1], 1] = p
    return out

