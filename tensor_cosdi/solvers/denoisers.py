"""Plug-in denoisers for PnP-ADMM (SPEC §6): scikit-image's TV and wavelet denoisers, and a
registry.

A denoiser is a callable ``denoise(x, sigma) -> x`` on a tensor whose axes 0
and 1 are spatial (any further axes are channels: bands, patterns…);
``sigma`` is the noise level in the tensor's units.  Register your own (e.g.
a trained network) with :func:`register_denoiser`.
"""

from __future__ import annotations

import os
from typing import Callable

import numpy as np

from .. import _backend as B
from .._registry import Registry
from ..validate import integer, number

__all__ = [
    "DENOISERS",
    "denoise",
    "register_denoiser",
    "denoisers",
    "tv",
    "WarmTV",
    "compiled_tv",
    "wavelet",
    "spectral_net",
    "self_ensemble",
]

DENOISERS = Registry("denoiser")
"""``name → denoise(x, sigma)``, read-only; add yours with :func:`register_denoiser`."""


def _host(x, who: str):
    """A host copy, ``(H, W, channels)``; float32 stays float32 (scikit-image keeps it: half the
    memory traffic of float64), anything else becomes float64.  ``x`` must be a finite real
    image or cube (a ``ValueError`` naming the denoiser ``who`` otherwise)."""
    a = np.asarray(B.to_numpy(x))
    if a.dtype.kind not in "biuf":
        raise ValueError(f"{who}: x must hold real numbers, got dtype {a.dtype}")
    if a.ndim < 2:
        raise ValueError(
            f"{who}: x must be an image (H, W) or a cube (H, W, …), got shape {a.shape}"
        )
    if not np.isfinite(a).all():
        raise ValueError(f"{who}: x holds NaN or inf")
    a = a if a.dtype == np.float32 else a.astype(np.float64)
    return a.reshape(a.shape[:2] + (-1,)), a.shape


def _like(out: np.ndarray, x):
    """``out`` on ``x``'s backend and device (a NumPy input gets NumPy back, whatever backend is
    active)."""
    return out if isinstance(x, np.ndarray) else B.tensor_like(out, x)


def _workers(channels: int) -> int:
    return max(1, min(channels, B.thread_limit(), 8))


_POOL: dict = {}


def _pool():
    """One thread pool for the channel chunks of every TV call, made on first use (and again
    in a forked child, which does not inherit the parent's threads).  A pool per call started
    its threads every time: 2 ms a call on the project machine, 0.4 s of OTD's start at
    256×256×28."""
    from concurrent.futures import ThreadPoolExecutor

    pid = os.getpid()
    if _POOL.get("pid") != pid:
        _POOL.update(pid=pid, pool=ThreadPoolExecutor(_workers(8), "tensor_cosdi-tv"))
    return _POOL["pool"]


def tv(x, sigma: float, *, n_iter: int = 50):
    """Isotropic TV (Chambolle, ``skimage.restoration.denoise_tv_chambolle``) per channel, weight
    ``sigma``.

    Channels are independent, so chunks of them run in threads (NumPy releases
    the GIL in the array operations): the same result as one call, 1.2×
    faster on two cores at 256×256×28 (median of 7, 0.146 → 0.121 s for 10
    Chambolle steps).  A tensor on a GPU is denoised where it lives, by the
    same iteration with the same per-channel stopping rule
    (:func:`_tv_on_device`).
    """
    from skimage.restoration import denoise_tv_chambolle

    weight = number("tv: sigma", sigma, low=0, low_open=True)
    n_iter = integer("tv: n_iter", n_iter, low=1)
    if B.on_accelerator(x):
        return _tv_on_device(x, weight, n_iter)
    flat, shape = _host(x, "tv")

    def run(chunk):
        return denoise_tv_chambolle(chunk, weight=weight, max_num_iter=n_iter, channel_axis=2)

    n = _workers(flat.shape[2])
    if n == 1:
        out = run(flat)
    else:
        bounds = np.linspace(0, flat.shape[2], n + 1).astype(int)
        chunks = [flat[:, :, a:b] for a, b in zip(bounds[:-1], bounds[1:])]
        out = np.concatenate(list(_pool().map(run, chunks)), axis=2)
    return _like(out.reshape(shape), x)


