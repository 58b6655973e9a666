"""Common machinery of the imagers: parameters, validation, simulate, panchromatic."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import tensorly as tl

from .. import _backend as B
from .._units import check_wavelengths_nm
from ..noise import add_noise
from ..operators import Code, SumAxis, TensorOperator, parse_shifts, sensing_gain
from ..operators.shear import MAX_BANDS
from ..validate import integer, real_array
from ._roles import SystemRoles
from .registry import REGISTRY

__all__ = ["System"]


# ---- parameter validation (shared by every system) ------------------------------------
def as_code(code, what: str, ndims) -> np.ndarray:
    """A read-only float64 copy of a code of transmittances (finite, ≥ 0)."""
    arr = np.array(B.to_numpy(code), copy=True)
    if arr.dtype.kind not in "biuf":
        raise ValueError(f"{what} must be a real array, got dtype {arr.dtype}")
    arr = arr.astype(np.float64)
    if arr.ndim not in ndims:
        names = " or ".join(str(n) for n in ndims)
        raise ValueError(f"{what} must have {names} axes, got shape {arr.shape}")
    if not np.isfinite(arr).all():
        raise ValueError(f"{what} contains NaN or inf")
    if (arr < 0).any():
        raise ValueError(
            f"{what} holds transmittances and must be ≥ 0; its minimum is {arr.min():g}"
        )
    arr.setflags(write=False)
    return arr


def count(value, what: str, minimum: int = 1) -> int:
    """A count ≥ ``minimum`` (``n_bands`` also ≤
    :data:`~tensor_cosdi.operators.shear.MAX_BANDS`, refused before anything that size is
    allocated)."""
    high = MAX_BANDS if what == "n_bands" else None
    return integer(what, value, low=minimum, high=high)


def shifts_for(shifts, n_bands: int) -> tuple[np.ndarray, int]:
    """Per-band shifts (read-only) and the extra measurement width ``⌈max s⌉``."""
    s = parse_shifts(shifts, n_bands)
    s.setflags(write=False)
    return s, int(np.ceil(s.max())) if s.size else 0


def wavelengths_for(wavelengths, n_bands: int) -> np.ndarray:
    """Validated band centres in nm (default: evenly spaced over 450–650 nm)."""
    if wavelengths is None:
        from ..scenes import default_wavelengths

        w = default_wavelengths(n_bands)
    else:
        w = np.array(real_array("wavelengths", B.to_numpy(wavelengths), finite=False))
        if w.ndim != 1:
            raise ValueError(f"wavelengths must be 1-D (one per band), got shape {w.shape}")
        if w.size != n_bands:
            raise ValueError(f"expected {n_bands} wavelengths (one per band), got {w.size}")
        check_wavelengths_nm(w)  # nanometres, or an error naming the unit
        if (np.diff(w) <= 0).any():
            raise ValueError(f"wavelengths must be strictly increasing, got {w.tolist()}")
    w.setflags(write=False)
    return w


def fractional_weights(shifts: np.ndarray):
    """For every band: integer offset and interpolation weight (linear, Shear's model)."""
    s = real_array("shifts", shifts, finite=False)
    lo = np.floor(s).astype(np.int64)
    return lo, s - lo


# ---- the base class ---------------------------------------------------------------
class System(SystemRoles):
    """Base of every imager in :mod:`tensor_cosdi.systems`.

    A system is a small frozen object: its physical parameters (codes,
    shifts, weights, PSFs, wavelengths) and the :class:`~tensor_cosdi.operators.TensorOperator`
    composed from them.  Subclasses set the parameters and call
    :meth:`_finish`; what the rest of the library asks of a system (state,
    frames, depth, seeded problems) is :class:`~tensor_cosdi.systems._roles.SystemRoles`.

    Attributes
    ----------
    cube_shape, measurement_shape : tuple of int
    axes, measurement_axes : tuple of str
        Axis names (SPEC §1): ``"x", "y", "λ"`` then ``"z"``, ``"u", "v"``, ``"t"``, ``"k"``.
    panchromatic_axes : tuple of str
        Cube axes summed by :meth:`panchromatic` (always ``"λ"``; CASSDI-DFA
        also ``"z"``, giving the all-in-focus grayscale image).
    wavelengths : ndarray of shape (Nλ,)
        Band centres in nm.
    operator : TensorOperator
        The sensing operator ``A``: ``cube_shape → measurement_shape``.
    """

    axes: tuple[str, ...]
    measurement_axes: tuple[str, ...]
    panchromatic_axes: tuple[str, ...] = ("λ",)
    #: ``ε`` of GAP's ``(AAᵀ + εI)⁻¹`` relative to the sensing gain when a method's ``eps`` is
    #: ``"auto"``: tiny where ``A Aᵀ`` is well conditioned; a system whose ``A Aᵀ`` has weak
    #: directions sets more, so GAP does not fit the noise along them.
    gap_eps: float = 1e-6
    #: The fit whose residual :func:`~tensor_cosdi.solvers.snr.estimate_snr` reads the noise
    #: from (``fit="auto"``): ``"gap_tv"``, a few plain GAP-TV iterations, or ``"subspace"``,
    #: GAP-TV in a spectral subspace, for a system whose every measurement pixel sums voxels
    #: along a sheared diagonal, which the subspace cannot hold, so the noise stays in the
    #: residual (see :mod:`tensor_cosdi.solvers.snr`).
    snr_fit: str = "gap_tv"
    #: Whether the plug-and-play methods' ``relax="auto"`` over-relaxes their ADMM
    #: (:data:`~tensor_cosdi.solvers.pnp_gap.FAST_RELAX`,
    #: :data:`~tensor_cosdi.solvers.pnp_gap.RELAX`; chosen on SD-CASSI): a system where it was
    #: measured to cost PSNR sets ``False`` and keeps plain ADMM
    #: (``benchmarks/results/relax_systems.md``, ``relax_c3slfi.md``).
    admm_relax: bool = True
    #: The TV weight of the ``"gap_tv"`` fit (the measurement at a peak of 1).  A system whose
    #: pixels each see only a few codes of one spectrum (C3SLFI) sets less: the fit cannot
    #: recover the spectral detail the codes mix, and the heavier weight's spectral error,
    #: modulated by the code, reads as noise.
    snr_fit_tv: float = 0.1
    #: Whether the noiseless frames of a measurement span fewer dimensions than there are frames,
    #: each frame with the same noise (CS2LI's phase steps): then
    #: :func:`~tensor_cosdi.solvers.snr.estimate_snr` also reads the noise from the frames'
    #: smallest singular value (:func:`tensor_cosdi.noise.frame_rank_sigma`).
    snr_frames_low_rank: bool = False
    #: Groups of measurement frames (indices along the axes after the first two, folded) whose
    #: noise is set against the group's own signal — one camera each, as the system's
    #: :meth:`simulate` adds it; ``None``: one group, the whole measurement.  The SNR estimate
    #: reads each group against its own power and reports the noisiest.
    snr_frame_groups: tuple[tuple[int, ...], ...] | None = None
    #: Anchors ``{SNR dB: weight}`` of OTD's ``lam="auto"`` schedule that this system replaces
    #: (cross-validated on it); the others stay those of
    #: :data:`~tensor_cosdi.solvers.otd.LAM_SCHEDULE` / ``LAM_SCHEDULE_MANY``.  ``None``: none.
    otd_lam_anchors: dict | None = None
    _frozen = False

    def _finish(self, operator: TensorOperator, *, wavelengths, axes, measurement_axes):
        if len(axes) != len(operator.input_shape) or len(measurement_axes) != len(
            operator.output_shape
        ):  # pragma: no cover - programming error in a subclass
            raise AssertionError("axis names do not match the operator's shapes")
        self.operator = operator
        self.wavelengths = wavelengths
        self.axes = tuple(axes)
        self.measurement_axes = tuple(measurement_axes)
        self._frozen = True

    def __setattr__(self, name, value):
        if self._frozen:
            raise AttributeError(
                f"{type(self).__name__} is immutable; build a new system to change {name!r}"
            )
        object.__setattr__(self, name, value)

    # ---- shapes ------------------------------------------------------------------
    @property
    def cube_shape(self) -> tuple[int, ...]:
        """Shape of the cube the system senses."""
        return self.operator.input_shape

    @property
    def measurement_shape(self) -> tuple[int, ...]:
        """Shape of the measurement it returns."""
        return self.operator.output_shape

    @property
    def n_bands(self) -> int:
        return self.cube_shape[self.axes.index("λ")]

    @property
    def compression(self) -> float:
        """Measurements per unknown, ``m / n``."""
        return float(np.prod(self.measurement_shape)) / float(np.prod(self.cube_shape))

    def __repr__(self):
        return (
            f"{type(self).__name__}(cube_shape={self.cube_shape} {self.axes}, "
            f"measurement_shape={self.measurement_shape} {self.measurement_axes})"
        )

    # ---- sensing -----------------------------------------------------------------
    def _check_shape(self, x, method, cube: bool):
        shape = self.cube_shape if cube else self.measurement_shape
        got = tuple(tl.shape(x)) if tl.is_tensor(x) else np.shape(x)
        if got != shape:
            names = self.axes if cube else self.measurement_axes
            what = "cube" if cube else "measurement"
            raise ValueError(
                f"{type(self).__name__}.{method}: expected a {what} of shape {shape} "
                f"(axes {', '.join(names)}), got shape {got}"
            )

    def forward(self, cube):
        """Noise-free measurement ``A(cube)``; ``cube`` of shape :attr:`cube_shape`."""
        self._check_shape(cube, "forward", True)
        return self.operator.forward(cube)

    def adjoint(self, measurement):
        """``Aᵀ(measurement)``, a tensor of shape :attr:`cube_shape`."""
        self._check_shape(measurement, "adjoint", False)
        return self.operator.adjoint(measurement)

    def simulate(self, cube, snr_db: float | None = None, rng=None):
        """Measurement of ``cube`` with white Gaussian noise at ``snr_db`` (SPEC §9).

        ``snr_db=None`` gives the noise-free measurement; ``rng`` seeds the noise.
        """
        return add_noise(self.forward(cube), snr_db, rng=rng)

    def gram_dual(self):
        """Structure of ``A Aᵀ`` (SPEC §4): Diagonal, PixelBlocks, RowBanded or ``None``."""
        return self.operator.gram_dual()

    def solve_normal(self, r, mu):
        """``(AᵀA + μI)⁻¹ r`` through the structured Woodbury identity (SPEC §4)."""
        self._check_shape(r, "solve_normal", True)
        return self.operator.solve_normal(r, mu)

    # ---- panchromatic ------------------------------------------------------------
    @property
    def panchromatic_shape(self) -> tuple[int, ...]:
        return self.decimation.output_shape

    @property
    def decimation(self) -> TensorOperator:
        """``D``: cube → panchromatic, the sum over :attr:`panchromatic_axes` (Equation 46, 62)."""
        op = None
        shape = self.cube_shape
        names = list(self.axes)
        for name in self.panchromatic_axes:
            axis = names.index(name)
            s = SumAxis(shape, axis)
            op = s if op is None else s @ op
            shape = s.output_shape
            names.pop(axis)
        return op

    def check_measurement(self, measurement, caller: str = "reconstruct"):
        """The measurement as a tensor, refused with a one-line ``ValueError`` naming
        ``caller`` unless it is a finite floating tensor of :attr:`measurement_shape`."""
        self._check_shape(measurement, caller, False)
        return self.operator.check_output(measurement, caller)

    @property
    def panchromatic_exact(self) -> bool:
        """Whether :meth:`panchromatic` returns ``D F`` exactly (up to noise) rather than an
        estimate."""
        return False

    def panchromatic(self, measurement, *, mu: float = 1e-2):
        """Panchromatic estimate ``Z ≈ D F`` (the cube summed over :attr:`panchromatic_axes`).

        SPEC §5 step 1.  Systems with an exact formula override this (C3SLFI:
        Lemma 1).  Otherwise ``Z`` is the regularised least-squares solution of
        the decimated model ``G ≈ A Dᵀ Z / n`` (Eq. 62; ``n`` = entries summed
        per pixel, so a spectrally flat cube has ``Z = D F`` exactly):
        ``min ‖G − A Dᵀ Z / n‖² + μ s ‖Z‖²`` with ``s = ‖A Dᵀ 1/n‖² / ‖1‖²``
        making ``mu`` scale-free.  The solve uses the structure of the
        decimated operator's Gram (or CG).

        Parameters
        ----------
        measurement : tensor of shape :attr:`measurement_shape`
        mu : float > 0
            Relative Tikhonov weight.

        Returns
        -------
        tensor of shape :attr:`panchromatic_shape`
        """
        g = self.check_measurement(measurement, "panchromatic")
        if not (np.isfinite(mu) and mu > 0):
            raise ValueError(f"mu must be a finite number > 0, got {mu!r}")
        D = self.decimation
        n = float(np.prod(self.cube_shape)) / float(np.prod(D.output_shape))
        Bop = (self.operator @ D.T) * (1.0 / n)
        return Bop.solve_normal(Bop.adjoint(g), mu * sensing_gain(Bop, g))

    # ---- explicit matrix (SPEC §11) --------------------------------------------------
    def matrix(self) -> sp.csr_matrix:
        """Explicit sensing matrix ``H`` from the thesis formulas, column-major ``vec`` (SPEC §1).

        Built from the equations, independently of :attr:`operator`; tests
        compare the two.  For small sizes only.
        """
        raise NotImplementedError  # pragma: no cover


def coded_state(system, *, code: str = "code") -> tuple[dict, dict]:
    """``(params, arrays)`` of the systems built from one code, shifts and ``n_bands``."""
    return {"n_bands": int(system.n_bands)}, {
        code: np.asarray(getattr(system, code)),
        "shifts": np.asarray(system.shifts),
    }


# ---- building blocks of the explicit matrices ----------------------------------------
def pixel_index(nx: int, ny: int) -> np.ndarray:
    """Column-major pixel index ``u = i1 + Nx i2`` as an ``(Nx, Ny)`` array."""
    return np.arange(nx * ny).reshape((nx, ny), order="F")


def coded_shear_sum_matrix(weights: np.ndarray, shifts, width: int) -> sp.csr_matrix:
    """``H = Σ_l P_{s_l} diag(w_l)`` (Equation 43): columns ``j = u + NxNy l``, rows ``u + Nx s_l``.

    ``weights`` has shape ``(Nx, Ny, Nλ)`` (the code each band sees); band
    ``l`` lands ``s_l`` columns to the right on an ``Nx × width`` detector.
    Fractional ``s_l`` splits each entry into rows ``u + Nx⌊s_l⌋`` (weight
    ``1 − t``) and ``u + Nx(⌊s_l⌋ + 1)`` (weight ``t``), ``t = s_l − ⌊s_l⌋``.
    """
    nx, ny, nl = weights.shape
    lo, t = fractional_weights(shifts)
    u = np.arange(nx * ny)
    rows, cols, vals = [], [], []
    for l in range(nl):
        w = weights[:, :, l].reshape(-1, order="F")
        j = u + nx * ny * l
        for off, f in ((lo[l], 1.0 - t[l]), (lo[l] + 1, t[l])):
            if f == 0.0:
                continue
            rows.append(u + nx * off)
            cols.append(j)
            vals.append(w * f)
    m = nx * width
    return sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(m, nx * ny * nl),
    )


