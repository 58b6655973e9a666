"""The cross-validation helpers of ``benchmarks/_protocol.py`` (choices and scene views)."""

import pytest


@pytest.fixture(scope="module")
def protocol(benchmark_script):
    return benchmark_script("_protocol")


def _two_candidates(seconds_a, seconds_b):
    """``(rows, candidates, folds, seconds_of)`` of two candidates on two one-scene folds:
    ``b`` 1 dB above ``a`` on each scene, at the given seconds a cube."""
    scores = {"a": {"s1": 30.0, "s2": 31.0}, "b": {"s1": 31.0, "s2": 32.0}}
    times = {"a": seconds_a, "b": seconds_b}
    rows = lambda c, scenes: [scores[c["w"]][s] for s in scenes]  # noqa: E731
    secs_of = lambda c, scenes: [times[c["w"]] for _ in scenes]  # noqa: E731
    return rows, [{"w": "a"}, {"w": "b"}], (("s1",), ("s2",)), secs_of


def test_pick_takes_the_best_unless_a_tie_goes_to_the_default_or_the_fastest(protocol):
    means, secs = [30.00, 30.04, 29.50], [5.0, 9.0, 1.0]
    assert protocol.pick(means) == 1
    assert protocol.pick(means, secs, tie_db=0.05) == 0  # a tie: the faster one
    assert protocol.pick(means, secs, tie_db=0.01) == 1  # no tie
    assert protocol.pick(means, secs, tie_db=0.05, keep=1) == 1  # the default wins its tie
    assert protocol.pick(means, secs, tie_db=0.05, keep=2) == 0  # 0.54 dB under: no tie
    assert protocol.pick(means, None, tie_db=0.05) == 1  # no times: the best


def test_pick_no_slower_than_the_default_in_use(protocol):
    """``no_slower``: a candidate slower than the one in use never wins, however good."""
    means, secs = [30.00, 30.80, 30.40, 29.00], [5.0, 5.5, 4.9, 1.0]
    assert protocol.pick(means, secs, keep=0) == 1
    assert protocol.pick(means, secs, keep=0, no_slower=True) == 2
    assert protocol.pick(means, secs, tie_db=0.3, keep=0, no_slower=True) == 2  # 30.00: no tie
    assert protocol.pick(means, secs, tie_db=0.5, keep=0, no_slower=True) == 0  # a tie: kept
    assert protocol.pick([30.0, 29.0], [5.0, 9.0], keep=0, no_slower=True) == 0
    with pytest.raises(ValueError, match="no_slower needs the candidate in use"):
        protocol.pick(means, None, keep=0, no_slower=True)
    rows, cands, folds, secs_of = _two_candidates(5.0, 6.0)
    res = protocol.cross_validate(rows, cands, folds, seconds_of=secs_of, keep={"w": "a"},
                                  tie_db=0.05, no_slower=True)  # fmt: skip
    assert res["chosen_on_all"] == {"w": "a"}
    res = protocol.cross_validate(rows, cands, folds, seconds_of=secs_of, keep={"w": "a"},
                                  tie_db=0.05)  # fmt: skip
    assert res["chosen_on_all"] == {"w": "b"}


def test_pick_within_a_time_budget(protocol):
    """``budget_s``: only candidates whose median seconds fit the budget compete; a tie among
    them goes to the faster; where none fits, the fastest."""
    means, secs = [30.00, 30.80, 30.75, 29.00], [4.9, 5.4, 4.6, 1.0]
    assert protocol.pick(means, secs) == 1
    assert protocol.pick(means, secs, budget_s=5.0) == 2
    assert protocol.pick(means, secs, budget_s=5.0, tie_db=1.8) == 3  # 29.00: within 1.8 dB
    assert protocol.pick(means, secs, budget_s=4.7, tie_db=0.05) == 2
    assert protocol.pick(means, secs, budget_s=0.5) == 3  # none fits: the fastest
    for bad in (0, -1.0):
        with pytest.raises(ValueError, match="budget_s needs"):
            protocol.pick(means, secs, budget_s=bad)
    with pytest.raises(ValueError, match="budget_s needs"):
        protocol.pick(means, None, budget_s=5.0)
    rows, cands, folds, secs_of = _two_candidates(4.5, 5.5)
    res = protocol.cross_validate(rows, cands, folds, seconds_of=secs_of, budget_s=5.0)
    assert res["chosen_on_all"] == {"w": "a"}
    assert [f["chosen"] for f in res["folds"]] == [{"w": "a"}, {"w": "a"}]
    res = protocol.cross_validate(rows, cands, folds, seconds_of=secs_of, budget_s=6.0)
    assert res["chosen_on_all"] == {"w": "b"}