def _device_step(f, p, g, w: float):
    """One Chambolle step in backend operations on channel-first planes ``f``: returns the
    primal ``f + d`` (``d`` the negative divergence of the dual ``p``), ``d``, the gradient
    norm, and the updated dual.  ``g`` is a work buffer of ``p``'s shape whose last row /
    column stay 0."""
    import tensorly as tl

    d = -(p[0] + p[1])
    d[:, 1:] += p[0][:, :-1]
    d[:, :, 1:] += p[1][:, :, :-1]
    out = f + d
    g[0][:, :-1] = out[:, 1:] - out[:, :-1]
    g[1][:, :, :-1] = out[:, :, 1:] - out[:, :, :-1]
    norm = tl.sqrt(g[0] * g[0] + g[1] * g[1])
    return out, d, norm, (p - 0.25 * g) / (1.0 + (0.25 / w) * norm)


def _tv_on_device(x, w: float, n_iter: int, eps: float = 2.0e-4):
    """scikit-image's ``denoise_tv_chambolle(x, weight=w, eps=eps, max_num_iter=n_iter,
    channel_axis=2)`` in backend operations, so the tensor never leaves its device.

    All channels step together; a channel stops as scikit-image stops it (its
    energy changed by less than ``eps`` times its first energy) and keeps the
    primal of that step.  One vector of energies per step comes to the host.
    """
    import tensorly as tl

    if not w > 0:
        raise ValueError(f"tv: sigma must be > 0, got {w!r}")
    shape = tuple(x.shape)
    f = tl.moveaxis(tl.reshape(x, shape[:2] + (-1,)), 2, 0)  # (channels, H, W)
    p = B.zeros_like_shape((2,) + tuple(f.shape), f)  # a zero dual: the first primal is f
    g = B.zeros_like_shape(tuple(p.shape), f)
    result, done = f, np.zeros(f.shape[0], bool)
    e_init = e_prev = None
    for i in range(int(n_iter)):
        out, d, norm, p = _device_step(f, p, g, w)
        energy = tl.sum(tl.reshape(d * d + w * norm, (f.shape[0], -1)), axis=1)
        e = np.asarray(B.to_numpy(energy), np.float64) / (shape[0] * shape[1])
        if i == 0:
            e_init, e_prev, result = e, e, out
            continue
        stop = (np.abs(e_prev - e) < eps * e_init) & ~done
        keep = B.tensor_like(np.where(done, 1.0, 0.0)[:, None, None], f)
        result = keep * result + (1.0 - keep) * out  # channels stopped before keep their primal
        done |= stop
        e_prev = np.where(done, e_prev, e)
        if done.all():
            break
    return tl.reshape(tl.moveaxis(result, 0, 2), shape)