def unsheared_code(code: np.ndarray, shifts, ny: int) -> np.ndarray:
    """``Ceff[:, c, l] = C[:, c + s_l, l]`` (dual disperser, Equation 113 with SPEC §12's indices).

    ``code`` is ``(Nx, Ny + ⌈max s⌉)`` (one code for all bands) or
    ``(Nx, Ny + ⌈max s⌉, Nλ)`` (colour-coded).  Fractional shifts read the code
    with linear interpolation, ``(1 − t) C[c + ⌊s⌋] + t C[c + ⌊s⌋ + 1]``.
    """
    lo, t = fractional_weights(shifts)
    nl = len(lo)
    out = np.empty((code.shape[0], ny, nl))
    for l in range(nl):
        c = code if code.ndim == 2 else code[:, :, l]
        band = (1.0 - t[l]) * c[:, lo[l] : lo[l] + ny]
        if t[l] != 0.0:
            band = band + t[l] * c[:, lo[l] + 1 : lo[l] + 1 + ny]
        out[:, :, l] = band
    out.setflags(write=False)
    return out


def check_code_width(code_width: int, extra: int, what: str) -> int:
    ny = code_width - extra
    if ny < 1:
        raise ValueError(
            f"{what} has {code_width} columns but the shifts need ⌈max s⌉ = {extra} extra "
            f"columns: the shifts do not fit (expected a code of Ny + {extra} columns, Ny ≥ 1)"
        )
    return ny


