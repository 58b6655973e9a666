"""Training the learned spectral denoiser (``tensor-cosdi train-denoiser``).

Patches of the tuning scenes (:data:`tensor_cosdi.datasets.TUNE_SCENES`; the
report scenes are never read) at their native 31 bands or resampled to the
28 KAIST bands, with random band ranges and strides (3 to 31 channels, so
that the network serves any band count), random subspace ranks, flips and
rotations, a random smooth illuminant and shading (:func:`_illuminate`),
optionally magnified views (``zoom``: a smaller crop upsampled to the patch
size, so that the network also meets the smoother, larger-scale structure of
scenes photographed closer up or at a higher resolution than the
2×2-downsampled CAVE scenes),
plus white Gaussian noise of a log-uniform level — for half of
the batches (``coded_fraction``) with its projection onto the row space of a
random SD-CASSI operator removed, which is the structured error a
plug-and-play GAP step hands the denoiser (a network trained on white noise
alone denoised white noise by 16 dB on a real scene but left that error
untouched, and lost 5 dB to GAP-TV inside PnP-GAP).  Each sample is
normalised by the noisy patch's maximum (the denoiser itself uses the 99.9th
percentile, which agrees within a few per cent on such patches but not on a
plug-and-play iterate, whose maximum is one outlier); the loss is the
squared error of the predicted eigen-image noise as a fraction of the noise
energy (so every level weighs the same).  Adam (gradients clipped to norm
1) with a linear warm-up and a cosine-decayed step, from a seeded random
start or, to fine-tune, from the shipped or another network of the same
shape (``init``; the shipped network is its base fine-tuned on 128×128 and
then 256×256 patches, closer to the whole-image subspaces the denoiser
meets).

Checkpoints (model, optimiser, step, random states) are written atomically
to ``OUT.ckpt`` every ``checkpoint_every`` steps; ``resume=True`` continues
from it with the same random stream, so an interrupted run ends with the
weights an uninterrupted one would have written (on the same device and
thread count).  The final weights (model, configuration, provenance) go to
``OUT`` and are never written over without ``force=True``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..validate import real_array

__all__ = [
    "TrainConfig", "magnify", "nullspace_noise", "sample_batch", "train_denoiser", "training_data",
]  # fmt: skip


#: Largest training patch side (the CAVE scenes are 512 × 512).
MAX_PATCH = 512
#: Most memory one batch of clean patches may take (before the network's activations).
MAX_BATCH_BYTES = 2 * 2**30


@dataclass(frozen=True)
class TrainConfig:
    """Every option of a training run (stored with the weights)."""

    steps: int = 6000
    batch: int = 16
    patch: int = 64
    lr: float = 1e-3
    lr_end: float = 1e-5
    sigma_min: float = 0.005
    sigma_max: float = 0.25
    warmup: int = 200
    coded_fraction: float = 0.5
    #: probability that a patch's spectra are tilted (a random smooth illuminant) and, apart,
    #: that it is shaded by a random linear ramp across the image plane
    illumination: float = 0.5
    #: probability that a batch is a magnified view: crops of ``patch / z`` pixels
    #: (``z`` log-uniform in [1, ``zoom_max``]) upsampled bicubically to ``patch``; 0 draws
    #: nothing from the random stream (earlier recipes reproduce exactly)
    zoom: float = 0.0
    zoom_max: float = 3.0
    #: the null-space noise's SD-CASSI operator: a shift of 1 to ``max_shift`` pixels per band
    #: and a code density drawn from ``0.5 ± density_spread`` (the recipe of the shipped
    #: weights: 2 and 0)
    max_shift: int = 3
    density_spread: float = 0.2
    r_max: int = 12
    width: int = 64
    blocks: int = 4
    #: 0: full 3×3 convolutions; ``k > 0``: each in Tucker-2 form through ``k`` channels
    #: (:func:`~tensor_cosdi.learn.spectral_net.factorise`); with a full network as ``init``,
    #: its kernels are decomposed to start from
    conv_rank: int = 0
    seed: int = 0
    checkpoint_every: int = 200
    #: -1: train on every tuning scene; k: leave fold k of ``tune_folds(4)`` out (validation)
    hold_out: int = -1
    #: the starting weights: ``""`` (random, seeded), ``"shipped"`` (fine-tune the package's
    #: network) or a ``train-denoiser`` weights file of the same ``r_max``, ``width``, ``blocks``
    init: str = ""

    def check(self):
        from ._loop import check_config

        check_config(
            self,
            (
                "steps",
                "batch",
                "patch",
                "r_max",
                "width",
                "blocks",
                "checkpoint_every",
                "max_shift",
            ),  # fmt: skip
        )
        d = self.density_spread
        if isinstance(d, bool) or not isinstance(d, (int, float)) or not 0 <= d < 0.5:
            raise ValueError(f"density_spread must be a number in [0, 0.5), got {d!r}")
        if self.patch < 8 or self.patch % 2 or self.patch > MAX_PATCH:
            raise ValueError(
                f"patch must be an even size in 8…{MAX_PATCH} (the training scenes' side), got "
                f"{self.patch}"
            )
        if self.max_shift > self.patch:
            raise ValueError(
                f"max_shift must be ≤ patch ({self.patch} px: a larger shift separates the bands "
                f"entirely), got {self.max_shift}"
            )
        batch_bytes = self.batch * self.patch**2 * 31 * 4  # float32, up to 31 bands
        if batch_bytes > MAX_BATCH_BYTES:
            raise ValueError(
                f"batch={self.batch} of {self.patch}×{self.patch} patches takes "
                f"{batch_bytes / 2**30:.1f} GiB a batch; at most {MAX_BATCH_BYTES / 2**30:.0f} "
                "GiB (lower batch or patch)"
            )
        for name in ("coded_fraction", "illumination", "zoom"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0 <= v <= 1:
                raise ValueError(f"{name} must be a number in [0, 1], got {v!r}")
        from ..datasets import training_scenes

        z = self.zoom_max
        top = self.patch / 8 if self.zoom > 0 else float("inf")  # crops of at least 8 px
        if isinstance(z, bool) or not isinstance(z, (int, float)) or not 1 <= z <= top:
            raise ValueError(
                "zoom_max must be a number ≥ 1"
                + (f" and ≤ patch/8 = {top:g} with zoom > 0" if self.zoom > 0 else "")
                + f", got {z!r}"
            )
        training_scenes(self.hold_out)
        from ..validate import integer
        from .spectral_net import ARCH_LIMITS

        for name, top in ARCH_LIMITS.items():  # a network its own loader would refuse
            integer(name, getattr(self, name), low=0 if name == "conv_rank" else 1, high=top)
        if not isinstance(self.init, str):
            raise ValueError(f"init must be '', 'shipped' or a weights file, got {self.init!r}")
        if not 0 < self.sigma_min < self.sigma_max < math.inf:
            raise ValueError(
                f"need 0 < sigma_min < sigma_max, got {self.sigma_min}, {self.sigma_max}"
            )
        return self


def training_data(folder=None, hold_out: int = -1):
    """The training scenes (every tuning scene, or all but fold ``hold_out`` of
    ``datasets.tune_folds(4)``) as float32 cubes: native bands and KAIST-resampled (a list)."""
    from ..datasets import load_hsi, training_scenes

    cubes = []
    for name in training_scenes(hold_out):
        for wl in (None, "kaist"):
            cubes.append(load_hsi(name, wl, folder=folder, dtype="float32")[0])
    return cubes


def sample_batch(rng, cubes, cfg: TrainConfig):
    """One training batch of clean patches, drawn from the random stream ``rng``.

    Parameters
    ----------
    rng : numpy.random.Generator
    cubes : list of arrays ``(rows, columns, bands)``
        The training scenes (:func:`training_data`); one band set per batch.
    cfg : TrainConfig
        Batch size, patch size, ranks, illumination and ``zoom`` options.

    Returns
    -------
    clean : float32 array ``(batch, side², channels)``
    rank : int
        The subspace rank of this batch.
    side : int
        ``cfg.patch``, or less for a magnified batch: :func:`magnify` brings it to
        ``cfg.patch``.
    """
    cube = cubes[int(rng.integers(len(cubes)))]  # one band set per batch
    nb = cube.shape[2]
    if rng.random() < 0.2:
        n = int(rng.integers(3, 13))
        stride = 1
    else:
        stride = int(rng.choice([1, 1, 1, 2]))
        n = int(rng.integers(max(3, nb // (2 * stride)), nb // stride + 1))
    start = int(rng.integers(0, nb - (n - 1) * stride))
    bands = start + stride * np.arange(n)
    rank = cfg.r_max if rng.random() < 0.7 else int(rng.integers(3, cfg.r_max + 1))
    p = cfg.patch
    if cfg.zoom > 0 and rng.random() < cfg.zoom:
        p = max(8, int(round(cfg.patch / np.exp(rng.uniform(0.0, np.log(cfg.zoom_max))))))
    out = np.empty((cfg.batch, p, p, n), dtype=np.float32)
    for i in range(cfg.batch):
        c = cubes[int(rng.integers(len(cubes)))] if i else cube
        if c.shape[2] != nb:
            c = cube
        r0 = int(rng.integers(0, c.shape[0] - p + 1))
        c0 = int(rng.integers(0, c.shape[1] - p + 1))
        patch = c[r0 : r0 + p, c0 : c0 + p][:, :, bands]
        patch = np.rot90(patch, int(rng.integers(4)))
        if rng.random() < 0.5:
            patch = patch[::-1]
        out[i] = _illuminate(rng, patch, bands / max(nb - 1, 1), cfg.illumination)
    return out.reshape(cfg.batch, p * p, n), rank, p


def magnify(torch, clean, side: int, patch: int):
    """A batch of :func:`sample_batch` upsampled bicubically to the patch size, floored at 0.

    Parameters
    ----------
    torch : module
        PyTorch (:func:`tensor_cosdi.learn.require_torch`).
    clean : torch.Tensor ``(batch, side², channels)``
    side, patch : int
        The batch's side and the patch size; equal sides return ``clean`` itself.

    Returns
    -------
    torch.Tensor ``(batch, patch², channels)``
    """
    if side == patch:
        return clean
    b, _, n = clean.shape
    img = clean.reshape(b, side, side, n).permute(0, 3, 1, 2)
    up = torch.nn.functional.interpolate(
        img, size=(patch, patch), mode="bicubic", align_corners=False
    ).clamp_min(0.0)
    return up.permute(0, 2, 3, 1).reshape(b, patch * patch, n).contiguous()


def _illuminate(rng, patch, position, probability):
    """``patch (p, p, n)`` under a random illuminant and shading, each with ``probability``.

    The illuminant is a smooth positive spectral weight ``1 + a t + b (t² − ⅓)``
    (``t`` the band's position in the scene's range mapped to [−1, 1], ``a`` in
    ±0.6, ``b`` in ±0.4, floored at 0.15): a warmer or bluer light than
    CAVE's calibrated reflectance.  The shading is a linear ramp across the
    patch (slopes in ±0.6, floored at 0.15).  Both keep a spectrum smooth and
    positive, so the denoiser meets more spectral shapes without leaving real
    reflectance behind.  The random stream is drawn from either way.
    """
    t = 2.0 * real_array("position", position, finite=False) - 1.0
    a, b = rng.uniform(-0.6, 0.6), rng.uniform(-0.4, 0.4)
    sx, sy = rng.uniform(-0.6, 0.6, 2)
    tilt, shade = rng.random() < probability, rng.random() < probability
    out = patch
    if tilt:
        w = np.maximum(1.0 + a * t + b * (t * t - 1.0 / 3.0), 0.15)
        out = out * w.astype(np.float32)
    if shade:
        ramp = np.linspace(-0.5, 0.5, patch.shape[0])
        s = np.maximum(1.0 + sx * ramp[:, None] + sy * ramp[None, :], 0.15)
        out = out * s[:, :, None].astype(np.float32)
    return out


def nullspace_noise(torch, noise, rng, p: int, max_shift: int = 3, density_spread: float = 0.2):
    """White noise ``(B, p², n)`` minus its projection onto the row space of a random SD-CASSI
    operator: ``(I − Aᵀ(AAᵀ)⁻¹A) n``, the error a plug-and-play GAP step leaves.

    A random binary code per sample (density drawn from ``0.5 ± density_spread`` per batch)
    and a random shift of 1 to ``max_shift`` pixels per band; ``AAᵀ`` is diagonal (the code
    sums ``Φ``), so the projection is one shear-sum, a division and the transposed shear.

    Parameters
    ----------
    torch : module
        PyTorch (:func:`tensor_cosdi.learn.require_torch`).
    noise : torch.Tensor ``(batch, p², bands)``
    rng : numpy.random.Generator
        Draws the shift, the density and the codes, in that order.
    p : int
        The patch side.
    max_shift : int
    density_spread : float

    Returns
    -------
    torch.Tensor of ``noise``'s shape
    """
    b, _, n = noise.shape
    step = int(rng.choice(np.arange(1, max_shift + 1)))
    density = rng.uniform(0.5 - density_spread, 0.5 + density_spread)
    x = noise.reshape(b, p, p, n)
    code = torch.from_numpy((rng.random((b, p, p)) < density).astype(np.float32)).to(noise.device)
    width = p + step * (n - 1)
    g = torch.zeros(b, p, width, dtype=noise.dtype, device=noise.device)
    phi = torch.zeros_like(g)
    for band in range(n):
        sl = slice(step * band, step * band + p)
        g[:, :, sl] += code * x[..., band]
        phi[:, :, sl] += code
    r = torch.where(phi > 0, g / phi.clamp_min(1.0), torch.zeros_like(g))
    proj = torch.stack([code * r[:, :, step * k : step * k + p] for k in range(n)], dim=-1)
    return (x - proj).reshape(noise.shape)


def _build(torch, cfg: TrainConfig):
    """The network of ``cfg``: random (seeded), or ``cfg.init``'s weights to fine-tune (a
    full network's kernels decomposed when ``cfg.conv_rank`` asks for a factored one)."""
    from . import load_weights
    from .spectral_net import _build_net, architecture, default_weights, factorise

    net = _build_net(torch, cfg.r_max, cfg.width, cfg.blocks, cfg.conv_rank)
    if not cfg.init:
        return net
    path = default_weights() if cfg.init == "shipped" else cfg.init
    ckpt = load_weights(path, "spectral-denoiser", "train-denoiser")
    got = architecture(ckpt["config"], path)
    rank = got.pop("conv_rank")
    want = {"r_max": cfg.r_max, "width": cfg.width, "blocks": cfg.blocks}
    if got != want or rank not in (0, cfg.conv_rank):
        raise ValueError(
            f"init weights {path} are a network of {dict(got, conv_rank=rank)}, not the "
            f"{dict(want, conv_rank=cfg.conv_rank)} being trained; pass the same "
            "--width/--blocks (and --conv-rank, or 0 in the file to factor it)"
        )
    target = net if rank == cfg.conv_rank else _build_net(torch, cfg.r_max, cfg.width, cfg.blocks)
    try:
        target.load_state_dict(ckpt["model"])
    except (KeyError, TypeError, RuntimeError) as exc:
        why = " ".join(str(exc).split())[:160]
        raise ValueError(
            f"init weights {path} do not fit the network their config describes ({why})"
        ) from None
    return target if rank == cfg.conv_rank else factorise(target, cfg.conv_rank)