def test_run_times_a_single_call_with_no_snr_estimate_cached(protocol, monkeypatch):
    """Every timed run starts with the SNR cache empty: a method timed after another on the
    same measurement pays the fit a user's single call pays."""
    import numpy as np

    import tensor_cosdi as tc
    from tensor_cosdi.solvers import snr as snr_module

    p = tc.studies.make_problem("sd_cassi", "chelsea", shape=(16, 16), n_bands=4, snr_db=30)
    fits = []
    real = snr_module.subspace_gap_tv
    monkeypatch.setattr(snr_module, "subspace_gap_tv",
                        lambda *a, **k: fits.append(1) or real(*a, **k))  # fmt: skip
    monkeypatch.setattr(protocol, "_warm_up", lambda method, options: None)
    quick = {"denoiser": "tv", "warm": "gap_tv", "warm_iter": 2, "max_iter": 2}  # reads the SNR
    for _ in range(2):  # the same measurement twice: the second call would hit the cache
        cube, secs = protocol.run("pnp_gap", p.system, np.asarray(p.measurement), quick)
        assert cube.shape == p.system.cube_shape and secs > 0
    assert len(fits) == 2  # fitted inside each timed call, not read from the cache


def test_cross_validate_keeps_the_default_in_a_tie(protocol):
    scores = {"a": {"s1": 30.0, "s2": 31.0}, "b": {"s1": 30.02, "s2": 31.02}}
    cands = [{"w": "a"}, {"w": "b"}]
    rows = lambda c, scenes: [scores[c["w"]][s] for s in scenes]  # noqa: E731
    folds = (("s1",), ("s2",))
    assert protocol.cross_validate(rows, cands, folds)["chosen_on_all"] == {"w": "b"}
    res = protocol.cross_validate(rows, cands, folds, tie_db=0.05, keep={"w": "a"})
    assert res["chosen_on_all"] == {"w": "a"}
    assert [f["chosen"] for f in res["folds"]] == [{"w": "a"}, {"w": "a"}]


def test_scene_views(protocol):
    assert protocol.scene_view("cloth") == ("cloth", 1.0, None)
    assert protocol.scene_view("cloth@2") == ("cloth", 2.0, None)
    assert protocol.scene_view("cloth~A") == ("cloth", 1.0, "A")
    assert protocol.scene_view("cloth@2~LED-B3") == ("cloth", 2.0, "LED-B3")
    assert protocol.views(("a", "b"), 2) == ("a", "b", "a@2", "b@2")
    assert protocol.views(("a",), None) == ("a",)
    assert protocol.views(("a",), 2, ("A", "LED-B3")) == ("a", "a@2", "a~A", "a~LED-B3")
    for bad in ("cloth@0.5", "cloth@x", "cloth@"):
        with pytest.raises(ValueError, match="zoom after '@'"):
            protocol.scene_view(bad)
    for bad in ("cloth~", "cloth~sun", "cloth@2~a"):
        with pytest.raises(ValueError, match="illuminant after '~'"):
            protocol.scene_view(bad)


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--cv", "otd", "--grid", '{"lam": [0.1]}', "--zoom", "0.5"], "--zoom must be"),
        (["--cv", "otd", "--grid", '{"lam": [0.1]}', "--tie-db", "-1"], "--tie-db must be"),
        (["--cv", "otd", "--grid", '{"lam": [0.1]}', "--light", "A,sun"], "--light: 'sun'"),
        (["--cv", "otd", "--grid", '{"lam": [0.1]}', "--keep", '{"lam": 0.1}'], "--keep needs"),
        (
            ["--cv", "otd", "--grid", '{"lam": [0.1]}', "--tie-db", "0.1", "--keep", "{lam"],
            "--keep must be a JSON object",
        ),
        (
            ["--cv", "otd", "--grid", '{"lam": [0.1]}', "--tie-db", "0.1", "--keep", '{"lam": 3}'],
            "is not a candidate",
        ),
        (
            ["--cv", "otd", "--grid", '{"lam": [0.1]}', "--tie-db", "0.1", "--no-slower"],
            "--no-slower needs --keep",
        ),
        (["--cv", "otd", "--grid", '{"lam": [0.1]}', "--budget-s", "0"], "--budget-s needs"),
        (["--methods", "otd", "--budget-s", "5"], "--budget-s needs --cv"),
        (["--methods", "otd,gap_tv", "--versus", "otd:pnp_gap"], "--versus: 'otd:pnp_gap'"),
        (["--methods", "otd,gap_tv", "--versus", "otd"], "must be METHOD:OTHER"),
    ],
)
def test_real_spectra_refuses_bad_cv_options(argv, message, benchmark_script, tmp_path):
    mod = benchmark_script("real_spectra")
    with pytest.raises(SystemExit, match=message):
        mod.main([*argv, "--out", str(tmp_path)])
    assert not any(tmp_path.iterdir())  # refused before any run or file


