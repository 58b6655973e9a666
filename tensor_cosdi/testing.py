"""Testing helpers: the dot test and a registry of small operator instances.

The generic tests loop over :func:`registry` (every primitive and the
compositions the imagers are made of); later modules add their own instances
with :func:`register`.
"""

from __future__ import annotations

import inspect
from typing import Callable

import numpy as np
import tensorly as tl

from . import _backend as B
from .operators import (
    Blur,
    Code,
    LightFieldLayout,
    ModeProduct,
    Pad,
    Replicate,
    Shear,
    Stack,
    SumAxis,
    TensorOperator,
    Transpose,
    validate_shape,
    weighted_sum,
)

__all__ = [
    "dot_test",
    "register",
    "registry",
    "random_tensor",
    "hostile_files",
    "rgb_values",
    "edit_bundle_document",
    "hostile_arguments",
]


def random_tensor(shape, *, rng=None, dtype="float64"):
    """Seeded standard-normal tensor of ``shape`` on the active backend."""
    shape = validate_shape(shape)
    rng = B.default_rng(rng)
    return B.as_tensor(rng.standard_normal(shape), dtype)


def dot_test(op: TensorOperator, *, rng=0, dtype: str = "float64") -> float:
    """Relative error of ``⟨A x, y⟩ = ⟨x, Aᵀ y⟩`` on seeded random ``x``, ``y``.

    Returns ``|⟨Ax, y⟩ − ⟨x, Aᵀy⟩| / (‖Ax‖ ‖y‖)``: the mismatch relative to the
    largest value the inner product can take (Cauchy–Schwarz), which does not
    blow up when the inner product happens to be near zero.

    Examples
    --------
    >>> from tensor_cosdi.operators import Shear
    >>> dot_test(Shear((4, 5, 3), 2)) < 1e-12
    True
    """
    if not isinstance(op, TensorOperator):
        raise ValueError(f"dot_test needs a TensorOperator, got {type(op).__name__}")
    rng = B.default_rng(rng)
    x = random_tensor(op.input_shape, rng=rng, dtype=dtype)
    y = random_tensor(op.output_shape, rng=rng, dtype=dtype)
    ax = op.forward(x)
    aty = op.adjoint(y)
    lhs = float(tl.sum(ax * y))
    rhs = float(tl.sum(x * aty))
    scale = float(tl.norm(ax)) * float(tl.norm(y))
    if scale == 0.0:
        return abs(lhs - rhs)
    return abs(lhs - rhs) / scale


_REGISTRY: dict[str, Callable[[np.random.Generator], TensorOperator]] = {}


def register(name: str, factory: Callable[[np.random.Generator], TensorOperator]) -> None:
    """Add a small operator instance (``factory(rng) -> TensorOperator``) to the registry."""
    if name in _REGISTRY:
        raise ValueError(f"an operator named {name!r} is already registered")
    _REGISTRY[name] = factory


def registry() -> dict[str, Callable[[np.random.Generator], TensorOperator]]:
    """Name → factory of every registered small operator instance."""
    return dict(_REGISTRY)


def _binary(rng, shape, transmittance=0.5):
    return (rng.random(shape) < transmittance).astype(float)


def _sd_cassi(rng, shape=(6, 7, 4), shifts=1):
    code = Code(_binary(rng, shape[:2]), shape)
    shear = Shear(shape, shifts)
    return SumAxis(shear.output_shape, 2) @ shear @ code


