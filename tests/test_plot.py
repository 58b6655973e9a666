"""tensor_cosdi.plot: what each function draws (images, titles, labels, lines), not just that it
ran; the exposure that keeps dark scenes visible; `tensor-cosdi preview`."""

import numpy as np
import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import tensor_cosdi as tc  # noqa: E402
from tensor_cosdi import plot  # noqa: E402

WL = np.linspace(450, 650, 6)


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def _cube(level=1.0):
    rng = np.random.default_rng(0)
    return level * rng.random((12, 10, 6))


def test_preview_exposes_dark_scenes_instead_of_showing_black():
    dark = _cube(0.02)
    ax = plot.preview(dark, WL)
    img = ax.get_images()[0].get_array()
    assert img.shape == (12, 10, 3) and float(np.mean(img)) > 0.3
    assert "÷" in ax.get_title()
    raw = plot.preview(dark, WL, percentile=None).get_images()[0].get_array()
    assert float(np.mean(raw)) < float(np.mean(img)) / 2  # what the exposure rescued
    assert plot.white_point(dark) == pytest.approx(np.percentile(dark.mean(axis=2), 99.5))


def test_bands_montage_is_labelled_in_nm_on_one_scale():
    fig = plot.bands(_cube(), WL)
    titles = [ax.get_title() for ax in fig.axes if ax.get_images()]
    assert titles == [f"{w:.0f} nm" for w in WL]
    clims = {ax.get_images()[0].get_clim() for ax in fig.axes if ax.get_images()}
    assert len(clims) == 1  # one grey scale for every band
    assert any(ax.get_ylabel() == "intensity" for ax in fig.axes)  # the colour bar


def test_spectra_plot_the_cube_values_and_the_reference():
    cube, ref = _cube(), _cube() * 0.5
    ax = plot.spectra(cube, WL, [(1, 2), (5, 6)], reference=ref)
    lines = ax.get_lines()
    assert len(lines) == 4 and ax.get_xlabel() == "wavelength (nm)"
    np.testing.assert_allclose(lines[0].get_ydata(), cube[1, 2])
    np.testing.assert_allclose(lines[1].get_ydata(), ref[1, 2])
    np.testing.assert_allclose(lines[2].get_xdata(), WL)
    with pytest.raises(ValueError, match="point row must be an integer ≥ 0 and ≤ 11, got 50"):
        plot.spectra(cube, WL, [(50, 0)])


def test_compare_titles_carry_psnr_and_error_maps_the_difference():
    truth = _cube()
    est = truth + 0.05
    fig = plot.compare(truth, {"a": est, "b": truth}, WL)
    titles = [ax.get_title() for ax in fig.axes]
    psnr = tc.metrics.psnr(truth, est, data_range=float(truth.max()))
    assert any(t.startswith("a\n") and f"{psnr:.2f} dB" in t for t in titles)
    err = next(ax for ax in fig.axes if ax.get_title() == "a: |error|").get_images()[0]
    np.testing.assert_allclose(err.get_array(), np.full((12, 10), 0.05), atol=1e-12)
    with pytest.raises(ValueError, match="does not match the truth"):
        plot.compare(truth, {"x": truth[:5]}, WL)


def test_depth_and_convergence():
    d = np.arange(20.0).reshape(4, 5)
    d[0, 0] = np.nan
    ax = plot.depth(d, label="height (mm)")
    img = ax.get_images()[0].get_array()
    assert img.mask[0, 0] and img[1, 1] == 6.0
    assert any(a.get_ylabel() == "height (mm)" for a in ax.figure.axes)
    p = tc.studies.make_problem("sd_cassi", "chelsea", shape=(16, 16), n_bands=4, rng=0)
    res = tc.reconstruct(p.system, p.measurement, "gap_tv", max_iter=5)
    ax = plot.convergence(res)
    np.testing.assert_allclose(ax.get_lines()[0].get_ydata(), res.history["residual"])
    assert ax.get_xlabel() == "iteration" and ax.get_title() == "gap_tv"


def test_cli_preview_writes_a_labelled_png_and_never_overwrites(tmp_path, capsys):
    from tensor_cosdi import cli
    from tensor_cosdi.io import write_cube

    write_cube(tmp_path / "c.h5", _cube(0.05).astype(np.float32), WL)
    assert cli.main(["preview", str(tmp_path / "c.h5"), "--points", "1,2", "3,4"]) == 0
    png = tmp_path / "c_preview.png"
    img = plt.imread(png)
    assert img.shape[0] > 200 and img.shape[1] > 2 * img.shape[0] * 0.9  # preview + spectra
    assert cli.main(["preview", str(tmp_path / "c.h5")]) == 2
    assert "--force" in capsys.readouterr().err
    np.save(tmp_path / "n.npy", _cube())
    assert cli.main(["preview", str(tmp_path / "n.npy")]) == 2
    assert "pass --wavelengths" in capsys.readouterr().err
    assert cli.main(["preview", str(tmp_path / "n.npy"), "--wavelengths", "450:650"]) == 0


