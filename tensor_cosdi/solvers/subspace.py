"""GAP-TV in a smooth spectral subspace, and how many atoms span a band axis.

:func:`subspace_gap_tv` fits a measurement with cubes whose panchromatic axes
(their bands) are spanned by a few DCT atoms, each coefficient image
regularised by 2-D total variation.  OTD's first stage
(:mod:`~tensor_cosdi.solvers.panchromatic`) starts from it, and the SNR
estimate (:mod:`~tensor_cosdi.solvers.snr`) reads the noise from its
residual.  Both take the atom count from :func:`pan_atoms_for`.
"""

from __future__ import annotations

import numbers

import numpy as np
from tensorly import tenalg

from .. import _backend as B
from ..bases import dct
from ..validate import imager, real_array
from . import engine
from ._base import relative_change
from .priors import TV

__all__ = [
    "subspace_gap_tv", "subspace_denoise", "pan_atoms_for", "has_many_bands",
    "fitted_mean_spectrum", "spectral_roughness", "gate_spectrum", "ROUGH_SPECTRUM", "GATE_FLOOR",
    "PAN_ATOMS", "PAN_ATOMS_MANY", "MANY_BANDS",
]  # fmt: skip

_check_int = engine.check_int

#: ``pan_atoms="auto"``: the DCT atoms spanning a panchromatic axis in the first stage, by the
#: axis' length: :data:`PAN_ATOMS` below :data:`MANY_BANDS`, :data:`PAN_ATOMS_MANY` from there
#: on.  The larger count was chosen by 4-fold cross-validation over 16 of the 28-band tuning
#: scenes (SD-CASSI, TSA mask, one setting for noiseless and 30 dB from 3, 6, 8, 12;
#: ``benchmarks/results/pan_atoms.md``): three atoms cannot follow the spectra of 28 bands, and
#: the first stage's cube is OTD's start.  Eight, not six: cross-validated again on all 28
#: tuning scenes as they are and magnified 4× (4 folds, TSA mask, noiseless and 30 dB;
#: ``benchmarks/results/otd_pan_atoms_zoom4.md``): 6 / 8 / 10 / 12 atoms → 33.02 / 33.22 /
#: 33.16 / 33.10 dB noiseless, 31.41 / 31.47 / 31.39 / 31.37 dB at 30 dB, every fold chose 8.
#: On the magnified views six atoms cannot follow large areas of saturated colour (superballs
#: ×4 30.51 dB against 34.38 with eight; clay ×4 34.86 against 39.63).  Shorter axes keep the
#: three atoms their studies were run with.
PAN_ATOMS = 3
PAN_ATOMS_MANY = 8
MANY_BANDS = 24


def pan_atoms_for(length: int, pan_atoms="auto", *, name: str = "pan_atoms") -> int:
    """The first stage's count of DCT atoms for a panchromatic axis.

    Parameters
    ----------
    length : int
        Samples along the axis (its band count).
    pan_atoms : int or "auto"
        An integer ≥ 1, or ``"auto"``: :data:`PAN_ATOMS` below :data:`MANY_BANDS`,
        :data:`PAN_ATOMS_MANY` from there on.
    name : str
        The option's name in the error message.

    Returns
    -------
    int
        The count, at most ``length``.

    Examples
    --------
    >>> from tensor_cosdi.solvers.subspace import pan_atoms_for
    >>> pan_atoms_for(28), pan_atoms_for(16), pan_atoms_for(2, 5)
    (8, 3, 2)
    """
    if isinstance(pan_atoms, str):
        if pan_atoms != "auto":
            raise ValueError(f"{name} must be an integer ≥ 1 or 'auto', got {pan_atoms!r}")
        pan_atoms = PAN_ATOMS_MANY if length >= MANY_BANDS else PAN_ATOMS
    return min(_check_int(name, pan_atoms, 1), int(length))


