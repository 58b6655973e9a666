"""Serial device triggers: the line protocol, retries, and a frame log that survives every
failure."""

import json
import os
from pathlib import Path

import numpy as np
import pytest

from tensor_cosdi import io
from tensor_cosdi.io import (
    Acquisition,
    AcquisitionPlan,
    DeviceError,
    FakeTriggerDevice,
    SerialDevice,
)
from tensor_cosdi.io.triggers import Step

pytestmark = pytest.mark.skipif(
    os.name != "posix", reason="pseudo-terminal fake device needs POSIX"
)


class Camera:
    """Writes a frame file per trigger, as a camera's software would (counts every capture)."""

    def __init__(self, folder):
        self.folder, self.shots = folder, []

    def __call__(self, step):
        p = self.folder / step.frame.replace(".tif", ".npy")
        np.save(p, np.full((4, 4), len(self.shots), np.uint16))
        self.shots.append(step.frame)
        return p


@pytest.fixture
def device():
    made = []

    def make(**kw):
        d = FakeTriggerDevice(**kw)
        made.append(d)
        return d

    yield make
    for d in made:
        d.disconnect()


def test_normal_plan_logs_every_frame(tmp_path, device):
    dev = device(echo=True)
    plan = AcquisitionPlan.patterns(5)
    cam = Camera(tmp_path)
    with SerialDevice(dev.port, timeout=0.5) as host:
        written = Acquisition(plan, host, tmp_path / "log.jsonl", cam).run()
    assert [e["step"] for e in written] == [0, 1, 2, 3, 4]
    assert dev.fired == [0, 1, 2, 3, 4]
    assert [line for line in dev.received if line.startswith("PROJ")] == [
        f"PROJ {t}" for t in range(5)
    ]
    header, entries = io.read_log(tmp_path / "log.jsonl")
    assert header["plan"] == plan.fingerprint() and [e["index"] for e in entries] == [
        {"t": t} for t in range(5)
    ]
    assert all(len(e["sha256"]) == 64 for e in entries)


def test_late_answer_then_retry_succeeds(tmp_path, device):
    dev = device(late_once={"DMD 1": 0.3})  # answers inside the second attempt's window
    with SerialDevice(dev.port, timeout=0.2, retries=2) as host:
        Acquisition(
            AcquisitionPlan.snapshots(3), host, tmp_path / "log.jsonl", Camera(tmp_path)
        ).run()
    assert dev.received.count("DMD 1") == 2 and dev.fired == [
        0,
        1,
        2,
    ]  # timed out once, the re-send succeeded


def test_garbage_reply_is_retried(tmp_path, device):
    dev = device(garbage_once={"TRIG 1"})
    with SerialDevice(dev.port, timeout=0.3, retries=1) as host:
        Acquisition(
            AcquisitionPlan.snapshots(2), host, tmp_path / "log.jsonl", Camera(tmp_path)
        ).run()
    assert dev.fired == [0, 1]  # the retried trigger fired once


def test_device_that_never_answers_then_resume(tmp_path, device):
    dev = device(silent={"PROJ 2"})
    plan = AcquisitionPlan.patterns(4)
    cam = Camera(tmp_path)
    log = tmp_path / "log.jsonl"
    with SerialDevice(dev.port, timeout=0.15, retries=1) as host:
        with pytest.raises(
            DeviceError, match="step 2 .*PROJ 2.*2 finished frame\\(s\\); run again to resume"
        ):
            Acquisition(plan, host, log, cam).run()
    _, entries = io.read_log(log)
    assert [e["step"] for e in entries] == [0, 1]  # log intact
    # the device is fixed; the same plan resumes at frame 2 without repeating 0 and 1
    dev2 = device()
    with SerialDevice(dev2.port, timeout=0.5) as host:
        acq = Acquisition(plan, host, log, cam)
        assert acq.remaining() == [2, 3]
        written = acq.run()
    assert [e["step"] for e in written] == [2, 3] and dev2.fired == [2, 3]
    assert cam.shots == ["frame_000.tif", "frame_001.tif", "frame_002.tif", "frame_003.tif"]
    assert [e["step"] for e in io.read_log(log)[1]] == [0, 1, 2, 3]


def test_loop_port_never_acknowledges(tmp_path):
    # pyserial's loop:// echoes every line back and never says OK: the echo is ignored, the wait
    # times out
    with SerialDevice("loop://", timeout=0.1, retries=2) as host:
        with pytest.raises(DeviceError, match="after 3 attempt\\(s\\)"):
            host.command("DMD 0")
        assert host.log.count("> DMD 0") == 3 and host.log.count("< DMD 0") == 3


