"""The learned spectral denoiser: errors without torch, the shipped weights on a real crop, any
band count, training with checkpoints and an exact resume, and PnP-GAP with it."""

import importlib.util
import json
import sys

import numpy as np
import pytest

import tensor_cosdi as tc
from tensor_cosdi import datasets, metrics

pnp_gap_module = importlib.import_module("tensor_cosdi.solvers.pnp_gap")

HAS_TORCH = importlib.util.find_spec("torch") is not None
needs_torch = pytest.mark.skipif(not HAS_TORCH, reason="PyTorch is not installed")


def _real(name="face", shape=(64, 64)):
    try:
        return datasets.load_hsi(name, "kaist", shape=shape, dtype="float32")[0]
    except FileNotFoundError:
        pytest.skip("hsi_train scenes not present (set TENSOR_COSDI_DATA)")


def test_without_torch_the_error_names_the_extra(monkeypatch):
    from tensor_cosdi.learn import require_torch

    monkeypatch.setitem(sys.modules, "torch", None)  # import torch now raises ImportError
    with pytest.raises(ImportError, match=r"tensor_cosdi\[torch\]"):
        require_torch()
    p = tc.studies.make_problem("sd_cassi", "chelsea", shape=(16, 16), n_bands=4, rng=0)
    with pytest.raises(ImportError, match="pip install"):
        tc.reconstruct(p.system, p.measurement, "pnp_gap")


def test_pnp_gap_runs_without_torch_with_a_classical_denoiser():
    p = tc.studies.make_problem("sd_cassi", "chelsea", shape=(32, 32), n_bands=8, snr_db=30, rng=0)
    lsq = tc.studies.score(p, tc.reconstruct(p.system, p.measurement, "lsq").cube)["psnr"]
    res = tc.reconstruct(
        p.system, p.measurement, "pnp_gap", denoiser="tv", max_iter=20, warm="gap_tv"
    )
    assert tc.studies.score(p, res.cube)["psnr"] > lsq + 1.0
    warm = tc.reconstruct(p.system, p.measurement, "gap_tv").iterations  # its own stop rule
    assert res.iterations == warm + 20  # warm start + PnP iterations, one history
    with pytest.raises(ValueError, match="warm must be one of"):
        tc.reconstruct(p.system, p.measurement, "pnp_gap", denoiser="tv", warm="wdct")
    with pytest.raises(ValueError, match="accelerate must be"):
        tc.reconstruct(p.system, p.measurement, "pnp_gap", denoiser="tv", accelerate=1)
    with pytest.raises(ValueError, match="eps must be 'auto'"):
        tc.reconstruct(p.system, p.measurement, "pnp_gap", denoiser="tv", eps="big")
    with pytest.raises(ValueError, match="sigma_end must be"):
        tc.reconstruct(p.system, p.measurement, "pnp_gap", denoiser="tv", sigma_end=0)


@needs_torch
def test_shipped_weights_denoise_a_real_crop_beyond_the_subspace_projection():
    from tensor_cosdi.learn.spectral_net import SpectralDenoiser

    den = SpectralDenoiser()
    clean = _real("face")
    rng = np.random.default_rng(0)
    for sigma, gain in ((0.05, 3.0), (0.1, 3.0)):
        noisy = clean + sigma * rng.standard_normal(clean.shape).astype(np.float32)
        out = den(noisy, sigma)
        assert out.shape == clean.shape and out.dtype == np.float32
        flat = noisy.reshape(-1, clean.shape[2]).astype(np.float64)
        _, u = np.linalg.eigh(flat.T @ flat)
        u = u[:, ::-1][:, : den.rank]
        proj = (flat @ u @ u.T).reshape(clean.shape)
        p_proj = metrics.psnr(clean, proj, data_range=1.0)
        p_net = metrics.psnr(clean, out, data_range=1.0)
        # the network's own share: it must beat the bare spectral projection clearly
        assert p_net > p_proj + gain, (sigma, p_net, p_proj)


@needs_torch
def test_any_band_count_and_extra_axes_and_torch_tensors():
    import torch

    from tensor_cosdi.learn.spectral_net import SpectralDenoiser

    den = SpectralDenoiser()
    clean = _real("face", (33, 30))  # odd size on purpose
    rng = np.random.default_rng(1)
    for bands in (clean[..., :4], clean, clean[..., ::3]):
        noisy = bands + 0.05 * rng.standard_normal(bands.shape).astype(np.float32)
        out = den(noisy, 0.05)
        assert out.shape == bands.shape
        assert metrics.psnr(bands, out, data_range=1.0) > metrics.psnr(bands, noisy, data_range=1)
    four = np.stack([clean[..., :8], 0.5 * clean[..., :8]], axis=-1)  # (x, y, λ, t)
    out4 = den(four, 0.01)
    assert out4.shape == four.shape
    t = torch.from_numpy(clean.astype(np.float64))
    out_t = den(t, 0.01)
    assert isinstance(out_t, torch.Tensor) and out_t.dtype == torch.float64
    np.testing.assert_allclose(out_t.numpy(), den(clean, 0.01), atol=1e-5)
    # views with negative strides (a flipped cube: the self-ensemble's input) are accepted;
    # their spectra are read in another pixel order (float rounding), the images are the same
    flipped = den(clean[::-1, :, ::-1], 0.01)
    np.testing.assert_allclose(flipped, den(clean[::-1, :, ::-1].copy(), 0.01), atol=1e-4)


