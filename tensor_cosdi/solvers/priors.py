"""Priors: the regularising parts the engines of :mod:`tensor_cosdi.solvers.engine` plug in.

The protocol is small:

``setup(start, *, penalty, gain)``
    Called once with the starting estimate; fixes the prior's absolute
    strength from its relative option (see the engine's objective
    convention).  ``penalty`` is the engine's step scale (ADMM ``ρ``, GAP 1,
    FISTA ``L``), ``gain`` the sensing gain ``s``.
``prox(v)``
    The proximal / denoising step at that strength.
``objective(z)``
    ``λ R(z)`` in the convention ``½‖A x − g‖² + λ R(x)`` (``0.0`` for
    implicit plug-and-play priors).
``update(x, iteration)``
    Hook after each iteration (learned priors re-fit themselves to ``x``).

=========================  ============================================================
prior                      prox
=========================  ============================================================
:class:`SparseInBasis`     ``Ψ soft(Ψᵀ v, t)`` in a fixed Kronecker basis (``"wdct"``)
:class:`TuckerDictionary`  the same, bases re-learned by HOSVD every few iterations
                           (online Tucker dictionary, ``"otd"``, thesis Alg. 5)
:class:`TV`                2-D isotropic total variation per slice (``"gap_tv"``, DFA)
:class:`Denoiser`          any registered denoiser at a fixed σ (``"pnp_admm"``)
:class:`Ridge`             ``v ρ / (ρ + λ)`` (``"lsq"`` with ``nonneg=True``)
:class:`NonNegative`       another prior's prox, then ``max(·, 0)`` (a cube of light)
=========================  ============================================================
"""

from __future__ import annotations

import numpy as np
import tensorly as tl

from .. import _backend as B
from ..bases import BlockDense, KroneckerBasis, block_hosvd, tucker_bases
from ..validate import flag, integer, number
from .denoisers import resolve

__all__ = [
    "Prior",
    "SparseInBasis",
    "TuckerDictionary",
    "FixedBasis",
    "TV",
    "Denoiser",
    "Ridge",
    "NonNegative",
    "PlaneSupport",
    "plane_axis",
    "with_plane_support",
    "soft",
    "omega_step",
    "rms",
    "total_variation",
]


def soft(x, t):
    """Soft thresholding ``sign(x) · max(|x| − t, 0)`` (``t`` a scalar or a tensor of ``x``'s
    shape).  On NumPy arrays as ``x − clip(x, −t, t)`` into one new array (the same numbers;
    the TensorLy form allocates four cube-sized temporaries)."""
    if isinstance(x, np.ndarray) and np.issubdtype(x.dtype, np.floating):
        c = np.clip(x, -t, t)
        return np.subtract(x, c, out=c)
    return tl.sign(x) * tl.clip(tl.abs(x) - t, 0, None)


def omega_step(theta, nu, prev, thresh, mu, beta):
    """Ω-step, exact (SPEC §12): ``argmin_Ω β‖Ω − Ω_prev‖² + λ‖Ω‖₁ + μ‖Θ − Ω − ν‖²``.

    ``= soft((βΩ_prev + μ(Θ − ν)) / (β + μ), λ / (2(β + μ)))``; here
    ``thresh`` is that threshold, ``λ / (2(β + μ))``, already.
    """
    v = theta if isinstance(nu, (int, float)) and nu == 0 else theta - nu
    if beta > 0:
        v = (beta * prev + mu * v) / (beta + mu)
    return soft(v, thresh)


def _l1(x, block: int = 1 << 18) -> float:
    """``Σ|x|``; on NumPy in blocks, without a cube-sized ``|x|`` temporary."""
    if not isinstance(x, np.ndarray):
        return float(tl.sum(tl.abs(x)))
    v = x.T if x.flags.f_contiguous and not x.flags.c_contiguous else np.ascontiguousarray(x)
    flat = v.reshape(-1)
    return float(
        sum(np.abs(flat[i : i + block]).sum(dtype=np.float64) for i in range(0, flat.size, block))
    )


def rms(x) -> float:
    """Root mean square of a tensor: the scale of ``Denoiser(scale="rms")``.

    Parameters
    ----------
    x : tensor
        Any tensor of the active backend (or array).

    Returns
    -------
    float
        ``‖x‖ / √size``, never 0 (the smallest positive float instead).

    Examples
    --------
    >>> import numpy as np
    >>> rms(np.array([3.0, -3.0, 3.0, -3.0]))
    3.0
    """
    n = float(np.prod(tl.shape(x)))
    return float(max(float(tl.norm(x)) / np.sqrt(n), np.finfo(float).tiny))


