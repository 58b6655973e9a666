"""The operator algebra: the protocol of matrix-free linear maps between tensors and its closed
set of combinators (identity, adjoint view, scaling, composition, sum, stack).

A :class:`TensorOperator` maps tensors of ``input_shape`` to tensors of
``output_shape``.  Operators compose (``A @ B``), add (``A + B``), scale
(``2.0 * A``), stack over a new axis (:class:`Stack`) and expose their adjoint
(``A.T``).  ``gram_dual()`` reports the structure of ``A Aᵀ`` (diagonal,
per-pixel blocks, banded along one axis) when it can be derived from the
operator's building blocks, and ``solve_dual`` / ``solve_normal`` use it for
closed-form (tensor-Woodbury) inverses (SPEC §4), falling back to conjugate
gradients otherwise.  ``to_matrix()`` builds the explicit ``scipy.sparse``
matrix in the column-major ``vec`` order of SPEC §1 (tests, small sizes).
"""

from __future__ import annotations

import numbers
from functools import cached_property

import numpy as np
import scipy.sparse as sp
import tensorly as tl

from .. import _backend as B
from ..validate import integer, number, real_array
from .gram import MAX_BANDWIDTH, Pattern, pattern_from_terms, probe_structure
from .routing import Routing
from .woodbury import conjugate_gradient, gram_eigenvalues

__all__ = [
    "TensorOperator",
    "validate_shape",
    "vec",
    "unvec",
    "vec_index",
    "sensing_gain",
    "Identity",
    "Adjoint",
    "Scaled",
    "Composition",
    "OperatorSum",
    "Stack",
    "weighted_sum",
]


# --------------------------------------------------------------------- helpers
#: Longest axis a shape may have (2³¹ − 1: beyond, an axis is a typo or an overflow).
MAX_AXIS_LENGTH = 2**31 - 1


def validate_shape(shape, what: str = "shape") -> tuple[int, ...]:
    """Return ``shape`` as a tuple of positive Python ints or raise ``ValueError``."""
    if isinstance(shape, numbers.Integral):
        shape = (shape,)
    try:
        items = tuple(shape)
    except TypeError:
        raise ValueError(f"{what} must be a sequence of positive integers, got {shape!r}") from None
    out = []
    for n in items:
        if isinstance(n, bool) or not isinstance(n, numbers.Integral):
            if not isinstance(n, bool) and isinstance(n, numbers.Real) and float(n).is_integer():
                n = int(n)
            else:
                raise ValueError(
                    f"{what} must contain positive integers, got {shape!r} "
                    f"({n!r} is not an integer)"
                )
        if n <= 0:
            raise ValueError(f"{what} must contain positive integers, got {shape!r} ({n} ≤ 0)")
        if n > MAX_AXIS_LENGTH:
            raise ValueError(
                f"{what} must contain integers ≤ {MAX_AXIS_LENGTH}, got {shape!r}"[:300]
            )
        out.append(int(n))
    if not out:
        raise ValueError(f"{what} must have at least one axis, got {shape!r}")
    return tuple(out)


def vec(x) -> np.ndarray:
    """Column-major vectorisation of SPEC §1: ``vec(F)[i1 + N1*i2 + …] = F[i1, i2, …]``."""
    return np.asarray(B.to_numpy(x)).reshape(-1, order="F")


def unvec(v, shape) -> np.ndarray:
    """Inverse of :func:`vec`."""
    return np.asarray(v).reshape(tuple(shape), order="F")


def vec_index(shape) -> np.ndarray:
    """Array of ``shape`` whose entry at a multi-index is its position in ``vec``."""
    shape = validate_shape(shape)
    return np.arange(int(np.prod(shape)), dtype=np.int64).reshape(shape, order="F")


def _normalize_axis(axis: int, ndim: int, what: str = "axis") -> int:
    if isinstance(axis, bool) or not isinstance(axis, numbers.Integral):
        raise ValueError(f"{what} must be an integer, got {axis!r}")
    if not -ndim <= axis < ndim:
        raise ValueError(f"{what}={axis} is out of range for a tensor with {ndim} axes")
    return int(axis) % ndim


def _as_scalar(value) -> float | None:
    if isinstance(value, numbers.Real) and not isinstance(value, bool):
        return float(value)
    if isinstance(value, np.ndarray) and value.ndim == 0 and np.isrealobj(value):
        return float(value)
    return None


