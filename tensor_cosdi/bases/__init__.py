"""Orthonormal per-mode bases applied by n-mode products (SPEC §4, §5; thesis Equation 82, 86).

A datacube is represented as ``F = Θ ×₁ Ψ1 ×₂ Ψ2 … ×_d Ψd`` with square
orthonormal *synthesis* matrices ``Ψn`` (columns are the atoms).  Because
every ``Ψn`` is orthonormal, the analysis is ``Θ = F ×₁ Ψ1ᵀ … ×_d Ψdᵀ`` and
``(ΨᵀAᵀAΨ + μI)⁻¹ = Ψᵀ (AᵀA + μI)⁻¹ Ψ``: the basis never enters a solve.

Per-mode bases: :func:`dct` (DCT-II), :func:`wavelet` (periodised discrete
wavelet transform from PyWavelets, default Symlet-8), :func:`identity`, and
bases learned from data, :func:`svd_basis` (left singular vectors of a
matrix) and :func:`tucker_bases` (HOSVD: eigenvectors of each mode's small
Gram).  :class:`KroneckerBasis` applies one per mode, DCT and wavelets as
fast transforms (:class:`DCT` through ``scipy.fft``, :class:`Wavelet` through
PyWavelets' multilevel transform) and learned matrices as GEMMs
(:class:`Dense`); the matrix functions above are the dense oracles.
"""

from .kronecker import KroneckerBasis
from .learned import block_hosvd, block_sizes, svd_basis, tucker_bases, unfolding_gram
from .matrices import AUTO_COARSEST, dct, identity, is_orthonormal, wavelet, wavelet_level
from .transforms import DCT, BlockDense, Dense, ModeTransform, Wavelet, as_transform

__all__ = [
    "dct",
    "wavelet",
    "wavelet_level",
    "AUTO_COARSEST",
    "identity",
    "svd_basis",
    "tucker_bases",
    "unfolding_gram",
    "KroneckerBasis",
    "is_orthonormal",
    "ModeTransform",
    "Dense",
    "DCT",
    "Wavelet",
    "as_transform",
    "BlockDense",
    "block_hosvd",
    "block_sizes",
]