@needs_torch
def test_every_symmetry_of_a_fortran_cube_comes_back_in_its_layout():
    """The self-ensemble hands the denoiser flipped and transposed views of a Fortran-ordered
    cube: each result, turned back, is Fortran-ordered again (no copy needed by the solver)
    and is the denoised copy of that view."""
    from tensor_cosdi.learn.spectral_net import SpectralDenoiser

    def view(a, k):  # the eight symmetries: transpose, then flip rows / columns
        a = a.transpose(1, 0, 2) if k & 4 else a
        return a[:: -1 if k & 1 else 1, :: -1 if k & 2 else 1]

    def unview(a, k):
        a = a[:: -1 if k & 1 else 1, :: -1 if k & 2 else 1]
        return a.transpose(1, 0, 2) if k & 4 else a

    den = SpectralDenoiser()
    rng = np.random.default_rng(2)
    clean = _real("face", (40, 36))
    x = np.asfortranarray(clean + 0.05 * rng.standard_normal(clean.shape).astype(np.float32))
    for k in range(8):
        v = view(x, k)
        out = den(v, 0.05)
        back = unview(out, k)
        assert back.flags.f_contiguous, k
        np.testing.assert_allclose(out, den(np.ascontiguousarray(v), 0.05), atol=1e-4)
        assert metrics.psnr(clean, back, data_range=1.0) > metrics.psnr(clean, x, data_range=1) + 5


@needs_torch
def test_bad_inputs_are_clear_errors(tmp_path):
    from tensor_cosdi.learn.spectral_net import SpectralDenoiser

    den = SpectralDenoiser()
    with pytest.raises(ValueError, match="sigma must be"):
        den(np.ones((8, 8, 3), np.float32), -1.0)
    with pytest.raises(ValueError, match="expected a cube"):
        den(np.ones((8, 8), np.float32), 0.1)
    with pytest.raises(ValueError, match="exceeds the network's r_max"):
        SpectralDenoiser(rank=99)
    with pytest.raises(FileNotFoundError, match="not found"):
        SpectralDenoiser(tmp_path / "missing.pt")
    import torch

    torch.save({"something": 1}, tmp_path / "other.pt")
    with pytest.raises(ValueError, match="not a spectral-denoiser checkpoint"):
        SpectralDenoiser(tmp_path / "other.pt")


@needs_torch
def test_training_checkpoints_resume_exactly_and_never_overwrite(tmp_path):
    import torch

    from tensor_cosdi.learn.train import TrainConfig, train_denoiser

    _real()  # skips without the scenes
    cfg = TrainConfig(steps=4, batch=2, patch=16, width=8, blocks=1, r_max=4, checkpoint_every=1)
    a = train_denoiser(tmp_path / "a.pt", cfg, progress=False, device="cpu")
    assert a["finished"] and a["steps"] == 4
    part = train_denoiser(tmp_path / "b.pt", cfg, progress=False, device="cpu", stop_after=2)
    assert not part["finished"] and not (tmp_path / "b.pt").exists()
    with pytest.raises(FileExistsError, match="--resume"):
        train_denoiser(tmp_path / "b.pt", cfg, progress=False, device="cpu")
    with pytest.raises(ValueError, match="resume without changing"):
        train_denoiser(
            tmp_path / "b.pt", TrainConfig(steps=5), resume=True, progress=False, device="cpu"
        )
    b = train_denoiser(tmp_path / "b.pt", cfg, resume=True, progress=False, device="cpu")
    assert b["finished"] and b["steps"] == 4
    wa = torch.load(tmp_path / "a.pt", weights_only=True)["model"]
    wb = torch.load(tmp_path / "b.pt", weights_only=True)["model"]
    for k in wa:
        torch.testing.assert_close(wa[k], wb[k], rtol=0, atol=0)
    with pytest.raises(FileExistsError, match="--force"):
        train_denoiser(tmp_path / "a.pt", cfg, progress=False, device="cpu")
    with pytest.raises(ValueError, match="patch must be"):
        TrainConfig(patch=15).check()
    # the trained file is a denoiser
    from tensor_cosdi.learn.spectral_net import SpectralDenoiser

    out = SpectralDenoiser(tmp_path / "a.pt")(np.random.default_rng(0).random((16, 16, 5)), 0.1)
    assert out.shape == (16, 16, 5)


