"""Block-diagonal learned bases: one orthonormal block per run of rows (or columns).

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

from . import _backend as B
from .bases import Dense, _gram_basis, unfolding_gram


def block_sizes(n: int, max_block: int) -> list[int]:
    """``n`` cut into ``⌈n / max_block⌉`` runs of near-equal length (they differ by at most 1)."""
    n, max_block = int(n), int(max_block)
    if n < 1 or max_block < 1:
        raise ValueError(f"block_sizes needs n ≥ 1 and max_block ≥ 1, got {n}, {max_block}")
    k = -(-n // max_block)
    return [n // k + (1 if i < n % k else 0) for i in range(k)]


class BlockDense(Dense):
    """A block-diagonal orthonormal transform: block ``k`` acts on its own run of indices.

    ``matrix`` is the dense block-diagonal ``Ψ`` (the oracle and the other
    backends' path); NumPy arrays go one GEMM per block.

    Examples
    --------
    >>> import numpy as np
    >>> from tensor_cosdi.bases import BlockDense, dct
    >>> t = BlockDense([dct(3), dct(2)])
    >>> t.sizes, t.matrix.shape
    ([3, 2], (5, 5))
    """

    kind = "block_dense"

    def __init__(self, blocks):
        from scipy.linalg import block_diag

        mats = [np.asarray(B.to_numpy(b), dtype=np.float64) for b in blocks]
        if not mats or any(m.ndim != 2 or m.shape[0] != m.shape[1] for m in mats):
            raise ValueError(
                f"BlockDense needs square blocks, got shapes {[m.shape for m in mats]}"
            )
        super().__init__(block_diag(*mats))
        self.blocks = [Dense(m) for m in mats]
        self.sizes = [m.shape[0] for m in mats]
        self._edges = np.cumsum([0] + self.sizes)

    def _along(self, x, axis, out, transpose):
        n = x.shape[axis]
        pre, post = int(np.prod(x.shape[:axis])), int(np.prod(x.shape[axis + 1 :]))
        v = x.reshape(pre, n, post)
        o = np.empty_like(v) if out is None else out.reshape(pre, n, post)
        for blk, a, b in zip(self.blocks, self._edges[:-1], self._edges[1:]):
            m = blk._typed(transpose, x.dtype)
            if post == 1:
                np.matmul(v[:, a:b, 0], m.T, out=o[:, a:b, 0])
            else:
                np.matmul(m, v[:, a:b, :], out=o[:, a:b, :])
        return o.reshape(x.shape)

    def _analysis(self, x, axis, out=None):
        return self._along(x, axis, out, True)

    def _synthesis(self, x, axis, out=None):
        return self._along(x, axis, out, False)

    def __repr__(self):
        return f"BlockDense(sizes={self.sizes})"


def block_hosvd(tensor, mode: int, sizes) -> BlockDense:
    """The HOSVD basis of ``mode`` learned per run of ``sizes`` indices: block ``k`` holds the
    eigenvectors of the diagonal block ``k`` of the mode-``mode`` unfolding's Gram matrix
    (strongest first), i.e. the left singular vectors of the unfolding's rows in that run."""
    shape = np.shape(tensor)  # not copied to the host: only the Gram matrix is
    if not -len(shape) <= mode < len(shape):
        raise ValueError(f"mode {mode} is not an axis of a tensor of shape {shape}")
    mode %= len(shape)
    sizes = [int(s) for s in sizes]
    if sum(sizes) != shape[mode] or min(sizes) < 1:
        raise ValueError(f"block sizes {sizes} do not cut an axis of {shape[mode]}")
    gram = unfolding_gram(tensor, mode)
    edges = np.cumsum([0] + sizes)
    blocks = [
        _gram_basis(gram[a:b, a:b], "block_hosvd: the tensor contains NaN or inf")
        for a, b in zip(edges[:-1], edges[1:])
    ]
    return BlockDense(blocks)
