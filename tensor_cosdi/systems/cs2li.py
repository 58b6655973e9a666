"""CS2LI: compressive spectral structured light, a dual disperser with a colour-coded mirror (SPEC
§3.4)."""

from __future__ import annotations

import numpy as np
import tensorly as tl

from .. import _backend as B
from .. import validate
from ..codes import colour_coded_aperture
from ..validate import real_array
from ._base import (
    System,
    as_code,
    coded_state,
    count,
    dual_disperser,
    dual_disperser_matrix,
    dual_disperser_operator,
    shifts_for,
    wavelengths_for,
)

__all__ = ["CS2LI", "fringe_cube"]


class CS2LI(System):
    """Spectral structured light through a double Amici prism passed twice (Equation 113-115).

    The prism, a colour-coded mirror and the prism again form a dual
    disperser, so each pattern's measurement is aligned with the scene::

        G[:, :, t] = Σ_l Ceff[:, :, l] ∘ P[:, :, l, t],   Ceff[:, :, l] = C[:, s_l : s_l + Ny, l]

    (Eq. 113 with the code index ``i2 + s_l`` of SPEC §12).

    Parameters
    ----------
    code : array_like of shape (Nx, Ny + S) or (Nx, Ny + S, Nλ)
        Binary coded aperture (the same for every band) or colour-coded
        aperture (:func:`tensor_cosdi.codes.colour_coded_aperture`), ``S =
        ⌈max s_l⌉`` extra columns.
    n_bands, n_patterns : int
        ``Nλ`` and ``Nt`` (projected patterns; :func:`fringe_cube` builds
        ``P`` from a reflectance cube and fringe phases).
    shifts, wavelengths
        As for :class:`~tensor_cosdi.systems.SDCASSI`.

    Attributes
    ----------
    cube_shape : ``(Nx, Ny, Nλ, Nt)``, axes ``("x", "y", "λ", "t")``
    measurement_shape : ``(Nx, Ny, Nt)``
    panchromatic_axes : ``("λ",)`` — the grayscale fringe images ``Z (Nx, Ny, Nt)``.

    Notes
    -----
    ``H = I_Nt ⊗ A`` and ``A Aᵀ = diag(Σ_l Ceff_l²)`` (Eq. 115, SPEC §4).

    Examples
    --------
    >>> import numpy as np
    >>> from tensor_cosdi.systems import CS2LI
    >>> CS2LI(np.ones((4, 7)), n_bands=3, n_patterns=8).cube_shape
    (4, 5, 3, 8)
    """

    name = "cs2li"
    demo_scene = "coffee"
    has_depth = True
    #: ``n_filters``: colour filters of the example's code (1: a binary code, the same for
    #: every band).
    example_options = {"n_steps": 4, "n_filters": 6}
    depth_kind = "phase"
    #: Phase-shifted fringes of one frequency are three images per pixel (``a``, ``b cos φ``,
    #: ``b sin φ``) over ``K ≥ 4`` steps: the frames' smallest singular value is noise, where a
    #: fit's residual reads the fringes' fine texture through the code as noise.
    snr_frames_low_rank = True

    @property
    def otd_lam_anchors(self):
        """OTD's sparsity weight at 30 and 20 dB (``System.otd_lam_anchors``) with a colour
        code, where a third of SD-CASSI's weight serves best.  4-fold cross-validation over 16
        tuning scenes at 64×64×16 with the example's colour code
        (``benchmarks/results/otd_lam_cs2li.md``): 30 dB 0.03 (every fold; held out 31.93 dB
        against 31.50 at SD-CASSI's 0.1), 20 dB 0.1 (three folds of four; 29.23 against 29.11
        at ≈ 0.3); noiseless stays at the general anchor.  A binary (2-D) code keeps the
        general schedule (``None``): cross-validated the same way
        (``benchmarks/results/otd_lam_cs2li_n_filters1.md``), its best at 30 dB (0.03) leads
        by 0.05 dB held out, the folds split between 0.03 and 0.06."""
        return {30.0: 0.03, 20.0: 0.1} if self.code.ndim == 3 else None

    def _state(self):
        params, arrays = coded_state(self)
        return {**params, "n_patterns": int(self.cube_shape[3])}, arrays

    def depth_from_cube(self, cube, *, n_steps: int = 4, max_disparity: float = 2.0):
        """Wrapped fringe phase per frequency ``(Nx, Ny, Nt / K)`` of the band sums (N-step PSA, ``K
        = n_steps``)."""
        return fringe_phase(cube, n_steps)

    def spectral_view(self, cube):
        """The reflectance: the mean over the phase steps (fringe offset 1, Equation 107)."""
        return real_array("cube", B.to_numpy(cube), finite=False).mean(axis=3)

    @classmethod
    def _example(cls, scene, shape, wl, seed, shifts, n_steps, n_filters):
        n_filters = validate.integer("n_filters", n_filters, low=1)
        return fringe_example(cls, scene, shape, wl, seed, shifts, n_steps, n_filters=n_filters)

    def __init__(self, code, *, n_bands, n_patterns, shifts=1, wavelengths=None):
        self.code = as_code(code, "code", (2, 3))
        nl = count(n_bands, "n_bands")
        nt = count(n_patterns, "n_patterns")
        self.shifts, self.effective_code = dual_disperser(self.code, nl, shifts)
        nx, ny = self.effective_code.shape[:2]
        self._finish(
            dual_disperser_operator(self.effective_code, (nx, ny, nl, nt)),
            wavelengths=wavelengths_for(wavelengths, nl),
            axes=("x", "y", "λ", "t"),
            measurement_axes=("x", "y", "t"),
        )

    @classmethod
    def example(
        cls, cube_shape=None, *, rng=0, n_filters: int = 6, transmittance: float = 0.5, **overrides
    ):
        """A seeded instance with a colour-coded aperture (default cube ``(16, 16, 8, 4)``).

        ``n_filters=1`` gives a binary code (2-D).
        """
        nx, ny, nl, nt = (16, 16, 8, 4) if cube_shape is None else cube_shape
        _, extra = shifts_for(overrides.get("shifts", 1), nl)
        nf = min(n_filters, nl)
        code = colour_coded_aperture(
            (nx, ny + extra), nl, n_filters=nf, transmittance=transmittance, rng=rng
        )
        if nf == 1:
            code = code[:, :, 0]
        return cls(code, n_bands=nl, n_patterns=nt, **overrides)

    def matrix(self):
        nx, ny, nl, nt = self.cube_shape
        return dual_disperser_matrix(self.code, self.shifts, ny, nt)