@needs_torch
def test_a_damaged_checkpoint_is_a_one_line_error_before_any_training(tmp_path):
    """An empty, foreign or edited ``.ckpt`` raised EOFError, KeyError or TypeError."""
    import json

    import torch

    from tensor_cosdi.learn._loop import CHECKPOINT_KEYS
    from tensor_cosdi.learn.train import train_denoiser

    good = {k: 0 for k in CHECKPOINT_KEYS} | {"rng": "{}", "config": json.dumps({"steps": 2})}
    cases = [
        (b"", "EOFError"),
        ({"model": {}}, "no optimizer, scheduler"),
        (good | {"config": json.dumps({"bogus": 1})}, "unexpected keyword argument 'bogus'"),
        (good | {"config": "[1, 2]"}, "the config is a list, not a mapping"),
        (good | {"config": "[" * 100_000 + "]" * 100_000}, "its config: nested too deeply"),
    ]
    for i, (state, why) in enumerate(cases):
        ckpt = tmp_path / f"w{i}.pt.ckpt"
        if isinstance(state, bytes):
            ckpt.write_bytes(state)
        else:
            torch.save(state, ckpt)
        with pytest.raises(ValueError, match=f"not a readable checkpoint of this training.*{why}"):
            train_denoiser(tmp_path / f"w{i}.pt", resume=True, progress=False, device="cpu")


@needs_torch
def test_a_checkpoint_whose_tensors_do_not_fit_is_refused(tmp_path):
    import torch

    from tensor_cosdi.learn.train import TrainConfig, train_denoiser

    _real()
    cfg = TrainConfig(steps=3, batch=2, patch=16, width=8, blocks=1, r_max=4, checkpoint_every=1)
    train_denoiser(tmp_path / "w.pt", cfg, progress=False, device="cpu", stop_after=1)
    ckpt = tmp_path / "w.pt.ckpt"
    state = torch.load(ckpt, weights_only=True)
    name = next(iter(state["model"]))
    state["model"][name] = torch.zeros(3)
    torch.save(state, ckpt)
    with pytest.raises(ValueError, match="w.pt.ckpt does not fit this training.*--force"):
        train_denoiser(tmp_path / "w.pt", cfg, resume=True, progress=False, device="cpu")


@needs_torch
def test_cli_train_denoiser(tmp_path, capsys):
    from tensor_cosdi import cli

    _real()
    out = tmp_path / "w.pt"
    args = ["train-denoiser", "--out", str(out), "--steps", "2", "--batch", "2", "--patch", "16"]
    args += ["--width", "8", "--blocks", "1", "--quiet", "--device", "cpu"]
    assert cli.main(args + ["--stop-after", "1"]) == 0
    assert "--resume" in capsys.readouterr().out and not out.exists()
    assert cli.main(args + ["--resume"]) == 0
    assert out.exists()
    assert cli.main(args) == 2  # exists: refuses without --force
    assert "--force" in capsys.readouterr().err
    # a held-out fold: the weights record the scenes they were trained on, the fold is not there
    held = tmp_path / "held.pt"
    hold = ["--out", str(held), "--hold-out", "1"]
    assert cli.main(args[:1] + hold + args[3:]) == 0
    import torch

    scenes = json.loads(torch.load(held, weights_only=True)["summary"])["scenes"]
    fold = tc.datasets.tune_folds(4)[1]
    assert len(scenes) == 28 - len(fold) and not set(fold) & set(scenes)
    assert cli.main(args[:1] + ["--out", str(tmp_path / "x.pt"), "--hold-out", "4"] + args[3:]) == 2
    assert "hold_out must be -1" in capsys.readouterr().err
    # magnified views: recorded in the weights' training configuration
    zoomed = tmp_path / "zoom.pt"
    zoom = ["--zoom", "0.5", "--zoom-max", "2"]
    assert cli.main(args[:1] + ["--out", str(zoomed)] + zoom + args[3:]) == 0
    cfg = json.loads(torch.load(zoomed, weights_only=True)["train_config"])
    assert cfg["zoom"] == 0.5 and cfg["zoom_max"] == 2.0
    assert cli.main(args[:1] + ["--out", str(tmp_path / "z.pt"), "--zoom", "2"] + args[3:]) == 2
    assert "zoom must be a number in [0, 1]" in capsys.readouterr().err
    # the shipped weights' recipe: no illumination, shifts of 1-2 px, codes of density ½
    old = tmp_path / "old.pt"
    recipe = ["--illumination", "0", "--max-shift", "2", "--density-spread", "0"]
    assert cli.main(args[:1] + ["--out", str(old)] + recipe + args[3:]) == 0
    cfg = json.loads(torch.load(old, weights_only=True)["train_config"])
    assert (cfg["illumination"], cfg["max_shift"], cfg["density_spread"]) == (0.0, 2, 0.0)
    for bad, msg in (
        (["--density-spread", "0.5"], "density_spread must be a number in [0, 0.5)"),
        (["--illumination", "-1"], "illumination must be a number in [0, 1]"),
    ):
        assert cli.main(args[:1] + ["--out", str(tmp_path / "b.pt")] + bad + args[3:]) == 2
        assert msg in capsys.readouterr().err


