"""Training D-CoSNet (``tensor-cosdi train-dcosnet``): crops of the tuning scenes measured
through crops of a real coded aperture, Equation 152's loss, the shared training loop of
:mod:`tensor_cosdi.learn._loop` (checkpoints, exact resume).  The network is in
:mod:`tensor_cosdi.learn.dcosnet`."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .dcosnet import (
    START_ADMM_ITER,
    STARTS,
    Sensing,
    _per_sample,
    build_dcosnet,
    noise_feature,
    seeded_code,
    ssim,
)

__all__ = [
    "DCoSNetConfig",
    "train_dcosnet",
    "training_data",
    "sample_batch",
    "TRAINABLE_SYSTEMS",
    "LOSSES",
    "STARTS",
]

#: Systems :func:`train_dcosnet` builds from crops of a coded aperture.
TRAINABLE_SYSTEMS = ("sd_cassi", "mu_cosdi", "cassi_vsi")
#: Loss choices (Eq. 152 and the thesis' Table 2 ablation).
LOSSES = ("l1+ssim", "l1", "ssim")


@dataclass(frozen=True)
class DCoSNetConfig:
    """Every option of a D-CoSNet training run (stored with the weights).

    ``mask``: ``"tsa"`` (random crops of the real TSA 256×256 coded aperture
    in ``../shared/data/masks``), ``"random"`` (a fresh Bernoulli(½) code per
    sample), ``"mixed"`` (per sample, a TSA crop or a fresh binary code of a
    density drawn from 0.3–0.7, half and half: a network for any binary code)
    ``"seeded"`` (one fixed Bernoulli(½) code of the crop's size drawn from
    ``seed``, :func:`~tensor_cosdi.learn.dcosnet.seeded_code`, used whole and
    never flipped) or a path to a ``.npy``/``.mat`` holding one 2-D code
    (``FILE.mat:NAME`` picks a variable of a file holding several), real,
    finite and non-negative, read with the bounded readers of
    :mod:`tensor_cosdi.io.files`.
    ``learn_code``: learn the code with the network (thesis §7.3), starting
    from the ``"seeded"`` code (the only mask it takes) during the first
    ``code_until`` of the steps, then holding it while the network adapts to
    the final code; the learned binary code is stored with the weights
    (:func:`~tensor_cosdi.learn.dcosnet.training_code`) and the network
    reconstructs only through it.
    ``hold_out``: -1 trains on every tuning scene, ``k`` leaves fold ``k`` of
    ``datasets.tune_folds(4)`` out for validation.
    ``prior``: ``"unet"`` (the thesis' per-stage U-Net, from scratch) or
    ``"spectral"`` (the learned subspace denoiser shared by the stages,
    starting from ``prior_weights``: ``"shipped"`` for the package's
    ``spectral_denoiser.pt``, or a file of ``tensor-cosdi train-denoiser``).
    Measurements are noiseless for ``noiseless_fraction`` of the samples, else
    at an SNR drawn uniformly from ``[snr_min, snr_max]`` dB.
    ``start``: ``"zero"`` (the thesis: the ADMM's ``w`` starts at 0) or ``"fast"`` (``w``
    starts at :func:`~tensor_cosdi.solvers.otd.fast_start`, the first-stage cube
    ``pnp_fast`` starts from, computed from each sample's measurement: 0.2-0.4 s a 64×64
    sample, about two thirds of a step of 8 on 2 CPU cores) or ``"adaptive"`` (pnp_fast's
    start on any measurement: the same where the sample's estimated SNR reads clean, with 10
    ADMM iterations after the first stage where it reads noisy,
    ``fast_start(admm_iter="auto")``).  The weights record it and the method computes the
    same start before the network runs.
    ``noise_input``: condition each stage on the sample's estimated SNR
    (:func:`~tensor_cosdi.learn.dcosnet.build_dcosnet`; the method estimates it the same
    way).  ``init``: a weights file of ``train-dcosnet`` of the same network (system, bands,
    shift, stages, widths, prior) to start from instead of the untrained network — a
    fine-tune; a noise input it lacks starts at 0, so the network starts as that file's.
    """

    system: str = "sd_cassi"
    n_bands: int = 28
    shift: int = 2
    stages: int = 3
    width: int = 16
    unet_width: int = 32
    prior: str = "unet"
    prior_weights: str = "shipped"
    loss: str = "l1+ssim"
    mask: str = "tsa"
    steps: int = 3000
    batch: int = 8
    patch: int = 64
    lr: float = 1e-3
    lr_end: float = 1e-5
    warmup: int = 100
    noiseless_fraction: float = 0.5
    snr_min: float = 20.0
    snr_max: float = 40.0
    seed: int = 0
    checkpoint_every: int = 100
    hold_out: int = -1
    #: CASSI-VSI's beam-splitting ratio (``system="cassi_vsi"`` only)
    alpha_t: float = 0.7
    learn_code: bool = False
    #: fraction of the steps during which a learned code changes (then it is held)
    code_until: float = 0.5
    start: str = "zero"
    noise_input: bool = False
    init: str = ""

    def check(self):
        if self.system not in TRAINABLE_SYSTEMS:
            raise ValueError(f"system must be one of {TRAINABLE_SYSTEMS}, got {self.system!r}")
        from .dcosnet import PRIORS

        if self.prior not in PRIORS:
            raise ValueError(f"prior must be one of {PRIORS}, got {self.prior!r}")
        if self.loss not in LOSSES:
            raise ValueError(f"loss must be one of {LOSSES}, got {self.loss!r}")
        if self.start not in STARTS:
            raise ValueError(f"start must be one of {STARTS}, got {self.start!r}")
        if self.start == "fast" and self.learn_code:
            raise ValueError(
                "start='fast' is computed outside the network, so no gradient reaches a code "
                "being learned: use start='zero' with learn_code"
            )
        from ._loop import check_config

        check_config(
            self,
            ("n_bands", "shift", "stages", "width", "unet_width", "steps", "batch", "patch",
             "checkpoint_every"),
        )  # fmt: skip
        from ..datasets import training_scenes
        from ..validate import integer
        from .dcosnet import CONFIG_LIMITS, MAX_CODE_SIDE

        for name in ("stages", "width", "unet_width"):  # a network its loader would refuse
            integer(name, getattr(self, name), low=1, high=CONFIG_LIMITS[name][1])
        if self.patch + self.margin > MAX_CODE_SIDE:  # the code a file records
            raise ValueError(
                f"the code would be {self.patch + self.margin} px wide (patch + shift × "
                f"(n_bands − 1)); at most {MAX_CODE_SIDE}"
            )
        training_scenes(self.hold_out)
        if not 2 <= self.n_bands <= 31:
            raise ValueError(f"n_bands must lie in 2..31 (the scenes have 31), got {self.n_bands}")
        if self.patch < 16 or self.patch % 4:
            raise ValueError(f"patch must be a multiple of 4, ≥ 16, got {self.patch}")
        if not 0 <= self.noiseless_fraction <= 1:
            raise ValueError(
                f"noiseless_fraction must lie in [0, 1], got {self.noiseless_fraction}"
            )
        if not isinstance(self.noise_input, bool):
            raise ValueError(f"noise_input must be True or False, got {self.noise_input!r}")
        if self.noise_input and self.prior != "unet":
            raise ValueError("noise_input conditions the U-Nets: it needs prior='unet'")
        if not isinstance(self.init, str):
            raise ValueError(f"init must be a weights file's path or '', got {self.init!r}")
        if self.init and self.learn_code:
            raise ValueError("init starts from trained weights; learn_code starts a code: pick one")
        if not isinstance(self.learn_code, bool):
            raise ValueError(f"learn_code must be True or False, got {self.learn_code!r}")
        a = self.alpha_t
        if isinstance(a, bool) or not isinstance(a, (int, float)) or not 0 < a < 1:
            raise ValueError(f"alpha_t must be a number in (0, 1), got {a!r}")
        u = self.code_until
        if isinstance(u, bool) or not isinstance(u, (int, float)) or not 0 < u <= 1:
            raise ValueError(f"code_until must be a fraction in (0, 1], got {u!r}")
        if self.learn_code and self.mask != "seeded":
            raise ValueError(
                f"learn_code starts from the seeded code: needs mask='seeded', got {self.mask!r}"
            )
        if self.learn_code and self.system not in ("sd_cassi", "cassi_vsi"):
            raise ValueError(
                f"learn_code is for sd_cassi and cassi_vsi, got system={self.system!r}"
            )
        if not self.snr_min <= self.snr_max:
            raise ValueError(f"need snr_min ≤ snr_max, got {self.snr_min}, {self.snr_max}")
        return self

    @property
    def fixed_code(self) -> bool:
        """One code used whole and never flipped (``"seeded"`` or a code being learned)."""
        return self.mask == "seeded" or self.learn_code

    @property
    def margin(self) -> int:
        """Extra code columns the system needs beyond the cube's width."""
        return self.shift * (self.n_bands - 1) if self.system == "mu_cosdi" else 0

    def make_system(self, code):
        from ..systems import REGISTRY

        cls = REGISTRY[self.system]
        extra = {"modality": "monocular"} if self.system == "mu_cosdi" else {}
        if self.system == "cassi_vsi":
            extra = {"alpha_t": self.alpha_t}
        return cls(code, n_bands=self.n_bands, shifts=self.shift, **extra)


def _load_mask(spec, folder=None):
    """The 2-D training code named by ``spec`` (see :class:`DCoSNetConfig`), or ``None`` for
    ``"random"``."""
    if spec == "random":
        return None
    if spec in ("tsa", "mixed"):
        from ..datasets import data_dir

        path = data_dir(folder).parent / "masks" / "tsa_mask256.mat"
        if not path.is_file():
            raise FileNotFoundError(
                f"the TSA mask is not at {path}; pass mask='random' (--mask random) or a path"
            )
    else:
        from ..io.files import split_key

        name, key = split_key(spec)
        path = Path(name)
        if path.suffix.lower() not in (".npy", ".mat"):
            raise ValueError(
                f"mask must be 'tsa', 'random', a .npy or a .mat file (FILE.mat:NAME picks a "
                f"variable), got {spec!r}"
            )
        return _code_file(path, key)
    return _code_file(path, None)


def _code_file(path: Path, key):
    """The one 2-D code of a ``.npy`` / ``.mat`` file (``key``: the variable), read through
    :func:`tensor_cosdi.io.read_array` (sizes checked before anything is allocated, regular
    files only, no pickles) and checked: real, finite and non-negative."""
    from ..io.files import array_entries, read_array, require_file

    require_file(path, "mask file")
    if key is None and path.suffix.lower() == ".mat":  # the one 2-D variable, if there is one
        found = array_entries(path, ".mat")
        codes = [k for k, v in found.items() if len(v[0]) == 2]
        if len(codes) != 1:
            listing = [(k, tuple(v[0])) for k, v in found.items()]
            raise ValueError(
                f"{path}: expected one 2-D code, found {listing}; name one with {path}:NAME"
            )
        key = codes[0]
    code = read_array(path, key)
    if code.dtype.kind not in "biuf":
        raise ValueError(f"{path}: the code must hold real numbers, got dtype {code.dtype}")
    if code.ndim != 2:
        raise ValueError(f"{path}: expected one 2-D code, got shape {code.shape}")
    code = code.astype(np.float64)
    if code.size == 0 or not np.all(np.isfinite(code)) or code.min() < 0:
        raise ValueError(f"{path}: the code must be non-empty, finite and non-negative")
    return code


def training_data(cfg: DCoSNetConfig, folder=None):
    """``(cubes, code, offsets)``: the training scenes at ``cfg``'s bands, the training mask
    (``None`` for ``"random"``) and, for SD-CASSI, the per-band column offsets a batch's sensing
    is built from (:meth:`~tensor_cosdi.learn.dcosnet.Sensing.coded_shear`)."""
    from ..datasets import KAIST_WAVELENGTHS, load_hsi, training_scenes

    if not isinstance(cfg, DCoSNetConfig):
        raise ValueError(f"training_data needs a DCoSNetConfig, got {type(cfg).__name__}")
    wl = KAIST_WAVELENGTHS if cfg.n_bands == 28 else np.linspace(400.0, 700.0, cfg.n_bands)
    names = training_scenes(cfg.hold_out)
    need = (cfg.patch, cfg.patch + cfg.margin)
    # the code first: a bad mask file fails before 28 scenes are read
    code = seeded_code(need, cfg.seed) if cfg.mask == "seeded" else _load_mask(cfg.mask, folder)
    if code is not None and (code.shape[0] < need[0] or code.shape[1] < need[1]):
        raise ValueError(f"the mask {code.shape} is smaller than a training crop {need}")
    cubes = [load_hsi(name, wl, folder=folder, dtype="float32")[0] for name in names]
    offsets = None  # SD-CASSI, CASSI-VSI: the batch's sensing is built from its codes alone
    if cfg.system in ("sd_cassi", "cassi_vsi"):
        offsets = tuple(int(v) for v in cfg.make_system(np.ones(need)).shifts)
    return cubes, code, offsets


def sample_batch(rng, cfg: DCoSNetConfig, data, *, windows: bool = False):
    """One batch ``(clean (B, p, p, L) float32, [code (p, p + margin), …])`` drawn from the
    random stream ``rng`` and :func:`training_data`'s ``data``; with ``windows=True`` also
    each code crop's ``(row, column)`` corner in the training code (a learned code is cropped
    at the same places)."""
    cubes, code, offsets = data
    p = cfg.patch
    clean = np.empty((cfg.batch, p, p, cfg.n_bands), dtype=np.float32)
    codes, corners = [], []
    for i in range(cfg.batch):
        c = cubes[int(rng.integers(len(cubes)))]
        r0 = int(rng.integers(0, c.shape[0] - p + 1))
        c0 = int(rng.integers(0, c.shape[1] - p + 1))
        patch = np.rot90(c[r0 : r0 + p, c0 : c0 + p], int(rng.integers(4)))
        clean[i] = patch[::-1] if rng.random() < 0.5 else patch
        w = p + cfg.margin
        if cfg.mask == "mixed":  # the random stream is drawn from either way
            density, fresh = rng.uniform(0.3, 0.7), rng.random() < 0.5
        else:
            density, fresh = 0.5, code is None
        if fresh:
            crop = (rng.random((p, w)) < density).astype(np.float64)
            corners.append(None)
        else:
            r0 = int(rng.integers(0, code.shape[0] - p + 1))
            c0 = int(rng.integers(0, code.shape[1] - w + 1))
            crop = code[r0 : r0 + p, c0 : c0 + w]
            if rng.random() < 0.5 and not cfg.fixed_code:
                crop = crop[::-1]
            corners.append((r0, c0))
        codes.append(np.ascontiguousarray(crop))
    return (clean, codes, corners) if windows else (clean, codes)


def _sensing(codes, offsets, cfg: DCoSNetConfig, dev):
    if offsets is not None:
        alpha = cfg.alpha_t if cfg.system == "cassi_vsi" else 1.0
        return Sensing.coded_shear(np.stack(codes), offsets, alpha_t=alpha, device=dev)
    return Sensing([cfg.make_system(c) for c in codes], device=dev)


def _loss_terms(torch, est, truth, g_est, g_true, dbar, loss: str):
    """Equation 152 with the ablation choices; ``G`` compared in units of ``d̄`` (cube-like)."""
    db = _per_sample(dbar, g_true)
    total = (g_est - g_true).abs().div(db).mean()
    if loss in ("l1+ssim", "l1"):
        total = total + (est - truth).abs().mean()
    if loss in ("l1+ssim", "ssim"):
        total = total + (1 - ssim(est, truth))
    return total


def _dcosnet_loss(torch, net, rng, dev, cfg: DCoSNetConfig, data, step=0):
    clean_np, codes, corners = sample_batch(rng, cfg, data, windows=True)
    if cfg.learn_code:  # the same crops of the code being learned (binary, straight-through)
        full = net.binary_code()
        if step >= cfg.code_until * cfg.steps:  # held: no gradient, Adam leaves it alone
            full = full.detach()
        w = cfg.patch + cfg.margin
        crops = torch.stack([full[r : r + cfg.patch, c : c + w] for r, c in corners])
        alpha = cfg.alpha_t if cfg.system == "cassi_vsi" else 1.0
        sensing = Sensing.coded_shear(crops, data[2], alpha_t=alpha, device=dev)
    else:
        sensing = _sensing(codes, data[2], cfg, dev)
    truth = torch.from_numpy(clean_np).to(dev).permute(0, 3, 1, 2)
    with torch.no_grad():
        g = sensing.forward(truth)
        power = g.pow(2).reshape(len(g), -1).mean(dim=1)
        snr = rng.uniform(cfg.snr_min, cfg.snr_max, cfg.batch)
        noisy = rng.random(cfg.batch) >= cfg.noiseless_fraction
        sig = torch.from_numpy(np.where(noisy, 10 ** (-snr / 20), 0.0).astype(np.float32)).to(dev)
        g_in = g + _per_sample(sig * power.sqrt(), g) * torch.randn(g.shape).to(dev)
        s = sensing.scale(g_in)
        start = noise = None
        if cfg.start != "zero" or cfg.noise_input:  # from each sample's own measurement
            start, noise = _starts(cfg, codes, g_in)
            start = None if start is None else start.to(dev) / _per_sample(s, truth)
            noise = None if noise is None else noise.to(dev)
    est, g_est = net(g_in / _per_sample(s, g), sensing, start=start, noise=noise)
    return _loss_terms(
        torch, est, truth / _per_sample(s, truth), g_est, g / _per_sample(s, g), sensing.dbar,
        cfg.loss,
    )  # fmt: skip


def _starts(cfg: DCoSNetConfig, codes, g):
    """``(starts, noise)`` of the batch ``g``, each measurement through its code, as the method
    computes them: :func:`~tensor_cosdi.solvers.otd.fast_start` for ``cfg.start``
    (``(B, C, H, W)`` float32 on the CPU; ``None`` for ``"zero"``) and the noise input of the
    estimated SNR (``(B,)``; ``None`` without ``noise_input``)."""
    import torch

    from ..solvers.otd import fast_start
    from ..solvers.snr import estimate_snr

    gs = g.detach().cpu().numpy().astype(np.float64)
    cubes, noise = [], []
    for c, gi in zip(codes, gs):
        system = cfg.make_system(c)
        if cfg.noise_input:
            noise.append(noise_feature(estimate_snr(system, gi).snr_db))
        if cfg.start != "zero":
            cubes.append(np.asarray(fast_start(system, gi, admm_iter=START_ADMM_ITER[cfg.start])))
    start = None
    if cubes:
        out = np.stack(cubes).astype(np.float32)
        out = out.reshape(len(cubes), *out.shape[1:3], -1)
        start = torch.from_numpy(out).permute(0, 3, 1, 2)
    return start, (torch.tensor(noise, dtype=torch.float32) if noise else None)


def build_network(torch, cfg: DCoSNetConfig, data):
    """The network; the ``"spectral"`` prior starts from the pretrained denoiser's weights."""
    net = build_dcosnet(
        torch, cfg.n_bands, cfg.stages, cfg.width, cfg.unet_width, cfg.prior,
        code_shape=data[1].shape if cfg.learn_code else None, noise_input=cfg.noise_input,
    )  # fmt: skip
    if cfg.init:
        _load_init(torch, net, cfg)
    if cfg.learn_code:  # logits ±1/2 around the starting code: a few hundred steps flip a pixel
        start = torch.from_numpy((np.asarray(data[1]) > 0).astype(np.float32) - 0.5)
        net.code_logits.data.copy_(start)
    if cfg.prior == "spectral":
        from .spectral_net import SpectralDenoiser

        pre = SpectralDenoiser(None if cfg.prior_weights == "shipped" else cfg.prior_weights)
        try:
            net.spectral.net.load_state_dict(pre.net.state_dict())
        except RuntimeError as exc:
            raise ValueError(
                f"{pre.path}: a denoiser of another shape than D-CoSNet's spectral prior "
                f"(r_max 12, width 64, 4 blocks, full convolutions): "
                f"{' '.join(str(exc).split())[:160]}"
            ) from None
    return net


def _init_checkpoint(cfg: DCoSNetConfig):
    """``(path, checkpoint)`` of ``cfg.init``, read and checked against this run's network (the
    same, or the same without the noise input) before any training data are read."""
    from .dcosnet import _checkpoint

    path, ckpt = _checkpoint(cfg.init)
    theirs = dict(ckpt["config"])
    mine = {"system": cfg.system, "channels": cfg.n_bands, "shift": cfg.shift,
            "stages": cfg.stages, "width": cfg.width, "unet_width": cfg.unet_width,
            "prior": cfg.prior}  # fmt: skip
    other = {k: theirs.get(k, "unet" if k == "prior" else None) for k in mine}
    if other != mine or (theirs.get("noise_input", False) and not cfg.noise_input):
        raise ValueError(
            f"init={path}: weights of another network ({other}, noise input "
            f"{theirs.get('noise_input', False)}) than this run's ({mine}, noise input "
            f"{cfg.noise_input})"
        )
    return path, ckpt


def _load_init(torch, net, cfg: DCoSNetConfig) -> None:
    """Load ``cfg.init``'s weights into ``net`` (a fine-tune's start): the same network, or the
    same with a noise input the file lacks (its parameters stay at their zero start)."""
    path, ckpt = _init_checkpoint(cfg)
    own = net.state_dict()
    for name, value in ckpt["model"].items():
        if not isinstance(value, torch.Tensor) or name not in own:
            raise ValueError(f"init={path}: parameter {name!r} is not one of this network's")
        target = own[name]
        if value.shape == target.shape:
            target.copy_(value)
        elif (
            value.ndim == 4
            and value.shape[1] + 1 == target.shape[1]
            and name.endswith("enc1.0.weight")
        ):  # the U-Net's first convolution: the noise map's input channel starts at 0
            target.zero_()
            target[:, : value.shape[1]].copy_(value)
        else:
            raise ValueError(
                f"init={path}: parameter {name!r} is {tuple(value.shape)}, this network's "
                f"{tuple(target.shape)}"
            )


def _code_record(cfg: DCoSNetConfig) -> dict:
    """What the weights record of their training code (:func:`~.dcosnet.training_code`)."""
    if not cfg.fixed_code:
        return {}
    need = [cfg.patch, cfg.patch + cfg.margin]
    return {
        "code": "learned" if cfg.learn_code else "seeded",
        "code_shape": need,
        "code_seed": cfg.seed,
    }


def train_dcosnet(
    out,
    config: DCoSNetConfig | None = None,
    *,
    resume: bool = False,
    force: bool = False,
    device: str | None = None,
    folder=None,
    progress: bool = True,
    command: str | None = None,
    stop_after: int | None = None,
):
    """Train D-CoSNet on crops of the tuning scenes; write its weights to ``out``.

    Same contract as :func:`tensor_cosdi.learn.train.train_denoiser`
    (checkpoints to ``OUT.ckpt``, ``resume``, ``force``, ``stop_after``).
    Returns a summary dict.
    """
    from ._loop import run

    if isinstance(config, DCoSNetConfig) and config.init:  # a bad file fails before the data load
        _init_checkpoint(config.check())
    return run(
        desc="train-dcosnet",
        out=out,
        config=config,
        config_cls=DCoSNetConfig,
        prepare=lambda cfg: training_data(cfg, folder),
        build=build_network,
        batch_loss=_dcosnet_loss,
        weights_config=lambda cfg: {
            "system": cfg.system,
            "channels": cfg.n_bands,
            "shift": cfg.shift,
            "stages": cfg.stages,
            "width": cfg.width,
            "unet_width": cfg.unet_width,
            "prior": cfg.prior,
            "start": cfg.start,
            "noise_input": cfg.noise_input,
            **({"init": Path(cfg.init).name} if cfg.init else {}),
            **({"alpha_t": cfg.alpha_t} if cfg.system == "cassi_vsi" else {}),
            **_code_record(cfg),
        },
        resume=resume,
        force=force,
        device=device,
        progress=progress,
        command=command,
        stop_after=stop_after,
    )