# --------------------------------------------------------------------- protocol
class TensorOperator:
    """A linear map between tensors of fixed shapes (the protocol of DESIGN.md).

    Subclasses set ``input_shape`` / ``output_shape`` through
    ``TensorOperator.__init__`` and implement ``_forward`` and ``_adjoint``
    (which may assume a correct shape), plus ``_to_matrix`` and, where they
    know it, ``_routing`` or ``_gram_pattern``.

    Notes
    -----
    ``forward`` and ``adjoint`` check the shape and the finiteness of their
    argument and raise ``ValueError`` naming both shapes.  ``apply`` and
    ``apply_adjoint`` skip those checks: iterative solvers, which check the
    measurement once at the door and then apply the operator hundreds of
    times to tensors they made themselves, call them.
    """

    input_shape: tuple[int, ...]
    output_shape: tuple[int, ...]

    def __init__(self, input_shape, output_shape):
        self.input_shape = validate_shape(input_shape, "input_shape")
        self.output_shape = validate_shape(output_shape, "output_shape")
        self._params = B.ParamCache()

    # ---- public application -------------------------------------------------
    def forward(self, x):
        """Apply the operator: tensor of ``input_shape`` → tensor of ``output_shape``."""
        return self._checked_apply(
            x, self.input_shape, self.output_shape, self._forward, "forward", "input"
        )

    def adjoint(self, y):
        """Apply the adjoint: tensor of ``output_shape`` → tensor of ``input_shape``."""
        return self._checked_apply(
            y, self.output_shape, self.input_shape, self._adjoint, "adjoint", "output"
        )

    __call__ = forward

    def apply(self, x):
        """``A x`` without the shape and finiteness checks of :meth:`forward`.

        For inner loops whose argument is known to have ``input_shape`` and a
        floating dtype (a solver's own iterates); anything else gives an
        undefined result or a low-level error.
        """
        return self._forward(x)

    def apply_adjoint(self, y):
        """``Aᵀ y`` without the checks of :meth:`adjoint` (see :meth:`apply`)."""
        return self._adjoint(y)

    def check_input(self, x, caller: str = "forward"):
        """``x`` as a tensor of the active backend, checked as :meth:`forward` checks it.

        Raises ``ValueError`` naming ``caller`` when ``x`` is not a floating
        tensor of ``input_shape`` or holds NaN or inf.
        """
        return self._check(x, self.input_shape, caller, "input")

    def check_output(self, y, caller: str = "adjoint"):
        """``y`` checked as a tensor of ``output_shape`` (a measurement), as :meth:`check_input`."""
        return self._check(y, self.output_shape, caller, "output")

    def _checked_apply(self, x, shape_in, shape_out, apply, method, side):
        """Check shape and dtype at the door; NaN/inf on the smaller of argument and result.

        A linear map with finite coefficients turns a NaN/inf that reaches the
        result into a NaN/inf there (``0 · inf`` is NaN), so when the result is
        smaller than the argument (a compressive forward) only the result is
        scanned — one pass over the measurement instead of the cube.  Entries
        the operator discards (a crop) are then not inspected: they cannot
        change the result.
        """
        if np.prod(shape_in) <= np.prod(shape_out):
            return apply(self._check(x, shape_in, method, side))
        x = self._check(x, shape_in, method, side, finite=False)
        with np.errstate(over="ignore", invalid="ignore"):  # reported below, with context
            out = apply(x)
        if not B.all_finite(out):
            if not B.all_finite(x):
                raise ValueError(
                    f"{type(self).__name__}.{method}: the argument of shape {shape_in} contains "
                    "NaN or inf"
                )
            raise ValueError(
                f"{type(self).__name__}.{method}: the result overflowed to inf for a finite "
                f"argument of shape {shape_in}; rescale the input"
            )
        return out

    def _check(self, x, shape, method, side, finite=True):
        if not tl.is_tensor(x):
            if B.backend_name() == "numpy" and not isinstance(x, (str, bytes)):
                x = np.asarray(x)
            else:
                raise ValueError(
                    f"{type(self).__name__}.{method} expects a tensor of the active TensorLy "
                    f"backend {B.backend_name()!r}, got {type(x).__name__}"
                )
        got = tuple(tl.shape(x))
        if got != shape:
            raise ValueError(
                f"{type(self).__name__}.{method}: expected a tensor of the operator's {side} "
                f"shape {shape}, got shape {got}"
            )
        B.check_floating(x, f"{type(self).__name__}.{method} argument")
        if finite and not B.all_finite(x):
            raise ValueError(
                f"{type(self).__name__}.{method}: the argument of shape {got} contains NaN or inf"
            )
        return x

    def _forward(self, x):  # pragma: no cover - abstract
        raise NotImplementedError

    def _adjoint(self, y):  # pragma: no cover - abstract
        raise NotImplementedError

    # ---- algebra ---------------------------------------------------------------
    @property
    def T(self) -> "TensorOperator":
        """The adjoint operator as an operator (``A.T.forward == A.adjoint``)."""
        return Adjoint(self)

    def __matmul__(self, other):
        if isinstance(other, TensorOperator):
            return Composition([self, other])
        return self.forward(other)

    def __add__(self, other):
        if isinstance(other, TensorOperator):
            return OperatorSum([self, other])
        return NotImplemented

    def __radd__(self, other):
        if isinstance(other, numbers.Number) and other == 0:  # sum([...])
            return self
        return NotImplemented

    def __sub__(self, other):
        if isinstance(other, TensorOperator):
            return OperatorSum([self, Scaled(-1.0, other)])
        return NotImplemented

    def __neg__(self):
        return Scaled(-1.0, self)

    def __mul__(self, other):
        alpha = _as_scalar(other)
        if alpha is None:
            return NotImplemented
        return Scaled(alpha, self)

    __rmul__ = __mul__

    def __truediv__(self, other):
        alpha = _as_scalar(other)
        if alpha is None:
            return NotImplemented
        if alpha == 0:
            raise ValueError("cannot divide an operator by zero")
        return Scaled(1.0 / alpha, self)

    def sensing_gain(self, like=None) -> float:
        """``‖A 1‖² / ‖1‖²``, the mean squared gain (:func:`sensing_gain`)."""
        return sensing_gain(self, like)

    def norm(self, like=None, *, n_iter: int = 20, seed: int = 0) -> float:
        """``‖A‖₂``, the largest singular value, by ``n_iter`` power iterations on ``AᵀA``.

        ``like`` fixes backend, dtype and device of the seeded random start
        (default: float64 NumPy).  Power iteration approaches ``‖A‖₂`` from
        below; :meth:`lipschitz` adds a margin.
        """
        if isinstance(n_iter, bool) or not isinstance(n_iter, numbers.Integral) or n_iter < 1:
            raise ValueError(f"n_iter must be a positive integer, got {n_iter!r}")
        start = np.random.default_rng(seed).random(self.input_shape)
        v = start if like is None else B.tensor_like(start, like)
        tiny = np.finfo(float).tiny
        for _ in range(int(n_iter)):
            v = self._adjoint(self._forward(v))
            v = v / max(float(tl.norm(v)), tiny)
        return float(np.sqrt(float(tl.norm(self._adjoint(self._forward(v))))))

    def lipschitz(self, like=None, *, n_iter: int = 20, seed: int = 0) -> float:
        """``1.05 ‖A‖₂²``: the Lipschitz constant of ``∇ ½‖A x − g‖²`` with a 5 % margin
        over the power-iteration estimate (the step bound of FISTA and TwIST)."""
        return 1.05 * self.norm(like, n_iter=n_iter, seed=seed) ** 2

    def conditioning(self, *, exact_below: int = 4096, tol: float = 1e-8) -> dict:
        """How well posed the Woodbury inner matrix ``A Aᵀ`` is.

        Returns ``lambda_min``, ``lambda_max`` (extreme eigenvalues of ``A Aᵀ``,
        i.e. squared extreme singular values of ``A``), ``cond`` =
        ``lambda_max / lambda_min`` (``inf`` when singular), ``zero`` (how many
        eigenvalues are below ``tol · lambda_max``: measurement entries no
        input entry reaches), ``lambda_min_nonzero`` and ``cond_nonzero`` (the
        same on the rest; Lanczos gives only the extremes, so there they
        equal the plain ones unless the smallest is zero), Gershgorin bounds
        ``gershgorin_min`` / ``gershgorin_max``, the ``structure`` of
        ``A Aᵀ``, its ``size`` and the ``method`` used: ``"structure"``
        (exact, from the diagonal / per-pixel blocks / banded rows that
        :meth:`gram_dual` finds), ``"dense"`` (exact, for at most
        ``exact_below`` measurements) or ``"lanczos"`` (SciPy ``eigsh``
        through :meth:`aslinearoperator`).
        """
        integer("exact_below", exact_below, low=0)
        number("tol", tol, low=0, low_open=True)
        gram = self.gram_dual()
        m = int(np.prod(self.output_shape))
        out = {"structure": None if gram is None else gram.kind, "size": m}
        if gram is not None:
            ev, (glo, ghi) = gram_eigenvalues(gram)
            method = "structure"
        elif m <= exact_below:
            M = self.to_matrix()
            G = (M @ M.T).toarray()
            ev = np.linalg.eigvalsh(G)
            radius = np.abs(G).sum(axis=1) - np.abs(np.diag(G))
            glo, ghi = float((np.diag(G) - radius).min()), float((np.diag(G) + radius).max())
            method = "dense"
        else:
            from scipy.sparse.linalg import LinearOperator, eigsh

            A = self.aslinearoperator()
            AAt = LinearOperator((m, m), matvec=lambda y: A.matvec(A.rmatvec(y)), dtype=np.float64)
            ncv = min(m, 40)
            # full precision (tol 0): a loose tolerance stops "SA" far above a clustered minimum
            hi = float(eigsh(AAt, k=1, which="LA", return_eigenvectors=False, ncv=ncv)[0])
            lo = float(
                eigsh(AAt, k=1, which="SA", return_eigenvectors=False, ncv=ncv, maxiter=100 * m)[0]
            )
            ev = np.array([lo, hi])
            glo, ghi = float("nan"), float("nan")
            method = "lanczos"
        lmax = float(ev.max())
        lmin = float(ev.min())
        nonzero = ev[ev > tol * lmax]
        lnz = float(nonzero.min()) if nonzero.size else float("nan")
        out.update(
            lambda_min=lmin,
            lambda_max=lmax,
            cond=float("inf") if lmin <= tol * lmax else lmax / lmin,
            lambda_min_nonzero=lnz,
            cond_nonzero=lmax / lnz,
            zero=int((ev <= tol * lmax).sum()),
            gershgorin_min=glo,
            gershgorin_max=ghi,
            method=method,
        )
        return out

    # ---- structure --------------------------------------------------------------
    def _routing(self) -> Routing | None:
        """Index map when every input entry reaches few outputs, else ``None``."""
        return None

    def _gram_pattern(self):
        """Pattern of ``A Aᵀ`` (see woodbury.Pattern) or ``None`` when unknown."""
        return pattern_from_terms(self, [self])

    @cached_property
    def _gram(self):
        pattern = self._gram_pattern()
        if pattern is None:
            return None
        return probe_structure(self, pattern)

    def gram_dual(self):
        """Structure of ``A Aᵀ``: a ``Diagonal``, ``PixelBlocks`` or ``RowBanded`` object.

        Returns ``None`` when no cheap structure is known; ``solve_dual`` then
        uses conjugate gradients.  The values are computed once, exactly, by
        applying ``A Aᵀ`` to a few probe tensors chosen from the pattern that
        the operator's building blocks imply, and cached.
        """
        return self._gram

    def solve_dual(self, b, mu, *, rtol: float = 1e-12, maxiter: int | None = None):
        """Solve ``(μI + A Aᵀ) x = b`` for ``b`` of ``output_shape`` (SPEC §4).

        Parameters
        ----------
        b : tensor of ``output_shape``
        mu : float
            Positive regularisation weight.
        rtol, maxiter :
            Conjugate-gradient settings, used only when ``gram_dual()`` is ``None``.
        """
        mu = _check_mu(mu)
        b = self._check(b, self.output_shape, "solve_dual", "output")
        gram = self.gram_dual()
        if gram is not None:
            return gram.solve(b, mu)
        return conjugate_gradient(
            lambda v: self._forward(self._adjoint(v)) + mu * v, b, rtol=rtol, maxiter=maxiter
        )

    def solve_normal(self, r, mu, *, rtol: float = 1e-12, maxiter: int | None = None):
        """Solve ``(AᵀA + μI) x = r`` for ``r`` of ``input_shape``.

        Uses the Woodbury identity ``(AᵀA + μI)⁻¹ = μ⁻¹ [I − Aᵀ (μI + AAᵀ)⁻¹ A]``
        when ``gram_dual()`` has a structure, else conjugate gradients on the
        normal equations directly.  For tall operators (more outputs than
        inputs) whose ``AᵀA`` itself is structured, that structure is solved
        directly: no division by a small ``μ``, no cancellation.
        """
        mu = _check_mu(mu)
        r = self._check(r, self.input_shape, "solve_normal", "input")
        if self.shape[0] > self.shape[1]:
            primal = self.T.gram_dual()
            if primal is not None:
                return primal.solve(r, mu)
        gram = self.gram_dual()
        if gram is not None:
            return (r - self._adjoint(gram.solve(self._forward(r), mu))) / mu
        return conjugate_gradient(
            lambda v: self._adjoint(self._forward(v)) + mu * v, r, rtol=rtol, maxiter=maxiter
        )

    # ---- SciPy interop --------------------------------------------------------
    def aslinearoperator(self):
        """This operator as a SciPy ``LinearOperator`` on the column-major ``vec`` of SPEC §1.

        ``matvec(v) = vec(A unvec(v))`` and ``rmatvec`` the adjoint, computed
        with NumPy (float64) whatever backend is active, so SciPy's ``lsqr``,
        ``cg``, ``eigsh``/``svds`` — and PyLops solvers — run on any system
        without forming the matrix.  (The library's own CG stays
        backend-neutral: it runs on torch tensors on the GPU.)

        Examples
        --------
        >>> import numpy as np
        >>> from scipy.sparse.linalg import lsqr
        >>> from tensor_cosdi.systems import SDCASSI
        >>> sd = SDCASSI(np.eye(4), n_bands=3)
        >>> A = sd.operator.aslinearoperator()
        >>> A.shape
        (24, 48)
        """
        from scipy.sparse.linalg import LinearOperator

        n_in, n_out = int(np.prod(self.input_shape)), int(np.prod(self.output_shape))

        def apply(v, shape_in, fn):
            x = real_array("the solver's vector", v, finite=False).reshape(shape_in, order="F")
            with tl.backend_context("numpy"):
                out = fn(x)
            return real_array("out", B.to_numpy(out), finite=False).reshape(-1, order="F")

        return LinearOperator(
            (n_out, n_in),
            matvec=lambda v: apply(v, self.input_shape, self.forward),
            rmatvec=lambda y: apply(y, self.output_shape, self.adjoint),
            dtype=np.float64,
        )

    # ---- explicit matrix ------------------------------------------------------
    def to_matrix(self) -> sp.csr_matrix:
        """Explicit sparse matrix in column-major ``vec`` order (tests, small sizes)."""
        return sp.csr_matrix(self._to_matrix())

    def _to_matrix(self):
        """Fallback: apply the operator to unit vectors (small operators only)."""
        n = int(np.prod(self.input_shape))
        if n > 4096:
            raise ValueError(
                f"{type(self).__name__} has no explicit matrix formula and {n} columns are "
                "too many to probe (limit 4096)"
            )
        cols = []
        for j in range(n):
            e = np.zeros(n)
            e[j] = 1.0
            cols.append(vec(self._forward(B.as_tensor(unvec(e, self.input_shape)))))
        return sp.csr_matrix(np.stack(cols, axis=1))

    # ---- misc -------------------------------------------------------------------
    @property
    def shape(self) -> tuple[int, int]:
        """Matrix shape ``(prod(output_shape), prod(input_shape))``."""
        return int(np.prod(self.output_shape)), int(np.prod(self.input_shape))

    #: True when the operator permutes entries (``A Aᵀ = AᵀA = I``).
    _is_permutation = False

    def _fuse_with(self, inner: "TensorOperator"):
        """Fused execution of ``self ∘ inner`` or ``None`` (execution plans only)."""
        return None

    def __repr__(self):
        return f"{type(self).__name__}({self.input_shape} → {self.output_shape})"