def _builtin():
    r = register
    r("code", lambda g: Code(g.random((5, 6)), (5, 6, 3)))
    r("code_axes", lambda g: Code(g.random((3, 4)), (4, 5, 3), axes=(2, 0)))
    r("code_full", lambda g: Code(g.standard_normal((3, 4, 2)), (3, 4, 2)))
    r("shear_step1", lambda g: Shear((4, 5, 3), 1))
    r("shear_step2", lambda g: Shear((4, 5, 3), 2))
    r("shear_per_band", lambda g: Shear((3, 4, 4), [0, 1, 1, 4]))
    r("shear_fractional", lambda g: Shear((3, 5, 4), [0.0, 0.6, 1.5, 2.25]))
    r("shear_axes", lambda g: Shear((4, 3, 5, 2), 1, axis=2, band_axis=1))
    r("sum_axis", lambda g: SumAxis((3, 4, 5), 2))
    r("sum_axis0", lambda g: SumAxis((3, 4, 5), 0))
    r("replicate", lambda g: Replicate((3, 4), 2, 3))
    r("mode_product_one", lambda g: ModeProduct((4, 5, 6), {2: g.standard_normal((3, 6))}))
    r(
        "mode_product_all",
        lambda g: ModeProduct(
            (3, 4, 5),
            [g.standard_normal((2, 3)), g.standard_normal((4, 4)), g.standard_normal((6, 5))],
        ),
    )
    r("blur", lambda g: Blur((6, 7, 2), g.random((3, 3, 2))))
    r("blur_even", lambda g: Blur((5, 6, 2, 3), g.random((4, 2, 2, 3))))
    r("transpose", lambda g: Transpose((2, 3, 4), (2, 0, 1)))
    r("pad", lambda g: Pad((3, 4), axis=1, before=2, after=1))
    r("lightfield_interleaved", lambda g: LightFieldLayout((3, 2, 2, 2, 3), "interleaved"))
    r("lightfield_tiled", lambda g: LightFieldLayout((3, 2, 2, 2, 3), "tiled"))
    r(
        "lightfield_tiled_to_interleaved",
        lambda g: (
            LightFieldLayout((2, 3, 2, 3, 2), "tiled")
            @ LightFieldLayout((2, 3, 2, 3, 2), "interleaved").T
        ),
    )
    r("sd_cassi", lambda g: _sd_cassi(g))
    r("sd_cassi_step2", lambda g: _sd_cassi(g, (5, 6, 4), 2))
    r("sd_cassi_fractional", lambda g: _sd_cassi(g, (5, 6, 4), [0.0, 0.5, 1.25, 3.0]))
    r("sd_cassi_adjoint", lambda g: _sd_cassi(g).T)
    r("multishot_cassi", lambda g: Stack([_sd_cassi(np.random.default_rng(k)) for k in range(3)]))

    def dd_cassi(g, shape=(5, 6, 4)):
        wide = _binary(g, (shape[0], shape[1] + shape[2] - 1))
        sheared = np.stack([wide[:, l : l + shape[1]] for l in range(shape[2])], axis=2)
        return SumAxis(shape, 2) @ Code(sheared, shape)

    r("dd_cassi", dd_cassi)

    def vsi(g, shape=(4, 6, 3), beta=1):
        code = Code(_binary(g, shape[:2]), shape)
        shear = Shear(shape, 1)
        dispersed = SumAxis(shear.output_shape, 2) @ shear @ code
        width = shape[2] - 1
        direct = Pad(shape[:2], axis=1, before=beta, after=width - beta) @ SumAxis(shape, 2) @ code
        return weighted_sum([dispersed, direct], [0.7, 0.3])

    r("vsi", vsi)

    def dfa(g, shape=(4, 5, 3, 2)):
        code = Code(_binary(g, (shape[0], shape[1], shape[3])), shape, axes=(0, 1, 3))
        shear = Shear(shape, 1)
        s1 = SumAxis(shear.output_shape, 2)
        return SumAxis(s1.output_shape, 2) @ s1 @ shear @ code

    r("dfa", dfa)

    def dfa_psf(g, shape=(5, 5, 2, 2)):
        blur = Blur(shape, g.random((3, 3, 2, 2)))
        return dfa(g, shape) @ blur

    r("dfa_psf", dfa_psf)

    def cs2li(g, shape=(4, 5, 3, 2)):
        wide = _binary(g, (shape[0], shape[1] + shape[2] - 1))
        ceff = np.stack([wide[:, l : l + shape[1]] for l in range(shape[2])], axis=2)
        return SumAxis(shape, 2) @ Code(ceff, shape, axes=(0, 1, 2))

    r("cs2li", cs2li)

    def c3slfi(g, shape=(3, 2, 4, 2, 2), K=2):
        raw = g.random(shape + (K,))
        codes = raw / raw.sum(-1, keepdims=True)  # complementary: Σ_k T = 1
        ops = [SumAxis(shape, 2) @ Code(codes[..., k], shape) for k in range(K)]
        return Stack(ops, axis=2)

    r("c3slfi", c3slfi)
    r(
        "c3slfi_3d",
        lambda g: (
            Stack([SumAxis((4, 6, 3), 2) @ Code(g.random((4, 6, 3)), (4, 6, 3)) for _ in range(3)])
            @ LightFieldLayout((2, 3, 3, 2, 2), "interleaved")
        ),
    )
    r("scaled_difference", lambda g: 2.0 * _sd_cassi(g) - 0.5 * _sd_cassi(g))
    _systems()


def _systems():
    """The operators of small seeded instances of every imager in :mod:`tensor_cosdi.systems`."""
    from . import systems as S

    r = register
    r("system_sdcassi", lambda g: S.SDCASSI.example((5, 6, 4), rng=g).operator)
    r(
        "system_sdcassi_shots",
        lambda g: S.SDCASSI.example((4, 5, 3), rng=g, shots=3, shifts=2).operator,
    )
    r(
        "system_ddcassi",
        lambda g: S.DDCASSI.example((5, 6, 4), rng=g, shifts=[0, 0.5, 1, 2.5]).operator,
    )
    r("system_dual_camera", lambda g: S.DualCameraCASSI.example((4, 5, 3), rng=g).operator)
    r(
        "system_lytro_cassi",
        lambda g: S.LytroCASSI.example((4, 6, 3), rng=g, shifts=[0, 0.5, 2]).operator,
    )
    r("system_cassi_vsi", lambda g: S.CASSIVSI.example((4, 6, 4), rng=g, beta=2).operator)
    r("system_cassdi_dfa", lambda g: S.CASSDIDFA.example((4, 5, 3, 2), rng=g).operator)
    r(
        "system_cassdi_dfa_psf",
        lambda g: S.CASSDIDFA.example((5, 5, 2, 2), rng=g, psf_size=3).operator,
    )
    r(
        "system_c3slfi_3d",
        lambda g: S.C3SLFI.example((4, 6, 5), rng=g, n_snapshots=3, views=(2, 3)).operator,
    )
    r("system_c3slfi_5d", lambda g: S.C3SLFI.example((2, 3, 4, 2, 2), rng=g).operator)
    r(
        "system_c3slfi_separable",
        lambda g: S.C3SLFI.separable(g.random((3, 5)), (4, 4, 5), complementary=False).operator,
    )
    r("system_cs2li", lambda g: S.CS2LI.example((4, 5, 4, 3), rng=g, n_filters=2).operator)
    r("system_mu_cosdi_sl", lambda g: S.MuCoSDI.example((4, 5, 3, 2), rng=g).operator)
    r("system_mu_cosdi_lf", lambda g: S.MuCoSDI.example((4, 6, 3), rng=g, modality="lf").operator)


_builtin()