def has_many_bands(system) -> bool:
    """Whether a panchromatic axis of ``system`` has :data:`MANY_BANDS` samples or more.

    The schedules chosen on 28-band scenes (:data:`PAN_WEIGHTS_MANY`,
    :data:`PAN_ATOMS_MANY`, OTD's ``LAM_SCHEDULE_MANY``) apply there; fewer
    bands keep the ones their studies ran with.

    Parameters
    ----------
    system : tensor_cosdi.systems.System

    Returns
    -------
    bool
        ``False`` for a system without panchromatic axes.

    Examples
    --------
    >>> import numpy as np
    >>> import tensor_cosdi as tc
    >>> code = np.ones((8, 8))
    >>> has_many_bands(tc.systems.SDCASSI(code, n_bands=28))
    True
    >>> has_many_bands(tc.systems.SDCASSI(code, n_bands=16))
    False
    """
    imager(system, "axes", "panchromatic_axes")
    names = list(system.axes)
    longest = max((system.cube_shape[names.index(a)] for a in system.panchromatic_axes), default=0)
    return longest >= MANY_BANDS


def subspace_gap_tv(
    system,
    measurement,
    *,
    n_atoms="auto",
    max_iter: int = 60,
    tv_weight: float = 0.05,
    tv_steps: int | None = 10,
    eps: float = 1e-6,
    spectral_weights=None,
    refit_at=None,
    refit_above: float | None = None,
    refit_floor: float | None = None,
    progress: bool = False,
):
    """A fast first estimate for the panchromatic image: GAP-TV in a smooth spectral subspace.

    The decimated model of Eq. 62 assumes flat spectra (``F = Dᵀ Z / n``);
    on sheared systems that mismatch dominates (relative error 0.7-0.9 on
    64×64×16 scenes).  Here the panchromatic axes are instead spanned by
    their first ``n_atoms`` DCT atoms (``n_atoms = 1`` is the flat model; ``"auto"``:
    :func:`pan_atoms_for` each axis' length)
    and regularised by 2-D total variation of each coefficient image, in
    accelerated GAP iterations ``x ← P TV(Pᵀ(x + Aᵀ(AAᵀ + εI)⁻¹(ĝ − Ax)))``.
    TV runs on ``n_atoms`` images instead of ``Nλ``, so it costs a fraction
    of full GAP-TV.  On NumPy data whose one spanned axis is the last and whose cubes the
    operator keeps in Fortran order (the shearing systems), the iterates are held as those
    coefficient images between iterations: the same iterates to float rounding, without
    the cube-sized sum and stopping quantity of each iteration.

    ``spectral_weights`` (``{axis name: positive weights of its length}``) spans an axis by
    its DCT atoms times those weights instead (orthonormalised): spectra that are a smooth
    reflectance times a light's spectrum with sharp features (a white LED's blue peak) need
    many plain DCT atoms but few weighted by the light
    (:func:`fitted_mean_spectrum` estimates it).

    ``refit_at`` (one panchromatic axis, no ``spectral_weights``): after that many
    iterations, fit the mean spectrum to the measurement from the iterate
    (:func:`gate_spectrum`) and, where it reads rougher than ``refit_above`` (``None``:
    :data:`ROUGH_SPECTRUM`), span the axis by the atoms weighted by it — raised to at least
    ``refit_floor`` of its peak (``None``: :data:`GATE_FLOOR`) — for the remaining iterations,
    in the same run (its acceleration kept); a smooth spectrum leaves the run as it would have
    been.

    Returns
    -------
    cube : tensor of ``system.cube_shape``
        The subspace estimate; ``system.decimation.forward(cube)`` is ``Z``.
    """
    from .denoisers import WarmTV, tv

    pan_atoms_for(MANY_BANDS, n_atoms, name="n_atoms")  # checked before any work
    max_iter = _check_int("max_iter", max_iter, 1)
    g = measurement
    names = list(system.axes)
    modes = [names.index(a) for a in system.panchromatic_axes]
    shape = system.cube_shape
    keep = {m: pan_atoms_for(shape[m], n_atoms, name="n_atoms") for m in modes}
    weights = _check_weights(spectral_weights, system)
    if refit_at is not None:  # checked before any work
        refit_at = _check_int("refit_at", refit_at, 1)
        if len(modes) != 1 or weights:
            raise ValueError("refit_at needs one panchromatic axis and no spectral_weights")
        refit_above = _check_above(refit_above)
        refit_floor = _check_floor(refit_floor)
    elif refit_above is not None or refit_floor is not None:
        raise ValueError("refit_above and refit_floor set the gate of refit_at, which is None")

    def span(m, w=None):
        """The first atoms spanning mode ``m``: DCT, or the span of the DCT atoms weighted by
        ``w``, orthonormal."""
        atoms = dct(shape[m]) if w is None else np.linalg.qr(w[:, None] * dct(shape[m]))[0]
        return B.tensor_like(atoms[:, : keep[m]], g)

    mats = [span(m, weights.get(names[m])) for m in modes]
    denoise = tv if tv_steps is None else WarmTV(_check_int("tv_steps", tv_steps, 1))

    def subspace_tv(v, weight):
        return subspace_denoise(v, mats, modes, denoise, weight)

    if refit_at is None:
        prior = TV(tv_weight, denoise=subspace_tv)
    else:

        def refit(x):
            w, rough = gate_spectrum(system, g, x, names[modes[0]])
            if rough > refit_above:
                mats[0] = span(modes[0], np.maximum(w, refit_floor))

        prior = _RefitTV(tv_weight, denoise=subspace_tv, at=refit_at, refit=refit)
    x0 = engine.least_norm(system.operator, g, eps)
    step = _CoefficientStep(prior, mats, denoise) if _in_coefficients(g, x0, modes) else None
    x, _, _ = engine.gap(
        system.operator,
        g,
        prior,
        eps=eps,
        start=x0,
        max_iter=max_iter,
        progress=progress,
        desc="OTD stage 1: panchromatic",
        objective=False,  # an internal stage: its history is not returned
        step=step,
    )
    return x


