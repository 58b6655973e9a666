"""Fault injection: a full disk or an I/O error at any step of a save leaves what was on disk
before exactly as it was, and no temporary files behind (issue: nothing lost)."""

import errno
import hashlib
import os
from pathlib import Path

import numpy as np
import pytest

import tensor_cosdi as tc
from tensor_cosdi.io import _atomic, save_bundle, write_frames
from tensor_cosdi.io.files import write_cube

CUBE = np.random.default_rng(0).random((8, 6, 4)).astype(np.float32)
WL = np.linspace(450.0, 650.0, 4)


def _digest(folder: Path) -> dict:
    """``{name: sha256}`` of every file in ``folder`` (hidden temporaries included)."""
    return {
        p.name: hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(folder.iterdir())
        if p.is_file()
    }


def _half_written(monkeypatch, code):
    """The step right after the data were written fails as a full disk would: the temporary
    file is cut to half its size and the call raises."""
    real = os.chmod

    def chmod(path, mode, *a, **k):
        size = os.path.getsize(path)
        with open(path, "r+b") as f:
            f.truncate(size // 2)
        raise OSError(code, os.strerror(code), str(path))

    monkeypatch.setattr(_atomic.os, "chmod", chmod)
    return real


def _fail(monkeypatch, name, code):
    def boom(*a, **k):
        raise OSError(code, os.strerror(code))

    monkeypatch.setattr(_atomic.os, name, boom)


FAULTS = {
    "disk full while writing": lambda mp: _half_written(mp, errno.ENOSPC),
    "I/O error on fsync": lambda mp: _fail(mp, "fsync", errno.EIO),
    "disk full on rename": lambda mp: _fail(mp, "replace", errno.ENOSPC),
}


def _system():
    return tc.systems.SDCASSI(np.ones((8, 6)), n_bands=4, shifts=1)


SAVES = {
    "write_cube .h5": lambda d, ow: write_cube(d / "c.h5", CUBE, WL, overwrite=ow),
    "write_cube .npz": lambda d, ow: write_cube(d / "c.npz", CUBE, WL, overwrite=ow),
    "write_cube .mat": lambda d, ow: write_cube(d / "c.mat", CUBE, WL, overwrite=ow),
    "write_cube .tif": lambda d, ow: write_cube(d / "c.tif", CUBE, WL, overwrite=ow),
    "save_bundle .h5": lambda d, ow: save_bundle(
        d / "b.h5", system=_system(), cube=CUBE, overwrite=ow
    ),
    "save_bundle .npz": lambda d, ow: save_bundle(
        d / "b.npz", system=_system(), cube=CUBE, overwrite=ow
    ),
    "write_frames": lambda d, ow: write_frames(CUBE, d, suffix=".npy", overwrite=ow),
}


@pytest.mark.parametrize("fault", sorted(FAULTS))
@pytest.mark.parametrize("save", sorted(SAVES))
def test_a_failed_overwrite_keeps_the_old_files(tmp_path, monkeypatch, save, fault):
    SAVES[save](tmp_path, False)  # the data a user saved earlier
    before = _digest(tmp_path)
    with monkeypatch.context() as mp:
        FAULTS[fault](mp)
        with pytest.raises(OSError) as err:
            SAVES[save](tmp_path, True)
    assert err.value.errno in (errno.ENOSPC, errno.EIO)
    assert _digest(tmp_path) == before  # old files intact, no temporary left


@pytest.mark.parametrize("fault", ["disk full while writing", "I/O error on fsync"])
@pytest.mark.parametrize("save", sorted(SAVES))
def test_a_failed_first_save_leaves_nothing(tmp_path, monkeypatch, save, fault):
    with monkeypatch.context() as mp:
        FAULTS[fault](mp)
        with pytest.raises(OSError):
            SAVES[save](tmp_path, False)
    assert _digest(tmp_path) == {}
    SAVES[save](tmp_path, False)  # and the same save works once the fault is gone
    assert _digest(tmp_path)


def test_a_failed_link_of_a_new_file_leaves_nothing(tmp_path, monkeypatch):
    with monkeypatch.context() as mp:
        _fail(mp, "link", errno.ENOSPC)
        with pytest.raises(OSError):
            write_cube(tmp_path / "c.h5", CUBE, WL)
    assert _digest(tmp_path) == {}