def test_disconnected_port_keeps_the_log(tmp_path, device):
    dev = device()
    plan = AcquisitionPlan.snapshots(4)
    log = tmp_path / "log.jsonl"

    class Unplug(Camera):
        def __call__(self, step):
            p = super().__call__(step)
            if step.index["k"] == 1:
                dev.disconnect()
            return p

    with SerialDevice(dev.port, timeout=0.2, retries=1) as host:
        with pytest.raises(DeviceError, match="step 2 .*serial port lost"):
            Acquisition(plan, host, log, Unplug(tmp_path)).run()
    assert [e["step"] for e in io.read_log(log)[1]] == [0, 1]


def test_truncated_log_line_and_foreign_plan(tmp_path, device):
    dev = device()
    plan = AcquisitionPlan.snapshots(3)
    log = tmp_path / "log.jsonl"
    cam = Camera(tmp_path)
    with SerialDevice(dev.port, timeout=0.5) as host:
        Acquisition(AcquisitionPlan.snapshots(3), host, log, cam).run()
    lines = log.read_text().splitlines(keepends=True)
    log.write_text("".join(lines[:-1]) + lines[-1][:20])  # crash while writing the last entry
    assert [e["step"] for e in io.read_log(log)[1]] == [0, 1]
    with SerialDevice(dev.port, timeout=0.5) as host:
        written = Acquisition(plan, host, log, cam).run()
    assert [e["step"] for e in written] == [2]
    assert all(json.loads(line) for line in log.read_text().splitlines())
    with SerialDevice(dev.port, timeout=0.5) as host:
        with pytest.raises(ValueError, match="belongs to another acquisition plan"):
            Acquisition(AcquisitionPlan.patterns(3), host, log, cam).run()


def test_err_reply_is_final(device):
    dev = device(refuse=("DMD 7",))
    with SerialDevice(dev.port, timeout=0.3, retries=3) as host:
        with pytest.raises(DeviceError, match="device refused 'DMD 7'"):
            host.command("DMD 7")
        with pytest.raises(ValueError, match="one integer"):  # the host never sends this
            host.command("TRIG x")
    assert dev.received.count("DMD 7") == 1 and "TRIG x" not in dev.received


def test_plans(tmp_path):
    plan = AcquisitionPlan.focal_sweep([{4: -0.5, 6: 0.9}, {4: 0.0, 6: 0.9}])
    assert plan.steps[0].commands == ("DMD 0", "DM 4:-0.5 6:0.9") and plan.steps[1].index == {
        "z": 1
    }
    p = plan.save(tmp_path / "plan.json")
    assert AcquisitionPlan.load(p) == plan
    with pytest.raises(FileExistsError):
        plan.save(p)
    with pytest.raises(ValueError, match="unknown command verb 'FIRE'"):
        AcquisitionPlan(({"index": {"k": 0}, "commands": ("FIRE 1",), "frame": "a.tif"},))
    with pytest.raises(ValueError, match="own, non-empty frame"):
        AcquisitionPlan(
            ({"index": {"k": 0}, "frame": "a.tif"}, {"index": {"k": 1}, "frame": "a.tif"})
        )


_OK_STEP = {"index": {"k": 0}, "commands": ["DMD 0"], "frame": "f0.tif"}


@pytest.mark.parametrize(
    "doc, message",
    [
        ({"steps": [dict(_OK_STEP, commands="DMD 0")]}, "commands must be a list"),
        ({"steps": [dict(_OK_STEP, index=[1, 2])]}, "index must be a non-empty mapping"),
        ({"steps": [dict(_OK_STEP, index={})]}, "index must be a non-empty mapping"),
        ({"steps": [dict(_OK_STEP, index={"k": -1})]}, "index 'k' must be an integer ≥ 0"),
        ({"steps": [dict(_OK_STEP, index={"k": 1.5})]}, "index 'k' must be an integer ≥ 0"),
        ({"steps": [dict(_OK_STEP, index={"k": True})]}, "index 'k' must be an integer ≥ 0"),
        ({"steps": [dict(_OK_STEP, index={"../x": 1})]}, "identifiers of at most 32"),
        ({"steps": [dict(_OK_STEP, frame=3)]}, "frame must be a file name"),
        ({"steps": [dict(_OK_STEP, foo=1)]}, r"got keys \['commands', 'foo'"),
        ({"steps": [_OK_STEP, dict(_OK_STEP, frame="f1.tif")]}, "steps 0 and 1 both fill"),
        ({"name": 5, "steps": [_OK_STEP]}, "name must be text"),
        ({"name": "x" * 500, "steps": [_OK_STEP]}, "at most 200 characters, got 'xxx.*…"),
        ({"steps": {"a": _OK_STEP}}, "a JSON object with a list of 'steps'"),
        ([_OK_STEP], "a JSON object with a list of 'steps'"),
    ],
)
def test_a_plan_file_is_checked_step_by_step(tmp_path, doc, message):
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(ValueError, match=message):
        AcquisitionPlan.load(path)