@needs_torch
def test_fine_tuning_starts_from_the_given_weights(tmp_path, capsys):
    import torch

    from tensor_cosdi import cli
    from tensor_cosdi.learn.spectral_net import default_weights

    _real()
    small = ["--steps", "1", "--batch", "2", "--patch", "16", "--quiet", "--device", "cpu"]
    # a learning rate of 1e-12: one Adam step moves no weight by more than ~1e-12
    out = tmp_path / "ft.pt"
    assert cli.main(["train-denoiser", "--out", str(out), "--init", "shipped", "--lr", "1e-12",
                     "--warmup", "0"] + small) == 0  # fmt: skip
    tuned = torch.load(out, weights_only=True)
    shipped = torch.load(default_weights(), weights_only=True)["model"]
    for k, v in shipped.items():
        torch.testing.assert_close(tuned["model"][k], v, rtol=0, atol=1e-9)
    cfg = json.loads(tuned["train_config"])
    assert (cfg["init"], cfg["lr"], cfg["warmup"]) == ("shipped", 1e-12, 0)
    # a random start (the default) is far from the shipped network
    scratch = tmp_path / "scratch.pt"
    assert cli.main(["train-denoiser", "--out", str(scratch)] + small) == 0
    w = torch.load(scratch, weights_only=True)["model"]
    assert max(float((w[k] - v).abs().max()) for k, v in shipped.items()) > 1e-2
    # a file of another shape, a missing file, a bad learning rate: one-line errors
    for bad, msg in (
        (["--init", str(out), "--width", "8"], "pass the same --width/--blocks"),
        (["--init", str(tmp_path / "none.pt")], "weights not found"),
        (["--lr", "-1"], "lr must be a finite positive number"),
        (["--lr", "inf"], "lr must be a finite positive number"),
    ):
        assert cli.main(["train-denoiser", "--out", str(tmp_path / "b.pt")] + bad + small) == 2
        assert msg in capsys.readouterr().err


@needs_torch
def test_factorised_network_is_the_full_one_at_full_rank_and_smaller_below():
    import torch

    from tensor_cosdi.learn.spectral_net import SubspaceDenoiserNet, factorise

    torch.manual_seed(0)
    full = SubspaceDenoiserNet(r_max=2, width=8, blocks=2).eval()
    with torch.no_grad():  # a trained network's zero-initialised layers are not zero
        for p in full.parameters():
            p.normal_(0, 0.2)
    y, s = torch.randn(2, 2, 12, 10), torch.tensor([0.05, 0.2])
    with torch.no_grad():
        ref = full(y, s)
        # 9 input channels (4·2 + the noise map) and 8 wide: rank 9 keeps every mode whole
        torch.testing.assert_close(factorise(full, 9).eval()(y, s), ref, rtol=1e-4, atol=1e-5)
        small = factorise(full, 3).eval()
        err = [float((factorise(full, k).eval()(y, s) - ref).norm() / ref.norm()) for k in (3, 6)]
    assert err[0] > err[1] > 1e-3  # truncated: nearer the full network the higher the rank
    count = lambda net: sum(p.numel() for p in net.parameters())  # noqa: E731
    assert count(small) < count(full) / 2
    assert small.conv_rank == 3 and full.conv_rank == 0
    for bad, msg in ((0, "conv_rank must be an integer ≥ 1"), (-2, "got -2"),
                     (2.5, "got 2.5"), (True, "got True")):  # fmt: skip
        with pytest.raises(ValueError, match=msg):
            factorise(full, bad)
    with pytest.raises(ValueError, match="already factored"):
        factorise(small, 2)


@needs_torch
def test_a_weights_file_describing_a_bad_network_is_a_one_line_error(tmp_path):
    import torch

    from tensor_cosdi.learn.spectral_net import SpectralDenoiser, default_weights
    from tensor_cosdi.learn.train import TrainConfig

    ckpt = torch.load(default_weights(), weights_only=True)
    for i, (config, msg) in enumerate((
        ([12, 64, 4], "its config is a list"),
        ({"width": 64, "blocks": 4}, "config r_max must be an integer ≥ 1 and ≤ 64, got None"),
        (dict(ckpt["config"], r_max=12.5), "config r_max must be an integer"),
        (dict(ckpt["config"], width=-1), "config width must be an integer ≥ 1 and ≤ 1024, got -1"),
        (dict(ckpt["config"], width=10**7), "got 10000000"),  # no gigabytes on request
        (dict(ckpt["config"], blocks=True), "config blocks must be an integer"),
        (dict(ckpt["config"], conv_rank="24"), "config conv_rank must be an integer ≥ 0"),
        (dict(ckpt["config"], conv_rank=24), "do not fit the network"),  # full weights
    )):  # fmt: skip
        path = tmp_path / f"bad{i}.pt"
        torch.save(dict(ckpt, config=config), path)
        with pytest.raises(ValueError, match="not a spectral-denoiser checkpoint") as err:
            SpectralDenoiser(path)
        assert msg in str(err.value) and "\n" not in str(err.value)
    with pytest.raises(ValueError, match="width must be an integer ≥ 1 and ≤ 1024, got 2048"):
        TrainConfig(width=2048).check()


