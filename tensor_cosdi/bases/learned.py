"""Bases learned from data: SVD and HOSVD (Tucker) factors, whole or block-diagonal.

Block-diagonal learned bases: one orthonormal block per run of rows (or columns).

A dense learned spatial basis of an ``n``-pixel axis costs ``n`` operations
per pixel in every transform, so a transform of an ``n × n × b`` cube grows
as ``n³``: at 660 × 660 × 28 the two spatial GEMMs of OTD took 28 of its
75 s.  Cutting the axis into runs of at most ``max_block`` pixels and
learning one basis per run (the HOSVD restricted to those rows — the
diagonal blocks of the unfolding's Gram matrix) keeps the basis orthonormal
and complete, the transform a Kronecker factor, and the cost per pixel
constant in ``n``.  :func:`tensor_cosdi.bases.tucker_bases` is the
``max_block = n`` case.
"""

from __future__ import annotations

import numpy as np

from .. import _backend as B
from ..validate import axis_index, integer, real_array
from .matrices import _polish, dct
from .transforms import BlockDense

__all__ = ["svd_basis", "tucker_bases", "unfolding_gram", "block_sizes", "block_hosvd"]


def svd_basis(matrix) -> np.ndarray:
    """Complete orthonormal basis of left singular vectors of ``matrix`` (``m × k``), strongest
    first.

    Learned spatial bases of SPEC §5 step 2: ``Ψ1, Ψ2`` from the panchromatic
    image ``Z`` are ``svd_basis(Z)`` and ``svd_basis(Z.T)``.  Computed from the
    small Gram ``M Mᵀ`` (``eigh``), which is complete even where ``k < m``.
    """
    m = real_array("matrix", B.to_numpy(matrix), finite=False)
    if m.ndim != 2:
        raise ValueError(f"svd_basis needs a 2-D matrix, got shape {m.shape}")
    return _gram_basis(m @ m.T, "svd_basis: the matrix contains NaN or inf")


#: Eigenvalues at or below this fraction of the largest are the Gram's numerical null space.
NULL_SPACE_TOL = 1e-9


def _gram_basis(gram, nonfinite: str) -> np.ndarray:
    """Eigenvectors of a Gram matrix, strongest first, polished to orthonormal.

    Two choices make the basis a continuous function of the data, so that a
    result does not jump when the data move by round-off (a measurement in
    other units): each eigenvector's largest entry is positive, and the
    numerical null space (eigenvalues ≤ :data:`NULL_SPACE_TOL` × the
    largest), whose eigenvectors ``eigh`` returns in whatever rotation
    round-off gives, is spanned by DCT atoms (lowest frequency first) with
    the kept eigenvectors projected out.
    """
    if not np.isfinite(gram).all():
        raise ValueError(nonfinite)
    vals, vecs = np.linalg.eigh(gram)
    vals, vecs = vals[::-1], vecs[:, ::-1]
    top = float(vals[0]) if vals.size else 0.0
    keep = int(np.sum(vals > NULL_SPACE_TOL * top)) if top > 0 else 0
    kept = vecs[:, :keep]
    lead = np.argmax(np.abs(kept), axis=0)
    kept = kept * np.where(kept[lead, np.arange(keep)] < 0, -1.0, 1.0)
    if keep < vecs.shape[1]:
        kept = np.concatenate([kept, _completion(kept, vecs.shape[1] - keep)], axis=1)
    return _polish(kept)


def _completion(u: np.ndarray, k: int) -> np.ndarray:
    """``k`` orthonormal vectors orthogonal to the columns of ``u``: DCT atoms, lowest frequency
    first, with ``u`` and the vectors already taken projected out (twice, for round-off)."""
    n = u.shape[0]
    out: list[np.ndarray] = []
    for atom in dct(n).T:
        v = atom
        for _ in range(2):
            v = v - u @ (u.T @ v)
            for w in out:
                v = v - w * (w @ v)
        norm = float(np.linalg.norm(v))
        if norm > 1e-6:
            out.append(v / norm)
            if len(out) == k:
                break
    return np.stack(out, axis=1)


#: Elements per block when :func:`unfolding_gram` streams a tensor (1/16 of a 256²×28 cube).
_GRAM_BLOCK = 1 << 17