def _check_mu(mu) -> float:
    val = _as_scalar(mu)
    if val is None or not np.isfinite(val) or val <= 0:
        raise ValueError(f"mu must be a finite positive number, got {mu!r}")
    return val


def sensing_gain(operator: "TensorOperator", like=None) -> float:
    """``‖A 1‖² / ‖1‖²``: the mean squared gain of ``A``, which makes Tikhonov weights and ``ε``
    scale-free (:meth:`TensorOperator.sensing_gain`).

    ``like`` fixes backend, dtype and device of the probe (default: float64 NumPy).
    """
    if not isinstance(operator, TensorOperator):
        raise ValueError(f"expected a TensorOperator, got {type(operator).__name__}")
    probe = np.ones(operator.input_shape)
    ones = probe if like is None else B.tensor_like(probe, like)
    s = float(tl.norm(operator._forward(ones))) ** 2 / float(np.prod(operator.input_shape))
    if s == 0.0:
        raise ValueError("the system measures nothing (A 1 = 0): every code element is closed")
    return s


# ------------------------------------------------------------ combinators


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
        if not isinstance(op, TensorOperator):
            raise ValueError(f"Scaled needs a TensorOperator to scale, got {type(op).__name__}")
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
        return pattern_from_terms(self, list(self.terms))

    def _to_matrix(self):
        m = self.terms[0].to_matrix()
        for t in self.terms[1:]:
            m = m + t.to_matrix()
        return m

    def __repr__(self):
        return "(" + " + ".join(repr(t) for t in self.terms) + ")"


def weighted_sum(operators, weights) -> TensorOperator:
    """``Σ_i w_i A_i`` (e.g. the two arms of CASSI-VSI, Equation 45)."""
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
