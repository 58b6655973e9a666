"""Zarr stores: written through xarray (dims, wavelength coordinate, metadata), atomically and
never over an existing store unasked; read from the store's own regular files only, numeric
arrays through standard codecs only, and no chunk decoded past its declared size."""

import json
import os
import zlib

import numpy as np
import pytest

from tensor_cosdi.io.files import read_array, read_cube, write_cube

zarr = pytest.importorskip("zarr")
xr = pytest.importorskip("xarray")

WL = np.linspace(450.0, 650.0, 5)


def _cube():
    return np.random.default_rng(0).random((6, 7, 5)).astype(np.float32)


def test_a_cube_round_trips_and_opens_in_xarray(tmp_path):
    cube = _cube()
    path = write_cube(tmp_path / "c.zarr", cube, WL, metadata={"scene": "x"})
    assert path.is_dir()
    back, wl = read_cube(path)
    np.testing.assert_array_equal(back, cube)
    assert back.dtype == np.float32
    np.testing.assert_allclose(wl, WL)
    ds = xr.open_zarr(path, consolidated=False)
    assert ds["cube"].dims == ("rows", "columns", "wavelength")
    assert ds["wavelength"].attrs["units"] == "nm"
    assert json.loads(ds.attrs["metadata"]) == {"scene": "x"}
    np.testing.assert_array_equal(read_array(f"{path}", "cube"), cube)


def test_an_existing_store_is_replaced_only_when_asked_and_nothing_is_left_behind(tmp_path):
    path = write_cube(tmp_path / "c.zarr", _cube(), WL)
    with pytest.raises(FileExistsError, match="overwrite=True"):
        write_cube(path, 2 * _cube(), WL)
    np.testing.assert_array_equal(read_cube(path)[0], _cube())  # untouched
    write_cube(path, 2 * _cube(), overwrite=True)
    back, wl = read_cube(path)
    np.testing.assert_array_equal(back, 2 * _cube())
    assert wl is None  # the new store, not a mix of old and new
    (tmp_path / "f.zarr").write_text("a file")
    with pytest.raises(FileExistsError, match="not a folder"):
        write_cube(tmp_path / "f.zarr", _cube(), overwrite=True)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.zarr", "f.zarr"]


def test_links_devices_and_fifos_inside_a_store_are_refused(tmp_path):
    path = write_cube(tmp_path / "c.zarr", _cube(), WL)
    chunk = next(p for p in (path / "cube").rglob("*") if p.is_file() and p.name != "zarr.json")
    secret = tmp_path / "secret.bin"
    secret.write_bytes(chunk.read_bytes())
    chunk.unlink()
    chunk.symlink_to(secret)  # a chunk that is another file
    with pytest.raises(ValueError, match="symbolic link"):
        read_cube(path)
    chunk.unlink()
    os.mkfifo(chunk)  # would block a reader forever
    with pytest.raises(ValueError, match="not a regular file"):
        read_cube(path)


def _v2_store(folder, dtype="<f8", filters=None, compressor=None, chunk=b"", chunks=(4,)):
    folder.mkdir()
    meta = {
        "zarr_format": 2, "shape": [4], "chunks": list(chunks), "dtype": dtype,
        "compressor": compressor, "fill_value": 0, "order": "C", "filters": filters,
    }  # fmt: skip
    (folder / ".zarray").write_text(json.dumps(meta))
    (folder / "0").write_bytes(chunk)
    return folder


def test_a_pickle_codec_or_object_values_are_refused_before_decoding(tmp_path):
    store = _v2_store(tmp_path / "p.zarr", filters=[{"id": "pickle"}], chunk=b"\x80\x04K\x01.")
    with pytest.raises(ValueError, match="pickle"):
        read_array(store)
    obj = _v2_store(tmp_path / "o.zarr", dtype="|O", filters=[{"id": "vlen-utf8"}])
    with pytest.raises(ValueError, match="vlen-utf8|only numbers"):
        read_array(obj)


