"""SIGKILL in the middle of a save: the file is the old one or the new one, never torn."""

import json
import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

from tensor_cosdi.io import load_bundle

pytestmark = pytest.mark.skipif(os.name != "posix", reason="SIGKILL is POSIX")

WRITER = textwrap.dedent(
    """
    import sys
    import numpy as np
    import tensor_cosdi as tc
    from tensor_cosdi.io import save_bundle
    path, = sys.argv[1:]
    system = tc.systems.SDCASSI(np.ones((64, 64)), n_bands=16, shifts=1)
    cubes = [np.full((64, 64, 16), float(v), dtype=np.float32) for v in (1, 2)]
    save_bundle(path, system=system, cube=cubes[0], metadata={"v": 1}, overwrite=True)
    print("ready", flush=True)
    i = 0
    while True:  # overwrite with alternating contents until killed
        i += 1
        save_bundle(path, system=system, cube=cubes[i % 2], metadata={"v": 1 + i % 2},
                    overwrite=True)
    """
)


@pytest.mark.parametrize("suffix", [".h5", ".npz"])
def test_a_bundle_save_killed_at_random_points_is_never_torn(tmp_path, suffix):
    path = tmp_path / f"b{suffix}"
    rng = np.random.default_rng(0)
    for delay in rng.uniform(0.0, 0.4, 6):
        proc = subprocess.Popen(
            [sys.executable, "-c", WRITER, str(path)], stdout=subprocess.PIPE, text=True
        )
        try:
            assert proc.stdout.readline().strip() == "ready"
            time.sleep(float(delay))
        finally:
            proc.send_signal(signal.SIGKILL)
            proc.wait(timeout=60)
        b = load_bundle(path)  # checksums verified on load: a torn file would fail here
        v = float(b.cube[0, 0, 0])
        assert v in (1.0, 2.0)
        np.testing.assert_array_equal(b.cube, v)
        # temporaries of the killed write may remain (hidden, never the target's name)
        assert all(p.name.startswith(".") for p in tmp_path.iterdir() if p != path)


# --- an acquisition killed at 30 random points ------------------------------------------------

N_STEPS = 40


def _acquire_until_killed(folder, log, kill_at):
    """In a forked child: run the acquisition and SIGKILL itself at its ``kill_at``-th event.
    Events are before/after each device command, before/mid/after each frame the camera writes
    (mid = half the bytes on disk, a torn frame) and before/mid/after each log line (mid = half
    a line flushed, a torn log)."""
    import io as _io

    from tensor_cosdi.io import Acquisition, AcquisitionPlan, FakeTriggerDevice, SerialDevice

    count = [0]

    def tick():
        count[0] += 1
        if count[0] == kill_at:
            os.kill(os.getpid(), signal.SIGKILL)

    def camera(step):
        i = int(step.frame.split("_")[1].split(".")[0])
        buf = _io.BytesIO()
        np.save(buf, np.full((16, 16), 1000 + i, np.uint16))
        data = buf.getvalue()
        p = folder / f"frame_{i:03d}.npy"
        tick()
        with open(p, "wb") as f:  # a camera writes in place, not atomically
            f.write(data[: len(data) // 2])
            f.flush()
            tick()
            f.write(data[len(data) // 2 :])
        tick()
        return p

    def torn_write(f, obj):
        line = json.dumps(obj) + "\n"
        tick()
        f.write(line[: len(line) // 2])
        f.flush()
        tick()
        f.write(line[len(line) // 2 :])
        f.flush()
        os.fsync(f.fileno())
        tick()

    Acquisition._write = staticmethod(torn_write)
    dev = FakeTriggerDevice()
    with SerialDevice(dev.port, timeout=2.0) as host:
        command = host.command

        def counted(line):
            tick()
            out = command(line)
            tick()
            return out

        host.command = counted
        Acquisition(AcquisitionPlan.snapshots(N_STEPS), host, log, camera).run()
    dev.disconnect()


def _run_child(folder, log, kill_at):
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child
        code = 0
        try:
            _acquire_until_killed(folder, log, kill_at)
        except BaseException:
            import traceback

            traceback.print_exc()
            code = 3
        os._exit(code)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            return status
        time.sleep(0.01)
    os.kill(pid, signal.SIGKILL)
    os.waitpid(pid, 0)
    raise AssertionError(f"acquisition child (kill at event {kill_at}) hung")


def _check_frames(folder, log):
    """Every logged frame is on disk with its step's content; returns the logged steps."""
    from tensor_cosdi.io import read_log

    _, entries = read_log(log)
    steps = [e["step"] for e in entries]
    for e in entries:
        frame = np.load(e["frame"])
        np.testing.assert_array_equal(frame, 1000 + e["step"])
    return steps


def test_an_acquisition_killed_at_30_random_points_loses_duplicates_and_corrupts_nothing(
    tmp_path,
):

    from tensor_cosdi.io import load_frames, read_log

    log = tmp_path / "log.jsonl"
    rng = np.random.default_rng(0)
    done_before = set()
    kills = 0
    for kill_at in rng.integers(1, 30, 30):  # ~10 events per step: kills land 0-3 steps in
        status = _run_child(tmp_path, log, int(kill_at))
        assert os.WIFSIGNALED(status) and os.WTERMSIG(status) == signal.SIGKILL, status
        kills += 1
        steps = _check_frames(tmp_path, log)
        assert len(steps) == len(set(steps)), f"a step logged twice after kill {kills}: {steps}"
        assert done_before <= set(steps), "a finished frame was lost by a kill"
        done_before = set(steps)
    assert kills == 30 and len(done_before) < N_STEPS  # every kill landed mid-acquisition
    assert _run_child(tmp_path, log, 0) == 0  # resumes to the end
    steps = _check_frames(tmp_path, log)
    assert sorted(steps) == list(range(N_STEPS))  # none lost, none duplicated
    header, _ = read_log(log)
    assert header["steps"] == N_STEPS
    assert "reacquire" not in log.read_text()  # no logged frame was ever damaged
    frames = load_frames(tmp_path, pattern="frame_*.npy", expected=N_STEPS)
    np.testing.assert_array_equal(frames[0, 0], 1000 + np.arange(N_STEPS))
    assert not (tmp_path / "log.jsonl.lock").exists()