def _in_coefficients(g, x0, modes) -> bool:
    """Whether :class:`_CoefficientStep` can run: NumPy arrays, one spanned axis, the last,
    and a Fortran-ordered start (the shear kernels' layout, whose band planes are contiguous)."""
    return (
        isinstance(g, np.ndarray)
        and isinstance(x0, np.ndarray)
        and len(modes) == 1
        and modes[0] == x0.ndim - 1
        and x0.ndim > 1
        and x0.flags.f_contiguous
        and not x0.flags.c_contiguous
    )


def _coefficients(v, m):
    """``v ×_last mᵀ`` for a Fortran-ordered ``v``: Fortran-ordered coefficient images."""
    rev = v.shape[::-1]
    return (m.T @ v.T.reshape(rev[0], -1)).reshape((m.shape[1], *rev[1:])).T


def _cube(c, m):
    """``c ×_last m`` for Fortran-ordered coefficient images: a Fortran-ordered cube."""
    rev = c.shape[::-1]
    return (m @ c.T.reshape(rev[0], -1)).reshape((m.shape[0], *rev[1:])).T


class _CoefficientStep:
    """:func:`~tensor_cosdi.solvers.engine.gap`'s ``step`` for the subspace TV prior with the
    iterates held as the coefficient images ``c`` of ``x = P c``: every iterate after the prox
    lies in the span of the atoms ``P`` (orthonormal columns), so ``Pᵀ(x + w) = c + Pᵀ w`` and
    ``‖x′ − x‖ / ‖x′‖ = ‖c′ − c‖ / ‖c′‖``, and the cube-sized sum and stopping quantity of an
    iteration shrink to the few coefficient images.  The same iterates up to float rounding;
    the start (the least-norm cube, outside the span) and an iteration after ``refit`` changed
    ``P`` take the full cube (``benchmarks/results/solver_steps.md``: a first stage at
    256×256×28)."""

    def __init__(self, prior, mats, denoise):
        self.prior, self.mats, self.denoise = prior, mats, denoise
        self.c, self.basis = None, None  # x's coefficients in ``basis`` (None: x is in no span)

    def __call__(self, x, w):
        m = self.mats[0]
        held = self.c is not None and self.basis is m
        if held:
            v = _coefficients(w, m)
            v += self.c
        else:  # the start, or the atoms changed: the full cube's coefficients
            v = _coefficients(w + x, m)
        c_new = np.asfortranarray(self.denoise(v, self.prior.strength))
        x_new = _cube(c_new, m)
        change = relative_change(c_new, self.c) if held else relative_change(x_new, x)
        self.c, self.basis = c_new, m
        return x_new, change


