"""Atomic, durable file writes: a temporary file in the same folder, written, flushed and
fsynced, then linked (refusing an existing name) or renamed over the target, and the folder
fsynced — a reader sees the old file or the new one, never a torn one."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from ..validate import flag, output_folder


def _fsync_path(path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _umask() -> int:
    old = os.umask(0o022)
    os.umask(old)
    return old


def atomic_write(path, write, *, overwrite: bool = False, suffix: str | None = None) -> Path:
    """Write ``path`` through ``write(tmp_path)`` atomically; returns ``path``.

    ``write`` receives the path of a fresh temporary file in the target's
    folder (with the target's suffix, or ``suffix``) and must write the whole
    file there.  Without ``overwrite`` an existing ``path`` is a
    ``FileExistsError`` (checked before writing and, atomically, at the end);
    with it, the old file is replaced only once the new one is complete.
    """
    overwrite = flag("overwrite", overwrite)  # "no" is not False: never a guess about a file
    p = Path(path)
    output_folder(p)
    if p.is_dir():
        raise IsADirectoryError(f"{p} is a folder; give the name of a file to write")
    if p.exists() and not overwrite:
        raise FileExistsError(f"{p} exists; pass overwrite=True (CLI: --force) to replace it")
    fd, tmp = tempfile.mkstemp(suffix=suffix or p.suffix, dir=p.parent, prefix=f".{p.name}.")
    os.close(fd)
    try:
        write(tmp)
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; a saved file follows the umask
        _fsync_path(tmp)
        if overwrite:
            os.replace(tmp, p)
        else:
            os.link(tmp, p)  # atomic: fails if someone created p meanwhile
            os.unlink(tmp)
        _fsync_path(p.parent)
    except FileExistsError:
        os.unlink(tmp)
        raise FileExistsError(
            f"{p} exists; pass overwrite=True (CLI: --force) to replace it"
        ) from None
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return p


def atomic_write_many(items, *, overwrite: bool = False) -> list[Path]:
    """Write several files so that none replaces an old one before all new ones are complete.

    ``items``: ``(path, write)`` pairs as for :func:`atomic_write`.  Every
    file is first written and fsynced under a temporary name; only then are
    they renamed into place (and the folders fsynced).  A failure while
    writing (full disk, I/O error) removes the temporaries and leaves every
    existing file as it was.
    """
    overwrite = flag("overwrite", overwrite)
    items = [(Path(p), w) for p, w in items]
    for p, _ in items:
        output_folder(p)
        if p.is_dir():
            raise IsADirectoryError(f"{p} is a folder; give the name of a file to write")
        if p.exists() and not overwrite:
            raise FileExistsError(f"{p} exists; pass overwrite=True (CLI: --force) to replace it")
    temps = []
    try:
        for p, write in items:
            fd, tmp = tempfile.mkstemp(suffix=p.suffix, dir=p.parent, prefix=f".{p.name}.")
            os.close(fd)
            temps.append(tmp)
            write(tmp)
            os.chmod(tmp, 0o666 & ~_umask())
            _fsync_path(tmp)
        for (p, _), tmp in zip(items, temps):
            if overwrite:
                os.replace(tmp, p)
            else:
                os.link(tmp, p)
                os.unlink(tmp)
        for folder in {p.parent for p, _ in items}:
            _fsync_path(folder)
    except BaseException:
        for tmp in temps:
            if os.path.exists(tmp):
                os.unlink(tmp)
        raise
    return [p for p, _ in items]


def atomic_write_folder(path, write, *, overwrite: bool = False) -> Path:
    """Write the folder ``path`` (a Zarr store) through ``write(tmp_folder)`` atomically.

    ``write`` fills a fresh temporary folder beside the target; it is then
    renamed into place.  Without ``overwrite`` an existing ``path`` is a
    ``FileExistsError``; with it, an existing *folder* is moved aside, the
    new one renamed in and the old one removed only then (a failure puts the
    old one back).  An existing file of that name is never replaced by a
    folder.
    """
    import shutil

    overwrite = flag("overwrite", overwrite)
    p = Path(path)
    output_folder(p)
    if p.exists() and not overwrite:
        raise FileExistsError(f"{p} exists; pass overwrite=True (CLI: --force) to replace it")
    if p.exists() and (p.is_symlink() or not p.is_dir()):
        raise FileExistsError(f"{p} exists and is not a folder; a Zarr store is a folder")
    tmp = Path(tempfile.mkdtemp(dir=p.parent, prefix=f".{p.name}."))
    old = None
    try:
        write(tmp)
        os.chmod(tmp, 0o777 & ~_umask())  # mkdtemp makes 0700; a saved folder follows the umask
        if p.exists():
            old = Path(tempfile.mkdtemp(dir=p.parent, prefix=f".{p.name}.old."))
            os.rmdir(old)
            os.rename(p, old)
        try:
            os.rename(tmp, p)  # fails if a folder of that name appeared meanwhile
        except OSError:
            if old is not None:
                os.rename(old, p)
                old = None
            raise FileExistsError(
                f"{p} exists; pass overwrite=True (CLI: --force) to replace it"
            ) from None
        _fsync_path(p.parent)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)
    return p