@needs_torch
def test_cli_fine_tunes_a_factored_copy_of_a_full_network(tmp_path, capsys):
    import torch

    from tensor_cosdi import cli
    from tensor_cosdi.learn.spectral_net import SpectralDenoiser, SubspaceDenoiserNet, factorise

    _real()
    small = ["--steps", "1", "--batch", "2", "--patch", "16", "--quiet", "--device", "cpu",
             "--width", "8", "--blocks", "1"]  # fmt: skip
    full = tmp_path / "full.pt"
    assert cli.main(["train-denoiser", "--out", str(full)] + small) == 0
    # a learning rate of 1e-12: the fine-tuned file holds the factored start itself
    out = tmp_path / "k4.pt"
    assert cli.main(["train-denoiser", "--out", str(out), "--init", str(full), "--conv-rank", "4",
                     "--lr", "1e-12", "--warmup", "0"] + small) == 0  # fmt: skip
    got = torch.load(out, weights_only=True)
    assert got["config"]["conv_rank"] == 4
    net = SubspaceDenoiserNet(width=8, blocks=1)
    net.load_state_dict(torch.load(full, weights_only=True)["model"])
    want = factorise(net, 4).state_dict()
    assert set(got["model"]) == set(want)
    for k, v in want.items():
        torch.testing.assert_close(got["model"][k], v, rtol=0, atol=1e-6)
    # the factored file is a denoiser, and fine-tunes again at its own rank
    cube = np.random.default_rng(0).random((16, 16, 5)).astype(np.float32)
    assert SpectralDenoiser(out)(cube, 0.1).shape == cube.shape
    again = tmp_path / "again.pt"
    assert cli.main(["train-denoiser", "--out", str(again), "--init", str(out),
                     "--conv-rank", "4"] + small) == 0  # fmt: skip
    for bad, msg in (
        (["--init", str(out), "--conv-rank", "3"], "conv_rank"),
        (["--init", str(out)], "conv_rank"),
        (["--conv-rank", "-1"], "conv_rank must be an integer ≥ 0"),
    ):
        assert cli.main(["train-denoiser", "--out", str(tmp_path / "b.pt")] + bad + small) == 2
        assert msg in capsys.readouterr().err


@needs_torch
def test_nullspace_noise_leaves_nothing_the_operator_sees_for_each_shift_and_density():
    """The training noise ``(I − Aᵀ(AAᵀ)⁻¹A) n``: the drawn SD-CASSI operator maps it to zero
    on every measured pixel, with shifts of 1 to ``max_shift`` and the drawn densities."""
    import torch

    from tensor_cosdi.learn import train

    p, n, b = 16, 5, 4
    seen_steps, seen_density = set(), []
    for seed in range(24):
        noise = torch.from_numpy(np.random.default_rng(100 + seed).normal(size=(b, p * p, n)))
        rng = np.random.default_rng(seed)
        peek = np.random.default_rng(seed)
        step = int(peek.choice(np.arange(1, 3)))
        density = peek.uniform(0.5 - 0.1, 0.5 + 0.1)
        code = (peek.random((b, p, p)) < density).astype(np.float64)
        out = train.nullspace_noise(torch, noise, rng, p, 2, 0.1).numpy().reshape(b, p, p, n)
        g = np.zeros((b, p, p + step * (n - 1)))
        for k in range(n):
            g[:, :, step * k : step * k + p] += code * out[..., k]
        assert np.abs(g).max() < 1e-9  # A (noise) = 0: nothing the measurement sees is left
        assert np.abs(out).mean() > 0.3  # and most of the noise is
        seen_steps.add(step)
        seen_density.append(code.mean())
    # densities drawn from 0.4-0.6 (each read on 1024 pixels: ±0.05 at 3σ), not all the same
    assert seen_steps == {1, 2} and 0.35 < min(seen_density) < max(seen_density) < 0.65
    assert max(seen_density) - min(seen_density) > 0.1