class WarmTV:
    """Chambolle's TV (the iteration of ``skimage.restoration.denoise_tv_chambolle``) that keeps
    its dual variable between calls: ``WarmTV(n_iter)(x, sigma)``.

    Inside an iterative solver the image to denoise changes little from one
    call to the next, so the last call's dual field is a close start and a
    few steps do what 50 cold ones did.  With a cold start (the first call,
    or after :meth:`reset`) ``n_iter`` steps equal scikit-image's
    ``denoise_tv_chambolle(x, weight=sigma, max_num_iter=n_iter, eps=0,
    channel_axis=-1)`` (tested).  The channels (axes ≥ 2) form one channel-first
    stack, split over threads, each channel taking its steps in turn; the dual
    is dropped when the shape changes.
    scikit-image has no warm start, hence this loop.

    ``compiled``: ``"auto"`` (default) takes a compiled kernel's steps where
    :func:`compiled_tv` is true (numba installed, the ``fast`` extra, and
    ``TENSOR_COSDI_JIT`` not ``0``), 3–4× faster with the same results bit
    for bit (``benchmarks/results/tv_speed.md``); ``True`` requires it (an
    ``ImportError`` without numba), ``False`` keeps the NumPy steps.
    """

    def __init__(self, n_iter: int = 10, *, compiled="auto"):
        if not (isinstance(n_iter, (int, np.integer)) and not isinstance(n_iter, bool)):
            raise TypeError(f"n_iter must be an int ≥ 1, got {n_iter!r}")
        if n_iter < 1:
            raise ValueError(f"n_iter must be ≥ 1, got {n_iter}")
        if not (compiled is True or compiled is False or compiled == "auto"):
            raise ValueError(f"compiled must be True, False or 'auto', got {compiled!r}")
        if compiled is True and _numba_kernel() is None:
            raise ImportError("WarmTV(compiled=True) needs numba: pip install 'tensor_cosdi[fast]'")
        self.n_iter, self.p, self.compiled = int(n_iter), None, compiled
        self._transposed = False  # how the planes of the dual ``p`` lie (:meth:`_match_dual`)

    def reset(self):
        self.p = None

    def __call__(self, x, sigma: float):
        w = number("WarmTV: sigma", sigma, low=0, low_open=True)
        if B.on_accelerator(x):  # a CUDA tensor, say: stays on its device
            return self._on_device(x, w)
        flat, shape = _host(x, "WarmTV")
        f = np.moveaxis(flat, 2, 0)  # (channels, H, W)
        # Planes held column by column (a Fortran-ordered cube, as the solvers keep theirs) are
        # stepped as they lie, as the transposed images: TV does not change under a transpose
        # (the dual's two halves trade places), and the planes are then read and returned
        # without two transposing copies (subspace TV at 256×256×28, 8 coefficient images:
        # ``benchmarks/results/solver_steps.md``).  Each step adds the divergence's two terms
        # in the untransposed order (``swap``), so the result is the same bit for bit.
        transposed = not f.flags.c_contiguous and f.transpose(0, 2, 1).flags.c_contiguous
        f = f.transpose(0, 2, 1) if transposed else np.ascontiguousarray(f)
        self._match_dual(f, transposed)
        out = np.empty_like(f)
        n = _workers(f.shape[0])
        use = compiled_tv() if self.compiled == "auto" else self.compiled
        kernel = _numba_kernel() if use else None
        if n == 1:
            _chambolle_steps(f, self.p, out, w, self.n_iter, kernel, transposed)
        else:  # channels are independent: chunks in threads (both step loops release the GIL)
            cuts = np.linspace(0, f.shape[0], n + 1).astype(int)
            pool = _pool()
            jobs = [
                pool.submit(
                    _chambolle_steps,
                    f[a:b],
                    self.p[:, a:b],
                    out[a:b],
                    w,
                    self.n_iter,
                    kernel,
                    transposed,
                )
                for a, b in zip(cuts[:-1], cuts[1:])
            ]
            for job in jobs:
                job.result()
        if transposed:
            out = out.transpose(0, 2, 1)
        return _like(np.moveaxis(out, 0, 2).reshape(shape), x)

    def _match_dual(self, f, transposed: bool) -> None:
        """The dual ``p`` for channel-first planes ``f``: zeros where it does not fit them, turned
        over (its halves swapped, each plane transposed) where the last call's planes lay the
        other way; ``transposed`` says how these lie."""
        p = self.p
        if isinstance(p, np.ndarray) and self._transposed != transposed:
            p = np.ascontiguousarray(p[::-1].transpose(0, 1, 3, 2))
        if not isinstance(p, np.ndarray) or p.shape[1:] != f.shape:
            p = np.zeros((2,) + f.shape, f.dtype)
        elif p.dtype != f.dtype:
            p = p.astype(f.dtype)
        self.p, self._transposed = p, transposed

    def _on_device(self, x, w):
        """The same steps with backend operations on ``x``'s device (no host round trip)."""
        import tensorly as tl

        shape = tuple(x.shape)
        f = tl.moveaxis(tl.reshape(x, shape[:2] + (-1,)), 2, 0)
        if (
            self.p is None
            or isinstance(self.p, np.ndarray)
            or tuple(self.p.shape[1:]) != tuple(f.shape)
        ):
            self.p = B.zeros_like_shape((2,) + tuple(f.shape), f)
        p = self.p
        g = B.zeros_like_shape(tuple(p.shape), f)
        for _ in range(self.n_iter):
            out, _, _, p = _device_step(f, p, g, w)
        self.p = p
        return tl.reshape(tl.moveaxis(out, 0, 2), shape)


