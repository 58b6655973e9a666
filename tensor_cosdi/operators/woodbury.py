"""Structured inverses ``(μI + A Aᵀ)⁻¹`` for tensor-Woodbury steps (SPEC §4).

Three structures cover the five imagers:

* :class:`Diagonal` — ``A Aᵀ = diag(d)`` (SD/DD-CASSI, CASSDI-DFA without PSFs,
  CS2LI, Mu-CoSDI): one Hadamard division.
* :class:`PixelBlocks` — one ``K × K`` block per pixel, coupling the entries
  along one axis (C3SLFI, multi-shot CASSI; Eq. 209-211): batched ``K × K``
  inverses, cached per ``μ``.
* :class:`RowBanded` — banded along one axis, independent across the others
  (CASSI-VSI): a banded Cholesky factor per fibre (``scipy.linalg``), cached
  per ``μ``; :class:`~tensor_cosdi.operators._folded.FoldedBanded` is the
  same with a frame axis folded into the band axis (a dispersed frame stacked
  with undispersed ones: dual-camera CASSI, Lytro-CASSI).

:func:`conjugate_gradient` is the fallback when no structure is known.

How structures are found: an operator reports a :class:`Pattern` (which
entries of ``A Aᵀ`` may be non-zero), derived from the index maps
(:class:`~tensor_cosdi.operators._base.Routing`) of its building blocks; the
values are then measured exactly by applying ``A Aᵀ`` to ``1``, ``K`` or
``2b + 1`` probe tensors (ones; one-hot along the block axis; combs of period
``2b + 1`` along the band axis), so no per-primitive formula for ``A Aᵀ`` is
needed and compositions, sums and stacks are covered alike.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from functools import partial

import numpy as np
import scipy.linalg
import tensorly as tl

from .. import _backend as B

__all__ = [
    "Pattern",
    "Diagonal",
    "PixelBlocks",
    "RowBanded",
    "conjugate_gradient",
    "probe_structure",
    "pattern_from_terms",
    "StructureError",
    "check_structure",
]

#: Largest relative error of the structured ``A Aᵀ v`` against ``A(Aᵀ v)`` on the float64 probe
#: that :func:`check_structure` accepts.
SELF_CHECK_RTOL = 1e-6


class StructureError(ValueError):
    """The structure derived for ``A Aᵀ`` does not reproduce ``A(Aᵀ v)``: a mis-routed operator."""


#: Widest band (one side) that is probed and factored; wider couplings use CG.
MAX_BANDWIDTH = 512
#: Largest per-pixel block that is probed and inverted; larger ones use CG.
MAX_BLOCK = 64


@dataclass(frozen=True)
class Pattern:
    """Which entries of ``A Aᵀ`` may be non-zero.

    ``kind`` is ``"diag"``; ``"blocks"`` (entries that differ only along
    ``axis``); or ``"band"`` (entries that differ only along ``axis``, by at
    most ``width``, and, with ``block_axis``, along ``block_axis`` freely:
    :class:`~tensor_cosdi.operators._folded.FoldedBanded`).
    """

    kind: str
    axis: int = -1
    width: int = 0
    block_axis: int | None = None


# --------------------------------------------------------------------- patterns
def pattern_from_terms(op, terms) -> Pattern | None:
    """Pattern of ``A Aᵀ`` for ``A = Σ terms`` where every term is a routing.

    For one input entry ``e``, term ``i`` writes at ``pos(e) + d_i(e) + [0, spread_i]``
    along every output axis, with ``d_i`` in the interval ``disp_i``.  Two
    outputs are coupled when one input entry reaches both, so along each axis
    the offsets between coupled outputs are bounded by the spreads (same
    term, or terms with equal index maps) and by the differences of the
    displacement intervals (other pairs).  Exactly one coupled axis gives a
    band; none gives a diagonal.
    """
    routes = [t._routing() for t in terms]
    if any(r is None for r in routes):
        return None
    if len({r.key for r in routes}) == 1 and routes[0].single:
        return Pattern("diag")
    if len({r.axis_map for r in routes}) != 1:
        return None
    ndim = len(op.output_shape)
    widths = []
    for o in range(ndim):
        w = 0
        for i, ri in enumerate(routes):
            for j, rj in enumerate(routes):
                if i == j or ri.key == rj.key:
                    si, sj = ri.spread[o], rj.spread[o]
                    if si is None or sj is None:
                        return None
                    w = max(w, si, sj)
                    continue
                di, dj = ri.disp[o], rj.disp[o]
                si, sj = ri.spread[o], rj.spread[o]
                if di is None or dj is None or si is None or sj is None:
                    return None
                lo = dj[0] - di[1] - si
                hi = dj[1] + sj - di[0]
                w = max(w, abs(lo), abs(hi))
        widths.append(w)
    coupled = [o for o in range(ndim) if widths[o] > 0]
    if not coupled:
        return Pattern("diag")
    if len(coupled) == 1:
        o = coupled[0]
        width = min(widths[o], op.output_shape[o] - 1)
        if width > MAX_BANDWIDTH:
            return None
        return Pattern("band", o, width)
    return None


# --------------------------------------------------------------------- probing
def _apply_gram(op, probe_np: np.ndarray) -> np.ndarray:
    v = B.as_tensor(probe_np, "float64")
    return np.asarray(B.to_numpy(op._forward(op._adjoint(v))), dtype=np.float64)


def probe_structure(op, pattern: Pattern):
    """Measure the entries of ``A Aᵀ`` allowed by ``pattern`` with probe tensors, then check them.

    The result is verified by :func:`check_structure` before it is returned,
    so a wrong pattern (an index map that misses a coupling) is an error
    instead of a silently wrong solve.
    """
    structure = _probe(op, pattern)
    if structure is not None:
        check_structure(op, structure)
    return structure


def check_structure(op, structure, *, rtol: float = SELF_CHECK_RTOL, seed: int = 12345) -> float:
    """One random probe: ``structure.matvec(v)`` against ``A(Aᵀ v)`` in float64.

    Returns the relative error; raises :class:`StructureError` naming the
    operator and the structure when it exceeds ``rtol``.
    """
    v = np.random.default_rng(seed).standard_normal(op.output_shape)
    exact = _apply_gram(op, v)
    got = np.asarray(B.to_numpy(structure.matvec(B.as_tensor(v, "float64"))), dtype=np.float64)
    err = float(np.linalg.norm(got - exact)) / max(
        float(np.linalg.norm(exact)), np.finfo(float).tiny
    )
    if not err <= rtol:
        raise StructureError(
            f"the {structure!r} derived for A Aᵀ of {op!r} does not reproduce A(Aᵀ v): relative "
            f"error {err:.3g} > {rtol:g}; an operator reports a wrong index map (_routing or "
            "_gram_pattern)"
        )
    return err


def _probe(op, pattern: Pattern):
    shape = op.output_shape
    if pattern.kind == "diag":
        return Diagonal(_apply_gram(op, np.ones(shape)))
    if pattern.kind == "blocks":
        axis = pattern.axis
        K = shape[axis]
        if K > MAX_BLOCK:
            return None
        cols = []
        for k in range(K):
            probe = np.zeros(shape)
            idx = [slice(None)] * len(shape)
            idx[axis] = k
            probe[tuple(idx)] = 1.0
            cols.append(np.moveaxis(_apply_gram(op, probe), axis, -1))
        # cols[k][..., k'] = (A Aᵀ)[k', k]
        Q = np.stack(cols, axis=-1)
        return PixelBlocks(Q, axis)
    if pattern.kind == "band" and pattern.block_axis is not None:
        from ._folded import probe_folded

        return probe_folded(op, pattern)
    if pattern.kind == "band":
        bands = _probe_band(partial(_apply_gram, op), shape, pattern.axis, pattern.width)
        return RowBanded(bands, pattern.axis)
    raise ValueError(f"unknown pattern kind {pattern.kind!r}")


def _probe_band(gram, shape, axis: int, b: int) -> np.ndarray:
    """``bands[o, ..., p] = (A Aᵀ)[p, p + o]`` along ``axis`` (moved last) from ``2b + 1`` combs."""
    n = shape[axis]
    m = 2 * b + 1
    pos = np.arange(n)
    results = []
    for r in range(min(m, n)):
        comb = (pos % m == r).astype(float)
        probe = np.broadcast_to(
            comb.reshape([-1 if a == axis else 1 for a in range(len(shape))]), shape
        ).copy()
        results.append(np.moveaxis(gram(probe), axis, -1))
    res = np.stack(results)  # (r, ..., n)
    bands = np.zeros((b + 1,) + res.shape[1:])
    for o in range(b + 1):
        p = np.arange(n - o)
        # the comb that holds column p + o has residue (p + o) mod m
        bands[o, ..., : n - o] = np.moveaxis(res[(p + o) % m, ..., p], 0, -1)
    return bands


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
        self.d = np.asarray(d, dtype=np.float64)

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
        self.Q = np.asarray(Q, dtype=np.float64)
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
        self.bands = np.asarray(bands, dtype=np.float64)
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
        return B.tensor_like(self._solve_host(np.asarray(B.to_numpy(b), dtype=np.float64), mu), b)

    def matvec(self, b):
        """``(A Aᵀ) b`` from the stored bands (host computation)."""
        return B.tensor_like(self._matvec_host(np.asarray(B.to_numpy(b), dtype=np.float64)), b)

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
def conjugate_gradient(apply, b, *, x0=None, rtol: float = 1e-12, maxiter: int | None = None):
    """Conjugate gradients for ``apply(x) = b`` with a symmetric positive-definite ``apply``.

    Backend-neutral (works on GPU tensors), so it is written on TensorLy
    operations rather than ``scipy.sparse.linalg.cg``, which needs NumPy
    vectors.  Stops when ``‖b − apply(x)‖ ≤ rtol ‖b‖`` or after ``maxiter``
    iterations (default: ten times the number of unknowns, between 100 and
    10 000 — round-off makes ill-conditioned systems need more than ``n``).
    Emits a ``RuntimeWarning`` with the reached residual when it stops
    before the tolerance.
    """
    n = int(np.prod(tl.shape(b)))
    if maxiter is None:
        maxiter = int(min(max(10 * n, 100), 10_000))
    x = B.zeros_like_shape(tl.shape(b), b) if x0 is None else x0
    r = b - apply(x) if x0 is not None else b
    p = r
    rs = float(tl.sum(r * r))
    bnorm2 = float(tl.sum(b * b))
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
        if rs > tol2:
            warnings.warn(
                f"conjugate gradients stopped after {maxiter} iterations at relative residual "
                f"{np.sqrt(rs / bnorm2):.2e} (> rtol={rtol:.0e})",
                RuntimeWarning,
                stacklevel=2,
            )
    return x
