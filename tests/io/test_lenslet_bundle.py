"""Lenslet grid calibration on the real microscope capture, and bundles that lose nothing."""

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest

import tensor_cosdi as tc
from tensor_cosdi import io

LF = Path(__file__).resolve().parents[2] / ".." / "shared" / "data" / "lenslet_raw_guv"


def _synthetic_flat(pitch, rotation, offset, shape=(160, 150)):
    yy, xx = np.mgrid[0 : shape[0], 0 : shape[1]].astype(float)
    u = np.cos(rotation) * (yy - offset[0]) + np.sin(rotation) * (xx - offset[1])
    v = -np.sin(rotation) * (yy - offset[0]) + np.cos(rotation) * (xx - offset[1])
    return 100 + 1000 * np.cos(np.pi * u / pitch) ** 2 * np.cos(np.pi * v / pitch) ** 2


@pytest.mark.parametrize(
    "pitch, rotation", [(9.7, 0.0), (12.31, 0.02), (15.38, -0.01), (11.3, 0.15), (10.2, -0.3)]
)
def test_lenslet_grid_on_synthetic_flats(pitch, rotation):
    flat = _synthetic_flat(pitch, rotation, (70.3, 66.8))
    grid = io.calibrate_lenslet_grid(flat)
    assert grid.pitch == pytest.approx(pitch, rel=2e-3)
    assert grid.rotation == pytest.approx(rotation, abs=2e-3)
    # the fitted lattice passes through the true lenslet centres
    c = grid.centre(0, 0)
    k = np.linalg.solve(grid.basis.T, c - np.array([70.3, 66.8]))
    assert np.all(np.abs(k - np.round(k)) < 0.02)
    assert np.sqrt(np.mean(grid.residuals**2)) < 0.1