def _chambolle_steps(f, p, out, w: float, n_iter: int, kernel=None, swap: bool = False) -> None:
    """``n_iter`` Chambolle steps on channel-first planes ``f``, updating the dual ``p`` (shape
    ``(2,) + f.shape``) in place; ``out`` receives the primal of the last step.  ``swap``: the
    planes are transposed images, and each step adds the divergence's two terms in the order of
    the untransposed ones (the second axis' first), so that the result is theirs bit for bit.

    ``kernel``: the compiled :func:`_chambolle_kernel` (:func:`_numba_kernel`) takes the steps,
    else (``None``) :func:`_numpy_steps`; both give the same primal and dual bit for bit
    (tested through :class:`WarmTV`).
    """
    if (
        kernel is None
        or f.size == 0  # the kernel reads the first pixel of every plane
        or not all(a.flags.c_contiguous for a in (f, p[0], p[1], out))
    ):
        _numpy_steps(f, p, out, w, n_iter, swap)
        return
    t = f.dtype.type  # every constant in the planes' precision, as NumPy casts a Python float
    kernel(f, p[0], p[1], out, t(0.25 / w), t(0.25), t(1), t(0), int(n_iter), bool(swap))


def _numpy_steps(f, p, out, w: float, n_iter: int, swap: bool = False) -> None:
    """:func:`_chambolle_steps` in NumPy operations.

    The planes are independent, so each takes all its steps before the next: one plane's
    working set stays in cache, and every temporary is a buffer reused in place.  The result is
    bit for bit that of applying each operation to all planes at once, in about half the time
    (``benchmarks/results/tv_speed.md``).
    """
    one = f.shape[1:]
    g, d = np.zeros((2, 1) + one, f.dtype), np.empty((1,) + one, f.dtype)
    nrm, tmp = np.empty_like(d), np.empty_like(d)
    tau = 0.25  # 1 / (2 · 2 axes)
    k = tau / w
    for c in range(f.shape[0]):
        fc, pc, oc = f[c : c + 1], p[:, c : c + 1], out[c : c + 1]
        p0, p1, g0, g1 = pc[0], pc[1], g[0], g[1]
        for _ in range(n_iter):
            np.add(p0, p1, out=d)  # d = div p (scikit-image's sign)
            np.negative(d, out=d)
            if swap:  # transposed images: the untransposed order of the two terms
                d[:, :, 1:] += p1[:, :, :-1]
                d[:, 1:] += p0[:, :-1]
            else:
                d[:, 1:] += p0[:, :-1]
                d[:, :, 1:] += p1[:, :, :-1]
            np.add(fc, d, out=oc)
            np.subtract(oc[:, 1:], oc[:, :-1], out=g0[:, :-1])  # the last row / column stay 0
            np.subtract(oc[:, :, 1:], oc[:, :, :-1], out=g1[:, :, :-1])
            np.multiply(g0, g0, out=nrm)
            np.multiply(g1, g1, out=tmp)
            nrm += tmp
            np.sqrt(nrm, out=nrm)
            nrm *= k
            nrm += 1.0
            g *= tau
            pc -= g
            p0 /= nrm
            p1 /= nrm


