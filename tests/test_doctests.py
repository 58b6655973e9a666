"""The docstring examples of every module of the package under test, run as doctests.

They run against the package that ``import tensor_cosdi`` finds (the installed one in CI), not
against the files of the source tree, so that a module left out of the wheel or an example that
works only in the checkout fails here."""

import doctest
import importlib
import pkgutil

import numpy as np
import pytest
import tensorly as tl

import tensor_cosdi


def module_names() -> list[str]:
    names = ["tensor_cosdi"]
    for info in pkgutil.walk_packages(tensor_cosdi.__path__, "tensor_cosdi."):
        names.append(info.name)
    return sorted(names)


MODULES = module_names()


def test_the_walk_finds_the_sub_packages_and_their_modules():
    for name in ("tensor_cosdi.operators.algebra", "tensor_cosdi.systems.cassi",
                 "tensor_cosdi.cli.files", "tensor_cosdi.studies.condition"):  # fmt: skip
        assert name in MODULES, name


NUMPY_PRINT_DEFAULTS = dict(
    edgeitems=3, threshold=1000, floatmode="maxprec", precision=8, suppress=False,
    linewidth=75, nanstr="nan", infstr="inf", sign="-", formatter=None, legacy=False,
)  # fmt: skip


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    module = importlib.import_module(name)
    tests = [t for t in doctest.DocTestFinder(exclude_empty=True).find(module, name) if t.examples]
    if not tests:
        return  # a module without examples: nothing to check
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    previous = tl.get_backend()
    state = np.get_printoptions()
    failures = []
    try:
        # NumPy's default print format, whatever an earlier test's imports left (a bare
        # `import colour` switches the process to the 1.13 legacy format)
        np.set_printoptions(**NUMPY_PRINT_DEFAULTS)
        for test in tests:
            result = runner.run(test, out=failures.append, clear_globs=True)
            assert result.attempted > 0
    finally:
        tl.set_backend(previous)
        np.set_printoptions(**state)
    assert runner.failures == 0, "".join(failures)
