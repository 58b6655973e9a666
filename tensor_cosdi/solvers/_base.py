"""The common harness of every reconstruction method: ``reconstruct``, ``Result``, the registry."""

from __future__ import annotations

import inspect
import logging
import time
import warnings
from dataclasses import dataclass, field
from typing import Any, Callable, NamedTuple

import numpy as np
import tensorly as tl

from .. import _backend as B
from .._registry import Registry
from ..validate import number, option_types

__all__ = [
    "Result",
    "reconstruct",
    "register_method",
    "methods",
    "METHODS",
    "Method",
    "History",
    "relative_change",
    "compiled_change",
]


class MethodOutput(NamedTuple):
    """What a registered method returns to :func:`reconstruct`: ``(cube, history, converged)`` and
    optionally the method's own ``depth`` map.  A plain tuple of three or four works too."""

    cube: Any
    history: dict
    converged: bool = True
    depth: Any = None

    @classmethod
    def of(cls, out, method: str) -> "MethodOutput":
        """``out`` as a :class:`MethodOutput`, or a ``TypeError`` naming the method."""
        if isinstance(out, cls):
            return out
        if isinstance(out, tuple) and len(out) in (3, 4):
            return cls(*out)
        raise TypeError(
            f"method {method!r} returned {type(out).__name__}; a method returns "
            "MethodOutput(cube, history, converged[, depth]) or that tuple"
        )


@dataclass(frozen=True)
class Result:
    """What a reconstruction returns.

    Attributes
    ----------
    cube : tensor of the system's ``cube_shape``
        The estimate, on the measurement's backend.
    depth : ndarray or None
        The depth channel where the system has a depth modality: the
        method's own estimate where it makes one (``"dfa"``, ``"pnp_admm"``),
        else :func:`tensor_cosdi.depth.depth_from_cube` of the cube, computed
        on first access (disparity estimates take seconds).  ``None`` for
        spectral-only systems.
    history : dict of lists
        One entry per iteration: ``"objective"``, ``"residual"`` (relative,
        ``‖G − A F‖ / ‖G‖``), ``"change"`` (relative change of ``F``),
        ``"seconds"`` (cumulative).
    seconds : float
        Wall time of the whole call.
    options : dict
        Every option the method ran with, defaults included.
    method : str
    converged : bool
        Whether the stopping tolerance was met (closed-form methods: True).
    """

    cube: Any
    history: dict
    seconds: float
    options: dict
    method: str
    converged: bool = True
    method_depth: Any = field(default=None, repr=False)
    system: Any = field(default=None, repr=False, compare=False)

    @property
    def depth(self):
        if self.method_depth is None and self.system is not None:
            from ..depth import depth_from_cube

            object.__setattr__(self, "method_depth", depth_from_cube(self.system, self.cube))
            object.__setattr__(self, "system", None)  # computed once
        return self.method_depth

    @property
    def iterations(self) -> int:
        return len(self.history.get("residual", []))


@dataclass(frozen=True)
class Method:
    """A registered reconstruction method: the function, every option with its default, one line.

    ``requires`` names the optional modules its *defaults* need (``("torch",)``
    for the learned prior); :attr:`available` says whether they import.
    ``systems`` names the imagers (:data:`tensor_cosdi.systems.REGISTRY` names)
    it reconstructs, empty for every one; ``needs`` maps an option that must
    be given (its default is ``None``) to what it is.  :func:`reconstruct`,
    the CLI's help, the docs and the registry tests read these.
    """

    func: Callable
    defaults: dict = field(default_factory=dict)
    summary: str = ""
    name: str = ""
    requires: tuple = ()
    systems: tuple = ()
    needs: dict = field(default_factory=dict)
    #: Whether it solves with ``(μI + A Aᵀ)`` of the whole system (GAP, ADMM x-steps, least
    #: squares): on a system without a cheap structure for it (PSFs) that is conjugate
    #: gradients, and :func:`reconstruct` warns.
    solves: bool = True

    def applies_to(self, system_name: str) -> bool:
        """Whether this method reconstructs the imager registered as ``system_name``."""
        return not self.systems or system_name in self.systems

    @property
    def available(self) -> bool:
        import importlib.util

        return all(importlib.util.find_spec(m) is not None for m in self.requires)

    def __call__(self, system, measurement, **options):
        return reconstruct(system, measurement, self.name, **options)


