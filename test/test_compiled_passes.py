# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Every compiled pass gives its numpy reference's answers on the examples it is warmed up on.

One parametrized check over the registry (:data:`dgmod_ros.core.numba_setup.PASSES`),
as scikit-learn's ``parametrize_with_checks`` runs one set of checks over every
estimator: a pass added to a ``kernels`` module with :func:`register_pass` is
checked here without a line added. The reference is called on fresh copies of
the same examples; a pass that writes into its arguments is compared on them too.
"""

import importlib

from dgmod_ros.core import numba_setup, warmup
import numpy as np
import pytest

for _name in warmup.kernel_modules():
    importlib.import_module(_name)
PASSES = list(numba_setup.PASSES)


def assert_same(got, want, atol, rtol, where):
    """Assert two results (arrays, numbers, sequences of them or None) agree within tolerance."""
    if isinstance(want, (tuple, list)):
        assert isinstance(got, (tuple, list)) and len(got) == len(want), where
        for index, (a, b) in enumerate(zip(got, want)):
            assert_same(a, b, atol, rtol, f'{where}[{index}]')
        return
    if want is None or got is None:
        assert got is want, where
        return
    got, want = np.asarray(got), np.asarray(want)
    assert got.shape == want.shape, where
    assert got.dtype == want.dtype, where
    if atol or rtol:
        np.testing.assert_allclose(got, want, rtol=rtol, atol=atol, equal_nan=True, err_msg=where)
    else:
        np.testing.assert_array_equal(got, want, err_msg=where)


def test_every_kernels_module_registers_a_pass():
    modules = {compiled_pass.compiled.__module__ for compiled_pass in PASSES}
    assert modules == set(warmup.kernel_modules())


@pytest.mark.parametrize('compiled_pass', PASSES, ids=lambda compiled_pass: compiled_pass.name)
def test_pass_has_its_numpy_reference_beside_it(compiled_pass):
    assert compiled_pass.reference is not None
    assert compiled_pass.reference.__module__ == compiled_pass.compiled.__module__


@pytest.mark.parametrize('compiled_pass', PASSES, ids=lambda compiled_pass: compiled_pass.name)
def test_pass_gives_its_references_answers_on_its_examples(compiled_pass):
    examples = compiled_pass.examples()
    assert examples, 'a pass is warmed up and checked on at least one example'
    for index, (args, copies) in enumerate(zip(examples, compiled_pass.examples())):
        got = compiled_pass.compiled(*args)
        want = compiled_pass.reference(*copies)
        where = f'{compiled_pass.name}, example {index}'
        # None from a pass whose reference returns a result: the pass left its
        # own example to the reference, and warming it up compiled nothing.
        assert (got is None) == (want is None), where + ': left to the reference'
        tolerance = compiled_pass.atol, compiled_pass.rtol
        assert_same(got, want, *tolerance, where)
        assert_same(list(args), list(copies), *tolerance, where + ', arguments')
