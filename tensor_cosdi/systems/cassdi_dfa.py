"""CASSDI-DFA: compressive spectral-depth imaging from aberrations (SPEC §3.2, thesis Ch. 4)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .. import _backend as B
from ..codes import depth_codes
from ..operators import Blur, BlurSum, Code, Shear, SumAxis
from ..validate import real_array
from ._base import (
    System,
    as_code,
    coded_shear_sum_matrix,
    coded_state,
    count,
    shifts_for,
    wavelengths_for,
)

__all__ = ["CASSDIDFA"]


class CASSDIDFA(System):
    """Focal sweep with a deformable mirror, one code per focal step, one exposure (Equation 57-60).

    ::

        G = Σ_z Σ_l shear_l( (F[:, :, l, z] ⊛ PSF[l, z]) ∘ C[:, :, z] )

    ``F[:, :, l, z]`` is the part of the scene at depth plane ``z`` in band
    ``l``; the mirror's PSF for that band and focal step blurs it, the DMD
    shows code ``C[:, :, z]`` during that step, the prism shears, the sensor
    integrates the whole sweep.

    Parameters
    ----------
    codes : array_like of shape (Nx, Ny, Nz)
        One code per focal step (depth plane).
    n_bands : int
    shifts, wavelengths
        As for :class:`~tensor_cosdi.systems.SDCASSI`.
    psfs : array_like of shape (h, w, Nλ, Nz) or (h, w, Nλ, Nz, K), optional
        Intensity PSF of every (band, depth) pair, from
        :mod:`tensor_cosdi.optics` (pupil + Zernike aberration + defocus,
        Eq. 51-53) or from calibration.  Sizes 1 along ``Nλ`` or ``Nz`` share
        a PSF; ``(h, w)`` shares one everywhere.  Non-negative, each summing
        to more than 0; used as given (normalise to 1 for energy
        conservation).  ``None``: ideal imaging (Eq. 58, 60).  The pure-defocus
        "CASSDI-DFD" baseline is this system with PSFs of aberration
        amplitude 0.  A 5-D stack (:func:`tensor_cosdi.optics.sweep_psf_stack`)
        is the **focal sweep**: ``K = codes.shape[2]`` focal steps, each
        seeing every one of ``Nz`` depth planes through its own PSF
        ``PSF[l, z, k]`` (in focus where the step's focus meets the plane)::

            G = Σ_k Σ_l shear_l( (Σ_z F[:, :, l, z] ⊛ PSF[l, z, k]) ∘ C[:, :, k] )

        The 4-D form is its diagonal ``z = k``: plane ``z`` is seen only at
        step ``z``, through code ``z`` — so the codes alone tell the planes
        apart, which the swept optics do not grant.  The inner sum runs in the Fourier
        domain (:class:`~tensor_cosdi.operators.BlurSum`: one transform per plane and per
        step rather than one per plane and step).

    Attributes
    ----------
    cube_shape : ``(Nx, Ny, Nλ, Nz)``, axes ``("x", "y", "λ", "z")``
    measurement_shape : ``(Nx, Ny + S)``
    panchromatic_axes : ``("λ", "z")`` — the all-in-focus grayscale image ``fg``.

    Notes
    -----
    Without PSFs ``A Aᵀ`` is diagonal (closed-form Woodbury); with PSFs it has
    no cheap structure and ``solve_normal`` uses conjugate gradients; ``method="split_tv"``
    splits the blur off instead and stays in closed form (SPEC §4).

    Examples
    --------
    >>> import numpy as np
    >>> from tensor_cosdi.systems import CASSDIDFA
    >>> dfa = CASSDIDFA(np.ones((4, 5, 3)), n_bands=2)
    >>> dfa.cube_shape, dfa.measurement_shape
    ((4, 5, 2, 3), (4, 6))
    """

    panchromatic_axes = ("λ", "z")

    def __init__(self, codes, *, n_bands, shifts=1, psfs=None, wavelengths=None):
        self.codes = as_code(codes, "codes", (3,))
        nl = count(n_bands, "n_bands")
        self.shifts, _ = shifts_for(shifts, nl)
        nx, ny, nz = self.codes.shape
        cube = (nx, ny, nl, nz)
        shear = Shear(cube, self.shifts)
        per_band = SumAxis(shear.output_shape, 2)
        op = (
            SumAxis(per_band.output_shape, 2)
            @ per_band
            @ shear
            @ Code(self.codes, cube, axes=(0, 1, 3))
        )
        self.psfs = None
        if psfs is not None:
            p = np.array(real_array("psfs", B.to_numpy(psfs), finite=False))  # a copy, real
            if p.ndim not in (2, 4, 5):
                raise ValueError(
                    f"psfs must have shape (h, w), (h, w, Nλ, Nz) = (h, w, {nl}, {nz}) or, for a "
                    f"focal sweep, (h, w, Nλ, Nz, K) with K = {nz} steps; got {p.shape}"
                )
            if p.ndim == 5:
                op = self._sweep(p, nl)
                self._finish(
                    op,
                    wavelengths=wavelengths_for(wavelengths, nl),
                    axes=("x", "y", "λ", "z"),
                    measurement_axes=("x", "y"),
                )
                return
            if p.ndim == 4 and (p.shape[2] not in (1, nl) or p.shape[3] not in (1, nz)):
                raise ValueError(
                    f"psfs shape {p.shape} does not match the cube: expected (h, w, {nl}, {nz}) "
                    "(one PSF per band and depth plane; size 1 shares)"
                )
            _check_psfs(p)
            p = p.reshape(p.shape + (1,) * (4 - p.ndim))
            p.setflags(write=False)
            self.psfs = p
            op = op @ Blur(cube, p)
        self._finish(
            op,
            wavelengths=wavelengths_for(wavelengths, nl),
            axes=("x", "y", "λ", "z"),
            measurement_axes=("x", "y"),
        )

    def _sweep(self, p, nl):
        """The focal-sweep operator of a 5-D PSF stack (see the class docstring)."""
        nx, ny, steps = self.codes.shape
        if p.shape[2] not in (1, nl) or p.shape[4] != steps or p.shape[3] < 1:
            raise ValueError(
                f"focal-sweep psfs {p.shape} must be (h, w, Nλ, Nz, K) with Nλ in (1, {nl}) and "
                f"K = {steps} focal steps (one per code)"
            )
        _check_psfs(p)
        p.setflags(write=False)
        self.psfs = p
        nz = p.shape[3]
        cube, steps_shape = (nx, ny, nl, nz), (nx, ny, nl, steps)
        shear = Shear(steps_shape, self.shifts)
        per_band = SumAxis(shear.output_shape, 2)
        return (
            SumAxis(per_band.output_shape, 2)
            @ per_band
            @ shear
            @ Code(self.codes, steps_shape, axes=(0, 1, 3))
            @ BlurSum(cube, p, sum_axis=3)
        )

    @property
    def sweep(self) -> bool:
        """True for a focal-sweep system (5-D PSFs: every plane seen at every step)."""
        return self.psfs is not None and self.psfs.ndim == 5

    @property
    def n_depths(self) -> int:
        return self.psfs.shape[3] if self.sweep else self.codes.shape[2]

    # ---- roles (systems/_roles.py) -------------------------------------------------------
    name = "cassdi_dfa"
    demo_scene = "motorcycle"
    #: Every pixel sums sheared diagonals of voxels, as in SD-CASSI (see ``SDCASSI.snr_fit``).
    snr_fit = "subspace"
    has_depth = True
    example_options = {"n_depths": 3}
    depth_kind = "planes"

    def _state(self):
        params, arrays = coded_state(self, code="codes")
        if self.psfs is not None:
            arrays["psfs"] = np.asarray(self.psfs)
        return params, arrays

    @classmethod
    def _from_state(cls, params, arrays):
        return cls(
            arrays["codes"],
            shifts=arrays["shifts"],
            psfs=arrays.get("psfs"),
            wavelengths=arrays["wavelengths"],
            **params,
        )

    def depth_from_cube(self, cube, *, n_steps: int = 4, max_disparity: float = 2.0):
        """Index of the depth plane holding most of each pixel's energy, ``argmax_z Σ_λ F``
        (float)."""
        x = real_array("cube", B.to_numpy(cube), finite=False)
        return np.argmax(x.sum(axis=2), axis=2).astype(np.float64)

    def spectral_view(self, cube):
        """The all-in-focus cube: the sum over depth planes."""
        return real_array("cube", B.to_numpy(cube), finite=False).sum(axis=3)

    @classmethod
    def _example(cls, scene, shape, wl, seed, shifts, n_depths):
        from .. import scenes

        reflectance = scenes.scene_cube(scene, shape, wl)
        _, disp = scenes.motorcycle(shape, [550.0])
        depth = scenes.depth_planes(disp, n_depths)
        cube = scenes.depth_layers(reflectance, depth, n_depths)
        system = cls.example(shape + (len(wl), n_depths), rng=seed, shifts=shifts, wavelengths=wl)
        return system, cube, reflectance, depth, {}

    @classmethod
    def example(
        cls, cube_shape=None, *, rng=0, transmittance: float = 0.5, psf_size: int = 0, **overrides
    ):
        """A seeded instance (default cube ``(16, 16, 8, 3)``).

        ``psf_size > 0`` adds random normalised ``psf_size × psf_size`` PSFs per
        (band, depth) — a stand-in for :mod:`tensor_cosdi.optics` PSFs.
        """
        nx, ny, nl, nz = (16, 16, 8, 3) if cube_shape is None else cube_shape
        g = B.default_rng(rng)
        codes = depth_codes((nx, ny), nz, transmittance=transmittance, rng=g)
        if psf_size:
            p = g.random((psf_size, psf_size, nl, nz))
            overrides.setdefault("psfs", p / p.sum(axis=(0, 1), keepdims=True))
        return cls(codes, n_bands=nl, **overrides)

    def matrix(self):
        nx, ny, nl, nz = self.cube_shape
        width = self.measurement_shape[1]
        # Eq. 60: H = [H_0 … H_{K−1}], H_k the coded shear-sum of code k (K = Nz but in a sweep)
        H = sp.hstack(
            [
                coded_shear_sum_matrix(
                    np.repeat(self.codes[:, :, k, None], nl, axis=2), self.shifts, width
                )
                for k in range(self.codes.shape[2])
            ],
            format="csr",
        )
        if self.psfs is None:
            return H
        if self.sweep:  # stack block (l, k) = Σ_z blur(l, z, k) of cube block (l, z)
            steps, p = self.codes.shape[2], self.psfs
            rows = [
                [
                    _convolution_matrix(p[:, :, min(l, p.shape[2] - 1), z, k], nx, ny)
                    if l == m else None
                    for z in range(nz) for m in range(nl)
                ]
                for k in range(steps) for l in range(nl)
            ]  # fmt: skip
            return (H @ sp.bmat(rows, format="csr")).tocsr()
        blocks = []
        for z in range(nz):
            for l in range(nl):
                p = self.psfs[:, :, min(l, self.psfs.shape[2] - 1), min(z, self.psfs.shape[3] - 1)]
                blocks.append(_convolution_matrix(p, nx, ny))
        return (H @ sp.block_diag(blocks, format="csr")).tocsr()


def _check_psfs(p: np.ndarray) -> None:
    if not np.isfinite(p).all():
        raise ValueError("psfs contain NaN or inf")
    if (p < 0).any():
        raise ValueError(f"psfs are intensities and must be ≥ 0; minimum is {p.min():g}")
    if (p.sum(axis=(0, 1)) <= 0).any():
        raise ValueError("every PSF must have a positive sum; got an all-zero PSF")


def _convolution_matrix(psf: np.ndarray, nx: int, ny: int) -> sp.csr_matrix:
    """``y[i, j] = Σ_{a,b} h[a, b] x[i − a + ⌊h/2⌋, j − b + ⌊w/2⌋]`` (zero outside),
    column-major."""
    h, w = psf.shape
    i, j = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    rows, cols, vals = [], [], []
    for a in range(h):
        for b in range(w):
            ii, jj = i - a + h // 2, j - b + w // 2
            ok = (ii >= 0) & (ii < nx) & (jj >= 0) & (jj < ny)
            rows.append((i + nx * j)[ok])
            cols.append((ii + nx * jj)[ok])
            vals.append(np.full(int(ok.sum()), psf[a, b]))
    return sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(nx * ny, nx * ny),
    )