log = logging.getLogger(__name__)

METHODS = Registry("method")
"""``name → Method``: every method :func:`reconstruct` accepts (read-only; add with
:func:`register_method`)."""


def signature_defaults(func: Callable) -> dict:
    """``{option: default}`` of ``func(system, measurement, *, option=default, …)``, read from its
    signature: the one place a method's defaults are written."""
    params = list(inspect.signature(func).parameters.values())
    if len(params) < 2 or params[1].kind not in (params[1].POSITIONAL_ONLY,
                                                 params[1].POSITIONAL_OR_KEYWORD):  # fmt: skip
        raise ValueError(f"a method takes (system, measurement, **options); got {func!r}")
    out = {}
    for p in params[2:]:
        if p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD):
            raise ValueError(
                f"{getattr(func, '__name__', func)}: a method's options are named one by one "
                f"(no *{p.name}); or pass defaults= to register_method"
            )
        if p.default is p.empty:
            raise ValueError(f"{getattr(func, '__name__', func)}: option {p.name} has no default")
        out[p.name] = p.default
    return out


def register_method(
    name: str,
    func: Callable,
    defaults: dict | None = None,
    summary: str = "",
    *,
    replace: bool = False,
    requires: tuple = (),
    systems: tuple = (),
    needs: dict | None = None,
    solves: bool = True,
) -> None:
    """Register ``func(system, measurement, **options) -> MethodOutput`` (or the tuple
    ``(cube, history, converged[, depth])``).

    ``defaults`` lists every option the method accepts with its default
    (``None``: read from ``func``'s signature, :func:`signature_defaults` — how
    every method of the library is registered, so that a default is written
    once); anything else passed to :func:`reconstruct` is an error.  A name
    that is taken needs ``replace=True``; the library's own methods cannot be
    replaced.  ``systems``, ``needs`` and ``solves``: see :class:`Method`.
    """
    if not callable(func):
        raise ValueError(f"a method must be callable, got {func!r}")
    if defaults is None:
        defaults = signature_defaults(func)
    builtin = getattr(func, "__module__", "").startswith("tensor_cosdi.")
    METHODS.register(
        name,
        Method(
            func,
            dict(defaults),
            summary,
            name,
            tuple(requires),
            tuple(systems),
            dict(needs or {}),
            bool(solves),
        ),  # fmt: skip
        replace=replace,
        builtin=builtin,
    )


def methods(system=None) -> tuple[str, ...]:
    """Names of the registered reconstruction methods (those for ``system``, a system or its
    registry name, when given)."""
    if system is None:
        return METHODS.names()
    name = system if isinstance(system, str) else getattr(system, "name", "")
    return tuple(n for n in METHODS.names() if METHODS[n].applies_to(name))


def require_system(method: str, system) -> None:
    """``ValueError`` unless ``method`` reconstructs ``system`` (its registered ``systems``),
    naming the methods that do."""
    entry = METHODS[method]
    name = getattr(system, "name", None) or type(system).__name__
    if not entry.applies_to(name):
        raise ValueError(
            f"method {method!r} reconstructs {' and '.join(entry.systems)} systems, got "
            f"{type(system).__name__}; methods for {name}: {', '.join(methods(name))}"
        )


#: Measurement dtypes promoted to float32 by :func:`reconstruct` (the cube comes back float32).
HALF_PRECISION = ("float16", "bfloat16")


def _context(x) -> dict:
    ctx = tl.context(x)
    ctx.pop("requires_grad", None)
    return ctx


