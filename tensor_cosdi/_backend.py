"""Thin glue over TensorLy backends.

Everything backend-specific in tensor_cosdi goes through this module: creating
tensors that follow the context (backend, dtype, device) of another tensor,
converting to NumPy, finiteness checks, FFTs and batched small solves, for which
TensorLy has no backend-neutral function.  Operators keep their parameters as
NumPy arrays and convert them once per context (see :class:`ParamCache`).
"""

from __future__ import annotations

import os
import threading

import numpy as np
import tensorly as tl

from .validate import seed as check_seed

__all__ = [
    "backend_name",
    "to_numpy",
    "tensor_like",
    "zeros_like_shape",
    "all_finite",
    "check_floating",
    "default_rng",
    "ParamCache",
    "thread_limit",
    "rfftn",
    "irfftn",
    "batched_solve",
    "unfolding_gram",
    "on_accelerator",
    "kth_smallest",
    "real_dtype_name",
]


def backend_name() -> str:
    """Name of the active TensorLy backend (``"numpy"``, ``"pytorch"`` …)."""
    return tl.get_backend()


def dtype(name: str):
    """The active backend's dtype object for ``"float32"``/``"float64"``.

    (``tensorly.float64`` is bound to NumPy's at import time; the backend
    module dispatches to the active backend.)
    """
    import tensorly.backend as tb

    return getattr(tb, name)


def as_tensor(array, dtype_name: str = "float64"):
    """NumPy array → tensor of the active backend with the named dtype."""
    return tl.tensor(np.asarray(array), dtype=dtype(dtype_name))


def to_numpy(x) -> np.ndarray:
    """Return ``x`` as a NumPy array (no copy for NumPy inputs)."""
    if isinstance(x, np.ndarray):
        return x
    if hasattr(x, "detach") and hasattr(x, "cpu"):  # a torch tensor, whatever backend is active
        return x.detach().cpu().numpy()  # (also on CUDA, where np.asarray would fail)
    return tl.to_numpy(x)


def on_accelerator(x) -> bool:
    """True for a tensor that is neither NumPy nor in host memory (a CUDA tensor, say).

    Steps that have a NumPy path (TV, HOSVD Grams, percentiles) take it for
    host tensors of other backends (PyTorch on the CPU) through a zero-copy
    view, and stay on the device only here: at 256×256×28 on two cores
    ``gap_tv`` took 6.6-6.9 s through the view against 11.6-13.0 s with the
    same iteration in torch operations (the same result to 1e-8 dB).
    """
    return not isinstance(x, np.ndarray) and str(getattr(x, "device", "cpu")) != "cpu"


def context_key(x) -> tuple:
    """Hashable key of the backend, dtype and device of tensor ``x``."""
    ctx = tl.context(x)
    return (backend_name(), str(ctx.get("dtype")), str(ctx.get("device", "")))


def tensor_like(array, like):
    """Create a tensor from ``array`` with the backend, dtype and device of ``like``."""
    ctx = tl.context(like)
    ctx.pop("requires_grad", None)
    return tl.tensor(array, **ctx)


def zeros_like_shape(shape, like):
    """Zeros of ``shape`` with the backend, dtype and device of ``like``."""
    ctx = tl.context(like)
    ctx.pop("requires_grad", None)
    return tl.zeros(tuple(shape), **ctx)


def real_dtype_name(x) -> str:
    """``"float32"``, ``"float64"`` … for any backend tensor."""
    return str(tl.context(x)["dtype"]).replace("torch.", "")


def check_floating(x, what: str = "input") -> None:
    """Raise ``ValueError`` unless ``x`` holds real floating-point numbers."""
    name = real_dtype_name(x)
    if not name.startswith(("float", "bfloat")):
        raise ValueError(
            f"{what} must be a real floating-point tensor (float32 or float64), got dtype {name}"
        )