def hostile_files(folder) -> dict:
    """Write the files a reader must refuse (or read exactly) into ``folder``; ``name → path``.

    ``hdf5_external`` (a dataset whose data is another file), ``hdf5_virtual``
    and ``hdf5_virtual_missing`` (virtual datasets, the second's source gone),
    ``hdf5_link`` (an external link named ``cube``), ``hdf5_soft`` (a soft link named ``cube``
    to a dataset of the file), ``hdf5_text`` and ``mat_text`` (text named ``cube``),
    ``hdf5_chunks`` (2×2×2
    data in 128³-element gzip chunks), ``npz_bomb`` (4 MiB of zeros in a few
    KiB), ``mat_bomb`` (2 MiB compressed), ``mat_padded`` (an 8 MiB padded
    compressed element), ``mat_sparse``, ``npz_complex``, ``mat_complex`` (MATLAB v5
    lists it as ``double``), ``npz_wavelengths``
    (3 wavelengths for 4 bands), ``tiff_mixed`` (pages of two shapes),
    ``tiff_rgb`` (a 12×16 RGB image, values ``rgb_values(0)``), and on POSIX
    ``fifo`` (a FIFO named ``.npy``) and ``dev_zero`` (a link to ``/dev/zero``
    named ``.npy``), JSON nested 200,000 deep as an acquisition plan (``plan_deep``), a
    frame log (``log_deep``), a bundle's document (``bundle_deep_npz``, ``bundle_deep_h5``)
    and a TIFF description (``tiff_deep``), ENVI headers of complex data (``envi_complex``),
    an unknown interleave (``envi_interleave``) and a data file that is a link to another
    (``envi_link``), and the Zarr stores of :func:`_hostile_zarr`
    where zarr is installed.
    Shared by the tests and ``benchmarks/robustness.py``.
    """
    import os
    import struct
    import zlib
    from pathlib import Path

    import h5py
    import scipy.io
    import scipy.sparse
    import tifffile

    folder = Path(folder)
    out = {name: folder / f"{name}{ext}" for name, ext in (
        ("hdf5_external", ".h5"), ("hdf5_virtual", ".h5"), ("hdf5_virtual_missing", ".h5"),
        ("hdf5_link", ".h5"), ("hdf5_chunks", ".h5"), ("npz_bomb", ".npz"),
        ("mat_bomb", ".mat"), ("mat_padded", ".mat"), ("mat_sparse", ".mat"),
        ("npz_complex", ".npz"), ("mat_complex", ".mat"), ("npz_wavelengths", ".npz"),
        ("tiff_mixed", ".tif"), ("tiff_rgb", ".tif"), ("hdf5_soft", ".h5"),
        ("hdf5_text", ".h5"), ("mat_text", ".mat"),
    )}  # fmt: skip
    secret = folder / "secret.bin"
    np.full(64, 7.0).tofile(secret)
    with h5py.File(out["hdf5_external"], "w") as f:
        f.create_dataset("cube", shape=(4, 4, 4), dtype="f8", external=[(str(secret), 0, 512)])
    source = folder / "virtual_source.h5"
    with h5py.File(source, "w") as f:
        f["data"] = np.ones((4, 4, 4))
    for name, src in (("hdf5_virtual", source), ("hdf5_virtual_missing", folder / "gone.h5")):
        layout = h5py.VirtualLayout(shape=(4, 4, 4), dtype="f8")
        layout[:] = h5py.VirtualSource(str(src), "data", shape=(4, 4, 4))
        with h5py.File(out[name], "w") as f:
            f.create_virtual_dataset("cube", layout, fillvalue=0)
    with h5py.File(out["hdf5_link"], "w") as f:
        f["cube"] = h5py.ExternalLink(str(source), "/data")
    with h5py.File(out["hdf5_soft"], "w") as f:  # a soft link named cube, to a cube in the file
        f["data"] = np.ones((4, 4, 4))
        f["cube"] = h5py.SoftLink("/data")
    with h5py.File(out["hdf5_text"], "w") as f:
        f["cube"] = np.array([b"not", b"numbers"])
    scipy.io.savemat(out["mat_text"], {"cube": "not numbers"})
    with h5py.File(out["hdf5_chunks"], "w") as f:
        ds = f.create_dataset("cube", shape=(2, 2, 2), maxshape=(None,) * 3, chunks=(128,) * 3,
                              dtype="f8", compression="gzip")  # fmt: skip
        ds[...] = 1.0
    np.savez_compressed(out["npz_bomb"], cube=np.zeros((256, 256, 8)))
    scipy.io.savemat(out["mat_bomb"], {"cube": np.zeros((128, 128, 16))}, do_compression=True)
    head = b"MATLAB 5.0 MAT-file".ljust(116, b" ") + b"\0" * 8 + struct.pack("<H", 0x0100) + b"IM"
    data = zlib.compress(b"\0" * (8 << 20), 9)
    out["mat_padded"].write_bytes(head + struct.pack("<II", 15, len(data)) + data)
    scipy.io.savemat(out["mat_sparse"], {"mask": scipy.sparse.eye(4, format="csc")})
    np.savez(out["npz_complex"], cube=np.ones((4, 4, 3), complex))
    scipy.io.savemat(out["mat_complex"], {"cube": np.ones((4, 4, 3)) + 1j})  # listed as double
    np.savez(out["npz_wavelengths"], cube=np.ones((4, 4, 4)), wavelengths=[450.0, 500.0, 550.0])
    with tifffile.TiffWriter(out["tiff_mixed"]) as w:
        for shape in ((8, 8), (8, 8), (4, 4), (8, 8)):
            w.write(np.ones(shape, np.float32), metadata=None)
    tifffile.imwrite(out["tiff_rgb"], rgb_values(0), photometric="rgb")
    if hasattr(os, "mkfifo"):
        out["fifo"] = folder / "fifo.npy"
        os.mkfifo(out["fifo"])
    if os.path.exists("/dev/zero"):
        out["dev_zero"] = folder / "zero.npy"
        os.symlink("/dev/zero", out["dev_zero"])
    deep = "[" * 200_000 + "]" * 200_000  # JSON past any parser's stack
    out["plan_deep"] = folder / "plan_deep.json"
    out["plan_deep"].write_text(deep)
    out["log_deep"] = folder / "log_deep.jsonl"
    out["log_deep"].write_text(deep + "\n")
    out["bundle_deep_npz"] = folder / "bundle_deep.npz"
    np.savez(out["bundle_deep_npz"], __bundle__=np.array(deep))
    out["bundle_deep_h5"] = folder / "bundle_deep.h5"
    with h5py.File(out["bundle_deep_h5"], "w") as f:
        f.attrs["tensor_cosdi_bundle"] = deep
    out["tiff_deep"] = folder / "tiff_deep.tif"
    tifffile.imwrite(out["tiff_deep"], np.ones((3, 4, 4), np.float32), description=deep,
                     photometric="minisblack", metadata=None)  # fmt: skip
    envi = "ENVI\nsamples = 4\nlines = 4\nbands = 2\nheader offset = 0\ndata type = {dt}\n" \
        "interleave = {il}\nbyte order = 0\n"  # fmt: skip
    for name, dt, il in (("envi_complex", 6, "bsq"), ("envi_interleave", 4, "xyz"),
                         ("envi_link", 4, "bsq")):  # fmt: skip
        out[name] = folder / f"{name}.hdr"
        out[name].write_text(envi.format(dt=dt, il=il))
        if name == "envi_link":  # the data "file" is a link to another file
            os.symlink(secret, folder / f"{name}.img")
        else:
            (folder / f"{name}.img").write_bytes(bytes(256))
    out.update(_hostile_zarr(folder, secret))
    return out


