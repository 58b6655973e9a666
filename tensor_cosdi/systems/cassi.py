"""The baselines the thesis compares against: SD-CASSI, DD-CASSI, dual-camera CASSI (SPEC §3.0)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import tensorly as tl

from .. import _backend as B
from ..codes import random_binary
from ..noise import add_noise
from ..operators import Code, Pad, Shear, Stack, SumAxis
from ._base import (
    System,
    as_code,
    coded_shear_sum_matrix,
    count,
    dual_disperser,
    dual_disperser_matrix,
    dual_disperser_operator,
    shifts_for,
    wavelengths_for,
)

__all__ = ["SDCASSI", "DDCASSI", "DualCameraCASSI"]


def _shots(code, colour: bool = False):
    """Split a code into a list of per-shot codes: 2-D ``(Nx, Ny)`` or, colour-coded, 3-D
    ``(Nx, Ny, Nλ)`` (the shots on the last axis)."""
    if code.ndim == 2 + colour:
        return [code]
    return [code[..., k] for k in range(code.shape[-1])]


def _finish_shots(system, ops, wavelengths):
    """One operator per shot → the system's operator; a ``k`` measurement axis for several shots."""
    multi = len(ops) > 1
    system._finish(
        Stack(ops, axis=2) if multi else ops[0],
        wavelengths=wavelengths,
        axes=("x", "y", "λ"),
        measurement_axes=("x", "y", "k") if multi else ("x", "y"),
    )