def all_finite(x) -> bool:
    """True when no entry of ``x`` is NaN or ±inf (exact, one pass).

    For contiguous NumPy floats the pass is one BLAS dot product ``v·v``
    (no temporary): a NaN or inf anywhere makes it NaN or inf; only when it
    is not finite (which a finite ``x`` can also cause, by overflow) is the
    exact elementwise test run.
    """
    if isinstance(x, np.ndarray):
        if x.dtype.kind == "f" and x.size and (x.flags.c_contiguous or x.flags.f_contiguous):
            v = x.ravel(order="K")
            with np.errstate(over="ignore", invalid="ignore"):
                if np.isfinite(np.dot(v, v)):
                    return True
        return bool(np.isfinite(x).all())
    if backend_name() == "pytorch":
        import torch

        return bool(torch.isfinite(x).all())
    return bool(np.isfinite(to_numpy(x)).all())


def default_rng(seed=None) -> np.random.Generator:
    """Seeded NumPy generator; passes an existing ``Generator`` through.  A seed that is not
    ``None``, an integer ≥ 0 (or a list of them), a ``BitGenerator`` or a ``SeedSequence`` is
    a ``ValueError`` (see :func:`tensor_cosdi.validate.seed`)."""
    if isinstance(seed, np.random.Generator):
        return seed
    return np.random.default_rng(check_seed("rng", seed))


class ParamCache:
    """Per-context cache of an operator's NumPy parameters.

    Operators are immutable; converting a 256×256 code to a float32 torch
    tensor on every call would cost more than the sensing itself, so the
    converted copy is kept per (backend, dtype, device).
    """

    def __init__(self):
        self._store: dict = {}
        self._lock = threading.Lock()

    def get(self, name: str, array: np.ndarray, like):
        if isinstance(like, np.ndarray):
            key = (name, "numpy", like.dtype.str, "")
            hit = self._store.get(key)
            if hit is None:
                hit = np.ascontiguousarray(array, dtype=like.dtype)
                with self._lock:
                    self._store[key] = hit
            return hit
        key = (name,) + context_key(like)
        hit = self._store.get(key)
        if hit is None:
            hit = tensor_like(np.ascontiguousarray(array), like)
            with self._lock:
                self._store[key] = hit
        return hit

    def __getstate__(self):
        return {}

    def __setstate__(self, state):
        self.__init__()


def jit_enabled() -> bool:
    """Whether the library may use its numba-compiled kernels: the environment variable
    ``TENSOR_COSDI_JIT`` is unset, ``1`` or empty (``0`` keeps the NumPy code; any other value
    is a ``ValueError``).  Whether numba is installed is each kernel's own question."""
    flag = os.environ.get("TENSOR_COSDI_JIT", "1").strip()
    if flag not in ("0", "1", ""):
        raise ValueError(f"TENSOR_COSDI_JIT must be 0 or 1, got {flag!r}")
    return flag != "0"


_NUMBA: dict = {}  # the compiled kernels, one a function (None: numba is not installed)


def numba_compiled(func, **options):
    """``func`` compiled by numba (``njit`` without the GIL, cached on disk, no bounds checks,
    NumPy's error model, and ``options``), made once a process, or ``None`` where numba is not
    installed (the ``fast`` extra).  Whether to use it is :func:`jit_enabled`'s question."""
    if func not in _NUMBA:
        try:
            import numba
        except ImportError:
            _NUMBA[func] = None
        else:
            _NUMBA[func] = numba.njit(
                nogil=True, cache=True, boundscheck=False, error_model="numpy", **options
            )(func)
    return _NUMBA[func]


