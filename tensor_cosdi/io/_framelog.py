"""The acquisition frame log: reading it, checking its frames on disk, and the lock a running
acquisition holds (:class:`tensor_cosdi.io.triggers.Acquisition`)."""

from __future__ import annotations

import os
from pathlib import Path

#: The largest frame log :func:`read_log` reads (bytes): a log of the largest plan is ~50 MB.
MAX_LOG_BYTES = 256 * 2**20


def read_log(path) -> tuple[dict | None, list[dict]]:
    """``(header, entries)`` of a frame log; a truncated last line (crash mid-write) is ignored.

    Nothing there: ``(None, [])``.  Something there that is not a regular file (a FIFO, a
    folder, a device), or a file over :data:`MAX_LOG_BYTES`, is refused before it is read."""
    from ._readers import parse_json, require_file

    p = Path(path)
    if not os.path.lexists(p):
        return None, []
    require_file(p, "frame log")
    size = p.stat().st_size
    if size > MAX_LOG_BYTES:
        raise ValueError(
            f"{p}: {size} bytes, above the {MAX_LOG_BYTES}-byte limit of a frame log; is this "
            "a frame log?"
        )
    header, entries = None, []
    text = p.read_text(encoding="utf-8", errors="replace")
    lines = text.split("\n")
    complete = lines[:-1]  # the part after the last newline is an unfinished write
    for n, line in enumerate(complete):
        if not line.strip():
            continue
        try:
            obj = parse_json(line, "the line")
        except ValueError:
            raise ValueError(f"{p}: line {n + 1} is not JSON; is this a frame log?") from None
        if not isinstance(obj, dict):
            raise ValueError(f"{p}: line {n + 1} is not a JSON object; is this a frame log?")
        if "plan" in obj and "started" in obj and header is None:
            header = obj
        elif "step" in obj and "sha256" in obj:  # frame entries; events ("reacquire") skipped
            entries.append(obj)
    return header, entries


def _verified(entries):
    """``({step: entry}, [(step, reason)])``: the last entry of each step whose frame file is on
    disk with the logged SHA-256, and the steps whose frame is missing or changed."""
    from .bundle import file_digest

    last = {}
    for e in entries:
        last[e["step"]] = e
    ok, bad = {}, []
    for step, e in sorted(last.items()):
        path = Path(e["frame"])
        if not path.is_file():
            bad.append((step, f"frame {path} is missing"))
        elif file_digest(path)["sha256"] != e["sha256"]:
            bad.append((step, f"frame {path} changed since it was logged (SHA-256 differs)"))
        else:
            ok[step] = e
    return ok, bad


class LockedError(RuntimeError):
    """Another live process holds the acquisition's lock."""


class _Lock:
    """``PATH.lock`` holding the owner's pid, created exclusively; a lock whose process is gone is
    stale and taken over."""

    def __init__(self, path: Path):
        self.path = path.with_name(path.name + ".lock")
        self.fd = None

    def __enter__(self):
        for _ in range(2):
            try:
                self.fd = os.open(self.path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                if not self.path.is_file() or self.path.is_symlink():  # never read a FIFO
                    raise ValueError(
                        f"{self.path}: not a regular file, so not a lock this library wrote; "
                        "remove it"
                    ) from None
                try:
                    pid = int(self.path.read_text().split()[0])
                except (OSError, ValueError, IndexError):
                    pid = None
                if pid is not None and _alive(pid):
                    raise LockedError(
                        f"{self.path}: another acquisition (pid {pid}) is running on this log; "
                        "wait for it or stop it"
                    ) from None
                self.path.unlink(missing_ok=True)  # stale: its process is gone
                continue
            os.write(self.fd, f"{os.getpid()}\n".encode())
            os.fsync(self.fd)
            return self
        raise RuntimeError(f"{self.path}: could not take the lock")  # pragma: no cover

    def __exit__(self, *exc):
        os.close(self.fd)
        self.path.unlink(missing_ok=True)


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by someone else
        return True
    return True