def _is_data_array(x) -> bool:
    """An ``xarray.DataArray`` (recognised without importing xarray)."""
    return type(x).__name__ == "DataArray" and hasattr(x, "dims") and hasattr(x, "coords")


def _as_data_array(cube, system, method: str):
    """The cube as an ``xarray.DataArray``: dims from ``system.axes``, the band centres (nm) as
    the ``"λ"`` coordinate."""
    import xarray as xr

    values = B.to_numpy(cube)
    coords = {}
    if "λ" in system.axes:
        coords["λ"] = ("λ", np.asarray(system.wavelengths), {"units": "nm"})
    return xr.DataArray(
        values, dims=tuple(system.axes), coords=coords,
        attrs={"method": method, "system": type(system).__name__},
    )  # fmt: skip


class SlowSolveWarning(UserWarning):
    """The method will solve with ``(μI + A Aᵀ)`` by conjugate gradients (no cheap structure)."""


def _warn_if_solves_are_slow(system, method: str) -> None:
    op = system.operator
    if op.gram_dual() is not None or (op.shape[0] > op.shape[1] and op.T.gram_dual() is not None):
        return
    probe = B.tensor_like(np.ones(op.output_shape), B.as_tensor(np.zeros(1)))
    t0 = time.perf_counter()
    op.apply(op.apply_adjoint(probe))
    product = time.perf_counter() - t0
    closed = [n for n in methods(system) if not METHODS[n].solves]
    warnings.warn(
        f"{type(system).__name__}: (μI + A Aᵀ) has no cheap structure here (PSFs), so {method!r} "
        f"solves it by conjugate gradients, tens of A Aᵀ products per solve (one took "
        f"{product:.2g} s); methods without such solves: {', '.join(closed) or 'none'}",
        SlowSolveWarning,
        stacklevel=3,
    )


def check_call(system, method: str, options: dict):
    """The registry entry of ``method`` once its name, its options' names and kinds, and the
    system fit it (what :func:`reconstruct` checks before it reads the measurement); an error
    naming what does not fit otherwise."""
    entry = METHODS[method]  # an unknown name lists the registered ones
    unknown = sorted(set(options) - set(entry.defaults))
    if unknown:
        raise ValueError(
            f"unknown option(s) {unknown} for method {method!r}; valid options: "
            f"{sorted(entry.defaults)}"
        )
    require_system(method, system)
    for opt, what in entry.needs.items():
        if options.get(opt) is None:
            raise ValueError(f"method {method!r} needs {opt}=: {what}")
    option_types(f"method {method!r}", options, entry.defaults)
    return entry