# ---------------------------------------------------------------- FFT and solves
def thread_limit() -> int:
    """Threads the library's own parallel NumPy work (FFTs, TV channel chunks) may use: the
    ``OMP_NUM_THREADS`` limit where the environment sets a positive one (a single-threaded
    Dask worker of :func:`tensor_cosdi.studies.local_client`, a batch job), else the CPUs this
    process may run on, so that processes sharing the CPUs do not each start one thread per
    CPU.  (Measured on the findings' CASSDI-DFA cells, two workers on two cores: 61-74 s
    with every CPU, 65-67 s with the limit — no difference beyond the run-to-run spread.)
    """
    limit = os.environ.get("OMP_NUM_THREADS", "").strip()
    if limit.isdigit() and int(limit) > 0:
        return int(limit)
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):  # not on Linux
        return max(1, os.cpu_count() or 1)


def contiguous(x):
    """``x`` with its memory in C order (a copy only when it is not)."""
    if isinstance(x, np.ndarray):
        return np.ascontiguousarray(x)
    if backend_name() == "pytorch":
        return x.contiguous()
    return x


def rfftn(x, s, axes):
    """Real FFT over ``axes`` with zero padding to sizes ``s`` (any backend)."""
    if isinstance(x, np.ndarray):
        import scipy.fft

        return scipy.fft.rfftn(x, s=s, axes=axes, workers=thread_limit())
    if backend_name() == "pytorch":
        import torch

        return torch.fft.rfftn(x, s=s, dim=axes)
    raise NotImplementedError(f"FFT is not wired for the {backend_name()!r} backend")


def irfftn(X, s, axes):
    """Inverse of :func:`rfftn` for real outputs of sizes ``s``."""
    if isinstance(X, np.ndarray):
        import scipy.fft

        return scipy.fft.irfftn(X, s=s, axes=axes, workers=thread_limit())
    if backend_name() == "pytorch":
        import torch

        return torch.fft.irfftn(X, s=s, dim=axes)
    raise NotImplementedError(f"FFT is not wired for the {backend_name()!r} backend")


def batched_solve(A, b):
    """Solve ``A[..., :, :] x[..., :] = b[..., :]`` for every leading index."""
    if isinstance(A, np.ndarray):
        return np.linalg.solve(A, b[..., None])[..., 0]
    if backend_name() == "pytorch":
        import torch

        return torch.linalg.solve(A, b)
    return tl.tensor(np.linalg.solve(to_numpy(A), to_numpy(b)[..., None])[..., 0])


def unfolding_gram(x, mode: int) -> np.ndarray:
    """``X₍ₘ₎ X₍ₘ₎ᵀ`` (float64) of a PyTorch tensor, summed where the tensor lives (CPU or GPU)
    in blocks; only the ``n × n`` result comes back, as a NumPy array.

    The HOSVD of a cube on a GPU thus never copies the cube to the host: the
    small eigenproblem that follows is ``n × n`` (``n`` ≤ a side of the cube).
    """
    import torch

    shape, mode = tuple(x.shape), int(mode)
    n = shape[mode]
    pre, post = int(np.prod(shape[:mode])), int(np.prod(shape[mode + 1 :]))
    v = x.detach().reshape(pre, n, post)
    gram = torch.zeros((n, n), dtype=torch.float64, device=x.device)
    cols = min(post, max(1, (1 << 22) // n))  # blocks of ≤ 4 Mi elements (32 MiB in float64)
    rows = max(1, (1 << 22) // (n * cols))
    for p0 in range(0, pre, rows):
        for c0 in range(0, post, cols):
            blk = v[p0 : p0 + rows, :, c0 : c0 + cols].to(torch.float64)
            gram += torch.einsum("anb,amb->nm", blk, blk)
    return gram.cpu().numpy()


def kth_smallest(x, k: int) -> float:
    """The ``k``-th smallest entry (from 0) of ``x`` flattened, without sorting it all (NumPy's
    ``partition``; PyTorch's ``kthvalue`` on the tensor's own device)."""
    if isinstance(x, np.ndarray):
        v = x.ravel()
        return float(np.partition(v, k)[k])
    if hasattr(x, "kthvalue"):
        return float(x.reshape(-1).kthvalue(int(k) + 1).values)
    return kth_smallest(np.asarray(to_numpy(x)), k)
