"""What the rest of the library asks of every system, in one place: state, frames, depth, examples.

:class:`SystemRoles` is a base of :class:`~tensor_cosdi.systems.System`;
each imager overrides only what differs from the defaults here:

* ``to_state()`` / ``from_state(state)`` — what a bundle stores (JSON-able
  ``params`` plus named ``arrays``); ``from_state(to_state())`` rebuilds a
  system with a bit-identical forward;
* ``frame_count`` / ``frames_to_measurement`` / ``measurement_to_frames`` —
  the documented order of sensor frames of one capture;
* ``depth_kind`` and ``depth_from_cube(cube)`` — the depth channel of a
  reconstructed cube (``None`` for spectral-only systems);
* ``spectral_view(cube)`` — an ``(Nx, Ny, Nλ)`` reflectance-like view for previews;
* ``example_problem(scene, …)`` — the seeded demo / study problem
  (:class:`Problem`: system, ground truth, noisy measurement).

``io``, ``depth``, ``studies``, ``cli`` and the tests call these through
:data:`tensor_cosdi.systems.REGISTRY`; none of them names a system class.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from .. import _backend as B
from ..validate import real_array
from .registry import REGISTRY

__all__ = ["Problem", "SystemRoles", "stack_frames"]


@dataclass(frozen=True)
class Problem:
    """A simulated acquisition.

    Attributes
    ----------
    name : str
        ``"<system>/<scene>"``.
    system : tensor_cosdi.systems.System
    cube : tensor of ``system.cube_shape``
        The ground truth the measurement was simulated from (a tensor of the
        TensorLy backend active when the problem was made; NumPy by default).
    measurement : tensor of ``system.measurement_shape`` (same backend)
    wavelengths : ndarray (Nλ,)
    snr_db : float or None
    reflectance : ndarray (Nx, Ny, Nλ)
        The scene's spectral reflectance (for sRGB previews; for C3SLFI the
        centre view, for CASSDI-DFA the all-in-focus cube).
    depth : ndarray (Nx, Ny) or None
        The depth-plane index (CASSDI-DFA), disparity (C3SLFI) or height
        (CS2LI, Mu-CoSDI) the scene was built with.
    extras : dict
        Anything else the scene was built with (CS2LI / Mu-CoSDI: the fringe
        ``"phase"`` and ``"phase_per_height"``).
    """

    name: str
    system: Any
    cube: np.ndarray
    measurement: Any
    wavelengths: np.ndarray
    snr_db: float | None
    reflectance: np.ndarray
    depth: np.ndarray | None = None
    extras: dict = field(default_factory=dict)


def _frame_values(f, what: str) -> np.ndarray:
    """``f`` as float64, or a ``ValueError`` naming ``what``: real numbers only (a complex frame
    would lose its imaginary part), all finite (a NaN pixel would reach every estimate)."""
    a = np.asarray(B.to_numpy(f))
    if a.dtype.kind not in "biuf":
        raise ValueError(f"{what} must hold real numbers, got dtype {a.dtype}")
    a = a.astype(np.float64)
    if not np.isfinite(a).all():
        bad = int(np.size(a) - np.count_nonzero(np.isfinite(a)))
        raise ValueError(
            f"{what} holds {bad} NaN or infinite pixel(s); replace them (e.g. by their "
            "neighbours' median) before stacking"
        )
    return a


def stack_frames(frames) -> np.ndarray:
    """A list of 2-D frames or an ``(H, W[, N])`` array → an ``(H, W, N)`` float64 stack of
    finite real values."""
    if isinstance(frames, (list, tuple)):
        if not frames:
            raise ValueError("no frames given")
        shapes = {np.shape(f) for f in frames}
        if len(shapes) != 1:
            raise ValueError(f"frames of different shapes: {sorted(shapes)}")
        a = np.stack([_frame_values(f, f"frame {i}") for i, f in enumerate(frames)], axis=-1)
    else:
        a = _frame_values(frames, "the frames")
        if a.ndim == 2:
            a = a[..., None]
    if a.ndim != 3:
        raise ValueError(
            f"frames must be a (H, W, N) stack or a list of 2-D frames, got shape {a.shape}"
        )
    return a


class SystemRoles:
    """Defaults of the per-system roles (see the module notes); subclasses override what differs."""

    #: The stable name of :data:`tensor_cosdi.systems.REGISTRY`.
    name: ClassVar[str] = ""
    #: Options of :meth:`example_problem` beyond the common ones, with defaults.
    example_options: ClassVar[dict] = {}
    #: ``"planes"``, ``"phase"``, ``"disparity"``, ``"estimator"`` or ``None`` (what
    #: :meth:`depth_from_cube` returns).
    depth_kind: ClassVar[str | None] = None
    #: Whether instances of the class can have a depth channel at all.
    has_depth: ClassVar[bool] = False
    #: The scene and options ``tensor-cosdi demo`` shows this imager with (``None``: not in the
    #: demo).
    demo_scene: ClassVar[str | None] = None
    demo_options: ClassVar[dict] = {}

    # ---- state (bundles) -------------------------------------------------------------
    def _state(self) -> tuple[dict, dict]:
        """``(params, arrays)``; this default fits the systems built from ``code``, ``shifts``,
        ``n_bands``."""
        return {"n_bands": int(self.n_bands)}, {
            "code": np.asarray(self.code),
            "shifts": np.asarray(self.shifts),
        }

    @classmethod
    def _from_state(cls, params: dict, arrays: dict):
        return cls(
            arrays["code"], shifts=arrays["shifts"], wavelengths=arrays["wavelengths"], **params
        )

    def to_state(self) -> dict:
        """``{"system", "class", "params", "arrays"}``: JSON-able parameters and named NumPy arrays.

        :meth:`from_state` of it rebuilds a system whose forward is bit-identical.
        """
        params, arrays = self._state()
        arrays = {
            "wavelengths": np.asarray(self.wavelengths),
            **{k: np.asarray(v) for k, v in arrays.items()},
        }
        return {
            "system": self.name,
            "class": type(self).__name__,
            "params": dict(params),
            "arrays": arrays,
        }

    @classmethod
    def from_state(cls, state: dict):
        """Rebuild a system from :meth:`to_state` (called on ``System``, the registry picks the
        class)."""
        if not isinstance(state, dict) or "params" not in state or "arrays" not in state:
            raise ValueError(
                "a system state is a dict with 'system', 'params' and 'arrays' (System.to_state())"
            )
        name = state.get("system") or REGISTRY.name_of_class(state.get("class"))
        target = REGISTRY[name]
        if cls.name and cls is not target:
            raise ValueError(f"the state describes a {name!r} system, not {cls.name!r}")
        arrays = dict(state["arrays"])
        if "wavelengths" not in arrays:
            raise ValueError(f"the {name!r} state has no 'wavelengths' array")
        return target._from_state(dict(state["params"]), arrays)

    # ---- frames (captures) -----------------------------------------------------------
    @property
    def frame_count(self) -> int:
        """How many sensor frames one measurement takes."""
        shape = self.measurement_shape
        return shape[2] if len(shape) == 3 else 1

    def frames_to_measurement(self, frames) -> np.ndarray:
        """Stack of sensor frames (list of ``(H, W)`` or ``(H, W, N)``) → the measurement tensor
        (NumPy)."""
        a = stack_frames(frames)
        n = self.frame_count
        if a.shape[2] != n:
            raise ValueError(
                f"{type(self).__name__} takes {n} frame(s) per measurement, got {a.shape[2]}"
            )
        shape = tuple(self.measurement_shape)
        target = shape if len(shape) == 3 else shape + (1,)
        if a.shape != target:
            raise ValueError(
                f"{type(self).__name__}: expected {target[2]} frame(s) of {target[:2]}, got "
                f"{a.shape}"
            )
        return a if len(shape) == 3 else a[..., 0]

    def measurement_to_frames(self, measurement) -> np.ndarray:
        """The measurement → the ``(H, W, N)`` stack of sensor frames (inverse of
        :meth:`frames_to_measurement`)."""
        g = self._frames_check(measurement)
        return g if g.ndim == 3 else g[..., None]

    def _frames_check(self, measurement) -> np.ndarray:
        g = real_array("measurement", B.to_numpy(measurement), finite=False)
        if g.shape != tuple(self.measurement_shape):
            raise ValueError(
                f"measurement shape {g.shape} does not match the system's "
                f"{tuple(self.measurement_shape)}"
            )
        return g

    # ---- depth and previews -------------------------------------------------------------
    def depth_from_cube(self, cube, *, n_steps: int = 4, max_disparity: float = 2.0):
        """The depth channel of a cube of :attr:`cube_shape` (see :attr:`depth_kind`); ``None``
        here."""
        return None

    def spectral_view(self, cube) -> np.ndarray:
        """An ``(Nx, Ny, Nλ)`` reflectance-like view of a cube (sRGB previews); the cube itself
        here."""
        return real_array("cube", B.to_numpy(cube), finite=False)

    def score_depth(self, depth, problem: Problem) -> dict:
        """How well ``depth`` (a :meth:`depth_from_cube` result) matches ``problem``'s truth; ``{}``
        if no truth.

        ``"planes_right"`` (fraction of pixels on the right plane),
        ``"disparity_mae"`` (px per view step) or ``"phase_mae"`` (rad, first
        frequency), by :attr:`depth_kind`.
        """
        from ..depth import wrap

        if depth is None or problem.depth is None:
            return {}
        d = real_array("depth", B.to_numpy(depth), finite=False)
        if self.depth_kind == "planes":
            return {"planes_right": float(np.mean(np.round(d) == problem.depth))}
        if self.depth_kind == "disparity":
            return {"disparity_mae": float(np.mean(np.abs(d - problem.depth)))}
        if self.depth_kind == "phase" and "phase" in problem.extras:
            return {
                "phase_mae": float(
                    np.mean(np.abs(wrap(d[..., 0] - problem.extras["phase"][..., 0])))
                )
            }
        return {}

    # ---- seeded problems --------------------------------------------------------------
    @classmethod
    def example_problem(
        cls,
        scene: str = "chelsea",
        *,
        shape=(64, 64),
        n_bands: int = 16,
        snr_db: float | None = 30.0,
        rng=0,
        shifts=1,
        **options,
    ) -> Problem:
        """A seeded problem: this imager viewing ``scene`` (a name of
        :data:`tensor_cosdi.scenes.SCENES`).

        ``shape`` is the detector-side spatial size, ``n_bands`` the bands
        between 450 and 650 nm, ``snr_db`` the measurement SNR (``None``:
        noise-free), ``rng`` seeds codes and noise.  ``options`` are the
        class's :attr:`example_options` (unknown ones are an error listing them).
        """
        from .. import scenes
        from ..operators import validate_shape

        unknown = sorted(set(options) - set(cls.example_options))
        if unknown:
            raise ValueError(
                f"{cls.name}: unknown option(s) {unknown}; its options are "
                f"{sorted(cls.example_options) or 'none'} (and shape, n_bands, snr_db, rng, shifts)"
            )
        opts = {**cls.example_options, **options}
        scenes.SCENES[scene]  # noqa: B018 - an unknown scene lists the valid ones
        nx, ny = validate_shape(shape, "shape")
        wl = scenes.default_wavelengths(n_bands)
        gen = B.default_rng(rng)
        seed = int(gen.integers(2**31))
        system, cube, reflectance, depth, extras = cls._example(
            scene, (nx, ny), wl, seed, shifts, **opts
        )
        if B.backend_name() != "numpy":  # the truth and the measurement on the active backend
            cube = B.as_tensor(cube, np.asarray(cube).dtype.name)
        g = system.simulate(cube, snr_db=snr_db, rng=gen)
        return Problem(
            f"{cls.name}/{scene}", system, cube, g, wl, snr_db, reflectance, depth, extras
        )

    @classmethod
    def _example(cls, scene, shape, wl, seed, shifts, **opts):
        """``(system, cube, reflectance, depth, extras)`` of a spectral-only system: cube =
        reflectance."""
        from .. import scenes

        reflectance = scenes.scene_cube(scene, shape, wl)
        code = opts.pop("code", None)
        if code is None:
            system = cls.example(shape + (len(wl),), rng=seed, shifts=shifts, wavelengths=wl)
        else:
            system = cls(code, n_bands=len(wl), shifts=shifts, wavelengths=wl)
            if system.cube_shape[:2] != shape:
                raise ValueError(f"code of shape {np.shape(code)} does not give a {shape} scene")
        return system, reflectance, reflectance, None, {}


# ---- shared by several imagers ------------------------------------------------------------
def views_disparity(light_field, max_disparity: float):
    """Centre-view disparity of a spectral light field ``(N1, N2, Nλ, U, V)`` (all bands)."""
    from ..depth import disparity_from_views

    lf = np.asarray(B.to_numpy(light_field))
    return disparity_from_views(np.moveaxis(lf, (3, 4), (0, 1)), max_disparity=max_disparity)