@needs_torch
def test_magnified_batches_are_smaller_crops_upsampled_to_the_patch():
    import torch

    from tensor_cosdi.learn.train import TrainConfig, magnify, sample_batch

    cube = _real("face", (96, 96))
    cfg = TrainConfig(batch=3, patch=32, zoom=1.0, zoom_max=4.0).check()
    sides = set()
    rng = np.random.default_rng(0)
    for _ in range(12):
        clean, _, side = sample_batch(rng, [cube], cfg)
        assert clean.shape[:2] == (3, side * side) and 8 <= side <= 32
        sides.add(side)
        up = magnify(torch, torch.from_numpy(clean), side, 32)
        assert up.shape == (3, 32 * 32, clean.shape[2]) and float(up.min()) >= 0
        # bicubic magnification keeps the mean level of each band (within 2 %)
        np.testing.assert_allclose(up.mean(1).numpy(), clean.mean(1), rtol=0.02, atol=1e-4)
    assert len(sides) > 3 and min(sides) < 16  # magnifications up to 4× were drawn
    # without zoom every batch is a full patch, and no random number is drawn for it
    plain = TrainConfig(batch=3, patch=32)
    a, _, side = sample_batch(np.random.default_rng(5), [cube], plain)
    assert side == 32
    r = np.random.default_rng(5)
    b, _, _ = sample_batch(r, [cube], TrainConfig(batch=3, patch=32, zoom=0.0, zoom_max=2.0))
    np.testing.assert_array_equal(a, b)
    for bad in ({"zoom": 1.5}, {"zoom": -0.1}, {"zoom_max": 0.5}, {"zoom": 0.5, "zoom_max": 5.0}):
        with pytest.raises(ValueError, match="zoom"):
            TrainConfig(patch=32, **bad).check()
    TrainConfig(patch=16).check()  # the default zoom_max only binds when zoom is on


@needs_torch
def test_pnp_gap_with_the_learned_denoiser_beats_gap_tv_on_a_real_crop():
    cube = _real("real_and_fake_apples", (64, 64))
    rng = np.random.default_rng(3)
    code = (rng.random((64, 64)) < 0.5).astype(np.float64)
    system = tc.systems.SDCASSI(code, n_bands=28, shifts=2)
    g = system.simulate(cube.astype(np.float64), snr_db=30, rng=0)
    tv = tc.reconstruct(system, g, "gap_tv").cube
    net = tc.reconstruct(system, g, "pnp_gap").cube
    p_tv = metrics.psnr(cube, np.asarray(tv), data_range=1.0)
    p_net = metrics.psnr(cube, np.asarray(net), data_range=1.0)
    # measured: 43.22 against 38.18 dB; plain GAP (the former noisy path) gave 40.29
    assert p_net > p_tv + 3.5, (p_net, p_tv)


@needs_torch
def test_cubes_with_more_axes_are_denoised_one_slice_at_a_time():
    from tensor_cosdi.learn.spectral_net import SpectralDenoiser

    rng = np.random.default_rng(4)
    x = (_real("face", (24, 24))[..., ::4, None] * rng.uniform(0.5, 1.5, 3)).astype(np.float32)
    x = x + rng.normal(0, 0.05, x.shape).astype(np.float32)  # (24, 24, 7, 3): three "patterns"
    den, joint = SpectralDenoiser(), SpectralDenoiser(joint=True)
    out = den(x, 0.05)
    assert out.shape == x.shape and out.dtype == x.dtype
    for t in range(3):
        np.testing.assert_allclose(out[..., t], den(x[..., t], 0.05), rtol=1e-5, atol=1e-6)
    assert np.abs(joint(x, 0.05) - out).max() > 1e-3  # folding the patterns is another denoiser


@needs_torch
def test_bfloat16_denoises_as_well_as_float32_and_auto_follows_the_cpu(monkeypatch):
    import torch

    from tensor_cosdi.learn import spectral_net
    from tensor_cosdi.learn.spectral_net import SpectralDenoiser

    clean = _real("face")
    noisy = clean + 0.05 * np.random.default_rng(5).standard_normal(clean.shape)
    noisy = noisy.astype(np.float32)
    f32 = SpectralDenoiser(precision="float32")(noisy, 0.05)
    b16 = SpectralDenoiser(precision="bfloat16")(noisy, 0.05)
    assert b16.dtype == np.float32 and np.abs(b16 - f32).max() > 0  # another arithmetic …
    p32 = metrics.psnr(clean, f32, data_range=1.0)
    p16 = metrics.psnr(clean, b16, data_range=1.0)
    assert abs(p16 - p32) < 0.1, (p16, p32)  # … within a tenth of a dB
    np.testing.assert_array_equal(SpectralDenoiser()(noisy, 0.05), f32)  # the default
    for fast, want in ((False, f32), (True, b16)):
        monkeypatch.setattr(spectral_net, "bfloat16_is_fast", lambda fast=fast: fast)
        auto = SpectralDenoiser(precision="auto")(noisy, 0.05)
        np.testing.assert_array_equal(auto, want)
    assert isinstance(spectral_net.bfloat16_is_fast(), bool)
    with pytest.raises(ValueError, match="precision must be one of"):
        SpectralDenoiser(precision="float16")
    assert torch.get_default_dtype() == torch.float32  # nothing global was changed