def fringe_cube(
    reflectance, phases, *, n_steps: int = 4, offset: float = 1.0, amplitude: float = 1.0
):
    """The cube ``P`` a CS2LI senses: reflectance under phase-shifted white fringes (Equation 107).

    ``P[x, y, l, f·K + k] = F[x, y, l] · (offset + amplitude · cos(φ_f(x, y) + 2πk/K))``
    for frequency ``f`` and step ``k = 0 … K−1`` — so each frequency
    contributes ``K`` consecutive patterns, and ``Σ_k`` over a full cycle
    gives ``K · offset · F``.

    Parameters
    ----------
    reflectance : tensor of shape (Nx, Ny, Nλ)
    phases : array_like of shape (Nx, Ny) or (Nx, Ny, n_freq)
        Fringe phase of each frequency at every pixel (radians), e.g. the
        projector phase ``2πν·y/L`` deformed by the scene's height.
    n_steps : int ≥ 3
        ``K`` phase steps per frequency (thesis: 4).
    offset, amplitude : float
        ``b`` and the fringe contrast; ``0 ≤ amplitude ≤ offset`` so that the
        projected light is never negative.

    Returns
    -------
    tensor of shape ``(Nx, Ny, Nλ, n_freq · K)`` on the reflectance's backend.

    Examples
    --------
    >>> import numpy as np
    >>> P = fringe_cube(np.ones((2, 3, 4)), np.zeros((2, 3)), n_steps=4)
    >>> P.shape, P[0, 0, 0].round(12).tolist()
    ((2, 3, 4, 4), [2.0, 1.0, 0.0, 1.0])
    """
    n_steps = validate.integer("n_steps (phase shifting needs 3)", n_steps, low=3, high=1024)
    offset = validate.number("offset", offset)
    amplitude = validate.number("amplitude", amplitude)
    if not 0 <= amplitude <= offset:
        raise ValueError(
            f"need 0 ≤ amplitude ≤ offset so the projected light is ≥ 0, got offset={offset!r}, "
            f"amplitude={amplitude!r}"
        )
    shape = tuple(tl.shape(reflectance)) if tl.is_tensor(reflectance) else np.shape(reflectance)
    if len(shape) != 3:
        raise ValueError(f"reflectance must have shape (Nx, Ny, Nλ), got {shape}")
    ph = real_array("phases", B.to_numpy(phases), finite=False)
    if ph.ndim == 2:
        ph = ph[:, :, None]
    if ph.ndim != 3 or ph.shape[:2] != shape[:2]:
        raise ValueError(
            f"phases must have shape {shape[:2]} or {shape[:2]} + (n_freq,), got {ph.shape}"
        )
    if not np.isfinite(ph).all():
        raise ValueError("phases contain NaN or inf")
    k = np.arange(n_steps)
    mod = offset + amplitude * np.cos(ph[:, :, :, None] + 2 * np.pi * k / n_steps)  # (Nx, Ny, f, K)
    mod = mod.reshape(shape[:2] + (-1,))  # t = f·K + k
    if isinstance(reflectance, np.ndarray) or not tl.is_tensor(reflectance):
        F = real_array("reflectance", reflectance)  # NumPy in, NumPy out (any backend)
        return F[:, :, :, None] * mod[:, :, None, :]
    F = reflectance
    return F[:, :, :, None] * B.tensor_like(mod[:, :, None, :], F)


