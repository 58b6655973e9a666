"""D-CoSNet: deep-unfolded ADMM with the system's closed-form Woodbury x-step (thesis §7.2).

The thesis' network (Fig. 80, Eq. 145-152) is one ADMM pass built from the
sensing layers of the imager — direct ``A`` (Eq. 149), transpose ``Aᵀ``
(Eq. 150) and the inverse ``(μ̃I + AAᵀ)⁻¹`` (Eq. 151, a Hadamard division
because ``AAᵀ`` is diagonal) — plus a U-Net.  Here the sensing layers are
the system's own :class:`~tensor_cosdi.operators.TensorOperator` run on
the TensorLy PyTorch backend, so autograd flows through the real ``A`` and
``Aᵀ`` of any system whose ``AAᵀ`` is diagonal (SD/DD-CASSI, CS2LI,
Mu-CoSDI, CASSDI-DFA without PSFs) or banded along one detector axis
(CASSI-VSI: the inverse is then a batched Cholesky solve of each detector
row's block, :meth:`Sensing.dual_solve`, as λ-net was retrained per forward
model in the thesis' §3.3.5).  One stage ``k`` is::

    r  = Aᵀg + μ̃ₖ (w − u)                     x-step right-hand side (Eq. 146)
    r' = r + d̄·Cᵢₙ(r/d̄)                        "transpose + two conv+ReLU layers"
    s  = (μ̃ₖI + AAᵀ)⁻¹ A r'                     direct and inverse layers
    f  = (r' − Aᵀs)/μ̃ₖ + Cₗₒ(r'/d̄) − Cᵤₚ(Aᵀs/d̄)   the two arms (3 and 4 conv layers)
    w  = UNetₖ(f + u)                           the denoising step (Eq. 147)
    u  = u + f − w                              multiplier update

with ``d = diag(AAᵀ)``, ``d̄`` its mean and ``μ̃ₖ = softplus(pₖ)·d̄`` learned.
Without the convolutions, ``f`` is exactly the Woodbury solution (Eq. 148)
``(AᵀA + μ̃I)⁻¹ r``; every convolution stack is residual with a zero-initialised
last layer, so the untrained network *is* that ADMM with an identity denoiser
and training learns corrections.  The thesis has one stage (``stages=1``);
more stages unfold more ADMM iterations.  The output is ``F̃ = w`` and
``G̃ = A F̃``; the loss is Eq. 152, ``ℓ1(F, F̃) + ℓ1(G, G̃) + (1 − SSIM(F, F̃))``
(``loss="l1"`` or ``"ssim"`` drop one term, the thesis' ablation).

Two corrections to the thesis' text: Eq. 148's right-hand side reads
``Aᵀg + μ̃⁻¹(w − d)``; minimising Eq. 146 gives ``Aᵀg + μ̃(w − d)``.  And
the conv layers sit beside exact identity paths (residual), not instead of
them, which is what lets one stage on 2 CPU cores train in minutes.

Scale: the measurement is divided by ``s``, the 99.9th percentile of
``g / d`` (where ``d > 0``) — about the cube's bright level — and the output
multiplied back, so the network is invariant to the measurement's units.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import tensorly as tl

from .. import _backend as B
from ..validate import integer, number, real_array
from . import load_weights, require_torch, torch_device

__all__ = [
    "DCoSNet",
    "Sensing",
    "build_dcosnet",
    "ssim",
    "default_weights",
    "PRIORS",
    "seeded_code",
    "tile_code",
    "training_code",
    "read_config",
    "STARTS",
    "noise_feature",
]

WEIGHTS_DIR = Path(__file__).resolve().parent / "weights"
#: Shipped weights per (system name, start, :data:`STARTS`): ``"adaptive"`` begins from
#: ``pnp_fast``'s start on any data and reads the estimated SNR, ``"fast"`` from the
#: first-stage cube ``pnp_fast`` starts from on clean data, ``"zero"`` is the thesis' network
#: from 0.
DEFAULT_WEIGHTS = {
    ("sd_cassi", "adaptive"): WEIGHTS_DIR / "dcosnet_adaptive_sd_cassi.pt",
    ("sd_cassi", "fast"): WEIGHTS_DIR / "dcosnet_fast_sd_cassi.pt",
    ("sd_cassi", "zero"): WEIGHTS_DIR / "dcosnet_sd_cassi.pt",
}
#: The start the shipped weights of :func:`default_weights` begin from unless asked otherwise.
DEFAULT_START = "adaptive"


def default_weights(system_name: str, start: str = DEFAULT_START) -> Path:
    """The shipped weights for ``system_name`` that begin from ``start`` (:data:`STARTS`);
    ``FileNotFoundError`` naming the command if none."""
    if start not in STARTS:
        raise ValueError(f"start must be one of {STARTS}, got {start!r}")
    path = DEFAULT_WEIGHTS.get((system_name, start))
    if path is None or not path.is_file():
        shipped = sorted(
            f"{k[0]} (start {k[1]})" for k, v in DEFAULT_WEIGHTS.items() if v.is_file()
        )
        raise FileNotFoundError(
            f"no shipped D-CoSNet weights for {system_name!r} with start {start!r} (shipped: "
            f"{', '.join(shipped) or 'none'}); train them with `tensor-cosdi train-dcosnet "
            f"--system {system_name} --start {start} --out weights.pt` and pass "
            "weights='weights.pt'"
        )
    return path


#: :meth:`Sensing.scale` reads ``g / d`` only where ``d = diag(AAᵀ)`` is at least this fraction
#: of its mean.
SCALE_MIN_D = 0.25


# ---- sensing layers ---------------------------------------------------------------------------
class Sensing:
    """``A``, ``Aᵀ`` and ``diag(AAᵀ)`` of a batch of systems as differentiable torch functions.

    Cubes are batches ``(B, C, H, W)`` with ``C`` the product of the cube's
    trailing axes (bands, patterns…); measurements ``(B, *measurement_shape)``.
    Single-shot SD-CASSI and CASSI-VSI systems with 2-D codes and the same
    whole-pixel shifts (and ``αT``, ``β``) run as one batched coded shear
    (:meth:`coded_shear`); any other system (or ``batched=False``) runs its
    own operator on the TensorLy PyTorch backend.
    """

    def __init__(self, systems, *, device=None, dtype=None, batched: bool = True):
        torch = require_torch()
        systems = list(systems)
        if not systems:
            raise ValueError("Sensing needs at least one system")
        if not isinstance(batched, (bool, np.bool_)):
            raise ValueError(f"batched must be True or False, got {batched!r}")
        shape = tuple(systems[0].cube_shape)
        mshape = tuple(systems[0].measurement_shape)
        for s in systems[1:]:
            if tuple(s.cube_shape) != shape or tuple(s.measurement_shape) != mshape:
                raise ValueError("every system of a batch must have the same cube shape")
        if len(shape) < 3:
            raise ValueError(f"D-CoSNet needs a cube (rows, columns, channels…), got {shape}")
        self.systems, self.ops = systems, [s.operator for s in systems]
        self.cube_shape, self.measurement_shape = shape, mshape
        self.channels = int(np.prod(shape[2:]))
        self.dtype = dtype or torch.float32
        self.device = torch.device(device or "cpu")
        self.codes, self.blocks = None, None
        shared = _shared_offsets(systems) if batched else None
        self.offsets, self.alpha_t, self.beta = (None, 1.0, 0) if shared is None else shared
        if self.offsets is not None:  # SD-CASSI or CASSI-VSI with a 2-D code: a batched shear
            self._set_codes(np.stack([s.code for s in systems]))
            return
        d, grams = [], [s.operator.gram_dual() for s in systems]
        kinds = {getattr(g, "kind", None) for g in grams}
        if kinds == {"row_banded"} and len(mshape) == 2 and len({g.axis for g in grams}) == 1:
            # CASSI-VSI: A Aᵀ banded along one measurement axis, one dense block per fibre
            self.band_axis = grams[0].axis
            blocks = np.stack([_banded_blocks(g) for g in grams])  # (B, fibres, n, n)
            self.blocks = torch.from_numpy(blocks).to(device=self.device, dtype=self.dtype)
            diag = torch.diagonal(self.blocks, dim1=-2, dim2=-1)  # (B, fibres, n)
            self.d = diag if self.band_axis == 1 else diag.transpose(1, 2)
            self.dbar = self.d.reshape(len(grams), -1).mean(dim=1)
            return
        for s, gram in zip(systems, grams):
            if getattr(gram, "kind", None) != "diagonal":
                kind = "none" if gram is None else gram.kind
                raise ValueError(
                    f"D-CoSNet needs a diagonal A Aᵀ (SD/DD-CASSI, CS2LI, Mu-CoSDI, CASSDI-DFA "
                    f"without PSFs) or one banded along a measurement axis (CASSI-VSI); "
                    f"{type(s).__name__} has structure {kind!r}"
                )
            d.append(np.asarray(gram.d))
        self.d = torch.from_numpy(np.stack(d)).to(device=self.device, dtype=self.dtype)
        self.dbar = self.d.reshape(len(d), -1).mean(dim=1)

    @classmethod
    def coded_shear(cls, codes, offsets, *, alpha_t=1.0, beta=0, device=None, dtype=None):
        """What ``Sensing`` builds from single-shot SD-CASSI systems with the 2-D ``codes``
        ``(B, H, W)`` and the whole-pixel per-band column ``offsets`` (one per band, the
        systems' ``shifts``), without building the systems (a training batch).

        ``alpha_t < 1`` is CASSI-VSI (Eq. 40): ``αT`` times that dispersed arm
        plus ``1 − αT`` times the coded grayscale arm landing ``beta``
        columns right; ``A Aᵀ`` is then one dense ``n × n`` block per detector
        row (banded inside), built as ``A_x A_xᵀ`` per row.
        ``codes`` may be a torch tensor that requires a gradient (a code being
        learned): ``A``, ``Aᵀ`` and ``A Aᵀ`` are then differentiable in it."""
        torch = require_torch()
        if not isinstance(codes, torch.Tensor):
            codes = np.asarray(codes)
        offsets = tuple(int(o) for o in offsets)
        if codes.ndim != 3 or not offsets or min(offsets) < 0:
            raise ValueError(
                f"need codes (B, H, W) and non-negative offsets, got {codes.shape}, {offsets}"
            )
        self = cls.__new__(cls)
        self.systems = self.ops = self.blocks = None
        h, w = codes.shape[1:]
        self.cube_shape = (h, w, len(offsets))
        self.measurement_shape = (h, w + max(offsets))
        self.channels = len(offsets)
        self.dtype = dtype or torch.float32
        self.device = torch.device(device or "cpu")
        self.offsets = offsets
        if not 0 < alpha_t <= 1 or not 0 <= int(beta) <= max(offsets):
            raise ValueError(f"need 0 < alpha_t ≤ 1 and 0 ≤ beta ≤ {max(offsets)}, got "
                             f"{alpha_t}, {beta}")  # fmt: skip
        self.alpha_t, self.beta = float(alpha_t), int(beta)
        self._set_codes(codes)
        return self

    def _set_codes(self, codes):
        torch = require_torch()
        if not isinstance(codes, torch.Tensor):
            codes = torch.from_numpy(np.ascontiguousarray(codes))
        self.codes = codes.to(device=self.device, dtype=self.dtype)
        if self.alpha_t == 1.0:
            self.d = self._shear_sum(self.codes[:, None] ** 2)
        else:  # CASSI-VSI: A Aᵀ per detector row, one n × n block each
            # voxel (column c, band l) reaches detector column c + offsets[l] with αT·code and
            # c + β with (1 − αT)·code, so it adds code² times αT², (1 − αT)² and αT(1 − αT)
            # (twice, symmetric) to four entries of its row's block: a scatter-add of
            # 4·W·L values per row (differentiable in the code), not the product of A's rows
            w = self.cube_shape[1]
            n = self.measurement_shape[1]
            a, r = self.alpha_t, 1.0 - self.alpha_t
            cols = torch.arange(w, device=self.device)
            p1 = cols[None, :] + torch.tensor(self.offsets, device=self.device)[:, None]  # (L, W)
            p2 = (cols + self.beta)[None, :].expand_as(p1)
            flat = torch.cat([p1 * n + p1, p2 * n + p2, p1 * n + p2, p2 * n + p1]).reshape(-1)
            weight = torch.tensor([a * a, r * r, a * r, a * r], dtype=self.dtype,
                                  device=self.device)  # fmt: skip
            c2 = self.codes**2  # (B, H, W)
            values = (weight[:, None, None, None, None] * c2[None, :, :, None, :]).expand(
                4, *c2.shape[:2], len(self.offsets), w
            )  # (4, B, H, L, W) in the order of flat
            values = values.permute(1, 2, 0, 3, 4).reshape(*c2.shape[:2], -1)
            blocks = torch.zeros(*c2.shape[:2], n * n, dtype=self.dtype, device=self.device)
            self.band_axis = 1
            self.blocks = blocks.index_add(2, flat, values).reshape(*c2.shape[:2], n, n)
            self.d = torch.diagonal(self.blocks, dim1=-2, dim2=-1)
        self.dbar = self.d.reshape(len(codes), -1).mean(dim=1)

    def _cube(self, x):
        return x.permute(1, 2, 0).reshape(self.cube_shape)

    def _batch(self, cube):
        h, w = self.cube_shape[:2]
        return cube.reshape(h, w, self.channels).permute(2, 0, 1)

    def _shear_sum(self, x):
        """``Σₖ`` band ``k`` of ``x (B, C | 1, H, W)`` moved ``offsets[k]`` columns right."""
        torch = require_torch()
        width = self.measurement_shape[1]
        pad = torch.nn.functional.pad
        parts = [
            pad(x[:, min(k, x.shape[1] - 1)], (o, width - x.shape[-1] - o))
            for k, o in enumerate(self.offsets)
        ]
        return torch.stack(parts).sum(dim=0)

    def forward(self, x):
        """``A x`` for ``x (B, C, H, W)``."""
        torch = require_torch()
        if self.codes is not None:
            coded = x * self.codes[:, None]
            if self.alpha_t == 1.0:
                return self._shear_sum(coded)
            grey = torch.nn.functional.pad(
                coded.sum(dim=1), (self.beta, self.measurement_shape[1] - x.shape[-1] - self.beta)
            )
            return self.alpha_t * self._shear_sum(coded) + (1 - self.alpha_t) * grey
        with tl.backend_context("pytorch"):
            return torch.stack([op.forward(self._cube(xi)) for op, xi in zip(self.ops, x)])

    def adjoint(self, y):
        """``Aᵀ y`` as ``(B, C, H, W)``."""
        torch = require_torch()
        if self.codes is not None:
            w = self.cube_shape[1]
            out = torch.stack([y[..., o : o + w] for o in self.offsets], dim=1)
            if self.alpha_t != 1.0:
                grey = y[..., self.beta : self.beta + w][:, None]
                out = self.alpha_t * out + (1 - self.alpha_t) * grey
            return out * self.codes[:, None]
        with tl.backend_context("pytorch"):
            return torch.stack([self._batch(op.adjoint(yi)) for op, yi in zip(self.ops, y)])

    def dual_solve(self, y, mu):
        """``(μ I + A Aᵀ)⁻¹ y`` for a measurement batch ``y`` and per-sample ``μ`` ``(B,)``: a
        division for a diagonal ``A Aᵀ``, a batched Cholesky solve per fibre for a banded one
        (differentiable in ``y`` and ``μ``)."""
        torch = require_torch()
        if self.blocks is None:
            d = self.d.to(y.dtype)
            return y / (_per_sample(mu, d) + d)
        m = self.blocks.to(y.dtype)
        eye = torch.eye(m.shape[-1], dtype=y.dtype, device=y.device)
        factor = torch.linalg.cholesky(m + mu.reshape(-1, 1, 1, 1) * eye)
        yy = y if self.band_axis == 1 else y.transpose(1, 2)  # (B, fibres, n)
        x = torch.cholesky_solve(yy.unsqueeze(-1), factor).squeeze(-1)
        return x if self.band_axis == 1 else x.transpose(1, 2)

    def scale(self, g):
        """Per-sample ``s``: the 99.9th percentile of ``g / d`` where ``d`` is at least
        :data:`SCALE_MIN_D` of its mean (``(B,)``).  Where ``d`` is a sliver of its mean (a
        real-valued code's near-zero entries) ``g / d`` is noise magnified a thousandfold."""
        torch = require_torch()
        d = self.d.to(device=g.device, dtype=torch.float32).reshape(len(g), -1)
        keep = (d > 0) & (d >= SCALE_MIN_D * d.mean(dim=1, keepdim=True))
        ratio = g.float().reshape(len(g), -1).abs() / torch.where(keep, d, 1.0)
        v = torch.where(keep, ratio, torch.nan)  # one batched quantile, no host round-trip
        q = torch.nan_to_num(torch.nanquantile(v, 0.999, dim=1), nan=0.0)
        top = torch.nan_to_num(v.nan_to_num(nan=-1.0).amax(dim=1).clamp_min(0), nan=0.0)
        out = torch.where(q > 0, q, torch.where(top > 0, top, 1.0))
        return out.to(dtype=g.dtype).clamp_min(1e-12)


def _banded_blocks(gram) -> np.ndarray:
    """A :class:`~tensor_cosdi.operators.woodbury.RowBanded` ``A Aᵀ`` of a 2-D measurement as
    one dense symmetric matrix per fibre, ``(fibres, n, n)`` with the band axis last."""
    bands = np.asarray(gram.bands)  # (b + 1, other axis, n): bands[o, f, p] = M_f[p, p + o]
    n = bands.shape[-1]
    out = np.zeros((bands.shape[1], n, n))
    idx = np.arange(n)
    for o in range(bands.shape[0]):
        out[:, idx[: n - o], idx[o:]] = bands[o, :, : n - o]
        out[:, idx[o:], idx[: n - o]] = bands[o, :, : n - o]
    return out


def _shared_offsets(systems):
    """``(offsets, αT, β)`` when every system is a single-shot SD-CASSI (``αT`` 1, ``β`` 0) or
    CASSI-VSI with a 2-D code and the same whole-pixel per-band column ``offsets`` (Python
    ints), ``αT`` and ``β`` — ``A`` is then one batched shear of the coded bands, plus the
    coded grayscale arm for CASSI-VSI (:meth:`Sensing.forward`) — else ``None`` (each
    system's own operator)."""
    from ..systems import CASSIVSI, SDCASSI

    first = None
    for s in systems:
        if type(s) is SDCASSI and not s.colour and np.ndim(s.code) == 2:
            arms = (1.0, 0)
        elif type(s) is CASSIVSI and np.ndim(s.code) == 2:
            arms = (float(s.alpha_t), int(s.beta))
        else:
            return None
        shifts = np.asarray(s.shifts, dtype=np.float64)
        if not np.array_equal(shifts, np.round(shifts)) or (shifts < 0).any():
            return None
        key = (tuple(int(v) for v in shifts),) + arms
        if not 0 < key[1] <= 1:  # αT = 0 leaves no dispersed arm: the systems' own operators
            return None
        if first is None:
            first = key
        elif key != first:
            return None
    return first


# ---- the network ------------------------------------------------------------------------------
def _per_sample(t, x):
    """``t (B,)`` broadcast against ``x``."""
    return t.reshape(-1, *([1] * (x.ndim - 1)))


#: Stage priors: the thesis' U-Net, or the learned subspace denoiser of ``spectral_net``.
PRIORS = ("unet", "spectral")


def _spectral_prior(torch, stages: int, r_max: int = 12, width: int = 64, blocks: int = 4):
    """The ``"spectral"`` stage prior: one :mod:`~tensor_cosdi.learn.spectral_net` network shared
    by the stages, each stage with its own learned noise level ``σₖ`` (in units of the
    normalised cube), applied as :class:`~tensor_cosdi.learn.spectral_net.SpectralDenoiser`
    does (robust-peak scale, ``r_max`` leading spectral eigen-images, the complement dropped)
    and kept non-negative.  The eigenvectors are held constant under differentiation."""
    from .spectral_net import _build_net, _robust_peak, _spectral_basis

    nn = torch.nn

    class SpectralPrior(nn.Module):
        def __init__(self):
            super().__init__()
            self.net = _build_net(torch, r_max, width, blocks)
            # σ from 0.1 down to 0.03 of the bright level: plug-and-play ADMM's usual schedule
            sig = torch.from_numpy(np.geomspace(0.1, 0.03, stages).astype(np.float32))
            self.sigma = nn.Parameter(torch.log(torch.expm1(sig)))

        def forward(self, x, k):
            b, c, h, w = x.shape
            flat = x.reshape(b, c, h * w).transpose(1, 2)  # (B, P, C)
            scale = torch.stack([torch.tensor(_robust_peak(f)) for f in flat]).to(x)
            flat = flat / _per_sample(scale.clamp_min(1e-12), flat)
            u = _spectral_basis(flat, min(r_max, c))  # held constant
            y = torch.matmul(flat, u).transpose(1, 2)  # (B, r, P)
            r = y.shape[1]
            img = torch.zeros(b, r_max, h * w, dtype=x.dtype, device=x.device)
            img[:, :r] = y
            img = img.reshape(b, r_max, h, w)
            sig = nn.functional.softplus(self.sigma[k]) / scale.clamp_min(1e-12)
            clean = (img - self.net(img, sig))[:, :r].reshape(b, r, h * w)
            out = torch.matmul(u, clean).reshape(b, c, h, w)
            return (out * _per_sample(scale, out)).clamp_min(0)

    return SpectralPrior()


def build_dcosnet(
    torch, channels: int, stages: int = 1, width: int = 32, unet_width: int = 32,
    prior: str = "unet", code_shape=None, noise_input: bool = False,
):  # fmt: skip
    """The untrained network (a ``torch.nn.Module``) for cubes of ``channels`` channels.

    ``noise_input=True`` conditions every stage on the measurement's noise: a number ``t``
    per sample (:func:`noise_feature`, from the estimated SNR) shifts each stage's penalty,
    ``μ̃ₖ = softplus(pₖ + qₖ·t)·d̄``, and enters each U-Net as one more input channel
    (a constant map, as FFDNet's noise map).  ``qₖ`` and that channel's weights start at 0, so
    weights trained without the input load into it unchanged
    (:func:`~tensor_cosdi.learn.dcosnet_train.train_dcosnet` with ``init``).

    ``code_shape`` ``(rows, columns)`` adds a learnable binary coded aperture
    (thesis §7.3: the code trained with the network): real logits ``θ``
    (``code_logits``), a code ``1[θ > 0]`` in the forward pass and the
    gradient of ``sigmoid(θ / τ)`` (``τ`` = :data:`CODE_TEMPERATURE`) in the
    backward pass (a straight-through estimator), so every code the network
    sees is binary.  ``binary_code()`` returns it.

    ``prior="unet"`` is the thesis' Module II, one U-Net per stage trained
    from scratch; ``"spectral"`` is the subspace denoiser of
    :mod:`~tensor_cosdi.learn.spectral_net` shared by the stages (to be
    loaded with pretrained weights: :func:`~tensor_cosdi.learn.dcosnet_train.train_dcosnet`
    starts from the shipped denoiser).
    """
    if prior not in PRIORS:
        raise ValueError(f"prior must be one of {PRIORS}, got {prior!r}")
    if not isinstance(noise_input, (bool, np.bool_)):
        raise ValueError(f"noise_input must be True or False, got {noise_input!r}")
    if noise_input and prior != "unet":
        raise ValueError("noise_input conditions the U-Nets: it needs prior='unet'")
    nn = torch.nn

    def conv_stack(n_layers):
        """``n_layers`` 3×3 conv layers with ReLU between; last layer zero (starts at 0)."""
        layers, cin = [], channels
        for _ in range(n_layers - 1):
            layers += [nn.Conv2d(cin, width, 3, padding=1), nn.ReLU(inplace=True)]
            cin = width
        last = nn.Conv2d(cin, channels, 3, padding=1)
        nn.init.zeros_(last.weight)
        nn.init.zeros_(last.bias)
        return nn.Sequential(*layers, last)

    def double(cin, cout):
        return nn.Sequential(
            nn.Conv2d(cin, cout, 3, padding=1),
            nn.ReLU(inplace=True),
            nn.Conv2d(cout, cout, 3, padding=1),
            nn.ReLU(inplace=True),
        )

    class UNet(nn.Module):
        """Module II: a three-level U-Net, residual (starts as the identity)."""

        def __init__(self):
            super().__init__()
            b = unet_width
            self.enc1 = double(channels + int(bool(noise_input)), b)
            self.enc2 = nn.Sequential(
                nn.Conv2d(b, 2 * b, 3, stride=2, padding=1),
                nn.ReLU(inplace=True),
                double(2 * b, 2 * b),
            )
            self.enc3 = nn.Sequential(
                nn.Conv2d(2 * b, 4 * b, 3, stride=2, padding=1),
                nn.ReLU(inplace=True),
                double(4 * b, 4 * b),
            )
            self.up3 = nn.ConvTranspose2d(4 * b, 2 * b, 2, stride=2)
            self.dec2 = double(4 * b, 2 * b)
            self.up2 = nn.ConvTranspose2d(2 * b, b, 2, stride=2)
            self.dec1 = double(2 * b, b)
            self.out = nn.Conv2d(b, channels, 3, padding=1)
            nn.init.zeros_(self.out.weight)
            nn.init.zeros_(self.out.bias)

        def forward(self, x, t=None):
            h, w = x.shape[-2:]
            ph, pw = (-h) % 4, (-w) % 4
            xp = nn.functional.pad(x, (0, pw, 0, ph), mode="replicate") if ph or pw else x
            if t is not None:  # the noise map: one more channel, constant per sample
                xp = torch.cat([xp, _per_sample(t, xp).expand(-1, 1, *xp.shape[2:])], dim=1)
            e1 = self.enc1(xp)
            e2 = self.enc2(e1)
            e3 = self.enc3(e2)
            d2 = self.dec2(torch.cat([self.up3(e3), e2], dim=1))
            d1 = self.dec1(torch.cat([self.up2(d2), e1], dim=1))
            return x + self.out(d1)[..., :h, :w]

    class DCoSNetModule(nn.Module):
        """``forward(g, sensing, start=None, noise=None) -> (F̃, G̃)`` for a normalised
        measurement batch ``g``; ``start`` (a cube batch in the same units, or ``None`` for 0)
        is where ``w`` begins (:data:`STARTS`); ``noise`` ``(B,)``: each sample's noise input
        (:func:`noise_feature`), needed with ``noise_input`` and refused without."""

        def __init__(self):
            super().__init__()
            self.channels, self.stages = channels, stages
            self.width, self.unet_width = width, unet_width
            mu0 = math.log(math.expm1(0.1))  # μ̃ = 0.1 d̄ at the start
            self.mu = nn.Parameter(torch.full((stages,), mu0))
            self.noise_input = bool(noise_input)
            if self.noise_input:
                self.mu_noise = nn.Parameter(torch.zeros(stages))
            self.c_in = nn.ModuleList([conv_stack(2) for _ in range(stages)])
            self.c_up = nn.ModuleList([conv_stack(4) for _ in range(stages)])
            self.c_lo = nn.ModuleList([conv_stack(3) for _ in range(stages)])
            self.prior = prior
            if code_shape is not None:
                self.code_logits = nn.Parameter(torch.zeros(tuple(int(n) for n in code_shape)))
            if prior == "unet":
                self.unet = nn.ModuleList([UNet() for _ in range(stages)])
            else:
                self.spectral = _spectral_prior(torch, stages)

        def binary_code(self):
            """The learned code (0/1, straight-through gradient); ``None`` without one."""
            theta = getattr(self, "code_logits", None)
            if theta is None:
                return None
            soft = torch.sigmoid(theta / CODE_TEMPERATURE)
            return (theta > 0).to(theta.dtype) + (soft - soft.detach())  # exactly 0 / 1

        def denoise(self, x, k, t=None):
            return self.unet[k](x, t) if self.prior == "unet" else self.spectral(x, k)

        def forward(self, g, sensing, start=None, noise=None):
            if sensing.channels != self.channels:
                raise ValueError(
                    f"the network was built for {self.channels} channels; the system's cube has "
                    f"{sensing.channels}"
                )
            if self.noise_input != (noise is not None):
                raise ValueError(
                    "this network takes each sample's noise input (noise=…)"
                    if self.noise_input
                    else "this network was built without a noise input: pass noise=None"
                )
            dbar = sensing.dbar.to(g.dtype)
            t = None if noise is None else noise.to(g.dtype).reshape(-1)
            atg = sensing.adjoint(g)
            db = _per_sample(dbar, atg)
            w = torch.zeros_like(atg) if start is None else start.to(atg.dtype)
            u = torch.zeros_like(atg)
            for k in range(self.stages):
                p = self.mu[k] if t is None else self.mu[k] + self.mu_noise[k] * t
                mu = nn.functional.softplus(p) * dbar
                muc = _per_sample(mu, atg)
                r = atg + muc * (w - u)
                r = r + db * self.c_in[k](r / db)
                s = sensing.dual_solve(sensing.forward(r), mu)
                ats = sensing.adjoint(s)
                f = (r - ats) / muc + self.c_lo[k](r / db) - self.c_up[k](ats / db)
                w = self.denoise(f + u, k, t)
                u = u + f - w
            return w, sensing.forward(w)

    return DCoSNetModule()


#: Temperature of the straight-through code's surrogate gradient (``sigmoid(θ/τ)``).
CODE_TEMPERATURE = 0.25


def seeded_code(shape, seed: int) -> np.ndarray:
    """The fixed Bernoulli(½) code ``mask="seeded"`` trains with (and a learned code starts from).

    Parameters
    ----------
    shape : (rows, columns)
    seed : int
        Seed of ``numpy.random.default_rng``.

    Returns
    -------
    ndarray of float64, 0/1

    Examples
    --------
    >>> seeded_code((2, 3), 0)
    array([[0., 1., 1.],
           [1., 0., 0.]])
    """
    rows, cols = _code_shape(shape)
    return (B.default_rng(integer("seed", seed, low=0)).random((rows, cols)) < 0.5).astype(
        np.float64
    )


def _code_shape(shape) -> tuple[int, int]:
    """``(rows, columns)`` of a code: two positive integers, or a one-line ``ValueError``."""
    try:
        rows, cols = shape
        return integer("rows", rows, low=1), integer("columns", cols, low=1)
    except (TypeError, ValueError):
        raise ValueError(
            f"a code's shape must be (rows, columns), two integers ≥ 1, got {shape!r}"
        ) from None


def tile_code(code, shape) -> np.ndarray:
    """``code`` repeated periodically (from its top-left corner) to cover ``shape`` — how a
    network trained on one patch-sized code is used on a larger scene.

    Parameters
    ----------
    code : array_like, 2-D
    shape : (rows, columns)

    Returns
    -------
    ndarray of ``shape``

    Examples
    --------
    >>> tile_code([[1, 0]], (2, 3))
    array([[1, 0, 1],
           [1, 0, 1]])
    """
    real_array("code", code)  # real and finite; tiled in its own dtype
    code = np.asarray(code)
    if code.ndim != 2 or code.size == 0:
        raise ValueError(f"need a non-empty 2-D code, got shape {code.shape}")
    rows, cols = _code_shape(shape)
    reps = (-(-rows // code.shape[0]), -(-cols // code.shape[1]))
    return np.tile(code, reps)[:rows, :cols]


#: The largest D-CoSNet a weights file may describe (a hostile file could otherwise ask for
#: terabytes): integer fields and their ranges, and the largest side of a recorded code.
CONFIG_LIMITS = {"channels": (1, 1024), "stages": (1, 64), "width": (1, 1024),
                 "unet_width": (1, 1024), "code_seed": (0, 2**63 - 1)}  # fmt: skip
MAX_CODE_SIDE = 8192
#: Where the unfolded ADMM's ``w`` starts: ``"zero"`` (the thesis) or ``"fast"``
#: (:func:`~tensor_cosdi.solvers.otd.fast_start`, the cube ``pnp_fast`` starts from; a
#: weights file records which).
STARTS = ("zero", "fast", "adaptive")
#: :func:`~tensor_cosdi.solvers.otd.fast_start`'s ``admm_iter`` for each start but ``"zero"``:
#: ``"fast"`` the first stage's cube alone, ``"adaptive"`` pnp_fast's start on any
#: measurement (10 ADMM iterations after the first stage where it reads noisy).
START_ADMM_ITER = {"fast": 0, "adaptive": "auto"}
#: The network's noise input ``t = 10^((NOISE_REF_DB − SNR)/20)`` (1 at 20 dB, 0.32 at 30 dB,
#: 0 for a clean reading), capped at :data:`NOISE_INPUT_MAX` (an SNR of 0 dB).
NOISE_REF_DB = 20.0
NOISE_INPUT_MAX = 10.0


def noise_feature(snr_db) -> float:
    """D-CoSNet's noise input for an estimated SNR of ``snr_db`` dB (:data:`NOISE_REF_DB`).

    Examples
    --------
    >>> noise_feature(20.0), round(noise_feature(40.0), 3), noise_feature(float("inf"))
    (1.0, 0.1, 0.0)
    """
    if isinstance(snr_db, (int, float, np.floating)) and snr_db == float("inf"):
        return 0.0  # no noise at all
    snr = number("snr_db", snr_db)
    return float(min(10 ** ((NOISE_REF_DB - snr) / 20), NOISE_INPUT_MAX))


def _checkpoint(weights):
    path = Path(weights)
    ckpt = load_weights(path, "D-CoSNet", "train-dcosnet")
    cfg = ckpt["config"]

    def bad(what):
        return ValueError(
            f"{path} is not a D-CoSNet checkpoint of tensor-cosdi train-dcosnet ({what})"
        )

    if not isinstance(cfg, dict):
        raise bad(f"its config is a {type(cfg).__name__}, not a dict")
    if "channels" not in cfg:  # another network's weights
        raise bad("no 'channels'")
    side = cfg.get("code_shape", (1, 1))
    if not isinstance(side, (list, tuple)) or len(side) != 2:
        raise bad(f"config code_shape={side!r}; expected (rows, columns)")
    try:
        for name, (low, top) in CONFIG_LIMITS.items():
            integer(f"config {name}", cfg.get(name, low), low=low, high=top)
        number("config shift", cfg.get("shift", 1), low=0, low_open=True, high=1024)
        for n in side:
            integer("config code_shape's sides", n, low=1, high=MAX_CODE_SIDE)
    except ValueError as exc:
        raise bad(exc) from None
    if cfg.get("prior", "unet") not in PRIORS:
        raise bad(f"config prior={cfg.get('prior')!r}; expected one of {PRIORS}")
    if cfg.get("start", "zero") not in STARTS:
        raise bad(f"config start={cfg.get('start')!r}; expected one of {STARTS}")
    if not isinstance(cfg.get("noise_input", False), bool):
        raise bad(f"config noise_input={cfg.get('noise_input')!r}; expected True or False")
    return path, ckpt


def read_config(weights) -> dict:
    """The configuration D-CoSNet ``weights`` record.

    Parameters
    ----------
    weights : path
        A file of ``tensor-cosdi train-dcosnet``.

    Returns
    -------
    dict
        System, channels, shift, stages, widths, prior, start (where absent: ``"zero"``);
        ``alpha_t`` for
        CASSI-VSI; for one seeded or learned code ``code``, ``code_shape``,
        ``code_seed``.

    Raises
    ------
    FileNotFoundError, ValueError
        A missing file; an empty, truncated or foreign one.
    """
    return dict(_checkpoint(weights)[1]["config"])


def training_code(weights):
    """The binary code that D-CoSNet ``weights`` were trained with.

    Parameters
    ----------
    weights : path
        A file of ``tensor-cosdi train-dcosnet``.

    Returns
    -------
    ndarray of 0/1 or None
        The code for one fixed code (``mask="seeded"``) or a learned one;
        ``None`` for crops of a mask or random codes.  Build the system with
        ``tile_code(training_code(weights), shape)``.
    """
    path, ckpt = _checkpoint(weights)
    try:
        cfg = dict(ckpt["config"])
        kind = cfg.get("code")
        if kind == "learned":
            return (ckpt["model"]["code_logits"] > 0).double().numpy()
        if kind == "seeded":
            return seeded_code(cfg["code_shape"], int(cfg["code_seed"]))
    except (KeyError, TypeError) as exc:
        raise ValueError(
            f"{path} is not a D-CoSNet checkpoint of tensor-cosdi train-dcosnet ({exc})"
        ) from None
    return None


def ssim(x, y, *, data_range: float = 1.0, sigma: float = 1.5, win: int = 11):
    """Mean SSIM of two batches ``(B, C, H, W)``, per channel, Gaussian window (as scikit-image
    with ``gaussian_weights=True, use_sample_covariance=False``, interior pixels)."""
    torch = require_torch()
    if not (isinstance(x, torch.Tensor) and isinstance(y, torch.Tensor)):
        raise ValueError(
            f"ssim needs two torch tensors, got {type(x).__name__} and {type(y).__name__}"
        )
    if x.shape != y.shape or x.ndim != 4:
        raise ValueError(f"ssim needs two batches (B, C, H, W) of one shape, got {tuple(x.shape)} "
                         f"and {tuple(y.shape)}")  # fmt: skip
    data_range = number("data_range", data_range, low=0, low_open=True, high=1e150)
    sigma = number("sigma", sigma, low=0, low_open=True, high=1e3)
    win = integer("win", win, low=1, high=min(x.shape[-2:]))
    half = win // 2
    t = torch.arange(win, dtype=x.dtype, device=x.device) - half
    k1 = torch.exp(-(t**2) / (2 * sigma**2))
    k1 = k1 / k1.sum()
    c = x.shape[1]
    kh = k1.reshape(1, 1, 1, win).expand(c, 1, 1, win)
    kv = k1.reshape(1, 1, win, 1).expand(c, 1, win, 1)

    def blur(z):
        z = torch.nn.functional.conv2d(z, kh, groups=c)
        return torch.nn.functional.conv2d(z, kv, groups=c)

    mx, my = blur(x), blur(y)
    vx = blur(x * x) - mx * mx
    vy = blur(y * y) - my * my
    cxy = blur(x * y) - mx * my
    c1, c2 = (0.01 * data_range) ** 2, (0.03 * data_range) ** 2
    s = ((2 * mx * my + c1) * (2 * cxy + c2)) / ((mx * mx + my * my + c1) * (vx + vy + c2))
    return s.mean()


# ---- inference --------------------------------------------------------------------------------
class DCoSNet:
    """A trained D-CoSNet as a reconstructor: ``DCoSNet(weights)(system, g) -> cube``.

    Parameters
    ----------
    weights : path, optional
        Written by :func:`train_dcosnet`; default: the shipped weights for
        the system it is called with that begin from ``start``.
    device : str, optional
        ``"cpu"``, ``"cuda"``…; default CUDA when available.
    start : {"adaptive", "fast", "zero"}
        Which shipped weights (:func:`default_weights`) where ``weights`` is not given; a file
        records its own start.
    """

    def __init__(self, weights=None, *, device=None, start: str = DEFAULT_START):
        self.torch = require_torch()
        if start not in STARTS:
            raise ValueError(f"start must be one of {STARTS}, got {start!r}")
        self.start = start
        self.path = None if weights is None else Path(weights)
        # a missing, truncated, foreign or hostile file is an error now; its contents are
        # kept for the first call (the file is read once)
        self._read = None if self.path is None else _checkpoint(self.path)
        if device is not None:
            torch_device(self.torch, device)  # refused now, not at the first call
        self.device = device
        self._nets = {}

    def _load(self, system_name):
        torch = self.torch
        path = self.path if self.path is not None else default_weights(system_name, self.start)
        if path in self._nets:
            return self._nets[path]
        if self._read is not None and self._read[0] == path:
            ckpt, self._read = self._read[1], None
        else:  # a clear error for a missing, truncated or foreign file
            ckpt = _checkpoint(path)[1]
        try:
            cfg = dict(ckpt["config"])
            learned = cfg.get("code") == "learned"
            net = build_dcosnet(
                torch, int(cfg["channels"]), int(cfg["stages"]), int(cfg["width"]),
                int(cfg["unet_width"]), cfg.get("prior", "unet"),
                code_shape=cfg["code_shape"] if learned else None,
                noise_input=cfg.get("noise_input", False),
            )  # fmt: skip
            net.load_state_dict(ckpt["model"])
            if cfg.get("code") in ("learned", "seeded"):
                cfg["trained_code"] = training_code(path)
        except (KeyError, TypeError, RuntimeError) as exc:
            why = " ".join(str(exc).split())[:160]
            raise ValueError(
                f"{path} is not a D-CoSNet checkpoint of tensor-cosdi train-dcosnet ({why})"
            ) from None
        net.eval()
        self._nets[path] = (net, cfg)
        return net, cfg

    def check(self, system, cfg):
        """``ValueError`` unless ``system`` is the kind the weights were trained for."""
        shifts = np.asarray(getattr(system, "shifts", []), dtype=float)
        step = float(shifts[1] - shifts[0]) if shifts.size > 1 else None
        mine = {"system": system.name, "channels": int(np.prod(system.cube_shape[2:]))}
        theirs = {"system": cfg["system"], "channels": int(cfg["channels"])}
        if "alpha_t" in cfg:  # CASSI-VSI: the splitting ratio and the grey arm's column shape A
            mine["alpha_t"] = round(float(getattr(system, "alpha_t", -1.0)), 6)
            theirs["alpha_t"] = round(float(cfg["alpha_t"]), 6)
            mine["beta"], theirs["beta"] = int(getattr(system, "beta", -1)), 0
        if mine != theirs or (step is not None and step != float(cfg["shift"])):
            raise ValueError(
                f"these D-CoSNet weights were trained for {cfg['system']} with "
                f"{cfg['channels']} channels and a shift of {cfg['shift']} px per band"
                + (f", αT {theirs['alpha_t']:g}, β 0" if "alpha_t" in theirs else "")
                + f"; this is {mine['system']} with {mine['channels']} channels and a shift of "
                f"{step}"
                + (f", αT {mine['alpha_t']:g}, β {mine['beta']}" if "alpha_t" in mine else "")
                + ": "
                f"train weights for it (tensor-cosdi train-dcosnet --system {system.name} …)"
            )
        code = cfg.get("trained_code")
        if code is not None:
            own = np.asarray(B.to_numpy(system.code))
            if own.ndim != 2 or not np.array_equal(own.astype(float), tile_code(code, own.shape)):
                raise ValueError(
                    f"these D-CoSNet weights were trained with one {cfg['code']} "
                    f"{code.shape[0]}×{code.shape[1]} code; build the system with it "
                    "(tensor_cosdi.learn.dcosnet.tile_code(training_code(weights), shape))"
                )

    def __call__(self, system, measurement):
        torch = self.torch
        net, cfg = self._load(system.name)
        self.check(system, cfg)
        dev = torch_device(torch, self.device)
        net.to(dev)
        sensing = Sensing([system], device=dev)
        g = torch.from_numpy(np.asarray(B.to_numpy(measurement), dtype=np.float32)).to(dev)[None]
        s = sensing.scale(g)
        start, noise = None, None
        kind = cfg.get("start", "zero")
        if kind != "zero":  # the cube the weights start from
            from ..solvers.otd import fast_start

            cube0 = fast_start(system, measurement, admm_iter=START_ADMM_ITER[kind])
            cube0 = np.asarray(B.to_numpy(cube0), dtype=np.float32)
            c0 = torch.from_numpy(cube0.reshape(*cube0.shape[:2], -1)).permute(2, 0, 1)[None]
            start = c0.to(dev) / _per_sample(s, c0)
        if cfg.get("noise_input", False):  # the estimated SNR (cached: the start read it too)
            from ..solvers.snr import estimate_snr

            t = noise_feature(estimate_snr(system, measurement).snr_db)
            noise = torch.tensor([t], dtype=torch.float32, device=dev)
        with torch.no_grad():
            x, _ = net(g / _per_sample(s, g), sensing, start=start, noise=noise)
        x = x * _per_sample(s, x)
        cube = x[0].permute(1, 2, 0).reshape(system.cube_shape).cpu().numpy()
        dtype = np.asarray(B.to_numpy(measurement)).dtype
        if dtype.kind != "f":
            dtype = np.float32
        return B.tensor_like(cube.astype(dtype, copy=False), measurement)