def test_positive_numbers_parses_a_list_and_refuses_anything_else_by_flag(protocol):
    assert protocol.positive_numbers("0.1,0.05,3", "--lams") == [0.1, 0.05, 3.0]
    for bad in ("", "0.1,", "x", "0", "-0.1", "nan", "inf", "0.1;0.2"):
        with pytest.raises(SystemExit, match="--lams takes finite numbers > 0"):
            protocol.positive_numbers(bad, "--lams")


@pytest.mark.parametrize(
    "options, message",
    [
        ("[1]", "--options must be a JSON object"),
        ("{n_filters", "--options must be a JSON object"),
        ('{"n_filters": 0}', "n_filters must be an integer ≥ 1"),
        ('{"nfilters": 1}', r"unknown option\(s\) \['nfilters'\]"),
        ('{"n_filters": "../x"}', "n_filters must be an integer"),
    ],
)
def test_otd_lam_systems_refuses_bad_options_before_any_run(
    benchmark_script, options, message, tmp_path
):
    mod = benchmark_script("otd_lam_systems")
    out = tmp_path / "lam.md"
    with pytest.raises(SystemExit, match=message):
        mod.main(["--system", "cs2li", "--options", options, "--out", str(out)])
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--margins", "0,-0.1"], "--margins and --against take numbers ≥ 0"),
        (["--margins", "x"], "--margins and --against take numbers ≥ 0"),
        (["--against", "nan"], "--margins and --against take numbers ≥ 0"),
        (["--masks", "tsa,kaist"], "--masks takes a comma list of tsa, random"),
        (["--scenes-per-fold", "0"], "--scenes-per-fold must be ≥ 1"),
        (["--light", "A,daylight"], "--light: .*must be a key of colour.SDS_ILLUMINANTS"),
    ],
)
def test_pan_spectrum_pick_refuses_bad_options_before_any_run(
    benchmark_script, argv, message, tmp_path
):
    mod = benchmark_script("pan_spectrum_pick")
    with pytest.raises(SystemExit, match=message):
        mod.main([*argv, "--out", str(tmp_path)])
    assert not any(tmp_path.iterdir())


def test_pan_spectrum_pick_margin_rule_is_the_library_s(benchmark_script):
    """A margin picks the weighted stage exactly where ``keeps_fitted`` does; ``inf`` always."""
    mod = benchmark_script("pan_spectrum_pick")
    row = {"misfit_flat": 2.0, "misfit_fitted": 2.1}  # 5 % above
    assert [mod.kept(row, m) for m in (0.0, 0.04, 0.05, 0.2, float("inf"))] == [
        False, False, True, True, True
    ]  # fmt: skip
    assert mod.kept({"misfit_flat": 2.0, "misfit_fitted": 1.0}, 0.0)


def test_denoiser_weights_refuses_an_unknown_illuminant(benchmark_script, tmp_path):
    pytest.importorskip("torch")
    mod = benchmark_script("denoiser_weights")
    weights = tmp_path / "w.pt"
    weights.write_bytes(b"")
    with pytest.raises(SystemExit, match="--illuminant: unknown 'a'"):
        mod.main([str(weights), "--illuminant", "a", "--out", str(tmp_path / "dw.md")])
    assert not (tmp_path / "dw.md").exists()