# ---- fringe helpers shared with Mu-CoSDI's structured-light modality ----------------------
def fringe_phase(cube, n_steps: int):
    """Wrapped fringe phase per frequency ``(Nx, Ny, Nt / K)`` of the band sums of a ``(Nx, Ny, Nλ,
    Nt)`` cube.

    ``K = n_steps`` when it divides ``Nt`` (frequency-major patterns), else
    all ``Nt`` patterns as one sequence; ``None`` with fewer than 3 patterns.
    """
    from ..depth import wrapped_phase

    z = real_array("cube", B.to_numpy(cube), finite=False).sum(axis=2)
    nt = z.shape[2]
    K = n_steps if nt % n_steps == 0 and n_steps >= 3 else nt
    if K < 3:
        return None
    return np.stack([wrapped_phase(z[..., i * K : (i + 1) * K]) for i in range(nt // K)], axis=-1)


def fringe_example(cls, scene, shape, wl, seed, shifts, n_steps, **example):
    """The CS2LI / Mu-CoSDI ``"sl"`` problem: one fringe frequency of ``n_steps`` phase steps
    (``example``: options of ``cls.example``)."""
    from .. import scenes

    reflectance = scenes.scene_cube(scene, shape, wl)
    sl = scenes.structured_light(shape, wl, rng=seed)
    cube = np.asarray(fringe_cube(reflectance, sl.phase, n_steps=n_steps, amplitude=0.5))
    system = cls.example(
        shape + (len(wl), n_steps), rng=seed, shifts=shifts, wavelengths=wl, **example
    )
    return (
        system,
        cube,
        reflectance,
        sl.height,
        {"phase": sl.phase, "phase_per_height": sl.phase_per_height},
    )