def _denoiser_loss(torch, net, rng, dev, cfg: TrainConfig, cubes, step=0):
    """One batch's loss (see the module docstring)."""
    from .spectral_net import subspace

    clean_np, rank, side = sample_batch(rng, cubes, cfg)
    sig_np = np.exp(rng.uniform(np.log(cfg.sigma_min), np.log(cfg.sigma_max), cfg.batch))
    clean = magnify(torch, torch.from_numpy(clean_np).to(dev), side, cfg.patch)
    sig = torch.from_numpy(sig_np.astype(np.float32)).to(dev)
    noise = sig[:, None, None] * torch.randn(clean.shape).to(dev)
    if rng.random() < cfg.coded_fraction:
        noise = nullspace_noise(torch, noise, rng, cfg.patch, cfg.max_shift, cfg.density_spread)
    noisy = clean + noise
    scale = noisy.abs().amax(dim=(1, 2)).clamp_min(1e-6)
    noisy, clean = noisy / scale[:, None, None], clean / scale[:, None, None]
    y, u = subspace(noisy, rank, cfg.r_max)
    k = u.shape[-1]
    target = torch.zeros_like(y)
    target[:, :k] = torch.matmul(clean, u).transpose(1, 2)
    p = cfg.patch
    y = y.reshape(cfg.batch, cfg.r_max, p, p)
    target = target.reshape(cfg.batch, cfg.r_max, p, p)
    rel = sig / scale
    pred = net(y, rel)
    # noise energy left, as a fraction of the input's (every level weighs the same)
    return torch.mean(torch.mean((pred - (y - target)) ** 2, dim=(1, 2, 3)) / rel**2) * (
        cfg.r_max / min(rank, clean.shape[-1])
    )


