"""CASSI-VSI: one sensor, a dispersed arm and a coded grayscale arm (SPEC §3.1, thesis Ch. 3)."""

from __future__ import annotations

import numbers

import numpy as np
import scipy.sparse as sp

from ..codes import random_binary
from ..operators import Code, Pad, Shear, SumAxis, weighted_sum
from ..validate import number
from ._base import (
    System,
    as_code,
    coded_shear_sum_matrix,
    coded_state,
    count,
    shifts_for,
    wavelengths_for,
)

__all__ = ["CASSIVSI"]


class CASSIVSI(System):
    """CASSI with virtual side information: two arms on one detector (Equation 40-44).

    A beam splitter sends ``αT`` of the light through the prism (the coded,
    dispersed arm) and ``αR = 1 − αT`` straight to the same sensor (the coded
    grayscale arm), landing ``β`` columns to the right::

        G = αT Σ_l shear_l(C ∘ F[:, :, l]) + αR shift_β(C ∘ Σ_l F[:, :, l])

    (Eq. 40 with the grayscale term outside the band sum, SPEC §12).

    Parameters
    ----------
    code : array_like of shape (Nx, Ny)
        Coded aperture, seen by both arms.
    n_bands : int
    alpha_t : float in [0, 1]
        Fraction of light in the dispersed arm (thesis optimum 0.7; the
        prototype used 0.75).  ``1`` is plain SD-CASSI, ``0`` a coded
        grayscale camera.
    beta : int, optional
        Column where the grayscale arm's first column lands,
        ``0 ≤ β ≤ S`` with ``S = ⌈max s_l⌉`` (``Nλ − 1`` for one column per
        band).  Default 0: ``HR = [Bᵀ, 0]ᵀ`` as in Eq. 44.
    shifts, wavelengths
        As for :class:`~tensor_cosdi.systems.SDCASSI`.

    Attributes
    ----------
    cube_shape : ``(Nx, Ny, Nλ)``
    measurement_shape : ``(Nx, Ny + S)``
    arms : (TensorOperator, TensorOperator)
        ``(HT, HR)`` without their weights: the coded-dispersed arm and the
        coded grayscale arm, ``operator = αT·HT + αR·HR`` (Eq. 45).

    Notes
    -----
    ``H = HT + HR`` with ``HT`` the SD-CASSI matrix scaled by ``αT`` and
    ``HR = αR`` times ``B = 1ᵀ_Nλ ⊗ diag(c)`` placed ``β`` columns down
    (Eq. 42-44).  ``A Aᵀ`` couples columns ``|p − q| ≤ S`` of one detector
    row: block-diagonal over rows, banded inside a row, solved by a banded
    Cholesky per row (SPEC §4).

    Examples
    --------
    >>> import numpy as np
    >>> from tensor_cosdi.systems import CASSIVSI
    >>> vsi = CASSIVSI(np.ones((4, 5)), n_bands=3, alpha_t=0.7, beta=1)
    >>> vsi.measurement_shape, vsi.alpha_r
    ((4, 7), 0.3)
    """

    name = "cassi_vsi"
    demo_scene = "chelsea"
    example_options = {"code": None}

    def _state(self):
        params, arrays = coded_state(self)
        return {**params, "alpha_t": float(self.alpha_t), "beta": int(self.beta)}, arrays

    def __init__(self, code, *, n_bands, alpha_t=0.7, beta=None, shifts=1, wavelengths=None):
        self.code = as_code(code, "code", (2,))
        nl = count(n_bands, "n_bands")
        self.shifts, extra = shifts_for(shifts, nl)
        a = number("alpha_t", alpha_t, low=0, high=1)  # the fraction of the light dispersed
        self.alpha_t = a
        self.alpha_r = round(1.0 - a, 15)
        beta = 0 if beta is None else beta
        if (
            isinstance(beta, bool)
            or not isinstance(beta, numbers.Integral)
            or not 0 <= beta <= extra
        ):
            raise ValueError(
                f"beta must be an integer column offset in [0, {extra}] (0 to ⌈max shift⌉), "
                f"got {beta!r}"
            )
        self.beta = int(beta)
        nx, ny = self.code.shape
        cube = (nx, ny, nl)
        code = Code(self.code, cube)
        shear = Shear(cube, self.shifts)
        dispersed = SumAxis(shear.output_shape, 2) @ shear @ code
        direct = (
            Pad((nx, ny), axis=1, before=self.beta, after=extra - self.beta)
            @ SumAxis(cube, 2)
            @ code
        )
        #: the two arms without their weights: ``H = αT·HT + αR·HR`` (Eq. 45), used by A-VSI (Alg.
        #: 1)
        self.arms = (dispersed, direct)
        terms = [(op, w) for op, w in ((dispersed, self.alpha_t), (direct, self.alpha_r)) if w != 0]
        self._finish(
            weighted_sum([t[0] for t in terms], [t[1] for t in terms]),
            wavelengths=wavelengths_for(wavelengths, nl),
            axes=("x", "y", "λ"),
            measurement_axes=("x", "y"),
        )

    @property
    def snr_fit(self) -> str:
        """``"subspace"`` without a direct arm (``alpha_t = 1``: SD-CASSI), else ``"gap_tv"``:
        the direct arm's pixels each hold one position's voxels, and the subspace fit would take
        up their noise (see :mod:`tensor_cosdi.solvers.snr`)."""
        return "subspace" if self.alpha_r == 0 else "gap_tv"

    @classmethod
    def example(cls, cube_shape=None, *, rng=0, transmittance: float = 0.5, **overrides):
        """A seeded instance with a random binary code (default cube ``(16, 16, 8)``)."""
        nx, ny, nl = (16, 16, 8) if cube_shape is None else cube_shape
        return cls(
            random_binary((nx, ny), transmittance=transmittance, rng=rng), n_bands=nl, **overrides
        )

    def matrix(self):
        nx, ny, nl = self.cube_shape
        width = self.measurement_shape[1]
        HT = coded_shear_sum_matrix(
            np.repeat(self.code[:, :, None], nl, axis=2), self.shifts, width
        )
        # HR (Eq. 44): entry αR c_u at row u + β Nx for every column j = u + NxNy l
        c = self.code.reshape(-1, order="F")
        u = np.tile(np.arange(nx * ny), nl)
        HR = sp.csr_matrix(
            (np.tile(c, nl), (u + self.beta * nx, np.arange(nx * ny * nl))),
            shape=(nx * width, nx * ny * nl),
        )
        return (self.alpha_t * HT + self.alpha_r * HR).tocsr()