def _chambolle_kernel(f, p0, p1, out, k, tau, one, zero, n_iter, swap):  # pragma: no cover
    """The loop that numba compiles for :func:`_chambolle_steps`: C-contiguous planes ``f``,
    ``out`` and dual halves ``p0``, ``p1`` of one shape ``(planes, H, W)``; ``k = τ / w``,
    ``τ``, 1 and 0 as scalars of the planes' dtype, so that no operation is promoted; ``swap``
    as there (the divergence's two terms added in the other order).

    One sweep a step: the primal row ``i + 1`` is formed from the old dual before the dual's
    row ``i``, which needs the primal rows ``i`` and ``i + 1``, is updated, so the dual is
    rewritten in place.  Each sum and product is the one :func:`_numpy_steps` evaluates, in
    its order (no fused multiply-add, no reciprocal), hence its results bit for bit; the inner
    loops are free of branches (the last row and column apart), so they vectorise.
    """
    planes, h, w = f.shape
    for c in range(planes):
        fc, a, b, oc = f[c], p0[c], p1[c], out[c]
        for _ in range(n_iter):
            oc[0, 0] = fc[0, 0] + (-(a[0, 0] + b[0, 0]))  # row 0: no dual row above
            for j in range(1, w):
                oc[0, j] = fc[0, j] + ((-(a[0, j] + b[0, j])) + b[0, j - 1])
            for i in range(h):
                last = i + 1 == h
                if not last:  # the primal row below, from the dual not yet updated
                    r = i + 1
                    oc[r, 0] = fc[r, 0] + ((-(a[r, 0] + b[r, 0])) + a[i, 0])
                    if swap:  # outside the loops over j: each stays free of branches
                        for j in range(1, w):
                            oc[r, j] = fc[r, j] + (((-(a[r, j] + b[r, j])) + b[r, j - 1]) + a[i, j])
                    else:
                        for j in range(1, w):
                            oc[r, j] = fc[r, j] + (((-(a[r, j] + b[r, j])) + a[i, j]) + b[r, j - 1])
                    for j in range(w - 1):  # the dual row i
                        g0 = oc[r, j] - oc[i, j]
                        g1 = oc[i, j + 1] - oc[i, j]
                        nrm = np.sqrt(g0 * g0 + g1 * g1) * k + one
                        a[i, j] = (a[i, j] - g0 * tau) / nrm
                        b[i, j] = (b[i, j] - g1 * tau) / nrm
                    g0 = oc[r, w - 1] - oc[i, w - 1]
                else:  # the last row has no gradient along axis 0
                    for j in range(w - 1):
                        g1 = oc[i, j + 1] - oc[i, j]
                        nrm = np.sqrt(zero * zero + g1 * g1) * k + one
                        a[i, j] = (a[i, j] - zero * tau) / nrm
                        b[i, j] = (b[i, j] - g1 * tau) / nrm
                    g0 = zero
                nrm = np.sqrt(g0 * g0 + zero * zero) * k + one  # the last column: none along 1
                a[i, w - 1] = (a[i, w - 1] - g0 * tau) / nrm
                b[i, w - 1] = (b[i, w - 1] - zero * tau) / nrm


def _numba_kernel():
    """:func:`_chambolle_kernel` compiled by numba (:func:`~tensor_cosdi._backend.numba_compiled`:
    the first call on a machine compiles it, a few seconds), or ``None`` where numba is not
    installed."""
    return B.numba_compiled(_chambolle_kernel)


def compiled_tv() -> bool:
    """Whether :class:`WarmTV` takes compiled Chambolle steps by default (``compiled="auto"``):
    numba is installed (``pip install "tensor_cosdi[fast]"``) and the environment variable
    ``TENSOR_COSDI_JIT`` is unset, ``1`` or empty (``0`` keeps the NumPy steps; any other
    value is a ``ValueError``).

    Returns
    -------
    bool
        ``True`` where ``WarmTV(n)`` runs the compiled kernel (the same results as the NumPy
        steps bit for bit, 3–4× faster: ``benchmarks/results/tv_speed.md``).

    Examples
    --------
    >>> isinstance(compiled_tv(), bool)
    True
    """
    return B.jit_enabled() and _numba_kernel() is not None