def reconstruct(system, measurement, method: str = "otd", **options) -> Result:
    """Reconstruct a cube from ``measurement`` of ``system`` with a registered ``method``.

    Parameters
    ----------
    system : tensor_cosdi.systems.System
    measurement : tensor of ``system.measurement_shape``
    method : str
        One of :func:`methods` (``reconstruct.methods()``).
    **options
        The method's options; unknown ones are a ``ValueError`` that lists
        the valid ones.

    Returns
    -------
    Result

    Notes
    -----
    An ``xarray.DataArray`` measurement gives a ``DataArray`` cube (dims the
    system's :attr:`~tensor_cosdi.systems.System.axes`, the band centres in
    nm as the ``"λ"`` coordinate).  A dask array is refused with a message: every
    method needs the whole measurement in memory; compute it
    (``measurement.compute()``) or give it to
    :func:`~tensor_cosdi.solvers.tiled.reconstruct_tiled`, which computes one
    tile's window at a time.
    A float16 (or bfloat16) measurement is promoted to float32 first: its
    three significant digits cost every method 1-4 dB in its own precision.
    Every method runs on the measurement divided by its peak ``max|g|`` and
    the cube is multiplied back (the history's objective too), so results do
    not depend on the measurement's units.  An all-zero or constant
    measurement, NaN out of a method, or a cube that overflows when scaled
    back raise errors that say so.
    """
    entry = check_call(system, method, options)
    if entry.solves:
        _warn_if_solves_are_slow(system, method)
    opts = {**entry.defaults, **options}
    labelled = _is_data_array(measurement)
    if labelled:  # an xarray.DataArray: its values, and the cube comes back labelled
        measurement = measurement.values
    elif hasattr(measurement, "__dask_graph__"):  # a dask array: no method works in pieces
        raise ValueError(
            f"the measurement is a lazy dask array {tuple(measurement.shape)}: every method needs "
            "it whole in memory — pass measurement.compute(), or use reconstruct_tiled, which "
            "computes one tile's window at a time (SD-/DD-CASSI)"
        )
    g = system.check_measurement(measurement, "reconstruct")  # shape, dtype, NaN/inf
    if B.real_dtype_name(g) in HALF_PRECISION:  # 3 significant digits: every method loses 1-4 dB
        g = tl.tensor(g, **{**_context(g), "dtype": B.dtype("float32")})
    peak, low = float(tl.max(tl.abs(g))), float(tl.min(g))
    if peak == 0:
        raise ValueError(
            "the measurement is all zero: there is no signal to reconstruct (check the exposure, "
            "the shutter and the frame files)"
        )
    if low == float(tl.max(g)):
        raise ValueError(
            f"the measurement is constant (every value {low:g}): a coded aperture cannot give "
            "that from a real scene — check for a saturated or disconnected sensor"
        )
    t0 = time.perf_counter()
    # every method sees the measurement scaled to a peak of 1 and the cube is scaled back: the
    # result does not depend on the measurement's units (1e-300 … 1e300), whatever constants a
    # method or library keeps in absolute units (Chambolle's stopping tolerance, ε floors)
    out = entry.func(system, g / peak, **opts)
    seconds = time.perf_counter() - t0
    out = MethodOutput.of(out, method)
    cube, history, converged = out.cube, out.history, out.converged
    if not B.all_finite(cube):
        raise FloatingPointError(
            f"method {method!r} produced NaN or inf from a finite measurement; this is a bug in "
            "the method or options far outside their range — please report it with the options"
        )
    with np.errstate(over="ignore"):
        cube = cube * peak
    if not B.all_finite(cube):
        raise OverflowError(
            f"the reconstruction overflows the {B.real_dtype_name(cube)} range when scaled back "
            f"to the measurement's units (peak {peak:g}); rescale the measurement"
        )
    if isinstance(history, dict) and "objective" in history:
        history["objective"] = [v * peak * peak for v in history["objective"]]
    depth = out.depth
    log.info(
        "%s on %s %s: %.2f s, %d iterations, converged %s",
        method, type(system).__name__, tuple(system.cube_shape), seconds,
        len(history.get("residual", [])) if isinstance(history, dict) else 0, bool(converged),
    )  # fmt: skip
    if labelled:
        cube = _as_data_array(cube, system, method)
    return Result(
        cube,
        history,
        seconds,
        opts,
        method,
        bool(converged),
        depth,
        system if depth is None else None,
    )


reconstruct.methods = methods  # tc.reconstruct.methods(), as the API contract promises


class History(dict):
    """The per-iteration record every iterative method returns (``Result.history``).

    A dict of four lists — ``"objective"``, ``"residual"``, ``"change"``,
    ``"seconds"`` (cumulative since the history was created) — filled by
    :meth:`record`; :meth:`extend` appends another stage's history with its
    seconds offset (multi-stage methods).
    """

    KEYS = ("objective", "residual", "change", "seconds")

    def __init__(self):
        super().__init__({k: [] for k in self.KEYS})
        self._t0 = time.perf_counter()

    def record(self, *, residual: float, objective: float, change: float) -> None:
        self["residual"].append(float(residual))
        self["objective"].append(float(objective))
        self["change"].append(float(change))
        self["seconds"].append(time.perf_counter() - self._t0)

    def extend(self, other: dict) -> None:
        base = self["seconds"][-1] if self["seconds"] else 0.0
        for k in ("objective", "residual", "change"):
            self[k].extend(other[k])
        self["seconds"].extend(base + s for s in other["seconds"])