# ---- the dual-disperser core (DD-CASSI, CS2LI, Mu-CoSDI) ------------------------------------
def dual_disperser(code, n_bands: int, shifts):
    """Validated code, shifts and effective per-band code ``Ceff[:, c, l] = C[:, c + s_l, l]``."""
    nl = count(n_bands, "n_bands")
    s, extra = shifts_for(shifts, nl)
    ny = check_code_width(code.shape[1], extra, "code")
    if code.ndim == 3 and code.shape[2] != nl:
        raise ValueError(
            f"colour-coded aperture of shape {code.shape} has {code.shape[2]} bands, expected "
            f"n_bands = {nl} (shape (Nx, Ny + {extra}, {nl}))"
        )
    return s, unsheared_code(code, s, ny)


def dual_disperser_operator(ceff: np.ndarray, cube_shape):
    """``G = Σ_l Ceff[:, :, l] ∘ F[:, :, l, …]`` for a cube ``(Nx, Ny, Nλ, …)``
    (Equations 113-115)."""
    return SumAxis(cube_shape, 2) @ Code(ceff, cube_shape, axes=(0, 1, 2))


def dual_disperser_matrix(code: np.ndarray, shifts, ny: int, repeats: int) -> sp.csr_matrix:
    """Equations 115 / 144: ``H = I_repeats ⊗ A``, ``A = [diag(c_0) … diag(c_{Nλ−1})]``,
    ``c_l = vec(C[:, s_l : s_l + Ny, l])``."""
    lo, t = fractional_weights(shifts)
    diags = []
    for l in range(len(lo)):
        c = code if code.ndim == 2 else code[:, :, l]
        w = (1 - t[l]) * c[:, lo[l] : lo[l] + ny]
        if t[l]:
            w = w + t[l] * c[:, lo[l] + 1 : lo[l] + 1 + ny]
        diags.append(sp.diags(w.reshape(-1, order="F")))
    A = sp.hstack(diags)
    return sp.kron(sp.identity(repeats), A, format="csr") if repeats > 1 else A.tocsr()


REGISTRY.base = System  # what the registry accepts (it imports no imager itself)