#: The percentile of ``|start|`` that stands for its peak (see :func:`robust_peak`).
PEAK_PERCENTILE = 99.9


def robust_peak(x) -> float:
    """The 99.9th percentile of ``|x|`` (its maximum where that is 0; never 0): the scale
    that TV and denoiser strengths are relative to.

    Not the maximum: the least-norm start ``Aᵀ(AAᵀ)⁻¹g`` divides by small
    code sums, so one noisy pixel sets its maximum — on the real-spectra
    protocol (TSA mask) the maximum grows 12× at 30 dB and 40× at 20 dB
    over the noiseless one while the 99.9th percentile moves by < 10 %, and
    a strength tied to the maximum over-smooths every noisy measurement.
    """
    # on an accelerator |x| stays on the device; else a NumPy array (a view for host tensors)
    a = tl.abs(x) if B.on_accelerator(x) else np.abs(np.asarray(B.to_numpy(x)))
    size = int(np.prod(tuple(a.shape)))
    if size == 0:
        return float(np.finfo(float).tiny)
    p = B.kth_smallest(a, min(int(np.ceil(PEAK_PERCENTILE / 100 * (size - 1))), size - 1))
    if not p > 0:
        p = float(tl.max(a))
    return max(p, float(np.finfo(float).tiny))


_peak = robust_peak

#: :class:`Denoiser`'s ``scale``: what its relative levels are relative to.
LEVEL_SCALES = ("peak", "rms")
#: ``Denoiser(scale="rms")``: the level's reference is this many times the start's RMS, the
#: median ratio of robust peak to RMS over the 28 tuning scenes (4.74; 3.25 to 7.80 from the
#: 10th to the 90th percentile; ``benchmarks/results/level_scale.md``), so that a relative
#: level means the same on a typical scene under either scale.
PEAK_PER_RMS = 4.74


def annealed(start: float, end: float, step: int, n_steps: int) -> float:
    """Geometric annealing: ``start`` at step 0, ``end`` at step ``n_steps − 1`` and after."""
    t = min(step / max(n_steps - 1, 1), 1.0)
    return start * (end / start) ** t


def total_variation(x) -> float:
    """Isotropic 2-D TV over axes 0 and 1, summed over every other index (in float64 on the
    host; a tensor on an accelerator stays there)."""
    if B.on_accelerator(x):  # backend operations on the device (in the tensor's dtype)
        inner = tl.sum(tl.sqrt((x[1:, :-1] - x[:-1, :-1]) ** 2 + (x[:-1, 1:] - x[:-1, :-1]) ** 2))
        edge = tl.sum(tl.abs(x[-1, 1:] - x[-1, :-1])) + tl.sum(tl.abs(x[1:, -1] - x[:-1, -1]))
        return float(inner + edge)
    a = np.asarray(B.to_numpy(x))
    dx = a[1:, :-1] - a[:-1, :-1]  # forward differences, the last row/column has one neighbour
    dy = a[:-1, 1:] - a[:-1, :-1]
    np.multiply(dx, dx, out=dx)
    np.multiply(dy, dy, out=dy)
    np.add(dx, dy, out=dx)
    inner = float(np.sqrt(dx, out=dx).sum(dtype=np.float64))
    edge = np.abs(a[-1, 1:] - a[-1, :-1]).sum(dtype=np.float64) + np.abs(
        a[1:, -1] - a[:-1, -1]
    ).sum(dtype=np.float64)
    return inner + float(edge)


class Prior:
    """Base of the priors (see the module notes for the protocol)."""

    name = "prior"
    penalty = 1.0

    def setup(self, start, *, penalty: float, gain: float) -> None:
        self.penalty = float(penalty)

    def prox(self, v):  # pragma: no cover - abstract
        raise NotImplementedError

    def objective(self, z) -> float:
        return 0.0

    def update(self, x, iteration: int) -> None:
        return None


def _prior(who: str, inner) -> Prior:
    """``inner`` if it is a :class:`Prior`, else a ``ValueError`` naming ``who``."""
    if not isinstance(inner, Prior):
        raise ValueError(f"{who} needs an inner Prior, got {type(inner).__name__}")
    return inner