def wavelet(x, sigma: float, *, wavelet_name: str = "db2", mode: str = "soft"):
    """BayesShrink wavelet denoising (``skimage.restoration.denoise_wavelet``) per channel, noise
    ``sigma``."""
    from skimage.restoration import denoise_wavelet

    sigma = number("wavelet: sigma", sigma, low=0, high=1e150)  # its square must not overflow
    if not isinstance(wavelet_name, str):
        raise ValueError(f"wavelet: wavelet_name must be a PyWavelets name, got {wavelet_name!r}")
    if mode not in ("soft", "hard"):
        raise ValueError(f"wavelet: mode must be 'soft' or 'hard', got {mode!r}")
    flat, shape = _host(x, "wavelet")
    out = denoise_wavelet(
        flat,
        sigma=sigma,
        wavelet=wavelet_name,
        mode=mode,
        channel_axis=2,
        method="BayesShrink",
        rescale_sigma=False,
    )
    return _like(out.reshape(shape), x)


_NETS: dict = {}


def spectral_net(x, sigma: float, *, weights=None, rank=None, precision="float32"):
    """The learned spectral denoiser (:class:`tensor_cosdi.learn.spectral_net.SpectralDenoiser`,
    needs torch): a small CNN on the eigen-images of the cube's spectral subspace, for any band
    count, noise ``sigma``.  ``weights`` default: the shipped ones (loaded once);
    ``precision`` as the class's (``"bfloat16"`` or ``"auto"``: twice as fast on a CPU that runs
    bfloat16 natively)."""
    from ..learn.spectral_net import SpectralDenoiser

    key = (None if weights is None else str(weights), rank, precision)
    if key not in _NETS:
        _NETS[key] = SpectralDenoiser(weights, rank=rank, precision=precision)
    return _NETS[key](x, sigma)


#: ``self_ensemble`` sizes: identity, flips, 180° turn (same shape), then the transposes.
ENSEMBLE_SIZES = (1, 2, 4, 8)


def _dihedral(x, k: int, inverse: bool = False):
    """The ``k``-th of the 8 symmetries of the square on axes 0, 1: ``k & 1`` flips axis 0,
    ``k & 2`` flips axis 1, ``k & 4`` swaps them (applied after the flips; undone first)."""
    import tensorly as tl

    if inverse and k & 4:
        x = tl.moveaxis(x, 0, 1)
    if k & 1:
        x = tl.flip(x, axis=0)
    if k & 2:
        x = tl.flip(x, axis=1)
    if not inverse and k & 4:
        x = tl.moveaxis(x, 0, 1)
    return x


