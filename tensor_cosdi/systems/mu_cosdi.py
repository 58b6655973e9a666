"""Mu-CoSDI: the multimodal dual-disperser imager (SPEC §3.5, thesis Ch. 7/8)."""

from __future__ import annotations

from .. import _backend as B
from ..codes import random_binary
from ..operators import LAYOUTS, LightFieldLayout
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
from ._roles import views_disparity
from .cs2li import fringe_example, fringe_phase

__all__ = ["MuCoSDI", "MODALITIES"]

#: modality → (required options, optional options with defaults)
MODALITIES = {
    "sl": ({"n_patterns"}, {}),
    "lf": ({"views"}, {"raw_layout": "interleaved"}),
    "monocular": (set(), {"depth_estimator": None}),
}


class MuCoSDI(System):
    """Dual-disperser spectral core plus one depth modality (Equation 144-151).

    A binary code sheared by ``Γ(l) = γ·l`` (``shifts=γ``) modulates the cube
    the way CS2LI's does, ``G = Σ_l Ceff_l ∘ F_l`` with
    ``Ceff[:, c, l] = C[:, c + Γ(l)]``; the modality decides what the cube is:

    ``modality="sl"`` (projector; option ``n_patterns``)
        cube ``(Nx, Ny, Nλ, Nt)`` under ``Nt`` patterns, measurement
        ``(Nx, Ny, Nt)``; depth by phase shifting.
    ``modality="lf"`` (lenslet array; options ``views=(Nu, Nv)``, ``raw_layout``)
        cube = the lenslet image ``(Nx·Nu, Ny·Nv, Nλ)`` of a spectral light
        field (interleaved as Eq. 85, or tiled), measurement ``(Nx·Nu, Ny·Nv)``;
        depth from the views (:meth:`to_views`).
    ``modality="monocular"`` (option ``depth_estimator``, a callable)
        cube ``(Nx, Ny, Nλ)``, measurement ``(Nx, Ny)``; depth from a
        user-supplied estimator (:meth:`estimate_depth`).

    Parameters
    ----------
    code : array_like of shape (H, W + S)
        Coded aperture; ``(H, W)`` is the measurement's spatial size and
        ``S = ⌈max Γ⌉``.
    n_bands : int
    modality : {"sl", "lf", "monocular"}
    shifts : int, float or sequence
        ``γ`` (``Γ(l) = γ·l``) or per-band shifts.
    wavelengths : sequence of float, optional
    **modality_options
        As listed above; unknown or missing ones are a ``ValueError``.

    Notes
    -----
    ``A Aᵀ = diag(Σ_l Ceff_l ∘ Ceff_l)`` (Eq. 148, 151 with SPEC §12's fix),
    ``H = I_Nt ⊗ A`` for structured light (Eq. 144).

    Examples
    --------
    >>> import numpy as np
    >>> from tensor_cosdi.systems import MuCoSDI
    >>> MuCoSDI(np.ones((8, 11)), n_bands=4, modality="lf", views=(2, 2)).cube_shape
    (8, 8, 4)
    """

    name = "mu_cosdi"
    demo_scene = "rocket"
    has_depth = True
    example_options = {"n_steps": 4}

    @property
    def depth_kind(self):
        if self.modality == "sl":
            return "phase"
        if self.modality == "lf":
            return "disparity"
        return None if self.depth_estimator is None else "estimator"

    @property
    def snr_frames_low_rank(self) -> bool:
        """``True`` with the projector (``"sl"``): its phase steps are low-rank as CS2LI's (see
        :attr:`CS2LI.snr_frames_low_rank`)."""
        return self.modality == "sl"

    def _state(self):
        params, arrays = coded_state(self)
        params["modality"] = self.modality
        if self.modality == "sl":
            params["n_patterns"] = int(self.n_patterns)
        elif self.modality == "lf":
            params.update(views=list(self.views), raw_layout=self.raw_layout)
        elif self.depth_estimator is not None:
            raise ValueError(
                "a Mu-CoSDI with a depth_estimator callable cannot be saved (code is not data); "
                "save it without one and pass the estimator again after loading"
            )
        return params, arrays

    @classmethod
    def _from_state(cls, params, arrays):
        if "views" in params:
            params["views"] = tuple(params["views"])
        return cls(
            arrays["code"], shifts=arrays["shifts"], wavelengths=arrays["wavelengths"], **params
        )

    def depth_from_cube(self, cube, *, n_steps: int = 4, max_disparity: float = 2.0):
        """``"sl"``: wrapped fringe phase per frequency; ``"lf"``: centre-view disparity;
        ``"monocular"``: the estimator."""
        if self.modality == "sl":
            return fringe_phase(cube, n_steps)
        if self.modality == "lf":
            return views_disparity(self.to_views(cube), max_disparity)
        return None if self.depth_estimator is None else self.estimate_depth(cube)

    def spectral_view(self, cube):
        """``"sl"``: the mean over the phase steps (the reflectance); otherwise the cube."""
        c = real_array("cube", B.to_numpy(cube), finite=False)
        return c.mean(axis=3) if self.modality == "sl" else c

    @classmethod
    def _example(cls, scene, shape, wl, seed, shifts, n_steps):
        return fringe_example(cls, scene, shape, wl, seed, shifts, n_steps)

    def __init__(
        self, code, *, n_bands, modality="sl", shifts=1, wavelengths=None, **modality_options
    ):
        if modality not in MODALITIES:
            raise ValueError(f"modality must be one of {tuple(MODALITIES)}, got {modality!r}")
        required, optional = MODALITIES[modality]
        unknown = set(modality_options) - required - set(optional)
        if unknown:
            valid = sorted(required | set(optional)) or ["none"]
            raise ValueError(
                f"unknown option(s) {sorted(unknown)} for modality {modality!r}; valid: {valid}"
            )
        missing = required - set(modality_options)
        if missing:
            raise ValueError(f"modality {modality!r} needs the option(s) {sorted(missing)}")
        opts = dict(optional, **modality_options)
        self.modality = modality
        self.code = as_code(code, "code", (2,))
        nl = count(n_bands, "n_bands")
        self.shifts, self.effective_code = dual_disperser(self.code, nl, shifts)
        h, w = self.effective_code.shape[:2]
        self.n_patterns = self.views = self.raw_layout = self.depth_estimator = None
        if modality == "sl":
            self.n_patterns = count(opts["n_patterns"], "n_patterns")
            cube = (h, w, nl, self.n_patterns)
            axes, maxes = ("x", "y", "λ", "t"), ("x", "y", "t")
        else:
            cube = (h, w, nl)
            axes, maxes = ("x", "y", "λ"), ("x", "y")
        if modality == "lf":
            views = opts["views"]
            try:
                nu, nv = (count(v, "views") for v in views)
            except TypeError:
                raise ValueError(
                    f"views must be a pair of positive integers (Nu, Nv), got {views!r}"
                ) from None
            if h % nu or w % nv:
                raise ValueError(
                    f"views ({nu}, {nv}) do not divide the lenslet image {(h, w)}: its size "
                    "must be "
                    "(Nx·Nu, Ny·Nv)"
                )
            if opts["raw_layout"] not in LAYOUTS:
                raise ValueError(f"raw_layout must be one of {LAYOUTS}, got {opts['raw_layout']!r}")
            self.views, self.raw_layout = (nu, nv), opts["raw_layout"]
        if modality == "monocular":
            est = opts["depth_estimator"]
            if est is not None and not callable(est):
                raise ValueError(
                    f"depth_estimator must be a callable cube → depth map, got {est!r}"
                )
            self.depth_estimator = est
        self._finish(
            dual_disperser_operator(self.effective_code, cube),
            wavelengths=wavelengths_for(wavelengths, nl),
            axes=axes,
            measurement_axes=maxes,
        )

    @classmethod
    def example(
        cls,
        cube_shape=None,
        *,
        rng=0,
        modality: str = "sl",
        transmittance: float = 0.5,
        **overrides,
    ):
        """A seeded instance with a random binary code.

        Default cubes: ``(16, 16, 8, 4)`` for ``"sl"``, ``(16, 16, 8)`` with
        ``views=(2, 2)`` for ``"lf"``, ``(16, 16, 8)`` for ``"monocular"``.
        """
        if cube_shape is None:
            cube_shape = (16, 16, 8, 4) if modality == "sl" else (16, 16, 8)
        h, w, nl = cube_shape[:3]
        if modality == "sl":
            overrides.setdefault("n_patterns", cube_shape[3])
        if modality == "lf":
            overrides.setdefault("views", (2, 2))
        _, extra = shifts_for(overrides.get("shifts", 1), nl)
        code = random_binary((h, w + extra), transmittance=transmittance, rng=rng)
        return cls(code, n_bands=nl, modality=modality, **overrides)

    def _lenslet(self):
        if self.modality != "lf":
            raise ValueError(
                f"views exist only for modality 'lf', this system is {self.modality!r}"
            )
        h, w, nl = self.cube_shape
        nu, nv = self.views
        return LightFieldLayout((h // nu, w // nv, nl, nu, nv), self.raw_layout)

    def to_views(self, cube):
        """Lenslet-layout cube → spectral light field ``(Nx, Ny, Nλ, Nu, Nv)`` (modality
        ``"lf"``)."""
        return self._lenslet().adjoint(cube)

    def from_views(self, light_field):
        """Spectral light field ``(Nx, Ny, Nλ, Nu, Nv)`` → this system's lenslet-layout cube."""
        return self._lenslet().forward(light_field)

    def estimate_depth(self, cube):
        """Depth map from a reconstructed cube with the user's estimator (modality
        ``"monocular"``)."""
        if self.modality != "monocular":
            raise ValueError(
                f"estimate_depth uses the monocular estimator; modality {self.modality!r} gets its "
                "depth from tensor_cosdi.depth"
            )
        if self.depth_estimator is None:
            raise ValueError("this system has no depth_estimator; pass one to the constructor")
        return self.depth_estimator(cube)

    def matrix(self):
        ny = self.cube_shape[1]
        return dual_disperser_matrix(self.code, self.shifts, ny, self.n_patterns or 1)