def test_machine_names_the_cpu_and_whether_it_runs_bfloat16_natively(protocol, monkeypatch):
    """A time means little without the CPU: ``pnp_fast`` runs its network in bfloat16 only
    where the CPU runs it natively, about twice as fast."""
    import sys

    import tensor_cosdi.learn.spectral_net as sn

    line = protocol.provenance()["machine"]
    assert protocol.cpu_model() in line and "CPUs" in line
    monkeypatch.setitem(sys.modules, "torch", sys.modules.get("torch") or object())
    for native, said in ((True, ", bfloat16 native"), (False, ", no native bfloat16")):
        monkeypatch.setattr(sn, "bfloat16_is_fast", lambda native=native: native)
        assert protocol.machine().endswith(said)
    monkeypatch.delitem(sys.modules, "torch")
    assert "bfloat16" not in protocol.machine()  # torch not loaded: nothing said


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--within-db", "1"], "--within-db and --budget-s go together"),
        (["--budget-s", "5"], "--within-db and --budget-s go together"),
        (["--within-db", "0", "--budget-s", "5"], "--within-db must be a positive number"),
        (["--within-db", "1", "--budget-s", "nan"], "--budget-s must be a positive number"),
        (["--reference", "missing.pt"], "reference weights not found"),
    ],
)
def test_denoiser_weights_refuses_a_bad_budget_question_or_reference(
    benchmark_script, extra, message, tmp_path
):
    pytest.importorskip("torch")
    mod = benchmark_script("denoiser_weights")
    weights = tmp_path / "w.pt"
    weights.write_bytes(b"")
    if "--reference" in extra:
        extra = ["--reference", str(tmp_path / extra[1])]
    with pytest.raises(SystemExit, match=message):
        mod.main([str(weights), *extra, "--out", str(tmp_path / "dw.md")])
    assert not (tmp_path / "dw.md").exists()


def test_denoiser_weights_verdict_is_computed_from_the_means_and_the_seconds(benchmark_script):
    mod = benchmark_script("denoiser_weights")
    snrs = [None, 30.0]
    assert "candidate replaces the reference (noiseless +0.00 dB, 30 dB +0.10 dB)" in mod.verdict(
        "candidate", [30.0, 28.1], [30.0, 28.0], snrs, [9.0]
    )
    assert "does not replace" in mod.verdict("candidate", [30.0, 27.9], [30.0, 28.0], snrs, [1.0])
    line = mod.verdict("candidate", [31.21, 29.65], [32.24, 30.28], snrs, [5.0, 6.8, 5.9], 1, 5)
    assert "is not within 1 dB" in line and "(5.9 s) exceeds the 5-s budget" in line
    line = mod.verdict("candidate", [31.5, 29.9], [32.24, 30.28], snrs, [4.0, 5.0, 6.0], 1, 5)
    assert "is within 1 dB" in line and "(5.0 s) fits the 5-s budget" in line


def test_real_spectra_versus_lines_are_computed_from_the_rows(benchmark_script):
    """``--versus A:B``: a line for ``A`` against ``B`` over every scene and condition, from the
    stored PSNRs, beside the lines against the reference."""
    import argparse

    mod = benchmark_script("real_spectra")
    psnr = {("plain_gap_tv", "a"): 25.0, ("plain_gap_tv", "b"): 25.0, ("otd", "a"): 27.0,
            ("otd", "b"): 24.0, ("dcosnet", "a"): 26.0, ("dcosnet", "b"): 26.5}  # fmt: skip

    class Store:
        def ensure(self, *args, **kwargs):
            pass

        def get(self, scene, snr, mask, method, options):
            return {"psnr": psnr[method, scene], "ssim": 0.5, "sam": 9.0, "seconds": 1.0}

    args = argparse.Namespace(
        methods="plain_gap_tv,otd,dcosnet", options="{}", scenes="a,b", snr="none",
        masks="tsa", versus="dcosnet:otd",
    )  # fmt: skip
    text = mod.report(args, Store(), None)
    assert "* `otd` against `plain_gap_tv`, per scene and condition: above it in 1 of 2 cases " \
        "(-1.00 to +2.00 dB, mean +0.50)." in text  # fmt: skip
    assert "* `dcosnet` against `otd`, per scene and condition: above it in 1 of 2 cases " \
        "(-1.00 to +2.50 dB, mean +0.75)." in text  # fmt: skip


def test_real_spectra_loads_torch_only_for_a_learned_method(benchmark_script):
    """Stored runs of a learned method still get the machine's bfloat16 line: torch is loaded
    for it (and only for it) before the results are written."""
    pytest.importorskip("torch")
    import sys

    mod = benchmark_script("real_spectra")
    assert mod._load_torch_if_needed(["plain_gap_tv", "otd", "gap_tv"]) is False
    assert mod._load_torch_if_needed(["otd", "pnp_fast+bf16"]) is True
    assert "torch" in sys.modules