def self_ensemble(denoiser, n: int = 2, *, cycle: bool = False) -> Callable:
    """``denoiser`` averaged over ``n`` symmetries of the image plane (geometric self-ensemble).

    Each call denoises ``x`` flipped (and, for ``n = 8``, transposed), undoes
    the symmetry and averages: a learned denoiser's errors that do not follow
    the symmetry average out.  On the tuning scenes (PnP-GAP, learned spectral
    denoiser, 40 iterations) ``n = 2`` gained +0.16 to +0.74 dB, ``n = 4``
    +0.19 to +0.89 dB.

    With ``cycle=True`` the symmetries move on from call to call through all
    eight: call ``i`` averages symmetries ``n·i … n·i + n − 1`` (mod 8), so an
    iterative solver's successive calls see the image in every orientation
    and their errors average out over the iterations, at ``n`` denoiser calls
    a call as before (``n = 1``: one call, each in the next symmetry).  The
    result depends on how many calls came before: make one per
    reconstruction.

    Parameters
    ----------
    denoiser : str or callable
        A registered denoiser name or a callable ``(x, sigma) -> x``.
    n : {1, 2, 4, 8}
        1 (the denoiser itself, or with ``cycle`` one symmetry a call), 2
        (identity and the up-down flip), 4 (both flips and the half turn) or 8
        (with the transposes); each call costs ``n`` denoiser calls.
    cycle : bool
        Cycle through the eight symmetries over successive calls (see above;
        with ``n = 8`` every call already takes all of them).

    Returns
    -------
    callable
        ``(x, sigma) -> x``, usable wherever a denoiser is.

    Examples
    --------
    >>> import numpy as np
    >>> smooth = self_ensemble("tv", 2)
    >>> smooth(np.random.default_rng(0).random((8, 8, 2)), 0.1).shape
    (8, 8, 2)
    """
    den = resolve(denoiser)
    if isinstance(n, bool) or n not in ENSEMBLE_SIZES:
        raise ValueError(f"the ensemble size must be one of {ENSEMBLE_SIZES}, got {n!r}")
    if not isinstance(cycle, (bool, np.bool_)):
        raise ValueError(f"cycle must be True or False, got {cycle!r}")
    if n == 1 and not cycle:
        return den
    cycle = bool(cycle) and n < 8
    first = [0]  # the first symmetry of the next call

    def one(x, sigma, k):
        if k == 0:  # the identity: no flipped copy
            return den(x, sigma)
        return _dihedral(den(_dihedral(x, k), sigma), k, inverse=True)

    def ensemble(x, sigma):
        k0 = first[0]
        if cycle:
            first[0] = (k0 + n) % 8
        acc = None
        for j in range(n):
            y = one(x, sigma, (k0 + j) % 8)
            acc = y if acc is None else acc + y
        out = acc if n == 1 else acc / n
        if isinstance(x, np.ndarray) and isinstance(out, np.ndarray):
            # a flipped or transposed first term leaves a strided view: the input's memory
            # order instead (the shear kernels run 5× slower on a cube in the other order)
            if x.flags.f_contiguous and not out.flags.f_contiguous:
                return np.asfortranarray(out)
            if not x.flags.f_contiguous and not out.flags.c_contiguous:
                return np.ascontiguousarray(out)
        return out

    ensemble.__name__ = f"self_ensemble_{n}{'_cycled' if cycle else ''}"
    return ensemble


def register_denoiser(name: str, func: Callable, *, replace: bool = False) -> None:
    """Make ``func(x, sigma)`` available to PnP methods as ``denoiser=name``.

    A name that exists needs ``replace=True``; ``"tv"`` and ``"wavelet"`` cannot be replaced.
    """
    if not callable(func):
        raise ValueError(f"a denoiser must be callable (x, sigma) -> x, got {func!r}")
    builtin = getattr(func, "__module__", "") == __name__
    DENOISERS.register(name, func, replace=replace, builtin=builtin)


def denoisers() -> tuple[str, ...]:
    """Names of the registered denoisers."""
    return DENOISERS.names()


def denoise(name_or_callable, x, sigma):
    """Apply a registered denoiser by name, or a callable ``(x, sigma) -> x``; ``x`` holds real
    numbers (a complex one is an error, not cast)."""
    f = resolve(name_or_callable)
    if isinstance(x, np.ndarray):
        bad = x.dtype.kind not in "iuf"  # complex, text, bytes, objects, booleans
    else:
        bad = hasattr(x, "dtype") and B.real_dtype_name(x).startswith(("complex", "bool"))
    if bad:
        raise ValueError(f"denoise: x must hold real numbers, got dtype {x.dtype}")
    return f(x, sigma)


def resolve(name_or_callable) -> Callable:
    if callable(name_or_callable):
        return name_or_callable
    try:
        return DENOISERS[name_or_callable]
    except KeyError:
        raise ValueError(
            f"unknown denoiser {name_or_callable!r}; registered: {list(denoisers())} "
            "(or pass a callable (x, sigma) -> x)"
        ) from None


register_denoiser("tv", tv)
register_denoiser("wavelet", wavelet)
register_denoiser("spectral_net", spectral_net)
