"""Shared fixtures: TensorLy backends × dtypes, seeded generators."""

import importlib.util

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