@needs_torch
def test_pnp_gap_takes_the_denoisers_precision():
    p = tc.studies.make_problem("sd_cassi", "chelsea", shape=(32, 32), n_bands=8, rng=0)
    quick = {"max_iter": 5, "warm": "gap_tv", "warm_iter": 5}
    psnr = {
        pr: tc.studies.score(p, tc.reconstruct(p.system, p.measurement, "pnp_gap",
                                               precision=pr, **quick).cube)["psnr"]
        for pr in ("float32", "bfloat16")
    }  # fmt: skip
    assert psnr["float32"] != psnr["bfloat16"]  # the option reaches the network …
    assert abs(psnr["float32"] - psnr["bfloat16"]) < 0.1, psnr  # … measured 0.004 dB apart
    with pytest.raises(ValueError, match="precision must be one of"):
        tc.reconstruct(p.system, p.measurement, "pnp_gap", precision="half")
    with pytest.raises(ValueError, match="option of the learned denoiser 'spectral_net'"):
        tc.reconstruct(p.system, p.measurement, "pnp_gap", precision="bfloat16", denoiser="tv")


@needs_torch
def test_pnp_fast_is_pnp_gap_with_fewer_cheaper_calls_and_still_beats_gap_tv():
    cube = _real("real_and_fake_apples", (64, 64))
    code = (np.random.default_rng(3).random((64, 64)) < 0.5).astype(np.float64)
    system = tc.systems.SDCASSI(code, n_bands=28, shifts=2)
    g = system.simulate(cube.astype(np.float64), snr_db=30, rng=0)
    fast = tc.reconstruct(system, g, "pnp_fast", precision="float32")
    relax = pnp_gap_module.fast_settings(system, g)["relax"]
    assert relax > 1.5  # over-relaxed at 30 dB (FAST_RELAX; 1.83 here)
    budget = pnp_gap_module.fast_budget(system, g, precision="float32")
    low = pnp_gap_module.float32_on_cpu(g, "float32")  # fewer calls of a float32 CPU network
    full = {"warm_iter": 10, "max_iter": 46, "sigma_end": "auto"}
    assert (budget["max_iter"] < 46) if low else (budget == full), budget
    same = tc.reconstruct(system, g, "pnp_gap", max_iter=budget["max_iter"], ensemble=1,
                          warm_iter=budget["warm_iter"], sigma_end=budget["sigma_end"],
                          pan_tv_steps=3, relax=relax)  # fmt: skip
    np.testing.assert_array_equal(np.asarray(fast.cube), np.asarray(same.cube))
    plain = tc.reconstruct(system, g, "pnp_fast", precision="float32", relax=1.0)
    gain = (metrics.psnr(cube, np.asarray(fast.cube), data_range=1.0)
            - metrics.psnr(cube, np.asarray(plain.cube), data_range=1.0))  # fmt: skip
    assert gain > 0.3, gain  # against plain ADMM (relax=1): +0.77 dB (float32 budget), +0.91 (full)
    assert fast.options["precision"] == "float32"
    # on clean data (read as clean: 40.4 dB) its start is OTD's first stage alone, and the time
    # saved goes to iterations
    face = _real("face", (128, 128))
    wide = tc.systems.SDCASSI(np.tile(code, (2, 2)), n_bands=28, shifts=2)
    clean = wide.simulate(face.astype(np.float64))
    budget = pnp_gap_module.fast_budget(wide, clean, precision="bfloat16")
    assert budget == {"warm_iter": 0, "max_iter": 66, "sigma_end": 0.04}, budget
    fast_clean = tc.reconstruct(wide, clean, "pnp_fast", precision="float32", max_iter=3)
    same_clean = tc.reconstruct(wide, clean, "pnp_gap", max_iter=3, ensemble=1, warm_iter=0,
                                pan_tv_steps=3, sigma_end=0.04, pan_spectrum="gated")  # fmt: skip
    np.testing.assert_array_equal(np.asarray(fast_clean.cube), np.asarray(same_clean.cube))
    # the start's first-stage TV steps are an option of the OTD start alone
    other = tc.reconstruct(system, g, "pnp_fast", warm="gap_tv", warm_iter=5, max_iter=2)
    assert other.cube.shape == cube.shape
    with pytest.raises(ValueError, match="pan_tv_steps sets the first stage of the OTD start"):
        tc.reconstruct(system, g, "pnp_fast", warm="gap_tv", pan_tv_steps=5)
    tv = tc.reconstruct(system, g, "gap_tv").cube
    p_tv = metrics.psnr(cube, np.asarray(tv), data_range=1.0)
    auto = np.asarray(tc.reconstruct(system, g, "pnp_fast").cube)  # bfloat16 where native
    p_fast = metrics.psnr(cube, auto, data_range=1.0)
    # measured 46.31 (bfloat16's budget) and 45.41 (float32 on a CPU) against 38.35 (pnp_gap 47.22)
    assert p_fast > p_tv + 6.0, (p_fast, p_tv)


