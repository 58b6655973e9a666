"""What ``A Aᵀ`` looks like: its sparsity :class:`Pattern`, measured by probes into the
structures of :mod:`tensor_cosdi.operators.woodbury`, and a self-check.

How structures are found: an operator reports a :class:`Pattern` (which
entries of ``A Aᵀ`` may be non-zero), derived from the index maps
(:class:`~tensor_cosdi.operators.Routing`) of its building blocks; the
values are then measured exactly by applying ``A Aᵀ`` to ``1``, ``K`` or
``2b + 1`` probe tensors (ones; one-hot along the block axis; combs of period
``2b + 1`` along the band axis), so no per-primitive formula for ``A Aᵀ`` is
needed and compositions, sums and stacks are covered alike.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import numpy as np

from .. import _backend as B
from .woodbury import Diagonal, FoldedBanded, PixelBlocks, RowBanded, fold_for

__all__ = [
    "Pattern",
    "pattern_from_terms",
    "probe_structure",
    "check_structure",
    "apply_gram",
    "probe_band",
    "probe_folded",
    "StructureError",
    "MAX_BANDWIDTH",
    "MAX_BLOCK",
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
    :class:`~tensor_cosdi.operators.woodbury.FoldedBanded`).
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
def apply_gram(op, probe_np: np.ndarray) -> np.ndarray:
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
    exact = apply_gram(op, v)
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
        return Diagonal(apply_gram(op, np.ones(shape)))
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
            cols.append(np.moveaxis(apply_gram(op, probe), axis, -1))
        # cols[k][..., k'] = (A Aᵀ)[k', k]
        Q = np.stack(cols, axis=-1)
        return PixelBlocks(Q, axis)
    if pattern.kind == "band" and pattern.block_axis is not None:
        return probe_folded(op, pattern)
    if pattern.kind == "band":
        bands = probe_band(partial(apply_gram, op), shape, pattern.axis, pattern.width)
        return RowBanded(bands, pattern.axis)
    raise ValueError(f"unknown pattern kind {pattern.kind!r}")


def probe_band(gram, shape, axis: int, b: int) -> np.ndarray:
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


def probe_folded(op, pattern):
    """Measure a folded band pattern: the band probes of the folded tensor, unfolded to ``op``."""
    shape = op.output_shape
    fold = fold_for(shape, pattern.axis, pattern.block_axis)
    width = (pattern.width + 1) * shape[pattern.block_axis] - 1

    def gram(folded_probe):
        return fold.fold(apply_gram(op, fold.unfold(folded_probe)))

    bands = probe_band(gram, fold.folded_shape, len(fold.folded_shape) - 1, width)
    return FoldedBanded(bands, shape, pattern.axis, pattern.block_axis)
