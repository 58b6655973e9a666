"""Combinators of the operator protocol: identity, adjoint view, scaling, composition, sum,
stack."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import tensorly as tl

from ._base import TensorOperator, _as_scalar, _normalize_axis, validate_shape, vec_index
from .routing import Routing

__all__ = ["Identity", "Adjoint", "Scaled", "Composition", "OperatorSum", "Stack", "weighted_sum"]


class Identity(TensorOperator):
    """The identity on tensors of ``shape``."""

    def __init__(self, shape):
        shape = validate_shape(shape)
        super().__init__(shape, shape)

    _is_permutation = True

    def _forward(self, x):
        return x

    def _adjoint(self, y):
        return y

    @property
    def T(self):
        return self

    def _routing(self):
        return Routing.identity(len(self.input_shape), ("identity", self.input_shape))

    def _to_matrix(self):
        return sp.identity(self.shape[0], format="csr")


class Adjoint(TensorOperator):
    """The adjoint ``Aᵀ`` of an operator, as an operator."""

    def __init__(self, op: TensorOperator):
        super().__init__(op.output_shape, op.input_shape)
        self.op = op

    def _forward(self, x):
        return self.op._adjoint(x)

    def _adjoint(self, y):
        return self.op._forward(y)

    @property
    def T(self):
        return self.op

    @property
    def _is_permutation(self):
        return self.op._is_permutation

    def _routing(self):
        adj = getattr(self.op, "_adjoint_routing", None)
        return adj() if adj is not None else None

    def _to_matrix(self):
        return sp.csr_matrix(self.op.to_matrix().T)

    def __repr__(self):
        return f"{self.op!r}.T"


class Scaled(TensorOperator):
    """``α A`` for a real scalar ``α``."""

    def __init__(self, alpha: float, op: TensorOperator):
        super().__init__(op.input_shape, op.output_shape)
        a = _as_scalar(alpha)
        if a is None or not np.isfinite(a):
            raise ValueError(f"scale must be a finite real number, got {alpha!r}")
        if isinstance(op, Scaled):
            a, op = a * op.alpha, op.op
        self.alpha, self.op = a, op

    def _forward(self, x):
        return self.alpha * self.op._forward(x)

    def _adjoint(self, y):
        return self.alpha * self.op._adjoint(y)

    @property
    def T(self):
        return Scaled(self.alpha, self.op.T)

    def _routing(self):
        return self.op._routing()

    def _gram_pattern(self):
        return self.op._gram_pattern()

    def _to_matrix(self):
        return self.alpha * self.op.to_matrix()

    def __repr__(self):
        return f"{self.alpha:g} * {self.op!r}"


class Composition(TensorOperator):
    """``A1 ∘ A2 ∘ … ∘ An`` (``An`` applied first), built by ``A1 @ A2 @ …``.

    Adjacent factors may be fused into a faster kernel for execution (e.g.
    sum over bands ∘ shear ∘ code becomes one coded shear-and-sum pass); the
    factors themselves are kept for the explicit matrix and for structure.
    """

    def __init__(self, factors):
        flat: list[TensorOperator] = []
        for f in factors:
            if not isinstance(f, TensorOperator):
                raise ValueError(f"can only compose TensorOperators, got {type(f).__name__}")
            flat.extend(f.factors if isinstance(f, Composition) else [f])
        for outer, inner in zip(flat[:-1], flat[1:]):
            if outer.input_shape != inner.output_shape:
                raise ValueError(
                    f"cannot compose {outer!r} after {inner!r}: the inner operator's output "
                    f"shape {inner.output_shape} differs from the outer operator's input shape "
                    f"{outer.input_shape}"
                )
        super().__init__(flat[-1].input_shape, flat[0].output_shape)
        self.factors = tuple(flat)
        self._plan = _fuse(list(flat))

    def _forward(self, x):
        for f in reversed(self._plan):
            x = f._forward(x)
        return x

    def _adjoint(self, y):
        for f in self._plan:
            y = f._adjoint(y)
        return y

    @property
    def _is_permutation(self):
        return all(f._is_permutation for f in self.factors)

    def _gram_pattern(self):
        # (S P)(S P)ᵀ = S Sᵀ when P permutes entries: the pattern is that of S
        outer = list(self.factors)
        while len(outer) > 1 and outer[-1]._is_permutation:
            outer.pop()
        if len(outer) < len(self.factors):
            head = outer[0] if len(outer) == 1 else Composition(outer)
            return head._gram_pattern()
        return super()._gram_pattern()

    def _routing(self):
        r = None
        for f in reversed(self.factors):
            fr = f._routing()
            if fr is None:
                return None
            r = fr if r is None else r.then(fr)
        return r

    def _to_matrix(self):
        m = self.factors[0].to_matrix()
        for f in self.factors[1:]:
            m = m @ f.to_matrix()
        return m

    def __repr__(self):
        return " @ ".join(repr(f) for f in self.factors)


def _fuse(factors: list) -> list:
    """Greedy right-to-left fusion of adjacent factors into faster kernels."""
    changed = True
    while changed and len(factors) > 1:
        changed = False
        for i in range(len(factors) - 2, -1, -1):
            fused = factors[i]._fuse_with(factors[i + 1])
            if fused is not None:
                factors[i : i + 2] = [fused]
                changed = True
                break
    return factors


class OperatorSum(TensorOperator):
    """``A1 + A2 + …`` for operators of equal shapes (weighted sums via scaling)."""

    def __init__(self, terms):
        flat: list[TensorOperator] = []
        for t in terms:
            if not isinstance(t, TensorOperator):
                raise ValueError(f"can only add TensorOperators, got {type(t).__name__}")
            flat.extend(t.terms if isinstance(t, OperatorSum) else [t])
        first = flat[0]
        for t in flat[1:]:
            if t.input_shape != first.input_shape or t.output_shape != first.output_shape:
                raise ValueError(
                    f"cannot add operators of different shapes: {first.input_shape} → "
                    f"{first.output_shape} and {t.input_shape} → {t.output_shape}"
                )
        super().__init__(first.input_shape, first.output_shape)
        self.terms = tuple(flat)

    def _forward(self, x):
        out = self.terms[0]._forward(x)
        for t in self.terms[1:]:
            out = out + t._forward(x)
        return out

    def _adjoint(self, y):
        out = self.terms[0]._adjoint(y)
        for t in self.terms[1:]:
            out = out + t._adjoint(y)
        return out

    @property
    def T(self):
        return OperatorSum([t.T for t in self.terms])

    def _gram_pattern(self):
        from .woodbury import pattern_from_terms

        return pattern_from_terms(self, list(self.terms))

    def _to_matrix(self):
        m = self.terms[0].to_matrix()
        for t in self.terms[1:]:
            m = m + t.to_matrix()
        return m

    def __repr__(self):
        return "(" + " + ".join(repr(t) for t in self.terms) + ")"


def weighted_sum(operators, weights) -> TensorOperator:
    """``Σ_i w_i A_i`` (e.g. the two arms of CASSI-VSI, Eq. 45)."""
    operators, weights = list(operators), list(weights)
    if len(operators) != len(weights) or not operators:
        raise ValueError(
            f"weighted_sum needs one weight per operator, got {len(operators)} operators "
            f"and {len(weights)} weights"
        )
    return OperatorSum([Scaled(w, a) for a, w in zip(operators, weights)])


class Stack(TensorOperator):
    """Stack operators of equal shapes along a new output axis (multi-shot sensing).

    ``Stack([A_1, …, A_K], axis=a).forward(x)`` has the outputs ``A_k(x)`` at
    index ``k`` of the new axis ``a`` of the output; the adjoint is
    ``Σ_k A_kᵀ(y[..., k, ...])``.
    """

    def __init__(self, operators, axis: int = -1):
        ops = list(operators)
        if not ops or not all(isinstance(o, TensorOperator) for o in ops):
            raise ValueError("Stack needs a non-empty sequence of TensorOperators")
        first = ops[0]
        for o in ops[1:]:
            if o.input_shape != first.input_shape or o.output_shape != first.output_shape:
                raise ValueError(
                    f"Stack needs operators of equal shapes: {first.input_shape} → "
                    f"{first.output_shape} and {o.input_shape} → {o.output_shape}"
                )
        ndim = len(first.output_shape) + 1
        self.axis = _normalize_axis(axis, ndim, "Stack axis")
        out = list(first.output_shape)
        out.insert(self.axis, len(ops))
        super().__init__(first.input_shape, out)
        self.operators = tuple(ops)

    def _forward(self, x):
        return tl.stack([o._forward(x) for o in self.operators], axis=self.axis)

    def _adjoint(self, y):
        out = None
        for k, o in enumerate(self.operators):
            idx = (slice(None),) * self.axis + (k,)
            term = o._adjoint(y[idx])
            out = term if out is None else out + term
        return out

    def _gram_pattern(self):
        """Per-pixel blocks across the shots when no shot couples pixels; a band along one
        axis with the shot axis folded in when the shots couple neighbours along it (a
        dispersed frame beside an undispersed one); else unknown."""
        from .woodbury import MAX_BANDWIDTH, Pattern, pattern_from_terms

        routes = [o._routing() for o in self.operators]
        if all(r is not None and r.single for r in routes) and len({r.key for r in routes}) == 1:
            return Pattern("blocks", self.axis)
        # shot k's entry o and shot k''s entry o' are coupled exactly when the terms of the sum
        # Σ_k A_k would couple o and o': the same widths, with the shot axis added
        inner = pattern_from_terms(self.operators[0], self.operators)
        if inner is None:
            return None
        if inner.kind == "diag":
            return Pattern("blocks", self.axis)
        axis = inner.axis + (inner.axis >= self.axis)
        if (inner.width + 1) * len(self.operators) - 1 > MAX_BANDWIDTH:
            return None
        return Pattern("band", axis, inner.width, block_axis=self.axis)

    def _to_matrix(self):
        K = len(self.operators)
        idx = vec_index(self.output_shape)
        m = None
        for k, o in enumerate(self.operators):
            rows = np.take(idx, k, axis=self.axis).reshape(-1, order="F")
            n_out = rows.size
            embed = sp.csr_matrix(
                (np.ones(n_out), (rows, np.arange(n_out))), shape=(self.shape[0], n_out)
            )
            term = embed @ o.to_matrix()
            m = term if m is None else m + term
        assert K == self.output_shape[self.axis]
        return m