class SDCASSI(System):
    """Single-disperser CASSI, single- or multi-shot (SPEC §3.0, thesis Equation 43).

    ``G[:, :, k] = Σ_l shear_l(C_k ∘ F[:, :, l])``: the coded cube is sheared
    by ``s_l`` columns per band and integrated on the detector.

    Parameters
    ----------
    code : array_like of shape (Nx, Ny) or (Nx, Ny, K)
        Coded aperture (transmittances ≥ 0: binary, or a measured mask); a
        third axis gives one code per shot.  With ``colour=True``: a
        colour-coded aperture ``(Nx, Ny, Nλ)`` (or ``(Nx, Ny, Nλ, K)``), one
        transmittance per pixel and band
        (:func:`tensor_cosdi.codes.colour_coded_aperture`), ``G = Σ_l
        shear_l(C[:, :, l] ∘ F[:, :, l])``.
    n_bands : int
        ``Nλ``.
    shifts : int, float or sequence
        A step (``s_l = step · l``) or one monotone shift per band
        (fractional values from a calibrated prism use linear interpolation).
    wavelengths : sequence of float, optional
        Band centres in nm (default: ``Nλ`` evenly spaced over 450–650 nm).
    shear_direction : {1, -1}
        ``1``: band ``l`` lands ``s_l`` columns to the right.  ``-1``: a
        mirrored dispersion, the shifts replaced by ``max(s) − s_l`` (the first
        band moves most).  A measurement cannot tell the two apart by itself:
        the mirrored system measures the band-reversed cube exactly as this
        one measures the cube, so the direction comes from the optics (or a
        calibration frame), not from the fit.
    colour : bool
        Whether ``code`` has a band axis (colour-coded CASSI).  ``A Aᵀ`` stays
        diagonal, so every closed-form step holds.

    Attributes
    ----------
    cube_shape : ``(Nx, Ny, Nλ)``, axes ``("x", "y", "λ")``
    measurement_shape : ``(Nx, Ny + S)`` or ``(Nx, Ny + S, K)``, ``S = ⌈max s_l⌉``

    Notes
    -----
    ``A Aᵀ`` is diagonal for integer shifts (one ``K × K`` block per pixel for
    ``K`` shots), so ``solve_normal`` is closed form (SPEC §4).

    Examples
    --------
    >>> import numpy as np
    >>> from tensor_cosdi.systems import SDCASSI
    >>> sd = SDCASSI(np.ones((4, 5)), n_bands=3, shifts=2)
    >>> sd.cube_shape, sd.measurement_shape
    ((4, 5, 3), (4, 9))
    """

    name = "sd_cassi"
    demo_scene = "colorchecker"
    example_options = {"code": None}
    #: Every pixel sums a sheared diagonal of voxels: the SNR estimate's subspace fit leaves
    #: the noise in its residual and follows a random code's texture that GAP-TV misses.
    snr_fit = "subspace"

    def __init__(
        self, code, *, n_bands, shifts=1, wavelengths=None, colour=False, shear_direction=1
    ):
        if isinstance(shear_direction, bool) or shear_direction not in (1, -1):
            raise ValueError(f"shear_direction must be 1 or -1, got {shear_direction!r}")
        if not isinstance(colour, (bool, np.bool_)):
            raise ValueError(f"colour must be True or False, got {colour!r}")
        self.colour = bool(colour)
        self.code = as_code(
            code, "colour-coded aperture" if colour else "code", (3, 4) if colour else (2, 3)
        )
        nl = count(n_bands, "n_bands")
        if colour and self.code.shape[2] != nl:
            raise ValueError(
                f"colour-coded aperture of shape {self.code.shape} has {self.code.shape[2]} bands, "
                f"expected n_bands = {nl} (shape (Nx, Ny, {nl}) or (Nx, Ny, {nl}, K))"
            )
        self.shifts, _ = shifts_for(shifts, nl)
        if shear_direction == -1:
            self.shifts, _ = shifts_for(self.shifts.max() - self.shifts, nl)
        nx, ny = self.code.shape[:2]
        cube = (nx, ny, nl)
        shear = Shear(cube, self.shifts)
        axes = (0, 1, 2) if colour else (0, 1)
        ops = [
            SumAxis(shear.output_shape, 2) @ shear @ Code(c, cube, axes=axes)
            for c in _shots(self.code, self.colour)
        ]
        _finish_shots(self, ops, wavelengths_for(wavelengths, nl))

    def _state(self):
        params, arrays = super()._state()
        if self.colour:  # older states (no key) are plain codes
            params["colour"] = True
        return params, arrays

    @classmethod
    def example(
        cls, cube_shape=None, *, rng=0, shots: int = 1, transmittance: float = 0.5, **overrides
    ):
        """A seeded instance: random binary code(s) for ``cube_shape`` (default ``(16, 16, 8)``).

        ``shots > 1`` gives a multi-shot system; ``overrides`` go to the constructor.
        """
        nx, ny, nl = (16, 16, 8) if cube_shape is None else cube_shape
        shape = (nx, ny) if shots == 1 else (nx, ny, count(shots, "shots"))
        code = random_binary(shape, transmittance=transmittance, rng=rng)
        return cls(code, n_bands=nl, **overrides)

    def with_code(self, code) -> "SDCASSI":
        """The same imager (shifts, wavelengths, colour) with another code of the same shape."""
        code = np.asarray(code)
        if code.shape != self.code.shape:
            raise ValueError(f"code of shape {code.shape}; this imager's is {self.code.shape}")
        return self._with_any_code(code)

    def _with_any_code(self, code) -> "SDCASSI":
        return SDCASSI(
            code, n_bands=self.cube_shape[2], shifts=self.shifts, wavelengths=self.wavelengths,
            colour=self.colour,
        )  # fmt: skip

    def mirrored(self) -> "SDCASSI":
        """The same imager with its dispersion mirrored: shifts ``s_l`` → ``max(s) − s_l`` (the
        band that moved least moves most), same code, wavelengths and colour.

        >>> import numpy as np
        >>> SDCASSI(np.ones((4, 5)), n_bands=3, shifts=[0, 1, 3]).mirrored().shifts.tolist()
        [3, 2, 0]
        """
        return SDCASSI(
            self.code, n_bands=self.cube_shape[2], shifts=self.shifts.max() - self.shifts,
            wavelengths=self.wavelengths, colour=self.colour,
        )  # fmt: skip

    @property
    def shear_direction(self) -> int:
        """``-1`` when the first band is shifted most (a mirrored dispersion), else ``1``."""
        return -1 if self.shifts[0] > self.shifts[-1] else 1

    @property
    def window_spill(self) -> int:
        """Measurement columns a cube window spills over on each side (the total shear ``S``)."""
        return self.measurement_shape[1] - self.cube_shape[1]

    def window(self, x0: int, x1: int, y0: int, y1: int):
        """The same imager on the cube window ``[x0, x1) × [y0, y1)`` and the measurement
        columns ``(m0, m1)`` it lands on (``[y0, y1 + S)``; the first and last ``S`` of them
        also hold light from outside the window)."""
        return self._with_any_code(self.code[x0:x1, y0:y1]), (y0, y1 + self.window_spill)

    def matrix(self):
        nx, ny, nl = self.cube_shape
        width = self.measurement_shape[1]
        blocks = [
            coded_shear_sum_matrix(
                c if self.colour else np.repeat(c[:, :, None], nl, axis=2), self.shifts, width
            )
            for c in _shots(self.code, self.colour)
        ]
        return sp.vstack(blocks, format="csr")  # shot k occupies rows Nx·W·k …