def test_a_compression_bomb_is_refused_before_it_inflates(tmp_path):
    bomb = zlib.compress(b"\0" * (2 << 20), 9)  # 2 MiB of zeros in ≈ 2 KiB, for 32 bytes
    store = _v2_store(tmp_path / "b.zarr", compressor={"id": "zlib", "level": 9}, chunk=bomb)
    with pytest.raises(ValueError, match="compression bomb"):
        read_array(store)
    # a Zstandard chunk of the writer's own format, swapped for a bomb
    from numcodecs import Zstd

    path = write_cube(tmp_path / "z.zarr", _cube(), WL)
    chunk = next(p for p in (path / "cube").rglob("*") if p.is_file() and p.name != "zarr.json")
    chunk.write_bytes(Zstd(level=3).encode(np.zeros(64 << 20, np.uint8)))
    with pytest.raises(ValueError, match="compression bomb"):
        read_cube(path)


def test_declared_sizes_are_bounded_before_reading(tmp_path):
    path = write_cube(tmp_path / "c.zarr", _cube(), WL)
    with pytest.raises(ValueError, match="limit"):
        read_cube(path, max_bytes=100)
    huge = _v2_store(tmp_path / "h.zarr", compressor={"id": "zlib", "level": 1},
                     chunk=zlib.compress(b"\0" * 32), chunks=(10**9,))  # fmt: skip
    with pytest.raises(ValueError, match="declares chunks"):
        read_array(huge)


def test_a_plain_array_store_and_a_missing_store(tmp_path):
    z = zarr.create_array(tmp_path / "a.zarr", shape=(3, 4), dtype="f8")
    z[:] = np.arange(12.0).reshape(3, 4)
    np.testing.assert_array_equal(read_array(tmp_path / "a.zarr"), np.arange(12.0).reshape(3, 4))
    with pytest.raises(FileNotFoundError, match="Zarr store"):
        read_array(tmp_path / "none.zarr")


def test_the_cli_shows_and_previews_a_store(tmp_path, capsys):
    from tensor_cosdi import cli

    path = write_cube(tmp_path / "c.zarr", _cube(), WL)
    assert cli.main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "Zarr store" in out and "cube: (6, 7, 5)" in out and "5 bands, 450–650 nm" in out
    assert cli.main(["preview", str(path), "--out", str(tmp_path / "c.png")]) == 0
    assert (tmp_path / "c.png").stat().st_size > 0
    assert cli.main(["info", str(tmp_path / "none.zarr")]) == 2
    assert "not found" in capsys.readouterr().err


def test_shuffled_and_checksummed_stores_read_and_an_oversized_chunk_file_is_refused(tmp_path):
    from zarr.codecs.numcodecs import Shuffle

    with pytest.warns(UserWarning, match="not in the Zarr version 3 specification"):
        shuffle = Shuffle(elementsize=8)
    z = zarr.create_array(
        tmp_path / "s.zarr", shape=(64,), dtype="f8", filters=None,
        compressors=[shuffle, zarr.codecs.ZstdCodec(), zarr.codecs.Crc32cCodec()],
    )  # fmt: skip
    z[:] = np.arange(64.0)
    with pytest.warns(UserWarning, match="not in the Zarr version 3"):  # zarr's, on opening
        back = read_array(tmp_path / "s.zarr")
    np.testing.assert_array_equal(back, np.arange(64.0))
    raw = zarr.create_array(tmp_path / "r.zarr", shape=(8,), dtype="f8", compressors=None)
    raw[:] = 1.0
    files = (tmp_path / "r.zarr").rglob("*")
    chunk = next(p for p in files if p.is_file() and p.name != "zarr.json")
    chunk.write_bytes(b"\0" * (1 << 20))  # 1 MiB stored for a 64-byte chunk
    with pytest.raises(ValueError, match="on disk for a chunk of 64"):
        read_array(tmp_path / "r.zarr")
