"""A learned spectral denoiser for plug-and-play reconstruction with any system (optional torch).

The denoiser is band-count agnostic because it works in a spectral subspace:

1. the cube ``x (rows, columns, channels)`` is scaled by its robust peak
   ``s`` (the 99.9th percentile of ``|x|``: a plug-and-play iterate has
   outliers); a cube with more axes (fringe patterns, depth planes, views)
   is denoised one ``(rows, columns, bands)`` slice at a time (``joint=True``
   folds the trailing axes into ``channels`` instead);
2. its ``r`` leading spectral eigenvectors ``U (channels, r)`` (the Tucker /
   HOSVD factor of the band mode, from the ``channels × channels`` Gram
   matrix) give ``r`` eigen-images ``Y = x ×₃ Uᵀ``; each eigenvector's sign
   makes its eigen-image sum non-negative, and ranks below the network's
   ``r_max`` are zero-padded;
3. a small convolutional network at half resolution (pixel-unshuffle by 2
   and a noise map ``σ/s`` as in FFDNet; a linear 3×3 path plus residual
   blocks; pixel-shuffle back) predicts the noise of ``Y``;
4. the denoised cube is ``(Y − N̂) ×₃ U · s`` — the orthogonal complement of
   the subspace, mostly noise on real spectra, is dropped.

White Gaussian noise of level ``σ`` stays white with level ``σ`` on the
eigen-images (``U`` is orthonormal), so one network trained on additive
Gaussian noise serves every band count, every system and every noise level
in its training range.  Trained by :mod:`tensor_cosdi.learn.train` on the
tuning scenes of :mod:`tensor_cosdi.datasets` (never the report scenes);
the shipped weights and the command that produced them are described in
``tensor_cosdi/learn/weights/README.md``.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import numpy as np

from .. import _backend as B
from ..validate import flag, integer, number
from . import load_weights, require_torch, torch_device

__all__ = [
    "SubspaceDenoiserNet",
    "SpectralDenoiser",
    "factorise",
    "architecture",
    "subspace",
    "default_weights",
    "PRECISIONS",
    "bfloat16_is_fast",
    "network_device",
    "network_precision",
]

#: ``SpectralDenoiser(precision=…)``: the network's arithmetic.  ``"auto"`` is bfloat16 on a CPU
#: with native bfloat16 instructions (:func:`bfloat16_is_fast`), float32 elsewhere.
PRECISIONS = ("auto", "float32", "bfloat16")

WEIGHTS_DIR = Path(__file__).resolve().parent / "weights"
DEFAULT_WEIGHTS = WEIGHTS_DIR / "spectral_denoiser.pt"


def default_weights() -> Path:
    """The shipped weights file (``FileNotFoundError`` naming the training command if absent)."""
    if not DEFAULT_WEIGHTS.is_file():
        raise FileNotFoundError(
            f"no shipped denoiser weights at {DEFAULT_WEIGHTS}; train them with "
            "`tensor-cosdi train-denoiser --out weights.pt` and pass weights='weights.pt'"
        )
    return DEFAULT_WEIGHTS


def _build_net(torch, r_max: int, width: int, blocks: int, conv_rank: int = 0):
    nn = torch.nn

    def conv(cin, cout, bias=True):
        """A 3×3 convolution, or its Tucker-2 form (:func:`factorise`) when ``conv_rank``."""
        if not conv_rank:
            return nn.Conv2d(cin, cout, 3, padding=1, bias=bias)
        k_in, k_out = min(conv_rank, cin), min(conv_rank, cout)
        return nn.Sequential(
            nn.Conv2d(cin, k_in, 1, bias=False),
            nn.Conv2d(k_in, k_out, 3, padding=1, bias=False),
            nn.Conv2d(k_out, cout, 1, bias=bias),
        )

    def last(m):  # the layer whose output leaves ``m``: zeroed for an identity start
        return m[-1] if isinstance(m, nn.Sequential) else m

    class _Block(nn.Module):
        def __init__(self):
            super().__init__()
            self.a = conv(width, width)
            self.b = conv(width, width)
            for layer in self.a if conv_rank else [self.a]:
                nn.init.kaiming_normal_(layer.weight, nonlinearity="relu")
            nn.init.zeros_(last(self.a).bias)
            nn.init.zeros_(last(self.b).weight)  # each block starts as the identity
            nn.init.zeros_(last(self.b).bias)

        def forward(self, x):
            # in place on the fresh outputs (no convolution's gradient needs its own output):
            # the same values as x + b(relu(a(x))) without two temporaries of the activations
            return self.b(torch.relu_(self.a(x))).add_(x)

    class SubspaceDenoiserNet(nn.Module):
        """Noise of ``r_max`` eigen-images ``(batch, r_max, H, W)`` given ``σ`` ``(batch,)``.

        Half resolution (pixel-unshuffle) with a noise-level map; a linear
        3×3 path (zero at the start) plus head, ``blocks`` residual blocks and
        tail — the linear path learns the bulk of the noise in the first
        hundred steps, the blocks the rest.  ``conv_rank > 0``: every 3×3
        convolution in Tucker-2 form (:func:`factorise`).
        """

        def __init__(self):
            super().__init__()
            self.r_max, self.width, self.blocks = r_max, width, blocks
            self.conv_rank = conv_rank
            self.channels_last = False  # weights in channels-last order (:func:`_fast_layout`)
            cin, cout = 4 * r_max + 1, 4 * r_max
            self.linear = conv(cin, cout)
            nn.init.zeros_(last(self.linear).weight)
            nn.init.zeros_(last(self.linear).bias)
            self.head = conv(cin, width)
            self.body = nn.Sequential(*[_Block() for _ in range(blocks)])
            self.tail = conv(width, cout)
            nn.init.zeros_(last(self.tail).weight)  # the network starts as "no noise"
            nn.init.zeros_(last(self.tail).bias)
            self.down = nn.PixelUnshuffle(2)
            self.up = nn.PixelShuffle(2)

        def forward(self, y, sigma):
            h, w = y.shape[-2:]
            ph, pw = h % 2, w % 2
            if ph or pw:  # odd sizes: repeat one row / column, crop after
                y = torch.nn.functional.pad(y, (0, pw, 0, ph), mode="replicate")
            d = self.down(y)
            smap = sigma.reshape(-1, 1, 1, 1).to(d.dtype).expand(-1, 1, *d.shape[-2:])
            d = torch.cat([d, smap], dim=1)
            if self.channels_last:  # once here, not once for each of the two layers that read it
                d = d.contiguous(memory_format=torch.channels_last)
            lin = self.linear(d)
            noise = self.up(self.tail(self.body(self.head(d))).add_(lin))
            return noise[..., :h, :w]

    return SubspaceDenoiserNet()


def SubspaceDenoiserNet(r_max: int = 12, width: int = 64, blocks: int = 4, conv_rank: int = 0):  # noqa: N802
    """The network (a ``torch.nn.Module``) of the module docstring, untrained.

    ``conv_rank > 0``: each 3×3 convolution in the Tucker-2 form of :func:`factorise`.
    """
    torch = require_torch()
    given = {"r_max": r_max, "width": width, "blocks": blocks, "conv_rank": conv_rank}
    sizes = {
        name: integer(name, v, low=0 if name == "conv_rank" else 1, high=ARCH_LIMITS[name])
        for name, v in given.items()
    }  # the limits a weights file is held to (ARCH_LIMITS)
    return _build_net(torch, **sizes)


#: The largest network a weights file may describe (a hostile file could otherwise ask for
#: gigabytes): ``r_max``, ``width``, ``blocks``, ``conv_rank``.
ARCH_LIMITS = {"r_max": 64, "width": 1024, "blocks": 64, "conv_rank": 1024}


def architecture(config, path="the weights file") -> dict:
    """The network a weights file's ``config`` describes, checked: ``{"r_max", "width",
    "blocks", "conv_rank"}`` as integers in ``[1, limit]`` (``conv_rank`` from 0, its default;
    :data:`ARCH_LIMITS`; :func:`tensor_cosdi.validate.integer`).  Anything else is a one-line
    ``ValueError`` naming the file and the field."""
    if not isinstance(config, dict):
        raise ValueError(
            f"{path} is not a spectral-denoiser checkpoint of tensor-cosdi train-denoiser "
            f"(its config is a {type(config).__name__}, not a dict)"
        )
    out = {}
    for name, top in ARCH_LIMITS.items():
        low = 0 if name == "conv_rank" else 1  # conv_rank: 0 (full) where a file has none
        try:
            v = config.get(name, 0 if name == "conv_rank" else None)
            out[name] = integer(f"config {name}", v, low=low, high=top)
        except ValueError as exc:
            raise ValueError(
                f"{path} is not a spectral-denoiser checkpoint of tensor-cosdi train-denoiser "
                f"({exc})"
            ) from None
    return out


def factorise(net, conv_rank: int):
    """A copy of a trained full network with every 3×3 convolution in Tucker-2 form.

    Each kernel ``W (out, in, 3, 3)`` is decomposed along its two channel modes by
    :func:`tensorly.decomposition.partial_tucker`, ``W ≈ C ×₁ U_out ×₂ U_in`` with a core
    ``C (k_out, k_in, 3, 3)``, ``k_· = min(conv_rank, ·)``; the convolution becomes a 1×1
    projection onto ``U_in``, a 3×3 convolution with ``C`` and a 1×1 expansion by
    ``U_out`` (with the bias): ``k²·9 + k·(in + out)`` multiply-adds a pixel instead of
    ``in·out·9`` (at width 64 and ``k = 24``, 4.4× fewer).  A mode of fewer than ``k``
    channels keeps them all; with ``conv_rank`` at least the widest layer the factored
    network computes the same function.  The factored network is a
    start for fine-tuning (``tensor-cosdi train-denoiser --conv-rank K --init …``): the
    truncation alone moves its output.
    """
    import tensorly as tl
    from tensorly.decomposition import partial_tucker

    torch = require_torch()
    conv_rank = integer("conv_rank", conv_rank, low=1)
    if getattr(net, "conv_rank", 0):
        raise ValueError("the network is already factored (conv_rank > 0)")
    small = _build_net(torch, net.r_max, net.width, net.blocks, conv_rank)
    full = dict(net.named_modules())
    with torch.no_grad():
        for name, mod in small.named_modules():
            if not isinstance(mod, torch.nn.Sequential) or name == "body":
                continue
            src = full[name]
            w = src.weight.detach().cpu().double().numpy()
            k_out, k_in = mod[1].weight.shape[:2]
            if np.any(w):
                (core, (u_out, u_in)), _ = partial_tucker(
                    tl.tensor(w), rank=[k_out, k_in], modes=[0, 1], init="svd", n_iter_max=50,
                    tol=1e-7,
                )  # fmt: skip
                core, u_out, u_in = (np.asarray(tl.to_numpy(a)) for a in (core, u_out, u_in))
            else:  # a layer still at its zero start: a zero core, any orthonormal factors
                core = np.zeros((k_out, k_in, *w.shape[2:]))
                u_out, u_in = np.eye(w.shape[0], k_out), np.eye(w.shape[1], k_in)
            as_t = functools.partial(torch.as_tensor, dtype=mod[0].weight.dtype)
            mod[0].weight.copy_(as_t(u_in.T[:, :, None, None].copy()))
            mod[1].weight.copy_(as_t(core))
            mod[2].weight.copy_(as_t(u_out[:, :, None, None].copy()))
            mod[2].bias.copy_(src.bias.detach())
    return small


#: Pixels per block of ``_spectral_basis``'s Gram matrix.
GRAM_BLOCK = 4096


def subspace(x, r: int, r_max: int):
    """``(Y, U)`` for a torch batch ``x (batch, P, C)``: eigen-images ``Y (batch, r_max, P)``
    (zero rows beyond ``min(r, C)``) and orthonormal ``U (batch, C, min(r, C))``
    (``_spectral_basis``; each eigen-image sums to ≥ 0)."""
    torch = require_torch()
    k = min(int(r), x.shape[-1], int(r_max))
    u = _spectral_basis(x, k)
    out = torch.zeros(x.shape[0], int(r_max), x.shape[1], dtype=x.dtype, device=x.device)
    out[:, :k] = torch.matmul(u.transpose(1, 2), x.transpose(1, 2))
    return out, u


def _spectral_basis(x, k: int):
    """The ``k`` leading eigenvectors ``U (batch, C, k)`` of the spectral Gram matrix of a torch
    batch ``x (batch, P, C)`` (any strides), in ``x``'s dtype, each signed so that its
    eigen-image ``x U`` sums to ≥ 0.  No gradient flows through it.

    The Gram matrix is summed in float64 over blocks of :data:`GRAM_BLOCK` pixels, each block's
    product in the input's precision: 7× faster than a float64 product at 256×256×28 (1.8
    against 13.6 ms on 2 threads) and within 6e-8 of it (relative to its largest entry) on a
    real cube.
    """
    torch = require_torch()
    x = x.detach()
    c = x.shape[-1]
    gram = torch.zeros(x.shape[0], c, c, dtype=torch.float64, device=x.device)
    for a in range(0, x.shape[1], GRAM_BLOCK):
        block = x[:, a : a + GRAM_BLOCK]
        gram += torch.matmul(block.transpose(1, 2), block).double()
    u = torch.linalg.eigh(gram)[1].flip(-1)[..., : int(k)]
    # each eigen-image's sum is the eigenvector against the spectra's sum over the pixels
    total = torch.matmul(torch.ones(1, x.shape[1], dtype=x.dtype, device=x.device), x)
    sign = torch.where(torch.matmul(total.double(), u) < 0, -1.0, 1.0)  # (batch, 1, k)
    return (u * sign).to(x.dtype)


def _eigen_images(xt, r: int, r_max: int, inv_scale: float):
    """:func:`subspace` of one image's spectra ``xt (C, P)`` (any strides) times ``inv_scale``,
    without scaling the cube: ``(Y (r_max, P), U (C, min(r, C)))``, the eigen-images ``Uᵀ xt ·
    inv_scale`` written straight into their rows.  The eigenvectors of a scaled cube are its
    own, so the scale rides on the ``k × C`` factor instead of on two passes over the cube."""
    torch = require_torch()
    c, p = xt.shape
    k = min(int(r), c, int(r_max))
    u = _spectral_basis(xt.T[None], k)[0]
    out = torch.zeros(int(r_max), p, dtype=xt.dtype, device=xt.device)
    torch.matmul(u.T * inv_scale, xt, out=out[:k])
    return out, u


#: :func:`_robust_peak` reads every ``PEAK_STRIDE``-th pixel (all its channels) of an image of at
#: least 2¹⁵ pixels: 5.7 → 1.0 ms at 256×256×28 on 2 threads, the quantile
#: of a uniform cube moved by 4e-5 of its value.  The stride is odd and prime, so on an image of
#: even width the samples move by a column from row to row instead of repeating one column.
PEAK_STRIDE = 5


def _robust_peak(t, q: float = 0.999) -> float:
    """The ``q`` quantile of ``|t (rows, columns, channels)|`` (as
    :func:`tensor_cosdi.solvers.priors.robust_peak`, over a sample of the pixels on large
    images: :data:`PEAK_STRIDE`): the scale the network sees its input at.  Not the maximum,
    which one outlier of a plug-and-play iterate sets."""
    torch = require_torch()
    t = t.detach()
    rows, cols = t.shape[0], t.shape[1]
    if rows * cols >= 1 << 15:  # every PEAK_STRIDE-th pixel in row-major order, in any layout
        idx = torch.arange(0, rows * cols, PEAK_STRIDE, device=t.device)
        pixels = t[idx // cols, idx % cols]
    else:
        pixels = t.reshape(-1, t.shape[-1])
    flat = pixels.abs().reshape(-1)
    k = min(int(math.ceil(q * (flat.numel() - 1))), flat.numel() - 1)
    # the (k+1)-th smallest is the least of the n − k largest: top-k is 3× faster than kthvalue
    p = float(flat.topk(flat.numel() - k, sorted=False).values.min())
    return p if p > 0 else float(t.abs().max())


def _fast_layout(torch, net):
    """``net`` with its convolution weights channels-last on a CPU: oneDNN then runs the
    convolutions without reordering their activations (the network's time in both layouts:
    ``benchmarks/results/denoiser_speed.md``).  The same arithmetic up to the order of the
    sums."""
    if next(net.parameters()).device.type == "cpu":
        net.to(memory_format=torch.channels_last)
        net.channels_last = True
    return net


@functools.lru_cache(maxsize=1)
def bfloat16_is_fast() -> bool:
    """Whether this CPU runs bfloat16 convolutions natively (oneDNN with AVX512-BF16 or AMX).

    Without such instructions bfloat16 is emulated and slower than float32, so
    ``precision="auto"`` keeps float32 there.
    """
    torch = require_torch()
    try:
        native = torch.ops.mkldnn._is_mkldnn_bf16_supported()
        return bool(torch.backends.mkldnn.is_available() and native)
    except (AttributeError, RuntimeError):  # an older or a reduced build: no way to tell
        return False


def network_device(x=None, device=None):
    """The ``torch.device`` the denoiser runs on for the input ``x``.

    Parameters
    ----------
    x : tensor or ndarray, optional
        The input: a torch tensor keeps its own device.
    device : str or torch.device, optional
        Given by the caller (``SpectralDenoiser(device=…)``): taken as it is.

    Returns
    -------
    torch.device
        ``device`` where given, else a torch tensor's own device, else CUDA when available,
        else the CPU.

    Examples
    --------
    >>> import torch
    >>> network_device(torch.zeros(3)), network_device(device="cpu")
    (device(type='cpu'), device(type='cpu'))
    """
    torch = require_torch()
    if device is not None:
        return torch_device(torch, device)
    if isinstance(x, torch.Tensor):
        return x.device
    return torch_device(torch, None)


def network_precision(precision: str, device) -> str:
    """The arithmetic the network runs in on ``device`` for
    ``SpectralDenoiser(precision=precision)``.

    Parameters
    ----------
    precision : {"auto", "float32", "bfloat16"}
        :data:`PRECISIONS`; anything else is a ``ValueError``.
    device : str or torch.device
        Where the network runs (:func:`network_device`).

    Returns
    -------
    str
        ``"bfloat16"`` or ``"float32"``: ``precision`` where given; ``"auto"`` is bfloat16 on
        a CPU with native bfloat16 instructions (:func:`bfloat16_is_fast`), float32 elsewhere.

    Examples
    --------
    >>> network_precision("float32", "cpu"), network_precision("auto", "cuda")
    ('float32', 'float32')
    """
    if precision not in PRECISIONS:
        raise ValueError(f"precision must be one of {PRECISIONS}, got {precision!r}")
    if precision != "auto":
        return precision
    torch = require_torch()
    cpu = torch.device(device).type == "cpu"
    return "bfloat16" if cpu and bfloat16_is_fast() else "float32"


class SpectralDenoiser:
    """The learned denoiser as a plug-in ``denoise(x, sigma) -> x``.

    Parameters
    ----------
    weights : path, optional
        A checkpoint written by :func:`tensor_cosdi.learn.train.train_denoiser`
        (default: the shipped one).
    rank : int, optional
        Spectral subspace size (default and maximum: the network's ``r_max``).
    device : str, optional
        ``"cpu"``, ``"cuda"``…; default: the input's device for torch
        tensors, else CUDA when available, else CPU.
    joint : bool
        For cubes of more than three axes: fold the trailing axes into the
        channels (one subspace for all) instead of one slice at a time.  On
        CS2LI (real scenes, 96×96×16×4, 30 dB, PnP from OTD) folding the
        four patterns into 64 channels gave 32.82 dB, per slice 36.95 dB
        (OTD alone 35.92): the 12-dimensional subspace cannot hold four
        differently modulated copies of the spectra.
    precision : {"auto", "float32", "bfloat16"}
        The network's arithmetic (the subspace, scaling and output stay
        float32).  ``"auto"``: bfloat16 on a CPU with native bfloat16
        instructions (:func:`bfloat16_is_fast`), else float32; on CUDA float32.
        ``benchmarks/results/denoiser_speed.md`` (a 2-core AVX512-BF16
        machine, 256×256×28): one call 0.044 s in bfloat16 against 0.073 s
        in float32 on 2 threads, and a denoised real cube loses 0.015 to
        0.022 dB.
        The default is float32: the same results on every machine, and a
        reconstruction that does not move when the measurement is rescaled
        (bfloat16's rounding turns a 1e-16 change of the input into a 1e-3
        change of a plug-and-play result).
    """

    def __init__(
        self, weights=None, *, rank: int | None = None, device=None, joint=False,
        precision: str = "float32",
    ):  # fmt: skip
        torch = require_torch()
        path = Path(weights) if weights is not None else default_weights()
        ckpt = load_weights(path, "spectral-denoiser", "train-denoiser")
        cfg = architecture(ckpt["config"], path)
        self.net = _build_net(torch, **cfg)
        try:
            self.net.load_state_dict(ckpt["model"])
        except (KeyError, TypeError, RuntimeError) as exc:
            why = " ".join(str(exc).split())[:160]
            raise ValueError(
                f"{path} is not a spectral-denoiser checkpoint of tensor-cosdi train-denoiser "
                f"(its weights do not fit the network of {cfg}: {why})"
            ) from None
        self.net.eval()
        self.r_max = int(cfg["r_max"])
        if rank is None:
            rank = self.r_max
        if isinstance(rank, bool) or not isinstance(rank, (int, np.integer)) or rank < 1:
            raise ValueError(f"rank must be a positive integer, got {rank!r}")
        if rank > self.r_max:
            raise ValueError(f"rank {rank} exceeds the network's r_max {self.r_max}")
        self.rank = int(rank)
        if precision not in PRECISIONS:
            raise ValueError(f"precision must be one of {PRECISIONS}, got {precision!r}")
        if device is not None:
            torch_device(torch, device)  # refused now, not at the first call
        self.device = device
        self.path = path
        self.joint = flag("joint", joint)
        self.precision = precision
        self._half = None  # the bfloat16 copy of the network, made on first use
        self._ready: dict = {}  # the network last prepared by :meth:`_network`, with its key

    def _network(self, dev):
        """``(net, dtype)`` the eigen-images go through on ``dev``, prepared once a device and
        precision (moving and re-laying the weights is a walk over every module: 1.7 ms a
        call)."""
        torch = require_torch()
        precision = network_precision(self.precision, dev)
        key = (str(dev), precision)
        if self._ready.get("key") == key:
            return self._ready["net"], self._ready["dtype"]
        if precision == "float32":
            net, dtype = _fast_layout(torch, self.net.to(dev)), torch.float32
        else:
            if self._half is None:
                import copy

                self._half = copy.deepcopy(self.net).to(torch.bfloat16)
            net, dtype = _fast_layout(torch, self._half.to(dev)), torch.bfloat16
        self._ready = {"key": key, "net": net, "dtype": dtype}
        return net, dtype

    def _device(self, x):
        return network_device(x, self.device)

    def __call__(self, x, sigma):
        torch = require_torch()
        sigma = number("sigma", sigma, low=0)  # a noise level
        if not hasattr(x, "shape") or not hasattr(x, "dtype"):
            raise ValueError(f"expected a cube (an array or tensor), got {type(x).__name__}")
        kind = str(x.dtype).replace("torch.", "")
        if not kind.startswith(("float", "bfloat", "int", "uint")):
            raise ValueError(f"expected a cube of real numbers, got dtype {kind}")
        shape = tuple(x.shape)
        if len(shape) < 3 or 0 in shape:
            raise ValueError(f"expected a cube (rows, columns, channels…), got shape {shape}")
        if len(shape) > 3 and not self.joint:  # one (rows, columns, bands) slice at a time
            out = [self(x[(..., *idx)], sigma) for idx in np.ndindex(*shape[3:])]
            if isinstance(x, torch.Tensor):
                return torch.stack(out, dim=-1).reshape(shape)
            stacked = np.stack([np.asarray(B.to_numpy(o)) for o in out], axis=-1)
            return B.tensor_like(stacked.reshape(shape), x)
        dev = self._device(x)
        flips: tuple = ()  # image axes a NumPy view runs backwards along (a flipped view)
        if isinstance(x, torch.Tensor):
            t = x
        else:  # torch takes no negative strides (a flipped view, as the self-ensemble hands
            # over): the view read forwards, and the flip done on the eigen-images instead
            # (the spectral subspace does not depend on the pixels' order), no copy of the cube
            a = np.asarray(B.to_numpy(x))
            flips = tuple(ax for ax in (0, 1) if a.strides[ax] < 0)
            a = np.flip(a, flips) if flips else a
            t = torch.from_numpy(a if all(s >= 0 for s in a.strides) else a.copy(order="K"))
        work_dtype = torch.float32
        t = t.to(device=dev, dtype=work_dtype).reshape(shape[0], shape[1], -1)
        scale = _robust_peak(t)
        if not np.isfinite(scale):
            raise ValueError("the cube holds NaN or inf values: nothing to denoise")
        if scale <= 0:  # all zero: already clean
            return x
        net, net_dtype = self._network(dev)
        # A NumPy cube whose bands are contiguous planes, Fortran-ordered (the shear kernels'
        # fast layout, which the solvers keep) or band by band in C order (its transpose, as the
        # self-ensemble hands over), is read and returned in that layout: a C-ordered result
        # would slow every later step of the solver that mixes it with its other iterates
        # (PnP-ADMM at 256×256×28: 10.5 against 2.7 ms per normal solve) or cost a transposing
        # copy each way (6.7 ms).  The network sees the same images; the spectral Gram matrix
        # is summed over other blocks of pixels (float rounding).
        layout = "c"
        if not isinstance(x, torch.Tensor) and len(shape) == 3 and not t.is_contiguous():
            if t.permute(2, 1, 0).is_contiguous():
                layout = "f"  # pixels column by column
            elif t.permute(2, 0, 1).is_contiguous():
                layout = "bands"  # pixels row by row
        n_bands = t.shape[-1]
        if layout == "f":  # the spectra as (bands, pixels), no copy in any layout
            xt = t.permute(2, 1, 0).reshape(n_bands, -1)
        elif layout == "bands":
            xt = t.permute(2, 0, 1).reshape(n_bands, -1)
        else:
            xt = t.reshape(-1, n_bands).T
        image_dims = tuple(2 + ax for ax in flips)
        with torch.no_grad():
            try:
                y, u = _eigen_images(xt, self.rank, self.r_max, 1.0 / scale)
            except torch.linalg.LinAlgError:  # a Gram matrix of NaN or inf
                u = None
            if u is None or not bool(torch.isfinite(u).all()):  # (a bands × k check: free)
                raise ValueError("the cube holds NaN or inf values: nothing to denoise")
            if layout == "f":
                y = y.reshape(1, self.r_max, shape[1], shape[0]).transpose(2, 3)
            else:
                y = y.reshape(1, self.r_max, shape[0], shape[1])
            if flips:  # the images as the caller's view has them
                y = torch.flip(y, image_dims)
            s = torch.tensor([sigma / scale], dtype=net_dtype, device=dev)
            clean = y.sub_(net(y.to(net_dtype), s).to(work_dtype))
            k = u.shape[-1]
            clean = clean[0, :k]
            if flips:  # back to the order the spectra were read in
                clean = torch.flip(clean, tuple(d - 1 for d in image_dims))
            back = u * scale  # (bands, k): the subspace and the scale in one small factor
            if layout == "f":  # (bands, columns, rows) in C order is (rows, columns, bands) in F
                eig = clean.transpose(1, 2).reshape(k, -1)
                out = torch.matmul(back, eig).reshape(shape[::-1]).permute(2, 1, 0)
            elif layout == "bands":
                out = torch.matmul(back, clean.reshape(k, -1)).reshape(n_bands, *shape[:2])
                out = out.permute(1, 2, 0)
            else:
                out = torch.matmul(clean.reshape(k, -1).T, back.T).reshape(shape)
        if isinstance(x, torch.Tensor):
            return out.to(device=x.device, dtype=x.dtype)
        a = out.cpu().numpy().astype(np.asarray(x).dtype, copy=False)
        a = np.flip(a, flips) if flips else a  # the caller's view, read backwards again
        return a if isinstance(x, np.ndarray) else B.tensor_like(a, x)