class DDCASSI(System):
    """Dual-disperser CASSI (SPEC §3.0): the code is seen sheared, the image is not.

    ``G = Σ_l C[:, s_l : s_l + Ny] ∘ F[:, :, l]``: a spatially aligned
    ``(Nx, Ny)`` measurement (a third code axis gives ``K`` shots).

    Parameters
    ----------
    code : array_like of shape (Nx, Ny + S) or (Nx, Ny + S, K)
        ``S = ⌈max s_l⌉`` extra columns, so that every band reads a full
        ``Ny``-column window of the code.
    n_bands, shifts, wavelengths
        As for :class:`SDCASSI`.

    Notes
    -----
    ``A Aᵀ = diag(Σ_l Ceff_l²)`` (one ``K × K`` block per pixel with shots).

    Examples
    --------
    >>> import numpy as np
    >>> from tensor_cosdi.systems import DDCASSI
    >>> DDCASSI(np.ones((4, 7)), n_bands=3, shifts=1).cube_shape
    (4, 5, 3)
    """

    name = "dd_cassi"

    def __init__(self, code, *, n_bands, shifts=1, wavelengths=None):
        self.code = as_code(code, "code", (2, 3))
        nl = count(n_bands, "n_bands")
        self.effective_codes = []
        for c in _shots(self.code):
            self.shifts, ceff = dual_disperser(c, nl, shifts)
            self.effective_codes.append(ceff)
        cube = self.effective_codes[0].shape
        ops = [dual_disperser_operator(ce, cube) for ce in self.effective_codes]
        _finish_shots(self, ops, wavelengths_for(wavelengths, nl))

    @classmethod
    def example(
        cls, cube_shape=None, *, rng=0, shots: int = 1, transmittance: float = 0.5, **overrides
    ):
        """A seeded instance for ``cube_shape`` (default ``(16, 16, 8)``)."""
        nx, ny, nl = (16, 16, 8) if cube_shape is None else cube_shape
        _, extra = shifts_for(overrides.get("shifts", 1), nl)
        shape = (nx, ny + extra) + (() if shots == 1 else (count(shots, "shots"),))
        return cls(
            random_binary(shape, transmittance=transmittance, rng=rng), n_bands=nl, **overrides
        )

    #: A cube window's measurement is exactly the same window (the image is not sheared).
    window_spill = 0

    def window(self, x0: int, x1: int, y0: int, y1: int):
        """The same imager on the cube window ``[x0, x1) × [y0, y1)`` (the code window with
        its ``S`` extra columns) and the measurement columns ``(y0, y1)`` it lands on."""
        extra = self.code.shape[1] - self.cube_shape[1]
        sub = DDCASSI(
            self.code[x0:x1, y0 : y1 + extra], n_bands=self.cube_shape[2], shifts=self.shifts,
            wavelengths=self.wavelengths,
        )  # fmt: skip
        return sub, (y0, y1)

    def matrix(self):
        ny = self.cube_shape[1]
        return sp.vstack(
            [dual_disperser_matrix(c, self.shifts, ny, 1) for c in _shots(self.code)], format="csr"
        )