#: ``refit_at``'s gate: a fitted mean spectrum whose :func:`spectral_roughness` exceeds this
#: weights the atoms.  Read on every tuning scene as it is and lit by A, D65, LED-B3, FL11
#: and FL2, noiseless, 30 and 20 dB (``benchmarks/results/spectral_roughness.md``).
ROUGH_SPECTRUM = 0.1
#: ``refit_at``'s weights are the fitted spectrum raised to at least this share of its peak: a
#: lamp's gaps between its lines (FL11) otherwise leave atoms that barely reach those bands.
#: Chosen with the gate's thresholds from 1e-3 / 0.1 / 0.3
#: (:data:`~tensor_cosdi.solvers.panchromatic.GATE_ABOVE_CLEAN`;
#: ``benchmarks/results/light_gate.md``): ``pnp_fast`` on 8 tuning scenes lit by FL11 with the
#: gate open, 30 dB 43.89 / 47.26 / 47.16 dB (noiseless 48.94 / 49.03 / 47.82).
GATE_FLOOR = 0.1
#: :func:`spectral_roughness`: the DCT atoms that count as smooth.
SMOOTH_ATOMS = 6


def spectral_roughness(w, n_smooth: int = SMOOTH_ATOMS) -> float:
    """How far a spectrum ``w`` lies from its projection onto its first ``n_smooth`` DCT atoms,
    relative to its norm: about 0 for a smooth spectrum, large for a light's sharp lines.

    Parameters
    ----------
    w : array_like of shape (Nλ,)
        A spectrum: at least 2 finite values, not all 0 (its scale does not matter).
    n_smooth : int
        The DCT atoms that count as smooth (default :data:`SMOOTH_ATOMS`).

    Returns
    -------
    float
        ``‖w − P w‖ / ‖w‖`` with ``P`` the projection onto those atoms.

    Examples
    --------
    >>> round(spectral_roughness([1.0, 1.0, 1.0, 1.0]), 6)
    0.0
    >>> spectral_roughness([0.0, 0.0, 1.0, 0.0], 2) > 0.5
    True
    """
    n_smooth = _check_int("n_smooth", n_smooth, 1)
    try:
        w = real_array("the spectrum", w, finite=False)
    except TypeError:
        raise ValueError(f"the spectrum must be numbers, got {type(w).__name__}") from None
    if w.ndim != 1 or w.size < 2 or not np.isfinite(w).all() or not np.abs(w).max() > 0:
        raise ValueError(
            f"the spectrum must be a 1-D array of at least 2 finite values, not all 0; got shape "
            f"{w.shape}"
        )
    atoms = dct(w.size)[:, : min(n_smooth, w.size)]
    rest = w - atoms @ (atoms.T @ w)
    return float(np.linalg.norm(rest) / max(np.linalg.norm(w), 1e-300))


def gate_spectrum(system, measurement, cube, axis: str):
    """``(w, roughness)``: the mean spectrum fitted from ``cube`` (:func:`fitted_mean_spectrum`)
    and its :func:`spectral_roughness`, the reading that ``refit_at`` of
    :func:`subspace_gap_tv` compares with :data:`ROUGH_SPECTRUM`.

    Parameters
    ----------
    system, measurement, cube, axis
        As in :func:`fitted_mean_spectrum`.

    Returns
    -------
    w : ndarray of the axis' length
        The fitted spectrum, peak 1.
    roughness : float
    """
    w = fitted_mean_spectrum(system, measurement, cube, axis)
    return w, spectral_roughness(w)