def _hostile_zarr(folder, secret) -> dict:
    """Zarr stores a reader must refuse (only where ``zarr`` is installed): ``zarr_link`` (a
    chunk that is a link to another file), ``zarr_fifo`` (a FIFO as a chunk, POSIX),
    ``zarr_pickle`` (a pickle filter), ``zarr_object`` (object values), ``zarr_bomb`` (2 MiB
    of zeros in a chunk declared 32 bytes), ``zarr_big_chunk`` (chunks of 8 GB declared)."""
    import importlib.util
    import json
    import os
    import zlib

    if importlib.util.find_spec("zarr") is None:
        return {}

    def v2(name, chunk=b"", dtype="<f8", filters=None, compressor=None, chunks=(4,)):
        store = folder / f"{name}.zarr"
        store.mkdir()
        meta = {
            "zarr_format": 2,
            "shape": [4],
            "chunks": list(chunks),
            "dtype": dtype,
            "compressor": compressor,
            "fill_value": 0,
            "order": "C",
            "filters": filters,
        }
        (store / ".zarray").write_text(json.dumps(meta))
        (store / "0").write_bytes(chunk)
        return store

    out = {
        "zarr_pickle": v2("zarr_pickle", b"\x80\x04K\x01.", filters=[{"id": "pickle"}]),
        "zarr_object": v2("zarr_object", dtype="|O", filters=[{"id": "vlen-utf8"}]),
        "zarr_bomb": v2("zarr_bomb", zlib.compress(b"\0" * (2 << 20), 9),
                        compressor={"id": "zlib", "level": 9}),
        "zarr_big_chunk": v2("zarr_big_chunk", zlib.compress(b"\0" * 32),
                             compressor={"id": "zlib", "level": 1}, chunks=(10**9,)),
        "zarr_link": v2("zarr_link"),
    }  # fmt: skip
    (out["zarr_link"] / "0").unlink()
    os.symlink(secret, out["zarr_link"] / "0")
    if hasattr(os, "mkfifo"):
        out["zarr_fifo"] = v2("zarr_fifo")
        (out["zarr_fifo"] / "0").unlink()
        os.mkfifo(out["zarr_fifo"] / "0")
    return out


def rgb_values(seed: int = 0) -> np.ndarray:
    """The 12×16×3 ``uint8`` image :func:`hostile_files` writes as ``tiff_rgb``."""
    return np.random.default_rng(seed).integers(0, 255, (12, 16, 3), dtype=np.uint8)