class SparseInBasis(Prior):
    """``λ‖w ∘ Ψᵀx‖₁`` in an orthonormal Kronecker basis, with an optional proximal memory ``β``.

    Parameters
    ----------
    bases : dict {mode: matrix, transform or name}
        The starting synthesis bases (:class:`~tensor_cosdi.bases.KroneckerBasis`).
    lam : float
        Relative sparsity weight: the soft threshold is
        ``lam · RMS(start) / (mu + beta)`` cube units.
    mu, beta : float
        The ADMM penalty and the proximal weight (``β‖Ω − Ω_prev‖²``, SPEC
        §12), both relative to the sensing gain; ``Ω_prev`` is the
        coefficient tensor at the last basis change.
    weights : array of the cube's shape, optional
        Per-coefficient ℓ1 weights (≥ 0).
    """

    name = "sparse"

    def __init__(self, bases, *, lam: float, mu: float, beta: float = 0.0, weights=None):
        if not isinstance(bases, dict):
            raise ValueError(f"bases must be a dict {{mode: basis}}, got {type(bases).__name__}")
        self.bases = dict(bases)
        self.lam = number(f"{type(self).__name__}: lam", lam, low=0)
        self.mu = number(f"{type(self).__name__}: mu", mu, low=0, low_open=True)
        self.beta = number(f"{type(self).__name__}: beta", beta, low=0)
        self.weights = weights
        self.basis = None
        self._prev = None  # coefficients Ω_prev (None: the next prox is a plain soft threshold)
        self._prev_cube = None

    def setup(self, start, *, penalty: float, gain: float) -> None:
        super().setup(start, penalty=penalty, gain=gain)
        shape = tuple(tl.shape(start))
        self.basis = KroneckerBasis(shape, self.bases)
        self.scale = rms(start)
        self.gain = float(gain)
        thresh = self.lam * self.scale / (self.mu + self.beta)
        if self.weights is not None:
            w = np.asarray(B.to_numpy(self.weights), dtype=np.float64)
            if w.shape != shape or not (np.isfinite(w).all() and (w >= 0).all()):
                raise ValueError(
                    f"weights must be finite, ≥ 0 and of shape {shape}, got shape {w.shape}"
                )
            self._w = B.tensor_like(w, start)
            thresh = B.tensor_like(w * thresh, start)
        else:
            self._w = None
        self.thresh = thresh
        self._prev = self._prev_cube = None
        self._omega_l1 = 0.0

    def prox(self, v):
        theta = self.basis.analysis(v)
        beta = self.beta if self._prev_cube is not None else 0.0  # the first step: plain soft
        if beta > 0 and self._prev is None:
            self._prev = self.basis.analysis(self._prev_cube)
        omega = omega_step(theta, 0.0, self._prev, self.thresh, self.mu, beta)
        del theta
        self._omega_l1 = _l1(omega if self._w is None else self._w * omega)
        # Ω is not kept when β = 0: synthesis may reuse its memory (one cube fewer at the peak)
        z = self.basis.synthesis(omega, overwrite=not self.beta > 0)
        if self._prev_cube is None and self.beta > 0:  # Ω_prev is kept only when β uses it
            self._prev_cube, self._prev = z, omega
        return z

    def objective(self, z) -> float:
        # λ = lam · RMS(start) · s, the ℓ1 weight whose threshold at ρ + β_s is the one above
        return self.lam * self.scale * self.gain * self._omega_l1

    def _rebase(self, mode, matrix, z_last):
        self.basis = self.basis.with_mode(mode, matrix)
        if self.beta > 0:
            self._prev_cube, self._prev = z_last, None  # Ω_prev = Ω at the basis change


class FixedBasis(SparseInBasis):
    """:class:`SparseInBasis` in a basis that never changes (WDCT: Symlet-8 ⊗ Symlet-8 ⊗ DCT)."""

    name = "fixed_basis"


class TuckerDictionary(SparseInBasis):
    """The online Tucker dictionary (thesis Algorithm 5): sparse in per-mode bases re-learned
    from the estimate.

    Every ``update_every`` iterations (0: never) the bases of ``update_modes``
    are replaced by the HOSVD bases of the current estimate's unfoldings
    (Eq. 97); the ADMM variables live in cube space, so they carry over to
    the new basis unchanged.
    """

    name = "tucker_dictionary"

    def __init__(
        self,
        bases,
        *,
        lam: float,
        mu: float,
        beta: float = 0.0,
        weights=None,
        update_modes=(),
        update_every: int = 10,
    ):
        super().__init__(bases, lam=lam, mu=mu, beta=beta, weights=weights)
        self.update_modes = tuple(update_modes)
        self.update_every = int(update_every)
        self._last = None

    def prox(self, v):
        z = super().prox(v)
        self._last = z if self.beta > 0 else None  # Ω_prev at a basis change needs it (β > 0)
        return z

    def update(self, x, iteration: int) -> None:
        if not (self.update_modes and self.update_every and iteration % self.update_every == 0):
            return
        trans = self.basis.transforms
        blocked = {m for m in self.update_modes if isinstance(trans.get(m), BlockDense)}
        learned = tucker_bases(x, modes=[m for m in self.update_modes if m not in blocked])
        for mode in blocked:  # a block-diagonal basis is re-learned with the same blocks
            learned[mode] = block_hosvd(x, mode, trans[mode].sizes)
        for mode in self.update_modes:
            self._rebase(mode, learned[mode], self._last)