@needs_torch
def test_a_fortran_ordered_cube_comes_back_fortran_ordered_with_the_same_values():
    """The solvers keep the shear kernels' Fortran order: the denoiser reads and returns a cube
    in that order (a C-ordered result slowed every later solver step) and denoises it as it
    does the C-ordered copy, to float rounding."""
    from tensor_cosdi.learn.spectral_net import SpectralDenoiser

    den = SpectralDenoiser()
    clean = _real("face", (192, 176))  # ≥ 2¹⁵ pixels (the sampled peak), not square
    noisy = clean + 0.05 * np.random.default_rng(1).standard_normal(clean.shape).astype(np.float32)
    c_in, f_in = np.ascontiguousarray(noisy), np.asfortranarray(noisy)
    c_out, f_out = den(c_in, 0.05), den(f_in, 0.05)
    assert c_out.flags.c_contiguous and f_out.flags.f_contiguous and not f_out.flags.c_contiguous
    # float32 sums in another order: 1.6e-5 of the peak on one CPU, under 1e-5 on earlier ones;
    # a layout mistake (a transposed or mis-strided plane) moves values by the signal itself
    assert np.abs(f_out - c_out).max() <= 1e-4 * np.abs(c_out).max()
    gain = metrics.psnr(clean, f_out, data_range=1.0) - metrics.psnr(clean, noisy, data_range=1.0)
    assert gain > 5, gain
    # the self-ensemble hands over a flipped view (negative strides): still no transposition
    from tensor_cosdi.solvers.denoisers import self_ensemble

    pair = self_ensemble(den, 2)
    c_two, f_two = pair(c_in, 0.05), pair(f_in, 0.05)
    assert f_two.flags.f_contiguous and not f_two.flags.c_contiguous
    assert np.abs(f_two - c_two).max() <= 5e-5 * np.abs(c_two).max()  # measured 1.7e-5


def test_a_training_seed_and_noise_range_are_checked():
    from tensor_cosdi.learn.train import TrainConfig

    for seed in (-1, 1.5, True):
        with pytest.raises(ValueError, match="seed must be an integer ≥ 0"):
            TrainConfig(seed=seed).check()
    with pytest.raises(ValueError, match="sigma_max"):
        TrainConfig(sigma_max=float("inf")).check()


def test_training_sizes_that_cannot_run_are_refused_before_any_work():
    from tensor_cosdi.learn.train import TrainConfig

    with pytest.raises(ValueError, match=r"patch must be an even size in 8…512"):
        TrainConfig(patch=100_000).check()
    with pytest.raises(ValueError, match="max_shift must be ≤ patch"):
        TrainConfig(max_shift=100_000).check()
    with pytest.raises(ValueError, match=r"batch=100000 of 64×64 patches takes 47.3 GiB"):
        TrainConfig(batch=100_000).check()
    assert TrainConfig(patch=512, batch=16, max_shift=3).check().patch == 512


@needs_torch
def test_a_device_this_torch_cannot_use_is_a_one_line_error():
    import torch

    from tensor_cosdi.learn import torch_device
    from tensor_cosdi.learn.spectral_net import SpectralDenoiser

    assert torch_device(torch, "cpu") == torch.device("cpu")
    assert torch_device(torch, None).type in ("cpu", "cuda")
    for bad in ("tpu", "gpu0", 3, "", "CPU "):
        with pytest.raises(ValueError, match="device must be"):
            torch_device(torch, bad)
        with pytest.raises(ValueError, match="device must be"):
            SpectralDenoiser(device=bad)  # refused when made, not at its first call
    if not torch.cuda.is_available():
        with pytest.raises(ValueError, match="sees no CUDA GPU; use --device cpu"):
            torch_device(torch, "cuda")
    else:
        with pytest.raises(ValueError, match="CUDA device"):
            torch_device(torch, f"cuda:{torch.cuda.device_count()}")


@needs_torch
def test_a_diverging_training_stops_with_its_step_and_keeps_the_checkpoint(tmp_path):
    from tensor_cosdi.learn.train import TrainConfig, train_denoiser

    _real()  # skips without the scenes
    cfg = TrainConfig(steps=6, batch=2, patch=16, width=8, blocks=1, r_max=4, lr=1e308,
                      warmup=0, checkpoint_every=1)  # fmt: skip
    with pytest.raises(ValueError, match=r"training diverged at step \d \(loss nan\)") as info:
        train_denoiser(tmp_path / "d.pt", cfg, progress=False, device="cpu")
    assert "the last checkpoint" in str(info.value) and (tmp_path / "d.pt.ckpt").is_file()
    assert not (tmp_path / "d.pt").exists()  # no weights of NaN were written