def train_denoiser(
    out,
    config: TrainConfig | None = None,
    *,
    resume: bool = False,
    force: bool = False,
    device: str | None = None,
    folder=None,
    progress: bool = True,
    command: str | None = None,
    stop_after: int | None = None,
):
    """Train the spectral denoiser; write its weights to ``out``.  Returns a summary dict.

    ``resume`` continues from ``OUT.ckpt`` (its configuration must be the
    same; ``config=None`` takes the checkpoint's).  ``device``: ``"cpu"``,
    ``"cuda"``… (default CUDA when available).  ``stop_after`` ends this run
    after that many steps with a checkpoint and no weights (a time-boxed
    session; resume later); the summary's ``finished`` says which happened.
    ``command`` is stored as provenance.
    """
    from ._loop import run

    return run(
        desc="train-denoiser",
        out=out,
        config=config,
        config_cls=TrainConfig,
        prepare=lambda cfg: training_data(folder, cfg.hold_out),
        build=lambda torch, cfg, data: _build(torch, cfg),
        batch_loss=_denoiser_loss,
        weights_config=lambda cfg: {
            "r_max": cfg.r_max,
            "width": cfg.width,
            "blocks": cfg.blocks,
            "conv_rank": cfg.conv_rank,
        },  # fmt: skip
        resume=resume,
        force=force,
        device=device,
        progress=progress,
        command=command,
        stop_after=stop_after,
    )
