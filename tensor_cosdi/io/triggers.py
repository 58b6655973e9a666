"""Device triggers over a serial port: acquisition plans, a line protocol, resumable frame logs.

The line protocol (ASCII, one command per line, ``\\n``-terminated)
-------------------------------------------------------------------
host → device::

    PING                      liveness check
    DMD <k>                   show code / pattern k on the DMD
    DM <j>:<a> [<j>:<a> …]    deformable mirror: Zernike j (Noll) to a waves
    PROJ <t>                  projector shows pattern t
    TRIG <n>                  fire the camera for frame n

device → host: ``OK <VERB>`` (``OK TRIG <n>`` for triggers) once the command
is applied, or ``ERR <VERB> <reason>``.  Lines echoing the command are
ignored (many microcontroller firmwares echo).  Anything else is garbage.

Every command sets state, so re-sending it is safe; the device must treat a
repeated ``TRIG n`` for the frame it just fired as already done (answer
``OK`` without firing again).  The host waits ``timeout`` seconds for the
acknowledgement and re-sends up to ``retries`` times on a timeout or garbage;
``ERR`` is final.  A port that disappears raises :class:`DeviceError`.

The frame log
-------------
:class:`Acquisition` writes one JSON line per finished frame — step number,
tensor indices (snapshot ``k``, pattern ``t``, depth plane ``z``), frame file,
its SHA-256, time — flushed and fsynced before the next step starts, after a
header line that fingerprints the plan.  Running the same plan against the
same log resumes after the last logged frame: nothing is lost or repeated.
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import json
import logging
import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path

from ..validate import integer, number
from ._atomic import atomic_write
from ._commands import DM_MAX_WAVES, _check_frame_name, check_command  # noqa: F401
from ._framelog import LockedError, _Lock, _verified, read_log  # noqa: F401
from .frames import FRAME_SUFFIXES

log = logging.getLogger(__name__)

#: Most frames one acquisition plan holds (a day of 1 Hz captures): more is refused up front.
MAX_PLAN_FRAMES = 100_000
#: The largest plan file :meth:`AcquisitionPlan.load` reads (bytes).
MAX_PLAN_FILE_BYTES = 64 * 2**20
#: The longest plan name, and the longest axis name of a step's index.
MAX_PLAN_NAME, MAX_AXIS_NAME = 200, 32


def _short(value, n: int = 60) -> str:
    """``repr(value)`` cut to ``n`` characters (an error message never echoes a whole file)."""
    text = repr(value)
    return text if len(text) <= n else text[: n - 1] + "…"


def _step(s, i: int) -> "Step":
    """Step ``i`` of a plan: a :class:`Step`, or a mapping of its fields (a saved plan's)."""
    if isinstance(s, Step):
        return s
    if not isinstance(s, dict):
        raise ValueError(f"step {i} must be a Step or a mapping, got {_short(s)}")
    unknown = set(s) - {"index", "commands", "frame"}
    if unknown or "index" not in s or "frame" not in s:
        raise ValueError(
            f"step {i} needs 'index' and 'frame' (and may have 'commands'), got keys {sorted(s)}"
        )
    return Step(s["index"], s.get("commands", ()), s["frame"])


__all__ = [
    "Step",
    "AcquisitionPlan",
    "SerialDevice",
    "DeviceError",
    "LockedError",
    "Acquisition",
    "FolderCamera",
    "FakeTriggerDevice",
    "read_log",
]


def _port_errors():
    """Exceptions a lost port raises: pyserial's, the OS's, and termios' (POSIX)."""
    import serial

    errs = [serial.SerialException, OSError]
    try:
        import termios

        errs.append(termios.error)
    except ImportError:  # pragma: no cover - Windows
        pass
    return tuple(errs)


class DeviceError(OSError):
    """The trigger device or the camera did not do what was asked (timeout after retries, ERR
    reply, lost port, no new frame): an ``OSError``, as the device I/O it reports."""


@dataclass(frozen=True)
class Step:
    """One frame of an acquisition: the commands to send before triggering, and where the frame
    lands.

    ``index`` names the frame's place in the measurement tensor, e.g.
    ``{"k": 2}`` (C3SLFI snapshot), ``{"t": 5}`` (structured-light pattern),
    ``{"z": 1}`` (DFA focal step).
    """

    index: dict
    commands: tuple = ()
    frame: str = ""

    def __post_init__(self):
        if not isinstance(self.index, dict) or not self.index:
            raise ValueError(
                f"a step's index must be a non-empty mapping of axis names to frame numbers, "
                f"e.g. {{'t': 3}}; got {_short(self.index)}"
            )
        index = {}
        for axis, n in self.index.items():
            if not (isinstance(axis, str) and axis.isidentifier() and len(axis) <= MAX_AXIS_NAME):
                raise ValueError(
                    f"a step's index names its axes by identifiers of at most {MAX_AXIS_NAME} "
                    f"characters (k, t, z…), got {_short(axis)}"
                )
            index[axis] = integer(f"index {axis!r}", n, low=0)
        if isinstance(self.commands, str) or not isinstance(self.commands, (list, tuple)):
            raise ValueError(
                f"a step's commands must be a list of command strings, got {_short(self.commands)}"
            )
        if not isinstance(self.frame, str):
            raise ValueError(f"a step's frame must be a file name, got {_short(self.frame)}")
        object.__setattr__(self, "index", index)
        object.__setattr__(self, "commands", tuple(self.commands))

    def to_dict(self):
        return {"index": dict(self.index), "commands": list(self.commands), "frame": self.frame}


@dataclass(frozen=True)
class AcquisitionPlan:
    """The ordered frames of an acquisition.

    Examples
    --------
    >>> plan = AcquisitionPlan.patterns(8)
    >>> plan.steps[3].commands, plan.steps[3].index, plan.steps[3].frame
    (('PROJ 3',), {'t': 3}, 'frame_003.tif')
    """

    steps: tuple = field(default_factory=tuple)
    name: str = "plan"

    def __post_init__(self):
        if not isinstance(self.name, str) or len(self.name) > MAX_PLAN_NAME:
            raise ValueError(
                f"a plan's name must be text of at most {MAX_PLAN_NAME} characters, got "
                f"{_short(self.name)}"
            )
        if not isinstance(self.steps, (list, tuple)):
            raise ValueError(f"a plan's steps must be a list, got {_short(self.steps)}")
        if len(self.steps) > MAX_PLAN_FRAMES:
            raise ValueError(f"a plan holds at most {MAX_PLAN_FRAMES} steps, got {len(self.steps)}")
        steps = tuple(_step(s, i) for i, s in enumerate(self.steps))
        if not steps:
            raise ValueError("an acquisition plan needs at least one step")
        seen = {}
        for i, st in enumerate(steps):
            key = tuple(sorted(st.index.items()))
            if key in seen:
                raise ValueError(
                    f"steps {seen[key]} and {i} both fill index {st.index}: every frame needs its "
                    "own place in the measurement"
                )
            seen[key] = i
        frames = [s.frame for s in steps]
        if any(not f for f in frames) or len(set(frames)) != len(frames):
            raise ValueError("every step needs its own, non-empty frame file name")
        for f in frames:
            _check_frame_name(f)
        for s in steps:
            for c in s.commands:
                check_command(c)
        object.__setattr__(self, "steps", steps)

    @staticmethod
    def _frames(n, suffix):
        n = integer("the number of frames in a plan", n, low=1, high=MAX_PLAN_FRAMES)
        if not isinstance(suffix, str) or suffix.lower() not in FRAME_SUFFIXES:
            raise ValueError(
                f"suffix must be a frame file type the readers know ({', '.join(FRAME_SUFFIXES)}"
                f"), got {_short(suffix)}"
            )
        width = max(3, len(str(n - 1)))
        return [f"frame_{i:0{width}d}{suffix}" for i in range(n)]

    @classmethod
    def snapshots(cls, n_snapshots: int, *, suffix: str = ".tif") -> "AcquisitionPlan":
        """``K`` snapshots, DMD code ``k`` for snapshot ``k`` (multi-shot CASSI, C3SLFI)."""
        names = cls._frames(n_snapshots, suffix)
        return cls(
            tuple(Step({"k": k}, (f"DMD {k}",), names[k]) for k in range(n_snapshots)), "snapshots"
        )

    @classmethod
    def patterns(cls, n_patterns: int, *, suffix: str = ".tif") -> "AcquisitionPlan":
        """``Nt`` projector patterns, frequency-major (CS2LI, Mu-CoSDI ``"sl"``)."""
        names = cls._frames(n_patterns, suffix)
        return cls(
            tuple(Step({"t": t}, (f"PROJ {t}",), names[t]) for t in range(n_patterns)), "patterns"
        )

    @classmethod
    def focal_sweep(cls, zernike_steps, *, suffix: str = ".tif") -> "AcquisitionPlan":
        """One frame per focal step ``z``: DMD code ``z`` and the mirror's Zernike coefficients
        (CASSDI-DFA calibration)."""
        steps = []
        names = cls._frames(len(zernike_steps), suffix)
        for z, coeffs in enumerate(zernike_steps):
            for j, a in dict(coeffs).items():
                if not math.isfinite(float(a)) or abs(float(a)) > DM_MAX_WAVES:
                    raise ValueError(
                        f"focal step {z}: Zernike {j} amplitude {a!r} is not a finite value "
                        f"within ±{DM_MAX_WAVES:g} waves"
                    )
            dm = " ".join(f"{int(j)}:{float(a):.6g}" for j, a in sorted(dict(coeffs).items()))
            steps.append(Step({"z": z}, (f"DMD {z}", f"DM {dm}"), names[z]))
        return cls(tuple(steps), "focal_sweep")

    def fingerprint(self) -> str:
        return hashlib.sha256(
            json.dumps([s.to_dict() for s in self.steps], sort_keys=True).encode()
        ).hexdigest()

    def save(self, path, *, overwrite: bool = False) -> Path:
        text = json.dumps({"name": self.name, "steps": [s.to_dict() for s in self.steps]}, indent=1)
        return atomic_write(path, lambda tmp: Path(tmp).write_text(text), overwrite=overwrite)

    @classmethod
    def load(cls, path) -> "AcquisitionPlan":
        """A plan written by :meth:`save`: a regular JSON file of at most
        :data:`MAX_PLAN_FILE_BYTES`, every step checked as :class:`Step` checks it."""
        from ._readers import parse_json, require_file

        p = Path(path)
        require_file(p, "acquisition plan")
        if p.stat().st_size > MAX_PLAN_FILE_BYTES:
            raise ValueError(
                f"{p}: {p.stat().st_size} bytes, larger than a plan of {MAX_PLAN_FRAMES} steps "
                f"can be ({MAX_PLAN_FILE_BYTES} bytes); not an acquisition plan"
            )
        try:
            doc = parse_json(p.read_text(encoding="utf-8"), "the plan")
            if not isinstance(doc, dict) or not isinstance(doc.get("steps"), list):
                raise ValueError("expected a JSON object with a list of 'steps'")
            return cls(tuple(doc["steps"]), doc.get("name", p.stem))
        except (OSError, ValueError, KeyError, TypeError) as e:
            raise ValueError(f"{p}: not an acquisition plan ({type(e).__name__}: {e})") from e


#: The longest reply line :class:`SerialDevice` accepts (bytes before the newline).
MAX_REPLY_BYTES = 4096


class SerialDevice:
    """The host side of the line protocol on a pyserial port.

    Parameters
    ----------
    port : str or serial.Serial
        A device path (``/dev/ttyACM0``), a pyserial URL (``loop://``,
        ``socket://host:port``) or an open port object.
    baudrate : int
    timeout : float
        Seconds to wait for each acknowledgement.
    retries : int
        Re-sends after a timeout or a garbage reply.
    """

    def __init__(self, port, *, baudrate: int = 115200, timeout: float = 1.0, retries: int = 2):
        import serial

        if not (timeout > 0):
            raise ValueError(f"timeout must be > 0 s, got {timeout!r}")
        if isinstance(retries, bool) or not isinstance(retries, int) or retries < 0:
            raise ValueError(f"retries must be an integer ≥ 0, got {retries!r}")
        self.timeout, self.retries = float(timeout), retries
        try:
            self.port = (
                serial.serial_for_url(port, baudrate=baudrate, timeout=0.05)
                if isinstance(port, str)
                else port
            )
        except serial.SerialException as e:
            raise DeviceError(f"cannot open serial port {port!r}: {e}") from e
        self.log: list[str] = []  # every line sent and received, for diagnostics
        self._pending = bytearray()  # bytes received after the last complete line

    def close(self):
        try:
            self.port.close()
        except Exception:
            pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def _readline(self, deadline):
        """The next reply line, or ``None`` at ``deadline``, whatever the device sends.

        Reads only the bytes already waiting (``in_waiting``), so no read blocks
        past the deadline on a port without a timeout of its own, and holds at
        most :data:`MAX_REPLY_BYTES` of a line: a device streaming bytes without
        a newline is an error, not an ever-growing buffer.
        """
        buf = self._pending
        while True:
            cut = buf.find(b"\n")
            if cut >= 0:
                line, self._pending = bytes(buf[:cut]), buf[cut + 1 :]
                return line.decode("ascii", errors="replace").strip()
            if len(buf) > MAX_REPLY_BYTES:
                self._pending = bytearray()
                raise DeviceError(
                    f"the device sent {len(buf)} bytes without a newline (a reply is one line of "
                    f"at most {MAX_REPLY_BYTES} bytes); check the baud rate and the firmware"
                )
            if time.monotonic() >= deadline:
                self._pending = buf
                return None
            try:
                waiting = getattr(self.port, "in_waiting", None)
                if waiting is None:  # a port object without in_waiting: its own timeout bounds
                    chunk = self.port.readline(MAX_REPLY_BYTES + 1)
                elif waiting:
                    chunk = self.port.read(min(int(waiting), MAX_REPLY_BYTES + 1))
                else:
                    time.sleep(min(0.002, max(deadline - time.monotonic(), 0.0)))
                    chunk = b""
            except _port_errors() as e:
                raise DeviceError(f"serial port lost while waiting for a reply: {e}") from e
            buf += chunk

    def command(self, line: str) -> str:
        """Send one command and return the device's ``OK`` line; raise :class:`DeviceError`
        otherwise."""
        line = check_command(line)
        verb = line.split()[0]
        expected = f"OK {line}" if verb == "TRIG" else f"OK {verb}"
        problems = []
        for attempt in range(self.retries + 1):
            try:
                self.port.reset_input_buffer()
                self._pending = bytearray()
                self.port.write((line + "\n").encode("ascii"))
                self.port.flush()
            except _port_errors() as e:
                raise DeviceError(f"serial port lost while sending {line!r}: {e}") from e
            self.log.append(f"> {line}")
            deadline = time.monotonic() + self.timeout
            while True:
                reply = self._readline(deadline)
                if reply is None:
                    problems.append(
                        f"attempt {attempt + 1}: no acknowledgement within {self.timeout:g} s"
                    )
                    break
                self.log.append(f"< {reply}")
                if reply == line or not reply:
                    continue  # echo or empty line
                if reply == expected:
                    return reply
                if reply.startswith(f"ERR {verb}"):
                    raise DeviceError(f"device refused {line!r}: {reply}")
                problems.append(f"attempt {attempt + 1}: garbage reply {reply!r}")
                break
        raise DeviceError(
            f"no valid acknowledgement for {line!r} after {self.retries + 1} attempt(s): "
            + "; ".join(problems)
        )


class FolderCamera:
    """The camera side for rigs whose camera software saves each triggered frame into a folder.

    ``capture(step)`` waits up to ``timeout`` seconds for ``folder / step.frame``
    to appear with a size that has stopped changing, and returns its path.
    Only a frame written after the trigger counts: :meth:`before_trigger`
    (called by :class:`Acquisition` before it sends the step's commands)
    notes what the folder holds under that name, and a file that is still
    the same one (same inode, size and modification time) is not taken as the
    new capture — a frame left from an earlier run times out with an error
    saying so.  Symbolic links are refused: a frame is a regular file the
    camera wrote.  Used alone, call ``before_trigger(step)`` yourself before
    triggering; without it, a file already present when ``capture`` is
    called counts as old.
    """

    def __init__(self, folder, *, timeout: float = 10.0, poll: float = 0.05):
        self.folder = Path(folder)
        if not self.folder.is_dir():
            raise FileNotFoundError(f"frame folder {self.folder} does not exist")
        self.timeout = number("timeout", timeout, low=0, low_open=True)
        self.poll = number("poll", poll, low=0, low_open=True, high=self.timeout)
        self._before: dict[str, tuple | None] = {}

    def _identity(self, p: Path):
        if p.is_symlink():
            raise DeviceError(
                f"frame {p} is a symbolic link; a frame must be a regular file the camera wrote"
            )
        try:
            st = p.stat()
        except FileNotFoundError:
            return None
        return (st.st_ino, st.st_dev, st.st_size, st.st_mtime_ns)

    def before_trigger(self, step: Step) -> None:
        """Note the file (if any) already named like ``step.frame``, before the trigger."""
        self._before[step.frame] = self._identity(self.folder / step.frame)

    def __call__(self, step: Step) -> Path:
        p = self.folder / step.frame
        if step.frame not in self._before:
            self.before_trigger(step)
        old = self._before.pop(step.frame)
        deadline = time.monotonic() + self.timeout
        last = -1
        while time.monotonic() < deadline:
            ident = self._identity(p)
            if ident is not None and ident != old:
                if not p.is_file():
                    raise DeviceError(f"frame {p} is not a regular file")
                size = ident[2]
                if size > 0 and size == last:
                    return p
                last = size
            time.sleep(self.poll)
        if old is not None and self._identity(p) == old:
            raise DeviceError(
                f"frame {p} was already in the folder before the trigger and no new one was "
                f"written within {self.timeout:g} s; move old frames away (an earlier run?)"
            )
        raise DeviceError(f"frame {p} did not appear within {self.timeout:g} s after the trigger")


class Acquisition:
    """Run an :class:`AcquisitionPlan` against a trigger device, logging each frame as it lands.

    Parameters
    ----------
    plan : AcquisitionPlan
    device : SerialDevice
    log_path : path
        JSON-lines frame log (created, or resumed if it exists for this plan).
    capture : callable ``step -> path``
        Returns the frame file once the camera wrote it (e.g.
        :class:`FolderCamera`); called after the trigger's acknowledgement.
        If it has a ``before_trigger(step)`` method, that is called before
        the step's commands are sent (a folder camera notes what the folder
        already holds, so an old file is never taken for the new frame).

    Every log line names the plan's fingerprint: a log of another plan, or
    one whose header line was removed, is an error, never taken over.
    """

    def __init__(self, plan: AcquisitionPlan, device: SerialDevice, log_path, capture):
        self.plan, self.device, self.log_path, self.capture = plan, device, Path(log_path), capture

    def _open_log(self):
        """Open the log for appending; returns ``(file, done steps)``.  A logged frame that is
        missing on disk or whose SHA-256 changed is not done: it is acquired again and the log
        says so."""
        header, entries = read_log(self.log_path)
        fp = self.plan.fingerprint()
        if header is not None and header["plan"] != fp:
            raise ValueError(
                f"{self.log_path} belongs to another acquisition plan (fingerprint "
                f"{header['plan'][:12]}… ≠ {fp[:12]}…); use a new log file"
            )
        if header is None and entries:
            raise ValueError(
                f"{self.log_path} holds {len(entries)} frame entries but no header line (edited "
                "or damaged); it is not taken over — use a new log file"
            )
        for e in entries:
            if e.get("plan", fp) != fp:
                raise ValueError(
                    f"{self.log_path}: the entry of step {e.get('step')} belongs to another plan "
                    f"({str(e['plan'])[:12]}… ≠ {fp[:12]}…); use a new log file"
                )
        if self.log_path.exists():  # drop an unfinished last line before appending
            text = self.log_path.read_text()
            keep = text[: text.rfind("\n") + 1] if "\n" in text else ""
            if keep != text:  # replaced atomically: a kill here must not empty the log
                atomic_write(self.log_path, lambda t: Path(t).write_text(keep), overwrite=True)
        f = open(self.log_path, "a")
        if header is None:
            self._write(
                f,
                {
                    "plan": fp,
                    "name": self.plan.name,
                    "steps": len(self.plan.steps),
                    "started": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
                },
            )
        ok, bad = _verified(entries)
        for step, reason in bad:
            self._write(f, {"event": "reacquire", "step_again": step, "reason": reason})
        return f, set(ok)

    @staticmethod
    def _write(f, obj):
        f.write(json.dumps(obj) + "\n")
        f.flush()
        os.fsync(f.fileno())

    def remaining(self) -> list[int]:
        """Steps not yet logged with their frame intact on disk."""
        _, entries = read_log(self.log_path)
        done = set(_verified(entries)[0])
        return [i for i in range(len(self.plan.steps)) if i not in done]

    def run(self, *, progress: bool = False) -> list[dict]:
        """Acquire every step not yet logged (or logged with a frame missing or changed on
        disk); returns the log entries written in this run.  ``LOG.lock`` holds this process'
        pid meanwhile: a second acquisition on the same log refuses, naming it; a lock left by a
        process that no longer exists is taken over."""
        with _Lock(self.log_path):
            return self._run(progress)

    def _run(self, progress):
        from tqdm import tqdm

        from .bundle import file_digest

        f, done = self._open_log()
        fp = self.plan.fingerprint()
        written = []
        try:
            todo = [i for i in range(len(self.plan.steps)) if i not in done]
            for i in tqdm(todo, desc="acquire", disable=not progress):
                step = self.plan.steps[i]
                try:
                    before = getattr(self.capture, "before_trigger", None)
                    if before is not None:  # the camera notes the folder before the trigger
                        before(step)
                    for c in step.commands:
                        self.device.command(c)
                    self.device.command(f"TRIG {i}")
                    path = Path(self.capture(step))
                except DeviceError as e:
                    raise DeviceError(
                        f"step {i} ({step.index}, {step.frame}): {e}. The log {self.log_path} "
                        "holds "
                        f"{len(done) + len(written)} finished frame(s); run again to resume"
                    ) from e
                entry = {
                    "plan": fp,
                    "step": i,
                    "index": dict(step.index),
                    "frame": str(path),
                    "sha256": file_digest(path)["sha256"],
                    "time": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="milliseconds"),
                }
                self._write(f, entry)
                written.append(entry)
                log.info("step %d %s: frame %s", i, dict(step.index), path)
        finally:
            f.close()
        return written


from .fake_device import FakeTriggerDevice  # noqa: E402  (re-exported: tests and examples use it)