class TV(Prior):
    """Isotropic 2-D total variation of every slice (axes 0, 1), by Chambolle's method
    (scikit-image).

    Parameters
    ----------
    weight : float
        Relative strength: the denoising weight is ``weight · P₉₉.₉|start|``
        (:func:`robust_peak`).
    denoise : callable ``(x, weight) -> x``, optional
        Replaces :func:`tensor_cosdi.solvers.denoisers.tv` (e.g. TV of a
        subspace's coefficient images).
    """

    name = "tv"

    def __init__(self, weight: float, *, denoise=None):
        self.weight = number("TV: weight", weight, low=0, low_open=True)
        self._denoise = resolve("tv") if denoise is None else denoise

    def setup(self, start, *, penalty: float, gain: float) -> None:
        super().setup(start, penalty=penalty, gain=gain)
        self.strength = self.weight * _peak(start)

    def prox(self, v):
        return self._denoise(v, self.strength)

    def objective(self, z) -> float:
        return self.penalty * self.strength * total_variation(z)


class Denoiser(Prior):
    """A plug-and-play denoiser (any of :func:`~tensor_cosdi.solvers.denoisers.denoisers` or a
    callable).

    ``sigma`` is relative: the denoiser runs at ``σ = sigma · P₉₉.₉|start|``
    (``scale="peak"``, :func:`robust_peak`), whatever the engine's step (the
    plug-and-play convention), or at ``σ = sigma · PEAK_PER_RMS · RMS(start)``
    (``scale="rms"``, :data:`PEAK_PER_RMS`): a level that follows the scene's
    mean brightness, as the noise of a measurement at a given SNR does, instead
    of its brightest voxels.  With
    ``sigma_end`` the level anneals geometrically from ``sigma`` to
    ``sigma_end`` over ``n_steps`` calls and then stays there.  ``nonneg``
    projects each output onto ``x ≥ 0`` (cubes of light are non-negative; a
    learned denoiser's negative excursions are what made plug-and-play ADMM
    diverge on weakly coded pixels, see :mod:`~tensor_cosdi.solvers.pnp_gap`).
    Implicit: its objective term is 0.
    """

    name = "denoiser"

    def __init__(
        self, denoiser="tv", *, sigma: float, sigma_end=None, n_steps: int = 1, nonneg=False,
        scale: str = "peak",
    ):  # fmt: skip
        if not isinstance(scale, str) or scale not in LEVEL_SCALES:
            raise ValueError(f"scale must be one of {LEVEL_SCALES}, got {scale!r}")
        self.scale = scale
        self._denoise = resolve(denoiser)
        self.sigma = number("Denoiser: sigma", sigma, low=0, low_open=True)
        self.sigma_end = (
            self.sigma if sigma_end is None
            else number("Denoiser: sigma_end", sigma_end, low=0, low_open=True)
        )  # fmt: skip
        self.n_steps = integer("Denoiser: n_steps", n_steps, low=1)
        self.nonneg = flag("Denoiser: nonneg", nonneg)
        self.calls = 0

    def setup(self, start, *, penalty: float, gain: float) -> None:
        super().setup(start, penalty=penalty, gain=gain)
        self.reference = _peak(start) if self.scale == "peak" else PEAK_PER_RMS * rms(start)
        self.strength = self.sigma * self.reference
        self.calls = 0

    def current_sigma(self) -> float:
        """The level of the next call, in cube units."""
        return self.reference * annealed(self.sigma, self.sigma_end, self.calls, self.n_steps)

    def prox(self, v):
        self.strength = self.current_sigma()
        self.calls += 1
        out = self._denoise(v, self.strength)
        return tl.clip(out, 0, None) if self.nonneg else out


