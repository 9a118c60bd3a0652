# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The parameter constraints: each kind at its bounds, and the table agreeing with the core."""

import inspect
from numbers import Integral, Real

from dgmod_ros import config
from dgmod_ros.core.dgmod import DualGraphMOD
from dgmod_ros.core.masks import MaskRule
from dgmod_ros.core.streaming import SlidingWindowDetector
from dgmod_ros.core.subtractors import OpenCVSubtractor
from dgmod_ros.core.validation import describe, Interval, Options, satisfies, validate_params
import numpy as np
import pytest

OWNERS = (SlidingWindowDetector, DualGraphMOD, OpenCVSubtractor, MaskRule)


@pytest.mark.parametrize('closed, low_in, high_in', [('both', True, True),
                                                     ('left', True, False),
                                                     ('right', False, True),
                                                     ('neither', False, False)])
def test_interval_takes_its_bounds_as_closed_says(closed, low_in, high_in):
    interval = Interval(Real, 0, 1, closed=closed)
    assert interval.is_satisfied_by(0) is low_in
    assert interval.is_satisfied_by(1) is high_in
    assert interval.is_satisfied_by(0.5) and interval.is_satisfied_by(np.float32(0.5))
    for outside in (-1e-9, 1 + 1e-9, np.nan, np.inf, -np.inf, '0.5', True, None):
        assert not interval.is_satisfied_by(outside)


def test_integer_intervals_take_integral_numbers_and_odd_ones_only_odd():
    count = Interval(Integral, 1, None)
    assert count.is_satisfied_by(1) and count.is_satisfied_by(30.0)   # as YAML may write it
    assert count.is_satisfied_by(np.int64(7)) and count.is_satisfied_by(10 ** 9)
    assert not count.is_satisfied_by(0) and not count.is_satisfied_by(2.5)
    odd = Interval(Integral, 1, None, odd=True)
    assert odd.is_satisfied_by(1) and odd.is_satisfied_by(5) and not odd.is_satisfied_by(4)


def test_a_bound_may_name_another_parameter():
    class Owner:
        window = 30
    stride = Interval(Integral, 1, 'window')
    assert stride.is_satisfied_by(30, Owner) and not stride.is_satisfied_by(31, Owner)
    assert stride.describe(Owner) == 'an integer in [1, window=30]'


def test_options_and_none_and_their_words():
    allowed = [None, Options('auto'), Interval(Real, 0, None, closed='neither')]
    assert satisfies(allowed, None) and satisfies(allowed, 'auto') and satisfies(allowed, 2.0)
    assert not satisfies(allowed, 'Auto') and not satisfies(allowed, 0.0)
    assert describe(allowed) == "None or 'auto' or a positive finite number"
    assert describe([Interval(Real, 0, 1, closed='right')]) == 'a finite number in (0, 1]'
    assert describe([Interval(Integral, 1, None, odd=True)]) == 'a positive odd integer'
    assert describe([Options('a', 'b', 'c')]) == "one of 'a', 'b', 'c'"


def test_validate_params_names_the_first_bad_parameter_in_declaration_order():
    class Owner:
        _parameter_constraints = {'a': [Interval(Integral, 2, None)],
                                  'b': [Interval(Integral, 1, 'a')]}
        a, b = 1, 5
    with pytest.raises(ValueError, match=r'^a must be an integer >= 2, got 1$'):
        validate_params(Owner())
    Owner.a = 4
    with pytest.raises(ValueError, match=r'^b must be an integer in \[1, a=4\], got 5$'):
        validate_params(Owner())
    Owner.b = 4
    assert validate_params(Owner()).b == 4


@pytest.mark.parametrize('owner', OWNERS, ids=lambda owner: owner.__name__)
def test_every_declared_constraint_is_of_a_constructor_parameter_and_takes_its_default(owner):
    parameters = inspect.signature(owner).parameters
    instance = owner()
    for name, allowed in owner._parameter_constraints.items():
        assert name in parameters, name
        assert satisfies(allowed, parameters[name].default, instance), name
    validate_params(instance)


def _shared_parameters():
    """Yield (table entry, core owner, constraints) for each table parameter the core declares."""
    for spec in config.PARAMETERS:
        for owner in OWNERS[:3]:                # MaskRule's are the table's mask_ ones
            constraints = owner._parameter_constraints.get(spec.name)
            if constraints is not None:
                yield spec, owner, constraints
        if spec.name.startswith('mask_') and spec.name[5:] in MaskRule._parameter_constraints:
            yield spec, MaskRule, MaskRule._parameter_constraints[spec.name[5:]]


SHARED = list(_shared_parameters())


def test_the_table_shares_most_of_its_solver_and_detector_parameters_with_the_core():
    assert len({spec.name for spec, _, _ in SHARED}) >= 30


@pytest.mark.parametrize('spec, owner, constraints', SHARED,
                         ids=[f'{owner.__name__}.{spec.name}' for spec, owner, _ in SHARED])
def test_the_tables_choices_and_range_lie_inside_the_cores_constraints(spec, owner, constraints):
    # What the node's descriptors and the command line let through, the core
    # takes; the table's 0 stands for the core's automatic value (None or 'auto').
    instance = owner()
    choices = tuple(value for c in constraints if isinstance(c, Options) for value in c.values)
    automatic = None in constraints or 'auto' in choices

    def takes(value):
        return satisfies(constraints, value, instance) or (value == 0 and automatic)

    if spec.choices:
        assert spec.choices == choices, 'the table takes its choices from the core'
        return
    assert takes(spec.default)
    if spec.low is not None:
        named = [c for c in constraints if isinstance(c, Interval)
                 and isinstance(c.high, str)]
        assert takes(spec.low)
        assert takes(spec.high) or named, f'{spec.high} outside {describe(constraints)}'
