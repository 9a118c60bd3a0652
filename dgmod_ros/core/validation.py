# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Parameter constraints declared once, beside the class they constrain.

scikit-learn's model (``sklearn/utils/_param_validation.py``): a class lists
its constructor parameters' constraints in ``_parameter_constraints``, a dict
``{name: [constraint, ...]}`` in the order they are checked (a value is
valid when one constraint of its list takes it), and :func:`validate_params`
checks an instance against it and raises ``ValueError`` naming the first bad
parameter and what it must be. The same declarations give the parameter
table (:mod:`dgmod_ros.config`) its choices and are what its ranges are
tested against, so the node's descriptors, the command line and the core
cannot disagree on what is valid.

Constraints: :class:`Interval` (numbers in a range, possibly integers,
possibly odd; a bound may name another parameter, as ``stride <= window``),
:class:`Options` (one of some values) and ``None``.
"""

from numbers import Integral, Real

import numpy as np


class Interval:
    """
    Numbers in a range: ``kind`` (``Integral`` or ``Real``) between ``low`` and ``high``.

    Parameters
    ----------
    kind : type
        ``Integral``: a number equal to an integer (``30.0`` counts, as a
        YAML file may write it); ``Real``: a finite number.
    low, high : float, str or None
        The bounds; a str names another parameter of the same instance; None: unbounded.
    closed : {'both', 'left', 'right', 'neither'}
        Which bounds belong to the range.
    odd : bool
        Odd integers only (a filter's side).

    """

    def __init__(self, kind, low, high, closed='both', odd=False):
        self.kind = kind
        self.low = low
        self.high = high
        self.closed = closed
        self.odd = odd

    def bounds(self, owner=None):
        """Return ``(low, high)`` with bounds that name a parameter read from ``owner``."""
        return tuple(getattr(owner, bound) if isinstance(bound, str) else bound
                     for bound in (self.low, self.high))

    def is_satisfied_by(self, value, owner=None):
        """Return whether ``value`` lies in the range (bounds named read from ``owner``)."""
        if isinstance(value, (bool, np.bool_, str)) or not isinstance(value, Real):
            return False
        if not np.isfinite(value):
            return False
        if self.kind is Integral and (int(value) != value or (self.odd and value % 2 == 0)):
            return False
        low, high = self.bounds(owner)
        left = self.closed in ('both', 'left')
        right = self.closed in ('both', 'right')
        if low is not None and not (low <= value if left else low < value):
            return False
        return high is None or (value <= high if right else value < high)

    def describe(self, owner=None):
        """Return what a valid value is, in words (the error messages')."""
        noun = ('odd integer' if self.odd else 'integer') if self.kind is Integral \
            else 'finite number'
        low, high = self.bounds(owner)
        left = self.closed in ('both', 'left')
        if high is None and low == 0:       # the common ranges, in their common words
            return f'a {"non-negative" if left else "positive"} {noun}'
        if high is None and low == 1 and self.kind is Integral and left:
            return f'a positive {noun}'
        article = 'an' if noun[0] in 'aeiou' else 'a'
        names = [f'{bound}={value}' if isinstance(bound, str) else f'{value}'
                 for bound, value in ((self.low, low), (self.high, high))]
        if high is None:
            if low is None:
                return f'{article} {noun}'
            return f'{article} {noun} {">=" if left else ">"} {names[0]}'
        opening = '[' if left else '('
        closing = ']' if self.closed in ('both', 'right') else ')'
        return f'{article} {noun} in {opening}{names[0]}, {names[1]}{closing}'


class Options:
    """One of a few values (strings, as the parameter table's choices)."""

    def __init__(self, *values):
        self.values = tuple(values)

    def is_satisfied_by(self, value, owner=None):
        """Return whether ``value`` is one of the options."""
        return isinstance(value, str) and value in self.values

    def describe(self, owner=None):
        """Return the options, in words."""
        if len(self.values) <= 2:
            return ' or '.join(repr(value) for value in self.values)
        return 'one of ' + ', '.join(repr(value) for value in self.values)


#: The common ranges, shared by every class that declares constraints (tuples:
#: a list of constraints is read, never changed; ``(None, *POSITIVE)`` adds None).
POSITIVE = (Interval(Real, 0, None, closed='neither'),)
NON_NEGATIVE = (Interval(Real, 0, None),)
POSITIVE_INTEGER = (Interval(Integral, 1, None),)
NON_NEGATIVE_INTEGER = (Interval(Integral, 0, None),)


def satisfies(constraints, value, owner=None):
    """Return whether ``value`` satisfies one of ``constraints`` (None: the value None)."""
    return any(value is None if constraint is None
               else constraint.is_satisfied_by(value, owner) for constraint in constraints)


def describe(constraints, owner=None):
    """Return what a value satisfying one of ``constraints`` is, in words."""
    return ' or '.join('None' if constraint is None else constraint.describe(owner)
                       for constraint in constraints)


def validate_params(owner, constraints=None):
    """
    Raise ``ValueError`` naming the first parameter of ``owner`` outside its constraints.

    ``constraints`` defaults to ``type(owner)._parameter_constraints``; they
    are checked in their order, so that a bound naming another parameter is
    checked after that parameter. Returns ``owner``.
    """
    if constraints is None:
        constraints = type(owner)._parameter_constraints
    for name, allowed in constraints.items():
        value = getattr(owner, name)
        if not satisfies(allowed, value, owner):
            raise ValueError(f'{name} must be {describe(allowed, owner)}, got {value!r}')
    return owner


def options(constraints):
    """Return the values of the :class:`Options` among ``constraints`` (the table's choices)."""
    return tuple(value for constraint in constraints if isinstance(constraint, Options)
                 for value in constraint.values)