class PlaneSupport(Prior):
    """One depth plane per pixel on top of any prior: after ``inner``'s prox, keep at each pixel
    only the plane (index along ``axis``) holding the most energy over the other non-spatial
    axes, and zero the rest — the structure of CASSDI-DFA's cube ``(Nx, Ny, Nλ, Nz)``, where a
    scene point lies at one depth.

    The projection is non-convex, so it starts after ``start_at`` prox calls,
    once the inner prior has found the rough support; the objective is the
    inner prior's.  On 64×64×8×3 DFA scenes at 30 dB (GAP-TV inside) it
    raised SSIM from 0.26-0.29 to 0.60-0.65 and PSNR by 0.2-1.3 dB, with the
    same depth-plane accuracy; applied from the first iteration it cost
    2-3 dB (the early estimate picks wrong planes and locks them in).
    """

    name = "plane_support"

    def __init__(self, inner: Prior, *, axis: int, start_at: int = 20):
        self.inner = _prior("PlaneSupport", inner)
        self.axis = integer("PlaneSupport: axis", axis, low=2)  # a non-spatial axis
        self.start_at = integer("PlaneSupport: start_at", start_at, low=0)
        self.calls = 0

    def setup(self, start, *, penalty: float, gain: float) -> None:
        self.inner.setup(start, penalty=penalty, gain=gain)
        self.penalty = self.inner.penalty
        self.calls = 0

    def prox(self, v):
        x = self.inner.prox(v)
        self.calls += 1
        if self.calls <= self.start_at:
            return x
        a = np.asarray(B.to_numpy(x))
        other = tuple(i for i in range(2, a.ndim) if i != self.axis)
        energy = (a * a).sum(axis=other, keepdims=True)
        keep = energy == energy.max(axis=self.axis, keepdims=True)
        return B.tensor_like(np.where(keep, a, 0.0).astype(a.dtype, copy=False), x)

    def objective(self, z) -> float:
        return self.inner.objective(z)

    def update(self, x, iteration: int) -> None:
        self.inner.update(x, iteration)


class Ridge(Prior):
    """``(λ/2)‖x‖²`` with ``λ = mu · s`` relative to the sensing gain ``s``: the regulariser of
    ``"lsq"`` as an engine prior (prox ``v ρ / (ρ + λ)``), so that :class:`NonNegative` around it
    is the exact prox of the non-negative ridge problem."""

    name = "ridge"

    def __init__(self, mu: float):
        self.mu = number("Ridge: mu", mu, low=0)

    def setup(self, start, *, penalty: float, gain: float) -> None:
        self.penalty = float(penalty)
        self.lam = self.mu * float(gain)

    def prox(self, v):
        return v * (self.penalty / (self.penalty + self.lam))

    def objective(self, z) -> float:
        return 0.5 * self.lam * float(tl.norm(z)) ** 2


class NonNegative(Prior):
    """``x ≥ 0`` on top of any prior: ``inner``'s prox, then the projection onto the
    non-negative orthant (a cube of light).  For a prior whose prox is separable in the
    voxel domain this is the exact prox of the sum; for a transform-domain prior (a
    dictionary, a wavelet) it is the usual projected step.  The objective is the inner
    prior's (the indicator is 0 on the iterates it returns)."""

    name = "nonneg"

    def __init__(self, inner: Prior):
        self.inner = _prior("NonNegative", inner)

    def setup(self, start, *, penalty: float, gain: float) -> None:
        self.inner.setup(start, penalty=penalty, gain=gain)
        self.penalty = self.inner.penalty

    def prox(self, v):
        return tl.clip(self.inner.prox(v), 0, None)

    def objective(self, z) -> float:
        return self.inner.objective(z)

    def update(self, x, iteration: int) -> None:
        self.inner.update(x, iteration)


def plane_axis(system):
    """The depth-plane axis of ``system``'s cube (``"z"`` of a system whose depth is a plane
    index, e.g. CASSDI-DFA), or ``None``."""
    if getattr(system, "depth_kind", None) == "planes" and "z" in getattr(system, "axes", ()):
        return list(system.axes).index("z")
    return None


def with_plane_support(prior: Prior, system, option, max_iter: int, auto_start: int) -> Prior:
    """``prior`` wrapped in :class:`PlaneSupport` as a method's ``plane_support`` option asks.

    ``option``: ``"auto"`` (on, from iteration ``auto_start``, for systems
    with a depth-plane axis — CASSDI-DFA — and off otherwise), ``False``
    (off), or an integer (the iteration it starts at; the system must have
    a depth-plane axis).
    """
    axis = plane_axis(system)
    if option is False or (option == "auto" and axis is None):
        return prior
    if option == "auto":
        start = auto_start
    elif isinstance(option, bool) or not isinstance(option, (int, np.integer)) or option < 0:
        raise ValueError(f"plane_support must be 'auto', False or an iteration ≥ 0, got {option!r}")
    else:
        start = int(option)
        if axis is None:
            raise ValueError(
                f"plane_support needs a system with depth planes (CASSDI-DFA); "
                f"{type(system).__name__} has none"
            )
    return PlaneSupport(prior, axis=axis, start_at=min(start, max_iter))