@pytest.mark.skipif(not LF.exists(), reason="../shared/data not present")
def test_lenslet_grid_on_the_real_capture():
    white = io.read_frame(LF / "Radiometry_GUVExperim1.tif")
    dark = io.read_frame(LF / "DarkFrame_GUVExperim1.tif")
    raw = io.read_frame(LF / "Lightfield_GUVExperim1.tif")
    grid = io.calibrate_lenslet_grid(white, dark=dark)
    # 100 µm lenslets over 6.5 µm pixels: 15.38 px
    assert abs(grid.pitch - 100 / 6.5) / (100 / 6.5) < 0.01  # measured 15.399 px (+0.13 %)
    assert abs(grid.rotation) < np.deg2rad(1)  # measured 0.117°
    assert len(grid.residuals) > 700  # 784 discs
    assert np.sqrt(np.mean(grid.residuals**2)) < 0.3  # measured 0.17 px RMS, 0.37 px max
    # the flat's centre view is bright and even: every lenslet's peak lines up with the fitted
    # centre
    views = grid.views(white.astype(float) - dark)
    n = views.shape[0]
    assert n == 15 and views.shape[2:] == (28, 28)
    centre = views[n // 2, n // 2]
    edge = views[0, 0]
    assert centre.mean() > 1.5 * edge.mean()
    assert centre.std() / centre.mean() < 0.25
    # the raw capture cuts into the same (U, V, Ni, Nj) views
    assert grid.views(raw).shape == views.shape


def test_lenslet_errors():
    with pytest.raises(ValueError, match="2-D frame"):
        io.calibrate_lenslet_grid(np.zeros((4, 4, 2)))
    with pytest.raises(ValueError, match="dark frame is as bright"):
        io.calibrate_lenslet_grid(np.ones((64, 64)), dark=np.full((64, 64), 2.0))
    flat = _synthetic_flat(10.0, 0.0, (30, 30), shape=(80, 80))
    grid = io.calibrate_lenslet_grid(flat)
    with pytest.raises(ValueError, match="raw frame shape"):
        grid.views(np.zeros((10, 10)))
    with pytest.raises(ValueError, match="n_views must be odd"):
        grid.views(flat, n_views=8)  # was cut to 7 views without a word
    with pytest.raises(ValueError, match="n_views must be an integer"):
        grid.views(flat, n_views=3.7)
    with pytest.raises(ValueError, match="order must be an integer"):
        grid.views(flat, order=9)
    bad = flat.copy()
    bad[0, 0] = np.nan
    with pytest.raises(ValueError, match="NaN or infinite"):
        grid.views(bad)
    assert grid.views(flat, n_views=3).shape[:2] == (3, 3)
    none = np.zeros((0, 2))
    fields = dict(pitch=10.0, offset=(40.0, 40.0), rotation=0.0, shape=(80, 80), centres=none,
                  indices=none, residuals=np.zeros(0))  # fmt: skip
    for change, match in (({"pitch": 0.0}, "pitch"), ({"rotation": np.nan}, "rotation"),
                          ({"offset": (np.nan, 1.0)}, "offset row"),
                          ({"shape": (-4, 4)}, "shape rows")):  # fmt: skip
        with pytest.raises(ValueError, match=match):
            io.LensletGrid(**{**fields, **change})


SYSTEMS = [
    tc.systems.SDCASSI(
        tc.codes.random_binary((8, 8), rng=0).astype(np.float32),
        n_bands=4,
        shifts=[0, 1.5, 2, 3.25],
    ),
    tc.systems.DualCameraCASSI.example((8, 8, 4)),
    tc.systems.CASSIVSI.example((8, 8, 4), alpha_t=0.75, beta=2),
    tc.systems.CASSDIDFA.example((8, 8, 4, 3), psf_size=3),
    tc.systems.C3SLFI.example((8, 8, 4), views=(2, 2), n_snapshots=3, raw_layout="tiled"),
    tc.systems.C3SLFI.example((4, 4, 4, 2, 2), n_snapshots=2),
    tc.systems.CS2LI.example((8, 8, 4, 6)),
    tc.systems.MuCoSDI.example((8, 8, 4), modality="lf"),
    tc.systems.MuCoSDI.example((8, 8, 4, 4)),
]


@pytest.mark.parametrize("system", SYSTEMS, ids=lambda s: f"{type(s).__name__}{s.cube_shape}")
def test_bundles_round_trip_bit_exactly(tmp_path, system):
    rng = np.random.default_rng(0)
    cube = rng.random(system.cube_shape).astype(np.float32)
    g = np.asarray(system.simulate(cube, snr_db=30, rng=1))
    src = tmp_path / "frame.bin"
    src.write_bytes(b"raw capture")
    path = io.save_bundle(
        tmp_path / "b.npz",
        system=system,
        measurement=g,
        cube=cube,
        depth=np.arange(4.0),
        calibration={"white": np.ones(3), "dark": np.zeros(3, np.uint16)},
        arrays={"note": np.array([1, 2, 3], np.int8)},
        metadata={"exposure_ms": 12.5, "op": "ana"},
        sources=[src],
    )
    assert path.name == "b.npz"
    b = io.load_bundle(path)
    assert np.array_equal(b.measurement, g) and b.measurement.dtype == g.dtype
    assert np.array_equal(b.cube, cube) and b.cube.dtype == np.float32
    assert b.calibration["dark"].dtype == np.uint16 and np.array_equal(b.arrays["note"], [1, 2, 3])
    assert b.metadata == {"exposure_ms": 12.5, "op": "ana"} and b.info["kind"] == "reconstruction"
    assert b.provenance[0]["sha256"] == hashlib.sha256(b"raw capture").hexdigest()
    assert b.info["software"]["tensor_cosdi"] == tc.__version__
    s = b.system
    assert type(s) is type(system) and s.cube_shape == system.cube_shape
    assert np.array_equal(s.wavelengths, system.wavelengths)
    # the rebuilt system is the same linear map, bit for bit
    assert np.array_equal(np.asarray(s.forward(cube)), np.asarray(system.forward(cube)))


def test_bundles_never_overwrite(tmp_path):
    sd = tc.systems.SDCASSI.example((8, 8, 4))
    p = io.save_bundle(tmp_path / "x.npz", system=sd)
    before = p.read_bytes()
    with pytest.raises(FileExistsError, match="overwrite=True"):
        io.save_bundle(p, system=sd, measurement=np.zeros(sd.measurement_shape))
    assert p.read_bytes() == before and not list(tmp_path.glob(".x.npz*"))
    io.save_bundle(p, system=sd, measurement=np.zeros(sd.measurement_shape), overwrite=True)
    assert io.load_bundle(p).info["kind"] == "measurement"


def test_bundle_errors(tmp_path):
    sd = tc.systems.SDCASSI.example((8, 8, 4))
    with pytest.raises(ValueError, match="measurement shape \\(3, 3\\) does not match"):
        io.save_bundle(tmp_path / "a.npz", system=sd, measurement=np.zeros((3, 3)))
    with pytest.raises(ValueError, match="JSON-serialisable"):
        io.save_bundle(tmp_path / "a.npz", metadata={"x": object()})
    with pytest.raises(ValueError, match="separable"):
        io.save_bundle(
            tmp_path / "a.npz",
            system=tc.systems.C3SLFI.separable(np.eye(2, 4) * 0 + 0.5, (4, 4, 4)),
        )
    np.savez(tmp_path / "plain.npz", a=np.ones(2))
    with pytest.raises(ValueError, match="not a tensor_cosdi bundle"):
        io.load_bundle(tmp_path / "plain.npz")
    (tmp_path / "junk.npz").write_bytes(b"junk")
    with pytest.raises(ValueError, match="junk.npz: not a readable"):
        io.load_bundle(tmp_path / "junk.npz")
    with pytest.raises(FileNotFoundError, match="source file not found"):
        io.save_bundle(tmp_path / "a.npz", sources=[tmp_path / "missing.tif"])
    assert not (tmp_path / "a.npz").exists()
    for name in ("a", "a.mat"):  # a name is never changed behind the user's back
        with pytest.raises(ValueError, match="a bundle is an .npz or .h5/.hdf5 file"):
            io.save_bundle(tmp_path / name, system=sd)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["junk.npz", "plain.npz"]


@pytest.mark.parametrize("layout", ["interleaved", "tiled"])
def test_rectified_lenslet_image_matches_the_system_layouts(layout):
    from tensor_cosdi.operators import LightFieldLayout

    flat = _synthetic_flat(9.6, 0.01, (40.2, 38.7), shape=(100, 100))
    grid = io.calibrate_lenslet_grid(flat)
    raw = flat * np.random.default_rng(0).random(flat.shape)
    views = grid.views(raw, 5)  # (U, V, Ni, Nj)
    img = grid.rectified(raw, 5, layout=layout)
    U, V, Ni, Nj = views.shape
    lf = views.transpose(2, 3, 0, 1)[:, :, None]  # (Ni, Nj, 1, U, V): the 5-D light field, one band
    expect = np.asarray(LightFieldLayout((Ni, Nj, 1, U, V), layout).forward(lf))[..., 0]
    assert img.shape == (Ni * U, Nj * V) and np.array_equal(img, expect)
    # one rectified frame per band is exactly a Mu-CoSDI "lf" measurement of that shape
    mu = tc.systems.MuCoSDI(
        np.ones((Ni * U, Nj * V + 1)), n_bands=2, modality="lf", views=(U, V), raw_layout=layout
    )
    assert io.frames_to_measurement(mu, img).shape == mu.measurement_shape


def test_load_bundle_verifies_checksum_shapes_and_values(tmp_path):
    from tensor_cosdi.io import load_bundle, save_bundle
    from tensor_cosdi.systems import SDCASSI

    sd = SDCASSI(np.random.default_rng(0).random((4, 5)), n_bands=3)
    g = np.random.default_rng(1).random(sd.measurement_shape)
    path = save_bundle(tmp_path / "b.npz", system=sd, measurement=g)
    with np.load(path) as z:
        data = {k: z[k] for k in z.files}

    def forged(name, **change):
        d = {**data, **change}
        np.savez(tmp_path / name, **d)
        return tmp_path / name

    with pytest.raises(ValueError, match="SHA-256"):
        load_bundle(forged("edit.npz", measurement=g * 2))
    doc = json.loads(str(data["__bundle__"]))
    # a format-1 bundle (no checksums) is still checked for shape and values
    doc.pop("sha256"), doc.pop("document_sha256")
    doc["format_version"] = 1
    with pytest.raises(ValueError, match="does not match the system's"):
        load_bundle(forged("shape.npz", measurement=g[:, :3], __bundle__=np.array(json.dumps(doc))))
    bad = g.copy()
    bad[0, 0] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        load_bundle(forged("nan.npz", measurement=bad, __bundle__=np.array(json.dumps(doc))))
    with pytest.raises(ValueError, match="lists arrays"):
        load_bundle(forged("extra.npz", stray=np.ones(2), __bundle__=np.array(json.dumps(doc))))
    np.testing.assert_array_equal(load_bundle(path).measurement, g)
