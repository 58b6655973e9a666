"""``A Aᵀ`` banded along one axis *and* coupling a second axis freely: stacked arms of one detector.

A :class:`~tensor_cosdi.operators.Stack` of a coded-dispersed frame and an
undispersed one (a panchromatic or RGB camera, several CASSI shots) couples
measurement column ``p`` of one frame with columns ``p − S … p + S`` of every
other frame, independently per detector row.  Folding the frame axis into
the column axis, ``q = p · F + f``, makes that a band of half-width
``(S + 1) F − 1`` along ``q``: :class:`FoldedBanded` is a
:class:`~tensor_cosdi.operators.woodbury.RowBanded` on the folded tensor, so
the banded Cholesky, the probes and the conditioning study apply unchanged.
"""

from __future__ import annotations

import numpy as np

from .. import _backend as B
from .woodbury import RowBanded, _apply_gram, _probe_band


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
        return self.fold.fold(np.asarray(B.to_numpy(b), dtype=np.float64))

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


def probe_folded(op, pattern):
    """Measure a folded band pattern: the band probes of the folded tensor, unfolded to ``op``."""
    shape = op.output_shape
    fold = _Fold(shape, pattern.axis, pattern.block_axis)
    width = (pattern.width + 1) * shape[pattern.block_axis] - 1

    def gram(folded_probe):
        return fold.fold(_apply_gram(op, fold.unfold(folded_probe)))

    bands = _probe_band(gram, fold.folded_shape, len(fold.folded_shape) - 1, width)
    return FoldedBanded(bands, shape, pattern.axis, pattern.block_axis)