def test_study_draws_one_line_per_group_averaging_repeats():
    recs = [
        {"n_filters": f, "transmittance": k, "seed": s, "psnr": 20 + f + k + s, "cond": 10.0**f}
        for k in (0.25, 0.5)
        for f in (4, 1, 2)  # unsorted on purpose
        for s in (0, 1)
    ]
    ax = plot.study(recs, "n_filters", "psnr", by="transmittance")
    lines = ax.get_lines()
    assert len(lines) == 2
    np.testing.assert_allclose(lines[0].get_xdata(), [1, 2, 4])
    np.testing.assert_allclose(lines[0].get_ydata(), [21.75, 22.75, 24.75])  # mean of seeds
    assert [t.get_text() for t in ax.get_legend().get_texts()] == [
        "transmittance = 0.25",
        "transmittance = 0.5",
    ]
    assert ax.get_xlabel() == "n_filters" and ax.get_ylabel() == "psnr"
    log = plot.study(recs, "n_filters", "cond", logy=True)
    assert log.get_yscale() == "log" and len(log.get_lines()) == 1 and log.get_legend() is None
    with pytest.raises(ValueError, match="record 0 has no 'depth'"):
        plot.study(recs, "n_filters", "depth")
    with pytest.raises(ValueError, match="at least one record"):
        plot.study([], "a", "b")


_C = np.random.default_rng(1).random((6, 5, 4))
_W = np.linspace(450, 650, 4)


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: plot.preview(_C + 1j, _W), "cube must hold real numbers, got dtype complex128"),
        (lambda: plot.preview(np.where(_C > 0.9, np.nan, _C), _W), "cube holds 9 NaN or inf"),
        (lambda: plot.preview(_C, _W.reshape(2, 2)), "wavelengths must be 1-D, got shape"),
        (lambda: plot.preview(_C, _W[::-1]), "wavelengths must be non-empty and strictly inc"),
        (lambda: plot.preview(_C, _W, percentile="50"), "percentile must be a finite number"),
        (lambda: plot.preview(_C, _W, ax=3), "ax must be a matplotlib Axes"),
        (lambda: plot.bands(np.where(_C > 0.5, np.inf, _C), _W), "NaN or infinite values"),
        (lambda: plot.bands(_C, _W, columns=0), "columns must be an integer ≥ 1, got 0"),
        (lambda: plot.bands(_C, _W, max_bands=2.5), "max_bands must be an integer ≥ 1"),
        (lambda: plot.bands(_C, _W, fig="x"), "fig must be a matplotlib Figure or SubFigure"),
        (lambda: plot.spectra(_C, _W, [(1.7, 2)]), "point row must be an integer"),
        (lambda: plot.spectra(_C, _W, [(1, True)]), "point column must be an integer"),
        (lambda: plot.spectra(_C, _W, (1, 2)), "point 1 is not a \\(row, column\\) pair"),
        (lambda: plot.spectra(_C, _W, []), "got none"),
        (lambda: plot.spectra(_C, _W, [(1, 2)], reference=_C * np.nan), "reference holds 120"),
        (lambda: plot.compare(_C, [_C], _W), "cubes must be a dict of name"),
        (lambda: plot.compare(_C, {"a": _C * np.nan}, _W), "reconstruction 'a' holds 120"),
        (lambda: plot.depth(np.zeros((4, 4)) + 1j), "depth_map must hold real numbers"),
        (lambda: plot.convergence({"residual": []}), "must be a non-empty 1-D sequence"),
        (lambda: plot.convergence({"residual": [0.5, -1]}), "must be ≥ 0 \\(a relative norm\\)"),
        (
            lambda: plot.convergence({"residual": [1, 0.5], "change": [1]}),
            "history\\['change'\\] has 1 entries for 2 residuals",
        ),
        (lambda: plot.study([{"x": 1, "y": "a"}], "x", "y"), "record 0: 'y' must be a number"),
        (
            lambda: plot.study([{"x": 1, "y": 1.0}, {"x": 2, "y": 0.0}], "x", "y", logy=True),
            "record 1: 'y' must be a number > 0 \\(logy\\)",
        ),
        (
            lambda: plot.study([{"x": 1, "y": 1.0}, {"x": "a", "y": 2.0}], "x", "y"),
            "the 'x' values cannot be ordered: they mix \\['int', 'str'\\]",
        ),
        (lambda: plot.study([3], "x", "y"), "record 0 must be a dict, got int"),
        (lambda: plot.study("xy", "x", "y"), "records must be a sequence of dicts, got str"),
    ],
)
def test_bad_input_is_a_one_line_error_naming_it(call, message):
    with pytest.raises(ValueError, match=message) as err:
        call()
    assert "\n" not in str(err.value)


def test_a_diverged_run_is_still_drawn():
    """NaN and inf in a trace are what a diverged run looks like: drawn, not refused."""
    ax = plot.convergence({"residual": [1.0, np.inf, np.nan]})
    assert np.isinf(ax.get_lines()[0].get_ydata()[1])
