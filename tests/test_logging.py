"""The library logs through the standard ``logging`` module under ``"tensor_cosdi"`` and stays
quiet until the application configures logging; ``import tensor_cosdi`` loads sub-packages on
first use."""

import logging
import subprocess
import sys

import numpy as np

import tensor_cosdi as tc


def test_reconstruct_and_reads_log_under_the_package_logger(caplog, tmp_path):
    p = tc.studies.make_problem("sd_cassi", "chelsea", shape=(16, 16), n_bands=4)
    with caplog.at_level(logging.DEBUG, logger="tensor_cosdi"):
        tc.reconstruct(p.system, p.measurement, "lsq")
        path = tc.io.write_cube(tmp_path / "c.npz", np.ones((4, 4, 3)))
        tc.io.read_cube(path)
    names = {r.name for r in caplog.records}
    assert "tensor_cosdi.solvers._base" in names and "tensor_cosdi.io.files" in names
    assert any("lsq on SDCASSI (16, 16, 4)" in r.getMessage() for r in caplog.records)


def test_import_is_lazy_and_quiet():
    code = (
        "import sys, tensor_cosdi as tc; "
        "assert 'tensor_cosdi.solvers' not in sys.modules and 'tensorly' not in sys.modules; "
        "tc.systems; assert 'tensor_cosdi.systems' in sys.modules; "
        "import logging; assert logging.getLogger('tensor_cosdi').handlers"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stderr == ""
