"""Structured inverses ``(μI + A Aᵀ)⁻¹`` for tensor-Woodbury steps (SPEC §4).

Three structures cover the five imagers:

* :class:`Diagonal` — ``A Aᵀ = diag(d)`` (SD/DD-CASSI, CASSDI-DFA without PSFs,
  CS2LI, Mu-CoSDI): one Hadamard division.
* :class:`PixelBlocks` — one ``K × K`` block per pixel, coupling the entries
  along one axis (C3SLFI, multi-shot CASSI; Eq. 209-211): batched ``K × K``
  inverses, cached per ``μ``.
* :class:`RowBanded` — banded along one axis, independent across the others
  (CASSI-VSI): a banded Cholesky factor per fibre (``scipy.linalg``), cached
  per ``μ``; :class:`FoldedBanded` is the
  same with a frame axis folded into the band axis (a dispersed frame stacked
  with undispersed ones: dual-camera CASSI, Lytro-CASSI).

:func:`conjugate_gradient` is the fallback when no structure is known.

How the structure of an operator is found: :mod:`tensor_cosdi.operators.gram`.
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg
import tensorly as tl

from .. import _backend as B
from ..validate import flag, integer, number, real_array

__all__ = [
    "Diagonal",
    "PixelBlocks",
    "RowBanded",
    "FoldedBanded",
    "fold_for",
    "conjugate_gradient",
    "gram_eigenvalues",
]


# --------------------------------------------------------------------- structures
class _Structure:
    """Common base: caches of converted arrays per (μ, context)."""

    def __init__(self):
        self._cache: dict = {}

    def _cached(self, key, make):
        hit = self._cache.get(key)
        if hit is None:
            if len(self._cache) > 8:
                self._cache.clear()
            hit = make()
            self._cache[key] = hit
        return hit


class Diagonal(_Structure):
    """``A Aᵀ = diag(d)`` with ``d`` of the measurement shape.

    ``solve(b, μ) = b / (μ + d)``.
    """

    kind = "diagonal"

    def __init__(self, d: np.ndarray):
        super().__init__()
        self.d = real_array("the diagonal", d)

    def solve(self, b, mu):
        denom = self._cached(("den", mu) + B.context_key(b), lambda: B.tensor_like(self.d + mu, b))
        return b / denom

    def matvec(self, b):
        return b * B.tensor_like(self.d, b)

    def to_dense(self) -> np.ndarray:
        return np.diag(self.d.reshape(-1, order="F"))

    def __repr__(self):
        return f"Diagonal(shape={self.d.shape})"


class PixelBlocks(_Structure):
    """One symmetric ``K × K`` block per pixel, coupling entries along ``axis``.

    ``Q[..., k1, k2]`` holds ``(A Aᵀ)`` between entries ``k1`` and ``k2`` of the
    block axis at each pixel (the other axes, in order).  ``solve`` applies
    the per-pixel inverse of ``μI + Q``, computed once per ``μ`` by batched
    LAPACK solves (Eq. 209-211).
    """

    kind = "pixel_blocks"

    def __init__(self, Q: np.ndarray, axis: int):
        super().__init__()
        self.Q = real_array("the pixel blocks", Q, finite=False)
        self.axis = axis

    @property
    def block_size(self) -> int:
        return self.Q.shape[-1]

    def _inverse(self, mu):
        K = self.block_size
        M = self.Q + mu * np.eye(K)
        eye = np.broadcast_to(np.eye(K), M.shape)
        return np.linalg.solve(M, eye)

    def solve(self, b, mu):
        inv = self._cached(
            ("inv", mu) + B.context_key(b), lambda: B.tensor_like(self._inverse(mu), b)
        )
        bm = tl.moveaxis(b, self.axis, -1)
        x = tl.sum(inv * bm[..., None, :], axis=-1)
        return tl.moveaxis(x, -1, self.axis)

    def matvec(self, b):
        Q = B.tensor_like(self.Q, b)
        bm = tl.moveaxis(b, self.axis, -1)
        return tl.moveaxis(tl.sum(Q * bm[..., None, :], axis=-1), -1, self.axis)

    def to_dense(self) -> np.ndarray:
        shape = self.Q.shape[:-2] + (self.Q.shape[-1],)
        full_shape = list(shape[:-1])
        full_shape.insert(self.axis, shape[-1])
        n = int(np.prod(full_shape))
        idx = np.moveaxis(np.arange(n).reshape(full_shape, order="F"), self.axis, -1)
        M = np.zeros((n, n))
        rows = np.broadcast_to(idx[..., :, None], self.Q.shape)
        cols = np.broadcast_to(idx[..., None, :], self.Q.shape)
        M[rows.ravel(), cols.ravel()] = self.Q.ravel()
        return M

    def __repr__(self):
        return f"PixelBlocks(K={self.block_size}, axis={self.axis}, pixels={self.Q.shape[:-2]})"


class RowBanded(_Structure):
    """Symmetric banded coupling along ``axis``, independent across other axes.

    ``bands[o, ..., p] = (A Aᵀ)[p, p + o]`` along the band axis (moved last),
    for ``o = 0 … b``.  ``solve`` factors ``μI + A Aᵀ`` per fibre with
    ``scipy.linalg.cholesky_banded`` once per ``μ`` and back-substitutes with
    ``cho_solve_banded``.
    """

    kind = "row_banded"

    def __init__(self, bands: np.ndarray, axis: int):
        super().__init__()
        self.bands = real_array("bands", bands, finite=False)
        self.axis = axis

    @property
    def bandwidth(self) -> int:
        return self.bands.shape[0] - 1

    def upper_form(self):
        """Each fibre's matrix in LAPACK's upper banded storage ``ab[b − o, p + o] = (A Aᵀ)[p,
        p + o]`` (a generator of ``(b + 1, n)`` arrays)."""
        b = self.bandwidth
        n = self.bands.shape[-1]
        fibres = self.bands.reshape(b + 1, -1, n)
        for f in range(fibres.shape[1]):
            ab = np.zeros((b + 1, n))
            for o in range(b + 1):
                ab[b - o, o:] = fibres[o, f, : n - o]
            yield ab

    def _factors(self, mu):
        out = []
        for ab in self.upper_form():
            ab[self.bandwidth] += mu
            out.append(scipy.linalg.cholesky_banded(ab, lower=False))
        return out

    def solve(self, b, mu):
        return B.tensor_like(
            self._solve_host(real_array("the right-hand side", B.to_numpy(b), finite=False), mu), b
        )

    def matvec(self, b):
        """``(A Aᵀ) b`` from the stored bands (host computation)."""
        return B.tensor_like(
            self._matvec_host(real_array("the right-hand side", B.to_numpy(b), finite=False)), b
        )

    def _solve_host(self, b: np.ndarray, mu) -> np.ndarray:
        factors = self._cached(("chol", mu), lambda: self._factors(mu))
        bn = np.moveaxis(b, self.axis, -1)
        lead = bn.shape[:-1]
        flat = bn.reshape(-1, bn.shape[-1])
        x = np.empty_like(flat)
        for f, cb in enumerate(factors):
            x[f] = scipy.linalg.cho_solve_banded((cb, False), flat[f], check_finite=False)
        return np.moveaxis(x.reshape(lead + (bn.shape[-1],)), -1, self.axis)

    def _matvec_host(self, b: np.ndarray) -> np.ndarray:
        bn = np.moveaxis(b, self.axis, -1)
        n = bn.shape[-1]
        out = self.bands[0] * bn
        for o in range(1, self.bandwidth + 1):
            out[..., : n - o] += self.bands[o, ..., : n - o] * bn[..., o:]
            out[..., o:] += self.bands[o, ..., : n - o] * bn[..., : n - o]
        return np.moveaxis(out, -1, self.axis)

    def to_dense(self) -> np.ndarray:
        n = self.bands.shape[-1]
        lead = self.bands.shape[1:-1]
        full_shape = list(lead)
        full_shape.insert(self.axis, n)
        N = int(np.prod(full_shape))
        idx = np.moveaxis(np.arange(N).reshape(full_shape, order="F"), self.axis, -1)
        M = np.zeros((N, N))
        for o in range(self.bandwidth + 1):
            r = idx[..., : n - o].ravel()
            c = idx[..., o:].ravel()
            v = self.bands[o, ..., : n - o].ravel()
            M[r, c] = v
            M[c, r] = v
        return M

    def __repr__(self):
        return f"RowBanded(bandwidth={self.bandwidth}, axis={self.axis})"


# --------------------------------------------------------------------- CG


# ------------------------------------------------- a frame axis folded into the band axis
class _Fold:
    """The permutation ``(…, axis, …, block_axis, …) → (others…, n · F)`` and its inverse."""

    def __init__(self, shape, axis: int, block_axis: int):
        self.shape = tuple(int(n) for n in shape)
        self.axis, self.block_axis = axis, block_axis
        others = [a for a in range(len(self.shape)) if a not in (axis, block_axis)]
        self.perm = tuple(others) + (axis, block_axis)
        self.inverse = tuple(np.argsort(self.perm))
        self.folded_shape = tuple(self.shape[a] for a in others) + (
            self.shape[axis] * self.shape[block_axis],
        )

    def fold(self, x: np.ndarray) -> np.ndarray:
        return np.transpose(x, self.perm).reshape(self.folded_shape)

    def unfold(self, y: np.ndarray) -> np.ndarray:
        split = tuple(self.shape[a] for a in self.perm)
        return np.transpose(y.reshape(split), self.inverse)


class FoldedBanded(RowBanded):
    """:class:`RowBanded` on the measurement with ``block_axis`` folded into ``axis``.

    ``bands`` are those of the folded tensor (band axis last); ``solve``,
    ``matvec`` and ``to_dense`` act on the measurement in its own shape.
    """

    def __init__(self, bands: np.ndarray, shape, axis: int, block_axis: int):
        self.fold = _Fold(shape, axis, block_axis)
        super().__init__(bands, len(self.fold.folded_shape) - 1)

    def _host(self, b) -> np.ndarray:
        return self.fold.fold(real_array("the right-hand side", B.to_numpy(b), finite=False))

    def solve(self, b, mu):  # on the host, as RowBanded; back on b's backend and device
        return B.tensor_like(self.fold.unfold(self._solve_host(self._host(b), mu)), b)

    def matvec(self, b):
        return B.tensor_like(self.fold.unfold(self._matvec_host(self._host(b))), b)

    def to_dense(self) -> np.ndarray:
        folded = super().to_dense()  # in the folded tensor's column-major order
        n = int(np.prod(self.fold.shape))
        where = self.fold.fold(np.arange(n).reshape(self.fold.shape, order="F"))
        order = where.reshape(-1, order="F")  # folded position → original index
        out = np.empty_like(folded)
        out[np.ix_(order, order)] = folded
        return out

    def __repr__(self):
        return (f"FoldedBanded(bandwidth={self.bandwidth}, axis={self.fold.axis}, "
                f"block_axis={self.fold.block_axis})")  # fmt: skip


def fold_for(shape, axis: int, block_axis: int):
    """The folding of ``block_axis`` into the band ``axis`` of a tensor of ``shape``."""
    return _Fold(shape, axis, block_axis)


def conjugate_gradient(
    apply, b, *, x0=None, rtol: float = 1e-12, maxiter: int | None = None, warn: bool = True
):
    """Conjugate gradients for ``apply(x) = b`` with a symmetric positive-definite ``apply``.

    Backend-neutral (works on GPU tensors), so it is written on TensorLy
    operations rather than ``scipy.sparse.linalg.cg``, which needs NumPy
    vectors.  Stops when ``‖b − apply(x)‖ ≤ rtol ‖b‖`` or after ``maxiter``
    iterations (default: ten times the number of unknowns, between 100 and
    10 000 — round-off makes ill-conditioned systems need more than ``n``).
    Emits a ``RuntimeWarning`` with the reached residual when it stops
    before the tolerance, unless ``warn=False`` (a deliberately inexact solve: a fixed
    number of warm-started steps inside an outer iteration).
    """
    rtol = number("rtol", rtol, low=0, high=1)
    maxiter = None if maxiter is None else integer("maxiter", maxiter, low=1)
    warn = flag("warn", warn)
    if not (hasattr(b, "shape") and hasattr(b, "dtype")) or (
        isinstance(b, np.ndarray) and b.dtype.kind not in "iuf"
    ):
        raise ValueError(
            f"b must be a tensor of real numbers, got {type(b).__name__} "
            f"{getattr(b, 'dtype', '')}".rstrip()
        )
    n = int(np.prod(tl.shape(b)))
    if maxiter is None:
        maxiter = int(min(max(10 * n, 100), 10_000))
    x = B.zeros_like_shape(tl.shape(b), b) if x0 is None else x0
    r = b - apply(x) if x0 is not None else b
    p = r
    rs = float(tl.sum(r * r))
    bnorm2 = float(tl.sum(b * b))
    if not np.isfinite(bnorm2):
        raise ValueError("conjugate_gradient: b holds NaN or inf (or overflows when squared)")
    if bnorm2 == 0.0:
        return x
    tol2 = (rtol**2) * bnorm2
    for _ in range(maxiter):
        if rs <= tol2:
            break
        Ap = apply(p)
        alpha = rs / float(tl.sum(p * Ap))
        x = x + alpha * p
        r = r - alpha * Ap
        rs_new = float(tl.sum(r * r))
        p = r + (rs_new / rs) * p
        rs = rs_new
    else:
        if rs > tol2 and warn:
            warnings.warn(
                f"conjugate gradients stopped after {maxiter} iterations at relative residual "
                f"{np.sqrt(rs / bnorm2):.2e} (> rtol={rtol:.0e})",
                RuntimeWarning,
                stacklevel=2,
            )
    return x


def gram_eigenvalues(gram):
    """All eigenvalues of a structured ``A Aᵀ`` (:class:`Diagonal`, :class:`PixelBlocks`,
    :class:`RowBanded`) and its Gershgorin ``(lower, upper)`` bounds, in float64 NumPy."""
    kind = getattr(gram, "kind", None)
    if not isinstance(kind, str):
        raise ValueError(
            "expected a structured A Aᵀ (Diagonal, PixelBlocks or RowBanded, e.g. "
            f"system.gram_dual()), got {type(gram).__name__}"
        )
    if kind == "diagonal":
        d = np.asarray(B.to_numpy(gram.d), dtype=np.float64).ravel()
        return d, (float(d.min()), float(d.max()))
    if kind == "pixel_blocks":
        q = np.asarray(B.to_numpy(gram.Q), dtype=np.float64)
        q = q.reshape(-1, *q.shape[-2:])
        ev = np.linalg.eigvalsh(q).ravel()
        centre = np.diagonal(q, axis1=1, axis2=2)
        radius = np.abs(q).sum(axis=2) - np.abs(centre)
        return ev, (float((centre - radius).min()), float((centre + radius).max()))
    if kind == "row_banded":
        b = gram.bandwidth
        evs, lo, hi = [], np.inf, -np.inf
        for ab in gram.upper_form():
            diag, radius = ab[b], np.zeros(ab.shape[1])
            for o in range(1, b + 1):  # off-diagonal o: ab[b − o, o:] couples p and p + o
                off = np.abs(ab[b - o, o:])
                radius[:-o] += off
                radius[o:] += off
            evs.append(scipy.linalg.eig_banded(ab, eigvals_only=True))
            lo, hi = min(lo, float((diag - radius).min())), max(hi, float((diag + radius).max()))
        return np.concatenate(evs), (lo, hi)
    raise ValueError(f"no eigenvalues for an A Aᵀ structure of kind {kind!r}")