class DualCameraCASSI(System):
    """SD-CASSI plus a separate panchromatic camera (side information, thesis Chapter 3).

    Two frames in one tensor of shape ``(Nx, Ny + S, 2)`` (axes ``x, y,
    camera``): ``G[:, :, 0]`` is the SD-CASSI frame, ``G[:, :Ny, 1] = Σ_l
    F[:, :, l]`` the panchromatic image (columns ``Ny:`` of frame 1 are always
    zero).  The thesis compares against a *noise-free* panchromatic image,
    so :meth:`simulate` adds noise to frame 0 only unless ``pan_snr_db`` is
    given.

    Parameters
    ----------
    code : array_like of shape (Nx, Ny)
    n_bands, shifts, wavelengths
        As for :class:`SDCASSI`.

    Notes
    -----
    ``A Aᵀ`` couples every panchromatic pixel with the ``Nλ`` CASSI pixels its
    bands land on: banded along the columns once the two frames are folded
    into them (:class:`~tensor_cosdi.operators.woodbury.FoldedBanded`), so
    ``solve_normal`` is a banded Cholesky per detector row.

    Examples
    --------
    >>> import numpy as np
    >>> from tensor_cosdi.systems import DualCameraCASSI
    >>> DualCameraCASSI(np.ones((4, 5)), n_bands=3).measurement_shape
    (4, 7, 2)
    """

    name = "dual_camera_cassi"
    example_options = {"code": None}
    #: Two cameras: the CASSI frame's noise is set against its own signal (:meth:`simulate`), and
    #: the brighter panchromatic frame must not make it read cleaner.
    snr_frame_groups = ((0,), (1,))

    @property
    def frame_count(self) -> int:
        return 2

    def frames_to_measurement(self, frames):
        """The CASSI frame ``(Nx, Ny + S)`` and the panchromatic one zero-padded to it → ``(Nx, Ny +
        S, 2)``.

        Use :func:`tensor_cosdi.io.dual_camera_frames` to pad an ``(Nx, Ny)`` panchromatic frame.
        """
        from ._roles import stack_frames

        a = stack_frames(frames)
        if a.shape[2] != 2:
            raise ValueError(f"DualCameraCASSI takes 2 frame(s) per measurement, got {a.shape[2]}")
        nx, w = self.measurement_shape[:2]
        ny = self.cube_shape[1]
        if a.shape[:2] != (nx, w):
            raise ValueError(
                f"DualCameraCASSI frames must be {nx}×{w} (CASSI) and {nx}×{ny} (panchromatic, "
                f"give it zero-padded to {nx}×{w} or use dual_camera_frames); got {a.shape[:2]}"
            )
        if np.any(a[:, ny:, 1] != 0):
            raise ValueError(
                f"the panchromatic frame has non-zero columns beyond {ny}: not a {nx}×{ny} image"
            )
        return a.copy()

    def __init__(self, code, *, n_bands, shifts=1, wavelengths=None):
        self.code = as_code(code, "code", (2,))
        nl = count(n_bands, "n_bands")
        self.shifts, extra = shifts_for(shifts, nl)
        nx, ny = self.code.shape
        cube = (nx, ny, nl)
        shear = Shear(cube, self.shifts)
        cassi = SumAxis(shear.output_shape, 2) @ shear @ Code(self.code, cube)
        pan = Pad((nx, ny), axis=1, before=0, after=extra) @ SumAxis(cube, 2)
        self._finish(
            Stack([cassi, pan], axis=2),
            wavelengths=wavelengths_for(wavelengths, nl),
            axes=("x", "y", "λ"),
            measurement_axes=("x", "y", "camera"),
        )

    @classmethod
    def example(cls, cube_shape=None, *, rng=0, transmittance: float = 0.5, **overrides):
        """A seeded instance for ``cube_shape`` (default ``(16, 16, 8)``)."""
        nx, ny, nl = (16, 16, 8) if cube_shape is None else cube_shape
        return cls(
            random_binary((nx, ny), transmittance=transmittance, rng=rng), n_bands=nl, **overrides
        )

    def simulate(
        self, cube, snr_db: float | None = None, rng=None, *, pan_snr_db: float | None = None
    ):
        """Both frames; noise at ``snr_db`` on the CASSI frame, at ``pan_snr_db`` (default none) on
        the panchromatic one."""
        g = self.forward(cube)
        rng = B.default_rng(rng)
        ny = self.cube_shape[1]
        cassi = add_noise(g[:, :, 0], snr_db, rng=rng)
        pan = add_noise(g[:, :ny, 1], pan_snr_db, rng=rng)
        pad = g[:, ny:, 1]  # zeros
        return tl.stack([cassi, tl.concatenate([pan, pad], axis=1)], axis=2)

    @property
    def panchromatic_exact(self) -> bool:
        return True

    def panchromatic(self, measurement, *, mu=None):
        """The panchromatic camera's frame, ``G[:, :Ny, 1]`` (exact: no solve, ``mu`` unused)."""
        g = self.check_measurement(measurement, "panchromatic")
        return g[:, : self.cube_shape[1], 1]

    def matrix(self):
        nx, ny, nl = self.cube_shape
        width = self.measurement_shape[1]
        top = coded_shear_sum_matrix(
            np.repeat(self.code[:, :, None], nl, axis=2), self.shifts, width
        )
        # panchromatic: row Nx·W + u for every band of pixel u (B = 1ᵀ ⊗ I)
        u = np.tile(np.arange(nx * ny), nl)
        cols = np.arange(nx * ny * nl)
        bottom = sp.csr_matrix((np.ones(cols.size), (u, cols)), shape=(nx * width, nx * ny * nl))
        return sp.vstack([top, bottom], format="csr")