def edit_bundle_document(path, edit) -> None:
    """Change a saved bundle's JSON document in place, as a hand edit would: ``edit(doc)``
    mutates the parsed document of the ``.npz`` or HDF5 bundle at ``path`` (its checksums are
    left as they were, so :func:`tensor_cosdi.io.load_bundle` must notice)."""
    import json
    from pathlib import Path

    import h5py

    path = Path(path)
    if path.suffix.lower() == ".npz":
        with np.load(path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
        doc = json.loads(str(data["__bundle__"]))
        edit(doc)
        data["__bundle__"] = np.array(json.dumps(doc))
        path.unlink()
        np.savez(path, **data)
    else:
        with h5py.File(path, "r+") as f:
            doc = json.loads(f.attrs["tensor_cosdi_bundle"])
            edit(doc)
            f.attrs["tensor_cosdi_bundle"] = json.dumps(doc)


def hostile_arguments() -> list[tuple[str, str, Callable[[], object], tuple[str, ...]]]:
    """Bad arguments, one at a time, for the public functions beyond ``reconstruct``:
    ``(module, label, call, words)``.

    Each ``call`` passes one wrong value (NaN, ±inf, a boolean or a string where a number
    goes, a number too large to compute with, an axis that does not exist, an object that is
    not what the argument names) and every other argument valid; it must raise a
    ``ValueError`` or ``TypeError`` whose message holds one of ``words`` (lower case), the
    argument's name as a rule.  Shared by the tests and ``benchmarks/robustness.py``.
    """
    from . import bases, codes, colour, depth, metrics, noise, optics, scenes
    from .io import calibration, layouts, lenslet
    from .operators import Diagonal, Scaled, conjugate_gradient, unshear_bands
    from .solvers import denoisers, priors
    from .solvers.snr import estimate_snr
    from .systems import SDCASSI, fringe_cube

    rng = np.random.default_rng(0)
    cube = rng.random((16, 16, 8))
    wl = np.linspace(450.0, 650.0, 8)
    img = rng.random((16, 16))
    phase = img * 6.0
    frames = rng.random((16, 16, 4))
    views = rng.random((3, 3, 16, 16))
    nan_cube, inf_img = cube.copy(), img.copy()
    nan_cube[0, 0, 0], inf_img[0, 0] = np.nan, np.inf
    lenslets = 1.0 + np.cos(np.arange(64)[:, None] * 0.8) * np.cos(np.arange(64)[None, :] * 0.8)
    sd = SDCASSI(codes.random_binary((16, 16), rng=0), n_bands=8)
    nan, inf = float("nan"), float("inf")
    number_slips = [nan, inf, True, "3", 1 + 1j]  # never a number, wherever a number goes
    table = [
        # module, function, positional args, keyword args, {argument (name or position): bad values}
        ("codes", codes.random_binary, ((16, 16),), {}, {"transmittance": number_slips + [0, 1.5],
         "rng": [True, -1, 2.5, "7"]}),
        ("codes", codes.depth_codes, ((16, 16), 3), {}, {"transmittance": [True, "0.5"]}),
        ("codes", codes.colour_coded_aperture, ((16, 16), 8), {}, {"transmittance": [True]}),
        ("codes", codes.complementary_colour_codes, ((16, 16, 8), 2), {},
         {"band_axis": [True, 3, -4, 1.0]}),
        ("codes", codes.is_complementary, (np.full((4, 4, 2), 0.5),), {},
         {"atol": number_slips + [-1.0], "axis": [True, 5]}),
        ("colour", colour.to_srgb, (cube, wl), {}, {"white_balance": [2, "yes", None, nan],
         "illuminant": [3, None, "D66"]}),
        ("colour", colour.rgb_to_cube, (rng.random((4, 4, 3)), wl), {},
         {"encoded": [2, "yes", None]}),
        ("colour", colour.reflectance, (cube, np.full(8, 2.0)), {}, {"dark": [True, nan]}),
        ("colour", colour.reflectance, (nan_cube, np.full(8, 2.0)), {}, {}),
        ("metrics", metrics.psnr, (cube, cube * 0.9), {},
         {"data_range": number_slips + [1e308, 0, -1.0]}),
        ("metrics", metrics.ssim, (cube, cube * 0.9), {"data_range": 1.0},
         {"data_range": [True, inf, 1e308], "win_size": [inf, 2.5, True, 1]}),
        ("noise", noise.add_noise, (img, 30.0), {"rng": 0}, {1: [-1e308, True, "30"],
         "rng": [True, 2.5, "7", -1]}),
        ("noise", noise.snr_db_from_sigma, (1.0, 0.1), {}, {0: [0.0, True], 1: [inf, "0.1"]}),
        ("noise", noise.snr_schedule, (25.0, {30.0: 0.1, 20.0: 0.3}), {},
         {0: [True, "25", None], 1: [{30.0: nan}, {}, {30.0: -1.0}, [0.1]]}),
        ("noise", noise.auto_weight, (img,), {"at_30db": 0.1, "at_20db": 0.3},
         {"at_30db": [nan, inf, 0.0, True], "at_20db": [0.0, 1e308], "floor": [nan, -1.0]}),
        ("scenes", scenes.depth_planes, (img, 3), {}, {1: [1e308, 2.5, True, 0],
         "near_is_large": [2, "yes", None]}),
        ("scenes", scenes.light_field, (cube, 0.5), {"views": (3, 3)},
         {1: [True, np.ones((3, 3))]}),
        ("scenes", scenes.light_field, (nan_cube, 0.5), {"views": (3, 3)}, {}),
        ("scenes", scenes.structured_light, ((16, 16), wl), {}, {"n_bumps": [10**6, 2.5, True],
         "phase_per_height": [True, "2", nan], "frequencies": [("4",), (nan,)]}),
        ("depth", depth.wrapped_phase, (frames,), {}, {"axis": [True, 3, -4, 1.5]}),
        ("depth", depth.fringe_modulation, (frames,), {}, {"axis": [5]}),
        ("depth", depth.decode_gray_code, (frames,), {}, {"axis": [7], "threshold": [True]}),
        ("depth", depth.temporal_unwrap, (phase, phase / 4, 4.0), {},
         {0: [inf_img], 2: [True, "4", nan, 0.0]}),
        ("depth", depth.phase_to_height, (phase, phase * 0), {"phase_per_height": 2.0},
         {0: [inf_img], "phase_per_height": [True, 1 + 1j, "2", 0.0]}),
        ("depth", depth.wrap, (phase,), {}, {0: [inf_img]}),
        ("depth", depth.depth_from_focus, (frames,), {}, {"axis": [9, True],
         "sigma": [1e308, 1e6]}),
        ("depth", depth.focus_measure, (img,), {}, {"sigma": [1e308]}),
        ("depth", depth.textured_mask, (img,), {}, {"sigma": [1e6]}),
        ("depth", depth.disparity_from_views, (views,), {"step": 0.5},
         {"max_disparity": [1e308, 1e6]}),
        ("depth", depth.guided_filter, (img, img), {}, {"eps": [True, "1e-4"]}),
        ("depth", depth.depth_from_disparity, (img + 1,), {"baseline_mm": 10.0, "focal_px": 100.0},
         {0: [inf_img], "baseline_mm": [True], "focal_px": ["3"], "offset": [1 + 1j, True, nan]}),
        ("optics", optics.psf, (550.0, 1200.0), {}, {0: [True, "550", 0.55, nan],
         1: [True, 2.5], "supersample": [10**6], "pupil_samples": [10**6, 1]}),
        ("optics", optics.Lens, (), {}, {"focal_mm": ["50", True], "pixel_um": [True, "6"],
         "aperture_radius_mm": ["2.5"]}),
        ("optics", optics.zernike_radial, (2, 0, np.linspace(0, 1, 5)), {},
         {0: [10**6], 2: [np.array([0.0, nan])]}),
        ("optics", optics.gray_code_bits, (4.0,), {}, {0: [1e308, True]}),
        ("optics", optics.phase_shift_patterns, (phase,), {}, {"n_steps": [10**6],
         "offset": [True], "amplitude": ["0.5"]}),
        ("optics", optics.projector_phase, ((16, 16), (4.0,)), {},
         {0: [(16.5, 16), ("16", 16)], "axis": [True]}),
        ("optics", optics.DoubleAmiciPrism, (), {}, {"phi1": [True]}),
        ("optics", optics.DoubleAmiciPrism().mean_deviation, (570.0,), {},
         {"field_deg": [True, "2", nan]}),
        ("optics", optics.psf_width, (np.ones((5, 5)),), {}, {0: [np.full((5, 5), inf)]}),
        ("bases", bases.dct, (8,), {}, {0: [10**6]}),
        ("bases", bases.wavelet_level, (16, "sym8"), {}, {1: ["nonexistent", 3]}),
        ("bases", bases.unfolding_gram, (cube, 1), {}, {1: [5, True], 0: ["abc", nan_cube]}),
        ("bases", bases.is_orthonormal, (np.eye(4),), {}, {"atol": [nan, -1.0, True]}),
        ("bases", bases.block_sizes, (28, 8), {}, {0: [2.5, "3", True, inf], 1: [1e308]}),
        ("bases", bases.block_hosvd, (cube, 2, [4, 4]), {},
         {2: [[4 + 1j, 4], ["4", "4"], [4.5, 3.5]]}),
        ("io.lenslet", lenslet.calibrate_lenslet_grid, (lenslets,), {"pitch_range": (4.0, 16.0)},
         {0: [-lenslets], "pitch_range": [(), (0, 0), (nan,), (16.0, 4.0)],
          "min_peak": [-1.0, True]}),
        ("io.calibration", calibration.shift_code, (img > 0.5, 0.5, 0.5), {},
         {0: [None, "abc", inf_img], 1: [nan, True], 2: [inf]}),
        ("io.calibration", calibration.mirror_symmetric, ([0.0, 1.0, 2.0],), {}, {"tol": [inf]}),
        ("operators", Scaled, (2.0, None), {}, {}),
        ("operators", conjugate_gradient, (lambda v: 2 * v, np.ones(5)), {},
         {1: [None, np.array("abc"), np.full(5, nan)], "rtol": [nan, 1e308, -1.0, True],
          "maxiter": [0, True, 2.5], "warn": ["yes"]}),
        ("operators", Diagonal, (np.full(4, nan),), {}, {}),
        ("operators", unshear_bands, (rng.random((16, 23, 8)), 16), {},
         {0: [None], 1: [1e308], "axis": [10**6]}),
        ("systems", fringe_cube, (cube, img), {}, {0: [nan_cube], "n_steps": [10**6],
         "offset": [True]}),
        ("io.frames", layouts.measurement_to_frames, (sd, np.ones(sd.measurement_shape)), {},
         {0: [None, "sd_cassi"]}),
        ("denoisers", denoisers.tv, (cube, 0.1), {"n_iter": 5},
         {0: [nan_cube, np.float64(1.0), None, cube.astype(complex)]}),
        ("denoisers", denoisers.wavelet, (cube, 0.1), {}, {0: [nan_cube, np.ones(8)],
         1: [1e308], "wavelet_name": [3], "mode": ["medium"]}),
        ("denoisers", denoisers.WarmTV(5), (nan_cube, 0.1), {}, {}),
        ("solvers", priors.SparseInBasis, ({0: np.eye(16)},), {"lam": 0.1, "mu": 1.0},
         {0: [np.eye(16)], "lam": number_slips + [-1.0], "mu": [0.0, True], "beta": [nan]}),
        ("solvers", priors.TV, (0.1,), {}, {0: number_slips + [0.0, -1.0]}),
        ("solvers", priors.Denoiser, ("tv",), {"sigma": 0.1}, {"sigma": number_slips + [0.0],
         "sigma_end": [nan], "n_steps": [0, 2.5, inf, True], "nonneg": [2, "yes", None]}),
        ("solvers", priors.Ridge, (1.0,), {}, {0: [nan, True, -1.0]}),
        ("solvers", priors.NonNegative, (priors.Ridge(1.0),), {}, {0: [None, "tv"]}),
        ("solvers", estimate_snr, (sd, np.ones(sd.measurement_shape)), {},
         {0: [None, "sd_cassi"]}),
    ]  # fmt: skip
    table += (
        _system_arguments()
        + _study_arguments()
        + _plot_arguments()
        + _lab_arguments()
        + _writer_arguments()
        + _reader_arguments()
        + _learned_arguments()
    )
    out = []
    for module, fn, args, kwargs, bad in table:
        name = getattr(fn, "__name__", type(fn).__name__)
        params = list(inspect.signature(fn).parameters)
        if not bad:  # the arguments as given are the bad input
            words = ("nan", "finite", "tensoroperator", "diagonal")
            out.append((module, f"{name}{_short(args)}", lambda f=fn, a=args, k=kwargs: f(*a, **k),
                        words))  # fmt: skip
            continue
        for key, values in bad.items():
            arg = params[key] if isinstance(key, int) else key
            # what the message must name: the argument ("anchors": "an anchor's …"), or what it
            # is where its name says little
            words = _ARGUMENT_WORDS.get(arg, (arg.lower(), arg.lower().removesuffix("s")))
            for value in values:
                a, k = list(args), dict(kwargs)
                if isinstance(key, int):
                    a[key] = value
                else:
                    k[key] = value
                label = f"{name} {arg}={_short(value)}"
                out.append((module, label, lambda f=fn, a=tuple(a), k=k: f(*a, **k), words))
    return out


def _system_arguments():
    """Imager constructors given a flag that is not one or PSFs that are not real."""
    from .codes import complementary_colour_codes
    from .systems import C3SLFI, CASSDIDFA

    codes = (np.random.default_rng(2).random((8, 8, 3)) > 0.5).astype(float)
    psfs = np.full((3, 3, 4, 3), 1 / 9)
    return [
        ("systems", C3SLFI, (complementary_colour_codes((8, 8, 4), 2, rng=0),), {},
         {"complementary": [2, "yes", None]}),
        ("systems", CASSDIDFA, (codes,), {"n_bands": 4}, {"psfs": [psfs.astype(complex),
         np.full((3, 3, 4, 3), "x")]}),
    ]  # fmt: skip


def _spectral_denoise(x, sigma):
    """``SpectralDenoiser()(x, sigma)`` with the shipped weights, made at the first call."""
    if not _SHIPPED:
        from .learn.spectral_net import SpectralDenoiser

        _SHIPPED.append(SpectralDenoiser())
    return _SHIPPED[0](x, sigma)


_SHIPPED: list = []  # the denoiser of _spectral_denoise, once made


def _study_arguments():
    """Design studies given seeds or values that are not a list of them (refused before any
    system is built)."""
    from . import studies

    return [
        ("studies", studies.conditioning_design, ("sd_cassi", "shots", (1, 2)),
         {"cube_shape": (8, 8, 4)}, {"seeds": [(), (True,), (2.5,), "0"], 2: [None, "12"]}),
        ("studies", studies.vsi_arms, (), {"shape": (8, 8), "n_bands": 4},
         {"seeds": [(), (-1,)]}),
        ("studies", studies.zernike_design, (), {"modes": (5,), "amplitudes": (0.25,),
         "psf_sizes": (15,), "shape": (16, 16), "n_bands": 4, "progress": False},
         {"seeds": [(), (True,)]}),
    ]  # fmt: skip


def _plot_arguments():
    """Figures given a colour map, a flag or a map they cannot draw (where matplotlib is
    installed; each is refused before a figure is made)."""
    import importlib.util

    if importlib.util.find_spec("matplotlib") is None:
        return []
    from . import plot

    depth_map = np.random.default_rng(3).random((8, 8))
    return [
        ("plot", plot.depth, (depth_map,), {}, {"cmap": ["", "VIRIDIS ", 3, None],
         0: [np.zeros((0, 8)), np.ones((8, 8, 2))]}),
        ("plot", plot.study, ([{"x": 1, "y": 2.0}], "x", "y"), {}, {"logy": [2, "yes", None]}),
    ]  # fmt: skip


def _lab_arguments():
    """Acquisition plans given a frame type the readers do not know, and a camera that would
    poll less often than it waits."""
    from .io.triggers import AcquisitionPlan, FolderCamera

    return [
        ("io.lab", AcquisitionPlan.snapshots, (2,), {}, {"suffix": ["", "tif", ".exe", 3]}),
        ("io.lab", FolderCamera, (_scratch(),), {}, {"poll": [1e9, 0.0]}),
    ]  # fmt: skip


def _scratch():
    """A fresh temporary folder for the files of :func:`hostile_arguments`, removed when the
    process exits."""
    import atexit
    import shutil
    import tempfile
    from pathlib import Path

    folder = Path(tempfile.mkdtemp(prefix="tensor_cosdi_hostile_"))
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    return folder


def _reader_arguments():
    """Readers given a size limit, a key or a channel that cannot apply (each would be ignored
    or taken as no limit)."""
    from .io import crop, load_bundle, read_array, read_cube, read_frame, save_bundle

    folder = _scratch()
    np.save(folder / "cube.npy", np.ones((4, 4, 3)))
    np.save(folder / "frame.npy", np.ones((4, 4)))
    save_bundle(folder / "b.npz", cube=np.ones((2, 2, 2)))
    limits = [float("nan"), float("inf"), 1e308, 0, True, "4096"]
    return [
        ("io.files", read_cube, (folder / "cube.npy",), {}, {"max_bytes": limits}),
        ("io.files", read_array, (folder / "cube.npy",), {}, {"max_bytes": limits}),
        ("io.bundle", load_bundle, (folder / "b.npz",), {}, {"max_bytes": limits}),
        ("io.frames", read_frame, (folder / "frame.npy",), {}, {"max_bytes": limits,
         "channel": ["x", 1, -1, 2.5], "key": ["frame", 3]}),
        ("io.frames", crop, (np.ones((8, 8)), (0, 4, 0, 4)), {}, {1: [(0, 4.5, 0, 4),
         ("0", 4, 0, 4), (0, 4, 0)]}),
    ]  # fmt: skip


def _learned_arguments():
    """The learned denoiser's and D-CoSNet's public entries (where PyTorch is installed)."""
    import importlib.util

    if importlib.util.find_spec("torch") is None:
        return []
    import torch

    from .learn import dcosnet, spectral_net

    cube = np.random.default_rng(1).random((16, 16, 8)).astype(np.float32)
    nan_cube = cube.copy()
    nan_cube[3, 3, 3] = np.nan
    # no network is made and nothing runs in torch here: a process forked after torch has
    # started its threads (the robustness catalogue's workers) would wait on them for ever
    batch = torch.from_numpy(np.random.default_rng(2).random((1, 2, 16, 16)).astype(np.float32))
    nan, inf = float("nan"), float("inf")
    return [
        ("learn", _spectral_denoise, (cube, 0.1), {}, {0: [nan_cube, None, np.zeros((0, 0, 3)),
         cube.astype(complex)], 1: [True, "0.1", nan, -1.0]}),
        ("learn", spectral_net.SpectralDenoiser, (), {}, {"device": ["tpu", 3, ""],
         "joint": [2, "yes"]}),
        ("learn", spectral_net.SubspaceDenoiserNet, (), {}, {"r_max": [0, 1e308, 65],
         "width": [10**6, 2.5], "blocks": [True], "conv_rank": [-1]}),
        ("learn", spectral_net.network_device, (None,), {}, {"device": ["", "CPU ", 3]}),
        ("learn", dcosnet.ssim, (batch, batch), {}, {0: [None, np.ones((1, 2, 16, 16))],
         1: [batch[:, :1]], "data_range": [0.0, nan, True], "sigma": [0.0, inf],
         "win": [0, 99, 2.5]}),
        ("learn", dcosnet.seeded_code, ((8, 8), 0), {}, {0: [(8.5, 8), (0, 8), 8],
         1: [True, -1, None]}),
        ("learn", dcosnet.tile_code, (np.ones((4, 4)), (8, 8)), {},
         {0: [np.full((4, 4), nan)], 1: [(8, 8.5), (8,)]}),
        ("learn", dcosnet.DCoSNet, (), {}, {"device": ["tpu"], "start": ["warm", 3, None,
         ["fast"]]}),
        ("learn", dcosnet.default_weights, ("sd_cassi",), {}, {"start": ["warm", None]}),
    ]  # fmt: skip


def _writer_arguments():
    """Writers given an ``overwrite`` that is not ``True``/``False`` (``"no"`` is truthy): each
    writes into a fresh temporary folder, over a file already there."""
    from .io import save_bundle, write_cube
    from .studies import write_csv

    folder = _scratch()
    cube = folder / "cube.npy"
    np.save(cube, np.ones((2, 2, 2)))
    csv, bundle = folder / "r.csv", folder / "b.npz"
    csv.write_text("a\n1\n")
    save_bundle(bundle, cube=np.ones((2, 2, 2)))
    slips = ["no", "False", 1, None]
    deep: dict = {}
    inner = deep
    for _ in range(5000):  # past the JSON encoder's recursion limit
        inner["a"] = inner = {}
    fresh = folder / "fresh.npz"
    return [
        ("io.files", write_cube, (cube, np.zeros((2, 2, 2))), {}, {"overwrite": slips}),
        ("io.files", write_cube, (fresh, np.zeros((2, 2, 2))), {}, {"metadata": [deep, [1, 2],
         {"x": float("nan")}], 1: [np.zeros((0, 2, 2)), np.zeros((2, 2))]}),
        ("io.bundle", save_bundle, (fresh,), {"cube": np.zeros((2, 2, 2))},
         {"metadata": [deep, [1, 2]]}),
        ("studies", write_csv, ([{"a": 2}], csv), {}, {"overwrite": slips}),
        ("io.bundle", save_bundle, (bundle,), {"cube": np.zeros((2, 2, 2))},
         {"overwrite": slips}),
    ]  # fmt: skip


_ARGUMENT_WORDS = {
    "x": ("tensor", "x must", "x holds", "cube"),
    "y": ("one shape", "tensors"),
    "name": ("wavelet",),
    "n": ("n must",),
    "shape": ("shape", "rows", "columns"),
}


def _short(value) -> str:
    """A label for a bad value: its repr, an array as its shape and what is wrong in it."""
    if isinstance(value, np.ndarray):
        flags = [w for w, bad in (("NaN", np.isnan), ("inf", np.isinf))
                 if value.dtype.kind == "f" and bad(value).any()]  # fmt: skip
        return " ".join([f"array{value.shape}"] + flags)
    if hasattr(value, "shape") and hasattr(value, "dtype"):  # a torch tensor, say
        return f"{type(value).__name__}{tuple(value.shape)}"
    try:
        text = repr(value)
    except RecursionError:  # a structure nested past the interpreter's limit
        return f"{type(value).__name__} nested too deeply to print"
    return text if len(text) <= 40 else text[:37] + "…"
