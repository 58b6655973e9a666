"""SIGKILL in the middle of a save: the file is the old one or the new one, never torn."""

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
