"""D-CoSNet: deep-unfolded ADMM with the system's closed-form Woodbury x-step (thesis §7.2).

The thesis' network (Fig. 80, Eq. 145-152) is one ADMM pass built from the
sensing layers of the imager — direct ``A`` (Eq. 149), transpose ``Aᵀ``
(Eq. 150) and the inverse ``(μ̃I + AAᵀ)⁻¹`` (Eq. 151, a Hadamard division
because ``AAᵀ`` is diagonal) — plus a U-Net.  Here the sensing layers are
the system's own :class:`~tensor_cosdi.operators.TensorOperator` run on
the TensorLy PyTorch backend, so autograd flows through the real ``A`` and
``Aᵀ`` of any system whose ``AAᵀ`` is diagonal (SD/DD-CASSI, CS2LI,
Mu-CoSDI, CASSDI-DFA without PSFs).  One stage ``k`` is::

    r  = Aᵀg + μ̃ₖ (w − u)                     x-step right-hand side (Eq. 146)
    r' = r + d̄·Cᵢₙ(r/d̄)                        "transpose + two conv+ReLU layers"
    s  = (μ̃ₖ + d)⁻¹ ∘ A r'                      direct and inverse layers
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
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import tensorly as tl

from .. import _backend as B
from . import require_torch

__all__ = [
    "DCoSNetConfig",
    "DCoSNet",
    "Sensing",
    "build_dcosnet",
    "ssim",
    "train_dcosnet",
    "default_weights",
    "TRAINABLE_SYSTEMS",
    "LOSSES",
]

WEIGHTS_DIR = Path(__file__).resolve().parent / "weights"
#: Shipped weights per system name.
DEFAULT_WEIGHTS = {"sd_cassi": WEIGHTS_DIR / "dcosnet_sd_cassi.pt"}
#: Systems :func:`train_dcosnet` builds from crops of a coded aperture.
TRAINABLE_SYSTEMS = ("sd_cassi", "mu_cosdi")
#: Loss choices (Eq. 152 and the thesis' Table 2 ablation).
LOSSES = ("l1+ssim", "l1", "ssim")


def default_weights(system_name: str) -> Path:
    """The shipped weights for ``system_name``; ``FileNotFoundError`` naming the command if none."""
    path = DEFAULT_WEIGHTS.get(system_name)
    if path is None or not path.is_file():
        raise FileNotFoundError(
            f"no shipped D-CoSNet weights for {system_name!r} (shipped: "
            f"{sorted(k for k, v in DEFAULT_WEIGHTS.items() if v.is_file())}); train them with "
            f"`tensor-cosdi train-dcosnet --system {system_name} --out weights.pt` and pass "
            "weights='weights.pt'"
        )
    return path


# ---- sensing layers ---------------------------------------------------------------------------
class Sensing:
    """``A``, ``Aᵀ`` and ``diag(AAᵀ)`` of a batch of systems as differentiable torch functions.

    Cubes are batches ``(B, C, H, W)`` with ``C`` the product of the cube's
    trailing axes (bands, patterns…); measurements ``(B, *measurement_shape)``.
    Each system's operator runs on the TensorLy PyTorch backend.
    """

    def __init__(self, systems, *, device=None, dtype=None):
        torch = require_torch()
        systems = list(systems)
        if not systems:
            raise ValueError("Sensing needs at least one system")
        shape = tuple(systems[0].cube_shape)
        mshape = tuple(systems[0].measurement_shape)
        for s in systems[1:]:
            if tuple(s.cube_shape) != shape or tuple(s.measurement_shape) != mshape:
                raise ValueError("every system of a batch must have the same cube shape")
        if len(shape) < 3:
            raise ValueError(f"D-CoSNet needs a cube (rows, columns, channels…), got {shape}")
        d = []
        for s in systems:
            gram = s.operator.gram_dual()
            if getattr(gram, "kind", None) != "diagonal":
                kind = "none" if gram is None else gram.kind
                raise ValueError(
                    f"D-CoSNet needs a diagonal A Aᵀ (SD/DD-CASSI, CS2LI, Mu-CoSDI, CASSDI-DFA "
                    f"without PSFs); {type(s).__name__} has structure {kind!r}"
                )
            d.append(np.asarray(gram.d))
        self.systems, self.ops = systems, [s.operator for s in systems]
        self.cube_shape, self.measurement_shape = shape, mshape
        self.channels = int(np.prod(shape[2:]))
        self.dtype = dtype or torch.float32
        self.device = torch.device(device or "cpu")
        self.d = torch.from_numpy(np.stack(d)).to(device=self.device, dtype=self.dtype)
        self.dbar = self.d.reshape(len(d), -1).mean(dim=1)

    def _cube(self, x):
        return x.permute(1, 2, 0).reshape(self.cube_shape)

    def _batch(self, cube):
        h, w = self.cube_shape[:2]
        return cube.reshape(h, w, self.channels).permute(2, 0, 1)

    def forward(self, x):
        """``A x`` for ``x (B, C, H, W)``."""
        torch = require_torch()
        with tl.backend_context("pytorch"):
            return torch.stack([op.forward(self._cube(xi)) for op, xi in zip(self.ops, x)])

    def adjoint(self, y):
        """``Aᵀ y`` as ``(B, C, H, W)``."""
        torch = require_torch()
        with tl.backend_context("pytorch"):
            return torch.stack([self._batch(op.adjoint(yi)) for op, yi in zip(self.ops, y)])

    def scale(self, g):
        """Per-sample ``s``: the 99.9th percentile of ``g / d`` where ``d > 0`` (``(B,)``)."""
        torch = require_torch()
        out = []
        for gi, di in zip(g, self.d):
            v = (gi[di > 0] / di[di > 0]).abs().reshape(-1)
            q = torch.quantile(v.float(), 0.999) if v.numel() else torch.tensor(0.0)
            out.append(q if float(q) > 0 else v.max() if v.numel() else torch.tensor(1.0))
        return torch.stack(out).to(device=g.device, dtype=g.dtype).clamp_min(1e-12)


# ---- the network ------------------------------------------------------------------------------
def _per_sample(t, x):
    """``t (B,)`` broadcast against ``x``."""
    return t.reshape(-1, *([1] * (x.ndim - 1)))


def build_dcosnet(torch, channels: int, stages: int = 1, width: int = 32, unet_width: int = 32):
    """The untrained network (a ``torch.nn.Module``) for cubes of ``channels`` channels."""
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
            self.enc1 = double(channels, b)
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

        def forward(self, x):
            h, w = x.shape[-2:]
            ph, pw = (-h) % 4, (-w) % 4
            xp = nn.functional.pad(x, (0, pw, 0, ph), mode="replicate") if ph or pw else x
            e1 = self.enc1(xp)
            e2 = self.enc2(e1)
            e3 = self.enc3(e2)
            d2 = self.dec2(torch.cat([self.up3(e3), e2], dim=1))
            d1 = self.dec1(torch.cat([self.up2(d2), e1], dim=1))
            return x + self.out(d1)[..., :h, :w]

    class DCoSNetModule(nn.Module):
        """``forward(g, sensing) -> (F̃, G̃)`` for a normalised measurement batch ``g``."""

        def __init__(self):
            super().__init__()
            self.channels, self.stages = channels, stages
            self.width, self.unet_width = width, unet_width
            mu0 = math.log(math.expm1(0.1))  # μ̃ = 0.1 d̄ at the start
            self.mu = nn.Parameter(torch.full((stages,), mu0))
            self.c_in = nn.ModuleList([conv_stack(2) for _ in range(stages)])
            self.c_up = nn.ModuleList([conv_stack(4) for _ in range(stages)])
            self.c_lo = nn.ModuleList([conv_stack(3) for _ in range(stages)])
            self.unet = nn.ModuleList([UNet() for _ in range(stages)])

        def forward(self, g, sensing):
            if sensing.channels != self.channels:
                raise ValueError(
                    f"the network was built for {self.channels} channels; the system's cube has "
                    f"{sensing.channels}"
                )
            d = sensing.d.to(g.dtype)
            dbar = sensing.dbar.to(g.dtype)
            atg = sensing.adjoint(g)
            db = _per_sample(dbar, atg)
            w = torch.zeros_like(atg)
            u = torch.zeros_like(atg)
            for k in range(self.stages):
                mu = nn.functional.softplus(self.mu[k]) * dbar
                muc = _per_sample(mu, atg)
                r = atg + muc * (w - u)
                r = r + db * self.c_in[k](r / db)
                s = sensing.forward(r) / (_per_sample(mu, d) + d)
                ats = sensing.adjoint(s)
                f = (r - ats) / muc + self.c_lo[k](r / db) - self.c_up[k](ats / db)
                w = self.unet[k](f + u)
                u = u + f - w
            return w, sensing.forward(w)

    return DCoSNetModule()


def ssim(x, y, *, data_range: float = 1.0, sigma: float = 1.5, win: int = 11):
    """Mean SSIM of two batches ``(B, C, H, W)``, per channel, Gaussian window (as scikit-image
    with ``gaussian_weights=True, use_sample_covariance=False``, interior pixels)."""
    torch = require_torch()
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
        the system it is called with.
    device : str, optional
        ``"cpu"``, ``"cuda"``…; default CUDA when available.
    """

    def __init__(self, weights=None, *, device=None):
        self.torch = require_torch()
        self.path = None if weights is None else Path(weights)
        self.device = device
        self._nets = {}

    def _load(self, system_name):
        torch = self.torch
        path = self.path if self.path is not None else default_weights(system_name)
        if path in self._nets:
            return self._nets[path]
        if not path.is_file():
            raise FileNotFoundError(f"D-CoSNet weights not found: {path}")
        ckpt = torch.load(path, map_location="cpu", weights_only=True)
        try:
            cfg = dict(ckpt["config"])
            net = build_dcosnet(
                torch, int(cfg["channels"]), int(cfg["stages"]), int(cfg["width"]),
                int(cfg["unet_width"]),
            )  # fmt: skip
            net.load_state_dict(ckpt["model"])
        except (KeyError, TypeError, RuntimeError) as exc:
            raise ValueError(
                f"{path} is not a D-CoSNet checkpoint of tensor-cosdi train-dcosnet ({exc})"
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
        if mine != theirs or (step is not None and step != float(cfg["shift"])):
            raise ValueError(
                f"these D-CoSNet weights were trained for {cfg['system']} with "
                f"{cfg['channels']} channels and a shift of {cfg['shift']} px per band; this is "
                f"{mine['system']} with {mine['channels']} channels and a shift of {step}: "
                f"train weights for it (tensor-cosdi train-dcosnet --system {system.name} …)"
            )

    def __call__(self, system, measurement):
        torch = self.torch
        net, cfg = self._load(system.name)
        self.check(system, cfg)
        dev = torch.device(self.device or ("cuda" if torch.cuda.is_available() else "cpu"))
        net.to(dev)
        sensing = Sensing([system], device=dev)
        g = torch.from_numpy(np.asarray(B.to_numpy(measurement), dtype=np.float32)).to(dev)[None]
        s = sensing.scale(g)
        with torch.no_grad():
            x, _ = net(g / _per_sample(s, g), sensing)
        x = x * _per_sample(s, x)
        cube = x[0].permute(1, 2, 0).reshape(system.cube_shape).cpu().numpy()
        dtype = np.asarray(B.to_numpy(measurement)).dtype
        if dtype.kind != "f":
            dtype = np.float32
        return B.tensor_like(cube.astype(dtype, copy=False), measurement)


# ---- training ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class DCoSNetConfig:
    """Every option of a D-CoSNet training run (stored with the weights).

    ``mask``: ``"tsa"`` (random crops of the real TSA 256×256 coded aperture
    in ``../shared/data/masks``), ``"random"`` (a fresh Bernoulli(½) code per
    sample) or a path to a ``.npy``/``.mat`` holding one 2-D code.
    Measurements are noiseless for ``noiseless_fraction`` of the samples, else
    at an SNR drawn uniformly from ``[snr_min, snr_max]`` dB.
    """

    system: str = "sd_cassi"
    n_bands: int = 28
    shift: int = 2
    stages: int = 3
    width: int = 16
    unet_width: int = 32
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

    def check(self):
        if self.system not in TRAINABLE_SYSTEMS:
            raise ValueError(f"system must be one of {TRAINABLE_SYSTEMS}, got {self.system!r}")
        if self.loss not in LOSSES:
            raise ValueError(f"loss must be one of {LOSSES}, got {self.loss!r}")
        for name in ("n_bands", "shift", "stages", "width", "unet_width", "steps", "batch",
                     "patch", "checkpoint_every"):  # fmt: skip
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
                raise ValueError(f"{name} must be a positive integer, got {v!r}")
        if not 2 <= self.n_bands <= 31:
            raise ValueError(f"n_bands must lie in 2..31 (the scenes have 31), got {self.n_bands}")
        if self.patch < 16 or self.patch % 4:
            raise ValueError(f"patch must be a multiple of 4, ≥ 16, got {self.patch}")
        if isinstance(self.warmup, bool) or not isinstance(self.warmup, int) or self.warmup < 0:
            raise ValueError(f"warmup must be an integer ≥ 0, got {self.warmup!r}")
        if not 0 < self.lr_end <= self.lr:
            raise ValueError(f"need 0 < lr_end ≤ lr, got {self.lr_end}, {self.lr}")
        if not 0 <= self.noiseless_fraction <= 1:
            raise ValueError(
                f"noiseless_fraction must lie in [0, 1], got {self.noiseless_fraction}"
            )
        if not self.snr_min <= self.snr_max:
            raise ValueError(f"need snr_min ≤ snr_max, got {self.snr_min}, {self.snr_max}")
        return self

    @property
    def margin(self) -> int:
        """Extra code columns the system needs beyond the cube's width."""
        return self.shift * (self.n_bands - 1) if self.system == "mu_cosdi" else 0

    def make_system(self, code):
        from ..systems import REGISTRY

        cls = REGISTRY[self.system]
        extra = {"modality": "monocular"} if self.system == "mu_cosdi" else {}
        return cls(code, n_bands=self.n_bands, shifts=self.shift, **extra)


def _load_mask(spec, folder=None):
    """The 2-D training code named by ``spec`` (see :class:`DCoSNetConfig`), or ``None`` for
    ``"random"``."""
    if spec == "random":
        return None
    if spec == "tsa":
        from ..datasets import data_dir

        path = data_dir(folder).parent / "masks" / "tsa_mask256.mat"
        if not path.is_file():
            raise FileNotFoundError(
                f"the TSA mask is not at {path}; pass mask='random' (--mask random) or a path"
            )
    else:
        path = Path(spec)
        if not path.is_file():
            raise FileNotFoundError(f"mask file not found: {path}")
    if path.suffix == ".npy":
        arrays = {"array": np.load(path, allow_pickle=False)}
    elif path.suffix == ".mat":
        import scipy.io

        arrays = {k: v for k, v in scipy.io.loadmat(path).items() if not k.startswith("__")}
    else:
        raise ValueError(f"mask must be 'tsa', 'random', a .npy or a .mat file, got {spec!r}")
    codes = {k: v for k, v in arrays.items() if np.ndim(v) == 2}
    if len(codes) != 1:
        raise ValueError(
            f"{path}: expected one 2-D code, found {[(k, np.shape(v)) for k, v in arrays.items()]}"
        )
    code = np.asarray(next(iter(codes.values())), dtype=np.float64)
    if not np.all(np.isfinite(code)) or code.min() < 0:
        raise ValueError(f"{path}: the code must be finite and non-negative")
    return code


def _training_data(cfg: DCoSNetConfig, folder=None):
    from ..datasets import KAIST_WAVELENGTHS, TUNE_SCENES, load_hsi

    wl = KAIST_WAVELENGTHS if cfg.n_bands == 28 else np.linspace(400.0, 700.0, cfg.n_bands)
    cubes = [load_hsi(name, wl, folder=folder, dtype="float32")[0] for name in TUNE_SCENES]
    code = _load_mask(cfg.mask, folder)
    need = (cfg.patch, cfg.patch + cfg.margin)
    if code is not None and (code.shape[0] < need[0] or code.shape[1] < need[1]):
        raise ValueError(f"the mask {code.shape} is smaller than a training crop {need}")
    return cubes, code


def _sample(rng, cfg: DCoSNetConfig, data):
    """``(clean (B, p, p, L) float32, [system, …])`` from the random stream."""
    cubes, code = data
    p = cfg.patch
    clean = np.empty((cfg.batch, p, p, cfg.n_bands), dtype=np.float32)
    systems = []
    for i in range(cfg.batch):
        c = cubes[int(rng.integers(len(cubes)))]
        r0 = int(rng.integers(0, c.shape[0] - p + 1))
        c0 = int(rng.integers(0, c.shape[1] - p + 1))
        patch = np.rot90(c[r0 : r0 + p, c0 : c0 + p], int(rng.integers(4)))
        clean[i] = patch[::-1] if rng.random() < 0.5 else patch
        w = p + cfg.margin
        if code is None:
            crop = (rng.random((p, w)) < 0.5).astype(np.float64)
        else:
            r0 = int(rng.integers(0, code.shape[0] - p + 1))
            c0 = int(rng.integers(0, code.shape[1] - w + 1))
            crop = code[r0 : r0 + p, c0 : c0 + w]
            if rng.random() < 0.5:
                crop = crop[::-1]
        systems.append(cfg.make_system(np.ascontiguousarray(crop)))
    return clean, systems


def _loss_terms(torch, est, truth, g_est, g_true, dbar, loss: str):
    """Eq. 152 with the ablation choices; ``G`` compared in units of ``d̄`` (cube-like)."""
    db = _per_sample(dbar, g_true)
    total = (g_est - g_true).abs().div(db).mean()
    if loss in ("l1+ssim", "l1"):
        total = total + (est - truth).abs().mean()
    if loss in ("l1+ssim", "ssim"):
        total = total + (1 - ssim(est, truth))
    return total


def _dcosnet_loss(torch, net, rng, dev, cfg: DCoSNetConfig, data):
    clean_np, systems = _sample(rng, cfg, data)
    sensing = Sensing(systems, device=dev)
    truth = torch.from_numpy(clean_np).to(dev).permute(0, 3, 1, 2)
    with torch.no_grad():
        g = sensing.forward(truth)
        power = g.pow(2).reshape(len(g), -1).mean(dim=1)
        snr = rng.uniform(cfg.snr_min, cfg.snr_max, cfg.batch)
        noisy = rng.random(cfg.batch) >= cfg.noiseless_fraction
        sig = torch.from_numpy(np.where(noisy, 10 ** (-snr / 20), 0.0).astype(np.float32)).to(dev)
        g_in = g + _per_sample(sig * power.sqrt(), g) * torch.randn(g.shape).to(dev)
        s = sensing.scale(g_in)
    est, g_est = net(g_in / _per_sample(s, g), sensing)
    return _loss_terms(
        torch, est, truth / _per_sample(s, truth), g_est, g / _per_sample(s, g), sensing.dbar,
        cfg.loss,
    )  # fmt: skip


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

    return run(
        desc="train-dcosnet",
        out=out,
        config=config,
        config_cls=DCoSNetConfig,
        prepare=lambda cfg: _training_data(cfg, folder),
        build=lambda torch, cfg, data: build_dcosnet(
            torch, cfg.n_bands, cfg.stages, cfg.width, cfg.unet_width
        ),
        batch_loss=_dcosnet_loss,
        weights_config=lambda cfg: {
            "system": cfg.system,
            "channels": cfg.n_bands,
            "shift": cfg.shift,
            "stages": cfg.stages,
            "width": cfg.width,
            "unet_width": cfg.unet_width,
        },
        resume=resume,
        force=force,
        device=device,
        progress=progress,
        command=command,
        stop_after=stop_after,
    )