class _RefitTV(TV):
    """:class:`TV` that calls ``refit(x)`` once, after iteration ``at``."""

    def __init__(self, weight, *, denoise, at, refit):
        super().__init__(weight, denoise=denoise)
        self.at, self.refit = at, refit

    def update(self, x, iteration: int) -> None:
        if iteration == self.at:
            self.refit(x)


def _check_above(above):
    if above is None:
        return ROUGH_SPECTRUM
    if isinstance(above, bool) or not isinstance(above, numbers.Real) or not above >= 0:
        raise ValueError(f"refit_above must be a number >= 0 (inf: never refit), got {above!r}")
    return float(above)


def _check_floor(floor):
    if floor is None:
        return GATE_FLOOR
    if isinstance(floor, bool) or not isinstance(floor, numbers.Real) or not 0 < floor <= 1:
        raise ValueError(f"refit_floor must be a number in (0, 1], got {floor!r}")
    return float(floor)


def _check_weights(spectral_weights, system) -> dict:
    if spectral_weights is None:
        return {}
    if not isinstance(spectral_weights, dict):
        raise ValueError(
            f"spectral_weights must be None or a dict {{axis name: weights}}, got "
            f"{type(spectral_weights).__name__}"
        )
    names = list(system.axes)
    out = {}
    for name, w in spectral_weights.items():
        if name not in system.panchromatic_axes:
            raise ValueError(
                f"spectral_weights: {name!r} is not a panchromatic axis of {system.name} "
                f"({list(system.panchromatic_axes)})"
            )
        n = system.cube_shape[names.index(name)]
        w = real_array(f"spectral_weights: the weights of {name!r}", B.to_numpy(w), finite=False)
        if w.shape != (n,) or not np.isfinite(w).all() or not (w > 0).all():
            raise ValueError(
                f"spectral_weights[{name!r}] must be {n} finite weights > 0, got shape "
                f"{w.shape} with values in [{np.min(w, initial=np.inf):g}, "
                f"{np.max(w, initial=-np.inf):g}]"
            )
        out[name] = w
    return out