def unfolding_gram(x: np.ndarray, mode: int) -> np.ndarray:
    """``X₍ₘ₎ X₍ₘ₎ᵀ`` of the mode-``mode`` unfolding in float64, streamed in blocks: no copy of
    the tensor (an unfolding of a non-leading mode and a float64 cast would cost three).  A
    PyTorch tensor on a GPU is summed there (:func:`tensor_cosdi._backend.unfolding_gram`)."""
    if not isinstance(x, np.ndarray):
        if B.on_accelerator(x) and hasattr(x, "detach"):
            return B.unfolding_gram(x, mode)
        x = np.asarray(B.to_numpy(x))
    if x.dtype.kind not in "biuf":
        raise ValueError(f"unfolding_gram needs a tensor of real numbers, got dtype {x.dtype}")
    if x.ndim == 0 or x.size == 0:
        raise ValueError(f"unfolding_gram needs a tensor with entries, got shape {x.shape}")
    mode = axis_index("mode", mode, x.ndim)
    n = x.shape[mode]
    pre, post = int(np.prod(x.shape[:mode])), int(np.prod(x.shape[mode + 1 :]))
    v = np.ascontiguousarray(x).reshape(pre, n, post)
    gram = np.zeros((n, n))
    cols = min(post, max(1, _GRAM_BLOCK // n))
    rows = max(1, _GRAM_BLOCK // (n * cols))
    for p0 in range(0, pre, rows):
        for c0 in range(0, post, cols):
            blk = v[p0 : p0 + rows, :, c0 : c0 + cols].astype(np.float64)  # a small copy
            blk = blk.transpose(1, 0, 2).reshape(n, -1)
            gram += blk @ blk.T
    if not np.isfinite(gram).all():  # NaN or inf anywhere in x reaches the Gram matrix
        raise ValueError("unfolding_gram: the tensor contains NaN or inf")
    return gram


def tucker_bases(tensor, modes=None) -> dict[int, np.ndarray]:
    """Complete HOSVD bases: ``{mode: svd_basis(unfolding(tensor, mode))}`` (thesis Equation 97).

    Examples
    --------
    >>> import numpy as np
    >>> from tensor_cosdi.bases import is_orthonormal
    >>> bases = tucker_bases(np.random.default_rng(0).random((6, 5, 4)), modes=[2])
    >>> bases[2].shape, is_orthonormal(bases[2])
    ((4, 4), True)
    """
    shape = np.shape(tensor)  # the tensor stays where it is (a GPU, say): see unfolding_gram
    dtype = str(getattr(tensor, "dtype", np.asarray(tensor).dtype))
    if "complex" in dtype or "bool" in dtype:
        raise ValueError(f"tucker_bases: the tensor must hold real numbers, got dtype {dtype}")
    if not shape or 0 in shape:
        raise ValueError(f"tucker_bases: the tensor has no entries (shape {shape})")
    modes = range(len(shape)) if modes is None else modes
    out = {}
    for m in modes:
        m = axis_index("mode", m, len(shape))
        try:
            gram = unfolding_gram(tensor, m)
        except ValueError as exc:
            raise ValueError(f"tucker_bases: {exc}".replace("unfolding_gram: ", "")) from None
        out[m] = _gram_basis(gram, "tucker_bases: the tensor contains NaN or inf")
    return out


# ---- fast per-mode transforms ----------------------------------------------------------


def block_sizes(n: int, max_block: int) -> list[int]:
    """``n`` cut into ``⌈n / max_block⌉`` runs of near-equal length (they differ by at most 1)."""
    n, max_block = integer("n", n, low=1), integer("max_block", max_block, low=1)
    k = -(-n // max_block)
    return [n // k + (1 if i < n % k else 0) for i in range(k)]


def block_hosvd(tensor, mode: int, sizes) -> BlockDense:
    """The HOSVD basis of ``mode`` learned per run of ``sizes`` indices: block ``k`` holds the
    eigenvectors of the diagonal block ``k`` of the mode-``mode`` unfolding's Gram matrix
    (strongest first), i.e. the left singular vectors of the unfolding's rows in that run."""
    shape = np.shape(tensor)  # not copied to the host: only the Gram matrix is
    mode = axis_index("mode", mode, len(shape))
    try:
        sizes = [integer("a block size", s, low=1) for s in np.asarray(sizes, dtype=object).ravel()]
    except TypeError:
        raise ValueError(f"block sizes must be a sequence of integers, got {sizes!r}") from None
    if sum(sizes) != shape[mode] or not sizes:
        raise ValueError(f"block sizes {sizes} do not cut an axis of {shape[mode]}")
    gram = unfolding_gram(tensor, mode)
    edges = np.cumsum([0] + sizes)
    blocks = [
        _gram_basis(gram[a:b, a:b], "block_hosvd: the tensor contains NaN or inf")
        for a, b in zip(edges[:-1], edges[1:])
    ]
    return BlockDense(blocks)