def test_a_plan_is_read_only_from_a_regular_file_of_bounded_size(tmp_path):
    from tensor_cosdi.io.triggers import MAX_PLAN_FILE_BYTES

    fifo = tmp_path / "plan.json"
    os.mkfifo(fifo)  # reading it would block for ever
    with pytest.raises(ValueError, match="not a regular file"):
        AcquisitionPlan.load(fifo)
    big = tmp_path / "big.json"
    with open(big, "wb") as f:
        f.truncate(MAX_PLAN_FILE_BYTES + 1)  # sparse: no disk used
    with pytest.raises(ValueError, match="larger than a plan"):
        AcquisitionPlan.load(big)
    with pytest.raises(FileNotFoundError, match="acquisition plan not found"):
        AcquisitionPlan.load(tmp_path / "missing.json")


@pytest.mark.parametrize(
    "command, message",
    [
        ("DM 6:nan", "not a finite value"),
        ("DM 4:1e9", "within ±10 waves"),
        ("DM 0:0.5", "Noll j ≥ 1"),
        ("DM 4", "j:a pairs"),
        ("DMD -1", "one integer ≥ 0"),
        ("PROJ 2 3", "one integer ≥ 0"),
        ("TRIG x", "one integer ≥ 0"),
        ("PING 1", "no arguments"),
    ],
)
def test_unsafe_commands_never_reach_the_device(command, message):
    from tensor_cosdi.io.triggers import check_command

    with pytest.raises(ValueError, match=message):
        check_command(command)
    with pytest.raises(ValueError, match=message):
        AcquisitionPlan((Step({"t": 0}, (command,), "f.tif"),))


def test_focal_sweep_refuses_nan_and_out_of_range_amplitudes():
    with pytest.raises(ValueError, match="focal step 1: Zernike 4 amplitude nan"):
        AcquisitionPlan.focal_sweep([{4: 0.1}, {4: float("nan")}])
    with pytest.raises(ValueError, match="within ±10 waves"):
        AcquisitionPlan.focal_sweep([{4: 50.0}])
    assert (
        AcquisitionPlan.focal_sweep([{4: -0.5, 6: 0.25}]).steps[0].commands[1] == "DM 4:-0.5 6:0.25"
    )


@pytest.mark.parametrize("name", ["../x.tif", "/etc/passwd", "a/b.tif", "..", ".hidden", "a\\b"])
def test_frame_names_are_confined_to_the_capture_folder(name):
    with pytest.raises(ValueError, match="plain file names"):
        AcquisitionPlan((Step({"t": 0}, ("PROJ 0",), name),))


def test_fake_device_never_touches_descriptors_it_closed(tmp_path):
    dev = FakeTriggerDevice()
    dev.disconnect()
    dev.disconnect()  # idempotent
    # the process reuses the lowest free descriptor numbers for new files
    fds = [os.open(tmp_path / f"f{i}", os.O_RDWR | os.O_CREAT) for i in range(4)]
    try:
        dev.send("OK TRIG 1")
        for i in range(4):
            assert (tmp_path / f"f{i}").read_bytes() == b""
    finally:
        for fd in fds:
            os.close(fd)


def test_resume_checks_the_disk_not_just_the_log(tmp_path, device):
    plan = AcquisitionPlan.patterns(4)
    cam = Camera(tmp_path)
    log = tmp_path / "log.jsonl"
    with SerialDevice(device().port, timeout=0.5) as host:
        Acquisition(plan, host, log, cam).run()
    _, entries = io.read_log(log)
    frames = {e["step"]: Path(e["frame"]) for e in entries}
    frames[1].unlink()  # deleted after it was logged
    frames[3].write_bytes(b"not the frame")  # changed after it was logged
    dev2 = device()
    with SerialDevice(dev2.port, timeout=0.5) as host:
        acq = Acquisition(plan, host, log, cam)
        assert acq.remaining() == [1, 3]
        written = acq.run()
    assert [e["step"] for e in written] == [1, 3] and dev2.fired == [1, 3]
    text = log.read_text()
    assert "is missing" in text and "SHA-256 differs" in text  # the log says why
    with SerialDevice(device().port, timeout=0.5) as host:
        assert Acquisition(plan, host, log, cam).remaining() == []


def test_a_second_acquisition_on_the_same_log_refuses_and_a_stale_lock_is_taken(tmp_path, device):
    import subprocess
    import sys

    plan = AcquisitionPlan.snapshots(2)
    log = tmp_path / "log.jsonl"
    holder = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        (tmp_path / "log.jsonl.lock").write_text(f"{holder.pid}\n")
        with SerialDevice(device().port, timeout=0.5) as host:
            with pytest.raises(RuntimeError, match=f"pid {holder.pid}"):
                Acquisition(plan, host, log, Camera(tmp_path)).run()
    finally:
        holder.kill()
        holder.wait()
    # the holder is gone: its lock is stale and taken over; released at the end
    with SerialDevice(device().port, timeout=0.5) as host:
        assert len(Acquisition(plan, host, log, Camera(tmp_path)).run()) == 2
    assert not (tmp_path / "log.jsonl.lock").exists()