def fitted_mean_spectrum(system, measurement, cube, axis: str, *, floor: float = 1e-3):
    """The scene's mean spectrum along the panchromatic ``axis``, fitted to the measurement.

    With ``a`` the sum of ``cube`` (a first estimate, e.g. :func:`subspace_gap_tv`'s) over
    ``axis``, the cube ``a ⊗ s`` — every pixel the same spectrum ``s``, scaled — is fitted to
    the measurement by non-negative least squares over ``s`` (one forward pass per band: the
    columns ``A(a ⊗ e_l)``).  A light's sharp spectral features (a white LED's blue peak)
    survive the fit, though the estimate itself had to be smooth; on a scene whose mean
    spectrum is flat the fit is mostly noise, which is why
    :func:`~tensor_cosdi.solvers.panchromatic.panchromatic_estimate` keeps the weighted basis
    only while it fits the measurement nearly as well as the plain one
    (:func:`~tensor_cosdi.solvers.panchromatic.keeps_fitted`).

    Parameters
    ----------
    system : tensor_cosdi.systems.System
    measurement : tensor of ``system.measurement_shape``
    cube : tensor of ``system.cube_shape``
        A first estimate; only its sum over ``axis`` is used (negative values count as 0).
    axis : str
        A name of ``system.panchromatic_axes`` (the bands, ``"λ"``).
    floor : float
        The smallest weight returned, relative to the peak (weighted atoms need weights > 0).

    Returns
    -------
    ndarray of the axis' length: ``s`` scaled to a peak of 1, at least ``floor``.
    """
    from scipy.optimize import nnls

    names = list(system.axes)
    if axis not in system.panchromatic_axes:
        raise ValueError(
            f"{axis!r} is not a panchromatic axis of {system.name} "
            f"({list(system.panchromatic_axes)})"
        )
    mode = names.index(axis)
    x = np.maximum(np.asarray(B.to_numpy(cube), dtype=np.float32), 0.0)
    if x.shape != tuple(system.cube_shape):
        raise ValueError(f"cube of shape {x.shape} does not match {tuple(system.cube_shape)}")
    a = x.sum(axis=mode, keepdims=True)
    g = np.asarray(B.to_numpy(measurement), dtype=np.float32).ravel()
    n = x.shape[mode]
    # one measurement per band, a column each (contiguous: written in one pass), from one cube
    # whose band slice is filled in turn, in the estimate's memory order: a solver's
    # Fortran-ordered iterate gives contiguous band slices and the shear kernels' fast layout.
    # A NumPy measurement's cube goes to the operator as it is, not copied per band.
    # 256×256×28, TSA mask: ``benchmarks/results/solver_steps.md``.
    cols = np.empty((g.size, n), dtype=np.float32, order="F")
    e = np.zeros(x.shape, dtype=np.float32, order="F" if x.flags.f_contiguous else "C")
    numpy_in = isinstance(measurement, np.ndarray)
    if numpy_in and measurement.dtype.kind == "f" and measurement.dtype != e.dtype:
        e = e.astype(measurement.dtype, order="K")  # (integer counts: the float32 cube)
    index = [slice(None)] * x.ndim
    for band in range(n):
        index[mode] = slice(band, band + 1)
        e[tuple(index)] = a
        cube_in = e if numpy_in else B.tensor_like(e, measurement)
        cols[:, band] = np.asarray(B.to_numpy(system.operator.apply(cube_in))).ravel()
        e[tuple(index)] = 0.0
    cols = cols.astype(np.float64)  # the normal equations summed in float64: 79,360 terms a
    # sum at 256×256×28, where a float32 sum's rounding depends on the order BLAS takes
    s, _ = nnls(cols.T @ cols, cols.T @ g.astype(np.float64))
    peak = s.max()
    if not peak > 0:
        return np.ones(n)
    return np.maximum(s / peak, floor)


def subspace_denoise(v, atoms, modes, denoise, weight):
    """``P denoise(Pᵀ v, weight)`` with ``P`` the ``atoms`` matrices along ``modes``: a denoiser
    run on a few coefficient images instead of every band (the subspace TV of
    :func:`subspace_gap_tv`).

    A Fortran-ordered NumPy ``v`` (the shear kernels' layout, which the solvers keep) with one
    mode, its last axis, gives a Fortran-ordered result: ``vᵀ`` is C-ordered with that axis
    first, so both products are single GEMMs.  The general mode products return the transformed
    axis first in memory, and every shear of the next iteration paid for it (90 iterations of
    :func:`subspace_gap_tv` at 256×256×28: 1.45 → 1.13 s, medians of four alternated runs, the
    same estimate).

    >>> import numpy as np
    >>> from tensor_cosdi.bases import dct
    >>> v = np.asfortranarray(np.random.default_rng(0).random((4, 5, 6)))
    >>> out = subspace_denoise(v, [dct(6)[:, :2]], [2], lambda c, w: c, 0.1)
    >>> out.flags.f_contiguous, out.shape
    (True, (4, 5, 6))
    """
    if (
        isinstance(v, np.ndarray)
        and list(modes) == [v.ndim - 1]
        and v.ndim > 1
        and v.flags.f_contiguous
        and not v.flags.c_contiguous
    ):
        m = np.asarray(atoms[0])
        return _cube(np.asfortranarray(denoise(_coefficients(v, m), weight)), m)
    coef = tenalg.multi_mode_dot(v, atoms, modes=modes, transpose=True)
    return tenalg.multi_mode_dot(denoise(coef, weight), atoms, modes=modes)
