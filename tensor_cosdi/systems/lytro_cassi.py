"""Lytro-CASSI: the dual-arm spectral light-field baseline of thesis Section 5.3 (Table 1).

Xiong et al. ("Snapshot hyperspectral light field imaging", CVPR 2017) split
the light of a scene between a plenoptic RGB camera (a Lytro) and a CASSI.
The thesis simulates it as a multi-shot system on the lenslet image of the
spectral light field: the Lytro arm records an RGB image of every view, the
CASSI arm ``K`` coded, dispersed snapshots of the same field of view through
a time-varying binary code of 50 % transmittance; the reconstruction
(:func:`tensor_cosdi.solvers.lytro.lytro_cassi`) learns a 2-D patch
dictionary from the RGB arm and uses a DCT across the bands.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import tensorly as tl

from .. import _backend as B
from ..codes import random_binary
from ..noise import add_noise
from ..operators import Code, Pad, Shear, Stack, SumAxis
from ..validate import real_array
from ._base import (
    System,
    as_code,
    coded_shear_sum_matrix,
    count,
    shifts_for,
    wavelengths_for,
)
from .cassi import _shots

__all__ = ["LytroCASSI", "camera_response"]

#: colour-science's measured camera sensitivities used by default (a DSLR: Lytro publishes none).
DEFAULT_CAMERA = "Nikon 5100 (NPL)"


def camera_response(wavelengths, camera: str = DEFAULT_CAMERA) -> np.ndarray:
    """An RGB camera's spectral sensitivities at ``wavelengths``, shape ``(Nλ, 3)``.

    Sampled from ``colour.MSDS_CAMERA_SENSITIVITIES[camera]`` (measured by the
    NPL) and scaled so that a flat unit reflectance gives 1 in the brightest
    channel.

    Examples
    --------
    >>> r = camera_response([450.0, 550.0, 650.0])
    >>> r.shape, round(float(r.sum(axis=0).max()), 6)
    ((3, 3), 1.0)
    """
    from ..colour import colour_science

    colour = colour_science()
    if camera not in colour.MSDS_CAMERA_SENSITIVITIES:
        raise ValueError(
            f"unknown camera {camera!r}; colour-science has "
            f"{sorted(colour.MSDS_CAMERA_SENSITIVITIES)}"
        )
    sens = colour.MSDS_CAMERA_SENSITIVITIES[camera]
    wl = real_array("wavelengths", wavelengths, finite=False).reshape(-1)
    lo, hi = float(sens.wavelengths[0]), float(sens.wavelengths[-1])
    if wl.size == 0 or not np.isfinite(wl).all() or wl.min() < lo or wl.max() > hi:
        raise ValueError(
            f"the {camera} sensitivities cover {lo:g}–{hi:g} nm; got wavelengths {wl.tolist()}"
        )
    r = np.stack([np.interp(wl, sens.wavelengths, sens.values[:, c]) for c in range(3)], axis=1)
    return r / r.sum(axis=0).max()


class LytroCASSI(System):
    """A plenoptic RGB arm plus a ``K``-shot SD-CASSI arm on one lenslet cube (thesis Section 5.3).

    ``gap_eps`` is 0.1: with ``A Aᵀ``'s κ ≈ 10⁸, accelerated GAP-TV (chelsea,
    32×32×8, the default problem) reached −7.5 dB at ε = 1e-6, 0.6 at 1e-4,
    16.9 at 1e-3, 23.6 at 1e-2 and 28.7 dB at 0.1 (least squares 23.2).

    ``G[:, :, k] = Σ_l shear_l(C_k ∘ F[:, :, l])`` for the CASSI shots
    ``k < K`` and ``G[:, :Ny, K + c] = Σ_l R[l, c] F[:, :, l]`` for the red,
    green and blue channels ``c`` of the Lytro arm (columns ``Ny:`` of those
    frames are always zero).

    Parameters
    ----------
    code : array_like of shape (Nx, Ny) or (Nx, Ny, K)
        The CASSI arm's code per shot (the thesis: random binary, 50 % open).
    n_bands, shifts, wavelengths
        As for :class:`~tensor_cosdi.systems.SDCASSI`.
    response : array_like of shape (Nλ, 3), optional
        The Lytro arm's RGB sensitivities per band (default:
        :func:`camera_response` of a measured DSLR at ``wavelengths``).
    views : (N4, N5), optional
        Views per lenslet of an interleaved lenslet cube; then
        :meth:`spectral_view` is the centre view.

    Notes
    -----
    The thesis counts the compression of this baseline by its ``K`` CASSI
    snapshots, as for C3SLFI; the RGB arm's three frames come on top.  Each
    arm is a camera of its own, so :meth:`simulate` adds noise at the given
    SNR to each arm separately.  ``A Aᵀ`` couples every RGB pixel with the
    CASSI pixels its bands land on: banded along the columns once the frames
    are folded into them (:class:`~tensor_cosdi.operators.woodbury.FoldedBanded`),
    a banded Cholesky per detector row.  It is ill-conditioned (κ ≈ 10⁸
    at 32 × 32 × 8): a CASSI column that sees one voxel repeats part of an
    RGB pixel.  GAP's ``(AAᵀ + εI)⁻¹`` with a small ``ε`` then amplifies
    noise; ``method="lytro"`` uses ADMM.

    Examples
    --------
    >>> import numpy as np
    >>> from tensor_cosdi.systems import LytroCASSI
    >>> LytroCASSI(np.ones((4, 6, 2)), n_bands=3).measurement_shape
    (4, 8, 5)
    """

    name = "lytro_cassi"
    example_options = {"views": (4, 4), "n_snapshots": 2, "max_disparity": 1.0}
    gap_eps = 0.1

    def __init__(self, code, *, n_bands, shifts=1, wavelengths=None, response=None, views=None):
        from .c3slfi import _views

        self.code = as_code(code, "code", (2, 3))
        nl = count(n_bands, "n_bands")
        self.shifts, extra = shifts_for(shifts, nl)
        wl = wavelengths_for(wavelengths, nl)
        if response is None:
            response = camera_response(wl)
        self.response = as_code(response, "response", (2,))
        if self.response.shape != (nl, 3):
            raise ValueError(
                f"response must be (Nλ, 3) = ({nl}, 3) RGB sensitivities per band, got "
                f"{self.response.shape}"
            )
        self.views = _views(views)
        nx, ny = self.code.shape[:2]
        if self.views is not None and (nx % self.views[0] or ny % self.views[1]):
            raise ValueError(f"a {nx}×{ny} lenslet image cannot hold views {self.views}")
        cube = (nx, ny, nl)
        shear = Shear(cube, self.shifts)
        cassi = [SumAxis(shear.output_shape, 2) @ shear @ Code(c, cube) for c in _shots(self.code)]
        pad = Pad((nx, ny), axis=1, before=0, after=extra)
        rgb = [
            pad @ SumAxis(cube, 2) @ Code(self.response[:, c], cube, axes=(2,)) for c in range(3)
        ]
        self._finish(
            Stack(cassi + rgb, axis=2), wavelengths=wl, axes=("x", "y", "λ"),
            measurement_axes=("x", "y", "frame"),
        )  # fmt: skip

    @property
    def n_snapshots(self) -> int:
        """``K``, the CASSI arm's snapshots."""
        return 1 if self.code.ndim == 2 else self.code.shape[2]

    @property
    def snr_frame_groups(self) -> tuple[tuple[int, ...], ...]:
        """The two arms, each a camera with noise against its own signal (:meth:`simulate`):
        the ``K`` CASSI frames, then the three RGB frames."""
        k = self.n_snapshots
        return (tuple(range(k)), (k, k + 1, k + 2))

    def _state(self):
        params = {"n_bands": int(self.n_bands)}
        if self.views is not None:
            params["views"] = list(self.views)
        arrays = {"code": self.code, "shifts": self.shifts, "response": self.response}
        return params, {k: np.asarray(v) for k, v in arrays.items()}

    @classmethod
    def _from_state(cls, params, arrays):
        return cls(
            arrays["code"], shifts=arrays["shifts"], wavelengths=arrays["wavelengths"],
            response=arrays["response"], **params,
        )  # fmt: skip

    @classmethod
    def example(
        cls, cube_shape=None, *, rng=0, n_snapshots: int = 2, transmittance: float = 0.5,
        **overrides,
    ):  # fmt: skip
        """A seeded instance: ``n_snapshots`` random binary codes (50 % open) for ``cube_shape``
        (default ``(16, 16, 8)``)."""
        nx, ny, nl = (16, 16, 8) if cube_shape is None else cube_shape
        k = count(n_snapshots, "n_snapshots")
        code = random_binary((nx, ny, k), transmittance=transmittance, rng=rng)
        return cls(code, n_bands=nl, **overrides)

    @classmethod
    def _example(cls, scene, shape, wl, seed, shifts, views, n_snapshots, max_disparity):
        """The lenslet image of the same spectral light field C3SLFI's examples image."""
        from .c3slfi import C3SLFI

        _, cube, centre, disparity, _ = C3SLFI._example(
            scene, shape, wl, seed, 1, views, 2, max_disparity
        )
        system = cls.example(
            shape + (len(wl),), rng=seed, n_snapshots=n_snapshots, shifts=shifts,
            wavelengths=wl, views=views,
        )  # fmt: skip
        return system, cube, centre, None, {"disparity": disparity}

    # ---- the two arms ----------------------------------------------------------------
    def simulate(self, cube, snr_db: float | None = None, rng=None):
        """All frames; each arm gets white Gaussian noise at ``snr_db`` of its own signal."""
        g = self.forward(cube)
        rng = B.default_rng(rng)
        k, ny = self.n_snapshots, self.cube_shape[1]
        cassi = add_noise(g[:, :, :k], snr_db, rng=rng)
        rgb = add_noise(g[:, :ny, k:], snr_db, rng=rng)
        rgb = tl.concatenate([rgb, g[:, ny:, k:]], axis=1)  # the padding stays zero
        return tl.concatenate([cassi, rgb], axis=2)

    def rgb_image(self, measurement) -> np.ndarray:
        """The Lytro arm's ``(Nx, Ny, 3)`` RGB lenslet image out of a measurement."""
        g = self.check_measurement(measurement, "rgb_image")
        return np.asarray(B.to_numpy(g[:, : self.cube_shape[1], self.n_snapshots :]))

    def frames_to_measurement(self, frames):
        """``K`` CASSI frames ``(Nx, Ny + S)`` then R, G, B frames zero-padded to the same width."""
        a = super().frames_to_measurement(frames)
        ny = self.cube_shape[1]
        if np.any(a[:, ny:, self.n_snapshots :] != 0):
            raise ValueError(
                f"the RGB frames have non-zero columns beyond {ny}: pad each {a.shape[0]}×{ny} "
                "channel with zeros to the CASSI width"
            )
        return a

    def spectral_view(self, cube) -> np.ndarray:
        """The centre view of the lenslet cube (the whole cube without ``views``)."""
        c = real_array("cube", B.to_numpy(cube), finite=False)
        if self.views is None:
            return c
        n4, n5 = self.views
        return c[n4 // 2 :: n4, n5 // 2 :: n5]

    def matrix(self):
        nx, ny, nl = self.cube_shape
        width = self.measurement_shape[1]
        blocks = [
            coded_shear_sum_matrix(np.repeat(c[:, :, None], nl, axis=2), self.shifts, width)
            for c in _shots(self.code)
        ]
        u = np.tile(np.arange(nx * ny), nl)  # pixel of every voxel (band-major columns)
        cols = np.arange(nx * ny * nl)
        for c in range(3):
            w = np.repeat(self.response[:, c], nx * ny)
            blocks.append(sp.csr_matrix((w, (u, cols)), shape=(nx * width, nx * ny * nl)))
        return sp.vstack(blocks, format="csr")