def test_a_fifo_as_the_log_or_its_lock_is_refused_not_read(tmp_path, device):
    """Reading a FIFO blocks for ever: neither the frame log nor its lock is ever read as one."""
    from tensor_cosdi.io.triggers import read_log

    plan = AcquisitionPlan.snapshots(2)
    log = tmp_path / "log.jsonl"
    os.mkfifo(log)
    with pytest.raises(ValueError, match="not a regular file"):
        read_log(log)
    with SerialDevice(device().port, timeout=0.5) as host:
        with pytest.raises(ValueError, match="not a regular file"):
            Acquisition(plan, host, log, Camera(tmp_path)).run()
    other = tmp_path / "other.jsonl"
    os.mkfifo(tmp_path / "other.jsonl.lock")
    with SerialDevice(device().port, timeout=0.5) as host:
        with pytest.raises(ValueError, match="not a regular file, so not a lock"):
            Acquisition(plan, host, other, Camera(tmp_path)).run()
    (tmp_path / "list.jsonl").write_text("[1, 2]\n")
    with pytest.raises(ValueError, match="line 1 is not a JSON object"):
        read_log(tmp_path / "list.jsonl")


class _StreamingPort:
    """A port that answers every read with bytes and never a newline (and has no timeout)."""

    in_waiting = 64

    def __init__(self):
        self.sent = b""

    def reset_input_buffer(self):
        pass

    def write(self, data):
        self.sent += data

    def flush(self):
        pass

    def read(self, n):
        return b"x" * n

    def close(self):
        pass


def test_a_device_streaming_without_newlines_is_an_error_in_bounded_time_and_bytes():
    import time

    from tensor_cosdi.io.triggers import MAX_REPLY_BYTES, DeviceError

    host = SerialDevice(_StreamingPort(), timeout=5.0, retries=3)
    t0 = time.monotonic()
    with pytest.raises(DeviceError, match="without a newline"):
        host.command("DMD 0")
    assert time.monotonic() - t0 < 1.0  # the byte cap ends it long before the 5 s timeout
    assert MAX_REPLY_BYTES <= 65536  # the buffer never held more than this


def test_folder_camera_takes_only_frames_written_after_the_trigger(tmp_path):
    from tensor_cosdi.io import FolderCamera

    step = AcquisitionPlan.snapshots(1).steps[0]
    old = tmp_path / step.frame
    old.write_bytes(b"frame from an earlier run")
    cam = FolderCamera(tmp_path, timeout=0.3, poll=0.02)
    cam.before_trigger(step)
    with pytest.raises(DeviceError, match="was already in the folder before the trigger"):
        cam(step)
    cam.before_trigger(step)
    old.unlink()
    old.write_bytes(b"the new capture, written after the trigger")
    assert cam(step) == old
    old.unlink()
    os.symlink(tmp_path / "elsewhere.tif", old)
    (tmp_path / "elsewhere.tif").write_bytes(b"x")
    with pytest.raises(DeviceError, match="symbolic link"):
        cam(step)


def test_a_log_belongs_to_one_plan_even_without_its_header(tmp_path, device):
    dev = device()
    log = tmp_path / "log.jsonl"
    cam = Camera(tmp_path)
    with SerialDevice(dev.port, timeout=0.5) as host:
        Acquisition(AcquisitionPlan.snapshots(2), host, log, cam).run()
    entries = [json.loads(line) for line in log.read_text().splitlines()]
    assert all("plan" in e for e in entries)
    log.write_text("".join(json.dumps(e) + "\n" for e in entries[1:]))  # header deleted
    with SerialDevice(dev.port, timeout=0.5) as host:
        with pytest.raises(ValueError, match="2 frame entries but no header line"):
            Acquisition(AcquisitionPlan.patterns(2), host, log, cam).run()
        with pytest.raises(ValueError, match="no header line"):
            Acquisition(AcquisitionPlan.snapshots(2), host, log, cam).run()
    other = AcquisitionPlan.patterns(2).fingerprint()
    entries[1]["plan"] = other  # one entry of another plan spliced in
    log.write_text("".join(json.dumps(e) + "\n" for e in entries))
    with SerialDevice(dev.port, timeout=0.5) as host:
        with pytest.raises(ValueError, match="entry of step 0 belongs to another plan"):
            Acquisition(AcquisitionPlan.snapshots(2), host, log, cam).run()
