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


def _python(code: str):
    """``code`` run by a fresh interpreter (nothing imported yet): its completed process."""
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)


def test_import_is_lazy_and_quiet():
    code = (
        "import sys, tensor_cosdi as tc; "
        "assert 'tensor_cosdi.solvers' not in sys.modules and 'tensorly' not in sys.modules; "
        "tc.systems; assert 'tensor_cosdi.systems' in sys.modules; "
        "import logging; assert logging.getLogger('tensor_cosdi').handlers"
    )
    out = _python(code)
    assert out.returncode == 0, out.stderr
    assert out.stderr == ""


def test_the_top_level_help_imports_no_registry_and_the_sub_command_help_lists_them():
    """``tensor-cosdi --help`` builds every sub-parser but imports neither TensorLy nor the
    registries (their lists are made when a sub-command's help is shown)."""
    code = (
        "import sys\n"
        "from tensor_cosdi.cli import main\n"
        "try:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
        "heavy = [m for m in ('tensorly', 'tensor_cosdi.solvers', 'tensor_cosdi.systems', "
        "'tensor_cosdi.io') if m in sys.modules]\n"
        "assert not heavy, heavy\n"
    )
    out = _python(code)
    assert out.returncode == 0, out.stderr
    assert "reconstruct" in out.stdout and "train-dcosnet" in out.stdout
    sub = _python("from tensor_cosdi.cli import main\nmain(['reconstruct', '--help'])\n")
    text = " ".join(sub.stdout.split())
    assert sub.returncode == 0, sub.stderr
    for name in list(tc.systems.REGISTRY.names()) + list(tc.solvers.methods()):
        assert name in text, name
    assert "pnp_admm (cs2li/mu_cosdi only)" in text