def relative_change(new, old) -> float:
    """``‖new − old‖ / ‖new‖`` (the stopping quantity of every iterative method); ``inf`` when
    ``new`` is all zero and ``old`` is not (a prior that zeroed the iterate has not converged).

    Two NumPy arrays of one float dtype and one memory order (C or Fortran) take one pass of a
    compiled loop where numba is installed (:func:`~tensor_cosdi._backend.jit_enabled`): both
    sums in float64, no cube-sized temporary (1.47 → 0.67 ms at 256×256×28 float32 in one run of
    ``benchmarks/results/solver_steps.md``).  Elsewhere a difference and two BLAS dot products.

    >>> relative_change(np.zeros(3), np.ones(3)), relative_change(np.zeros(3), np.zeros(3))
    (inf, 0.0)
    """
    if isinstance(new, np.ndarray) and isinstance(old, np.ndarray) and new.dtype.kind in "fc":
        order = _same_layout(new, old)
        kernel = _change_kernel() if order and new.dtype.kind == "f" else None
        if kernel is not None:
            d2, n2 = kernel(new.ravel(order), old.ravel(order))  # views: no copy
            diff, norm = float(np.sqrt(d2)), float(np.sqrt(n2))
        else:  # BLAS dot products instead of a squared copy: 3.5× faster at 256×256×28
            d, n = np.subtract(new, old).ravel("K"), new.ravel("K")  # views in C or F order
            diff, norm = float(np.sqrt(np.vdot(d, d).real)), float(np.sqrt(np.vdot(n, n).real))
    else:
        import tensorly as tl

        diff, norm = float(tl.norm(new - old)), float(tl.norm(new))
    if norm == 0.0:
        return 0.0 if diff == 0.0 else float("inf")
    return diff / norm


def _same_layout(new, old) -> str | None:
    """``"C"`` or ``"F"`` where both arrays have one shape, one dtype and that memory order, so
    that their flat views pair the same elements; else ``None``."""
    if new.shape != old.shape or new.dtype != old.dtype:
        return None
    if new.flags.c_contiguous and old.flags.c_contiguous:
        return "C"
    if new.flags.f_contiguous and old.flags.f_contiguous:
        return "F"
    return None


def _change_sums(new, old):  # pragma: no cover (compiled)
    """``(Σ (new − old)², Σ new²)`` over two flat arrays, in float64: the loop numba compiles for
    :func:`relative_change` (each difference in the arrays' own precision, as NumPy's)."""
    d2 = 0.0
    n2 = 0.0
    for i in range(new.size):
        a = new[i]
        d = np.float64(a - old[i])
        b = np.float64(a)
        d2 += d * d
        n2 += b * b
    return d2, n2


def compiled_change() -> bool:
    """Whether :func:`relative_change` takes its compiled pass for two NumPy arrays of one float
    dtype and memory order: numba is installed and :func:`~tensor_cosdi._backend.jit_enabled`.

    >>> isinstance(compiled_change(), bool)
    True
    """
    return _change_kernel() is not None


def _change_kernel():
    """:func:`_change_sums` compiled by numba (:func:`~tensor_cosdi._backend.numba_compiled`,
    reassociation allowed so that the sums vectorise), or ``None`` without numba or with
    ``TENSOR_COSDI_JIT=0``."""
    if not B.jit_enabled():
        return None
    return B.numba_compiled(_change_sums, fastmath={"reassoc", "contract", "nsz"})


def relative_residual(system, cube, g) -> float:
    import tensorly as tl

    r = system.operator.apply(cube) - g
    return float(tl.norm(r)) / max(float(tl.norm(g)), np.finfo(float).tiny)


def check_positive(name: str, value) -> float:
    """``value`` as a finite ``float > 0`` (:func:`tensor_cosdi.validate.number`)."""
    return number(name, value, low=0, low_open=True)
