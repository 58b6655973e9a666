"""Shared fixtures: TensorLy backends × dtypes, seeded generators; the report header names the
package under test (installed or the source tree) and whether PyTorch is there.

With ``TENSOR_COSDI_CI=1`` (set by ``.ci/run``) the run refuses to start unless it tests the
*installed* package (not the checkout's ``tensor_cosdi/``) with PyTorch importable, so that CI
tests what a user installs and skips none of the learned parts."""

import importlib.util
import os
from pathlib import Path

import numpy as np
import pytest
import tensorly as tl
from hypothesis import HealthCheck, settings

settings.register_profile(
    "tensor_cosdi",
    deadline=None,
    max_examples=40,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.load_profile("tensor_cosdi")

HAS_TORCH = importlib.util.find_spec("torch") is not None
SOURCE_TREE = Path(__file__).resolve().parents[1] / "tensor_cosdi"


def package_under_test() -> tuple[Path, bool]:
    """Where ``import tensor_cosdi`` finds the package, and whether that is the source tree."""
    import tensor_cosdi

    where = Path(tensor_cosdi.__file__).resolve().parent
    return where, where == SOURCE_TREE.resolve()


def pytest_report_header(config):
    where, source = package_under_test()
    kind = "the source tree (editable or not installed)" if source else "installed"
    torch = "PyTorch present" if HAS_TORCH else "PyTorch absent: the learned and torch tests skip"
    return [f"tensor_cosdi under test: {where} ({kind}); {torch}"]


def pytest_configure(config):
    if os.environ.get("TENSOR_COSDI_CI") != "1":
        return
    where, source = package_under_test()
    if source:
        raise pytest.UsageError(
            f"TENSOR_COSDI_CI=1: the tests import tensor_cosdi from the source tree ({where}); "
            "install it (pip install .) and run the pytest command, not python -m pytest"
        )
    if not HAS_TORCH:
        raise pytest.UsageError(
            "TENSOR_COSDI_CI=1: PyTorch is not installed, so the learned tests would skip; "
            "install torch==2.13.0 first"
        )


BACKENDS = [
    pytest.param(("numpy", "float64"), id="numpy-float64"),
    pytest.param(("numpy", "float32"), id="numpy-float32"),
    pytest.param(
        ("pytorch", "float64"),
        id="pytorch-float64",
        marks=pytest.mark.skipif(not HAS_TORCH, reason="PyTorch is not installed"),
    ),
    pytest.param(
        ("pytorch", "float32"),
        id="pytorch-float32",
        marks=pytest.mark.skipif(not HAS_TORCH, reason="PyTorch is not installed"),
    ),
]


@pytest.fixture(params=BACKENDS)
def backend(request):
    """Activate a TensorLy backend for the test; yields ``(name, dtype_name)``."""
    name, dtype = request.param
    previous = tl.get_backend()
    tl.set_backend(name)
    try:
        yield name, dtype
    finally:
        tl.set_backend(previous)


@pytest.fixture
def rng():
    return np.random.default_rng(20261122)


@pytest.fixture(autouse=True)
def _seed_torch():
    """Every test starts from the same torch random state: torch ≥ 2.13 seeds its default
    generator anew in each process, so an unseeded network initialisation (D-CoSNet's
    gradient test) differed from run to run and failed about one run in six."""
    if HAS_TORCH:
        import torch

        torch.manual_seed(0)
    yield


BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"


@pytest.fixture(scope="session")
def benchmark_script():
    """``load(name)``: the module of ``benchmarks/<name>.py`` (the folder is not a package; each
    script puts it on ``sys.path`` for its own ``_protocol`` import)."""

    def load(name: str):
        spec = importlib.util.spec_from_file_location(f"bench_{name}", BENCHMARKS / f"{name}.py")
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        return mod

    return load
