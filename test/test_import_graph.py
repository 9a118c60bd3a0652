# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The package's modules import one another without a circle, and the warm-up only from the top.

Every ``import`` of every module counts, at module level and inside
functions alike (a function-level import defers the load, not the
dependency): the layers are the compiled passes' leaf
(:mod:`dgmod_ros.core.numba_setup`), the compiled passes, the algorithms
that call them, and :mod:`dgmod_ros.core.warmup` above all of them, which
compiles every pass and is imported only by the entry points that must
have the passes compiled before the first frame.
"""

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / 'dgmod_ros'
WARMUP = 'dgmod_ros.core.warmup'
# The entry points, which compile every pass before a first frame would wait
# for one: the node, the command line and the demo (today all three through
# config's compile helper, load_kernels). Not kernel_cache: the leaf imports
# it, so its compile command lives in the warm-up module itself.
WARMUP_IMPORTERS = {'dgmod_ros.config', 'dgmod_ros.cli', 'dgmod_ros.demo',
                    'dgmod_ros.detector_node'}


def module_name(path):
    """Return the dotted name of a module file of the package."""
    parts = list(path.relative_to(PACKAGE.parent).with_suffix('').parts)
    if parts[-1] == '__init__':
        parts.pop()
    return '.'.join(parts)


def imported_modules(path, modules):
    """Return the package's modules that ``path`` imports anywhere in its body."""
    name = module_name(path)
    package = name if path.name == '__init__.py' else name.rpartition('.')[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ''
            if node.level:
                anchor = package.split('.')
                anchor = anchor[:len(anchor) - (node.level - 1)]
                base = '.'.join(anchor + ([base] if base else []))
            # ``from a import b``: b is a module of a, or a name defined in a.
            targets = [f'{base}.{alias.name}' if f'{base}.{alias.name}' in modules else base
                       for alias in node.names]
        else:
            continue
        for target in targets:
            # ``import a.b.c`` loads a, a.b and a.b.c: the deepest one of the package counts.
            while target and target not in modules:
                target = target.rpartition('.')[0]
            if target and target != name:
                found.add(target)
    return found


def import_graph():
    """Return {module: the package's modules it imports} over every module of the package."""
    paths = {module_name(path): path for path in PACKAGE.rglob('*.py')}
    return {name: imported_modules(path, paths) for name, path in paths.items()}


def find_cycle(graph):
    """Return one import circle as a list of modules (first one repeated at the end), or None."""
    state = {}
    stack = []

    def visit(node):
        state[node] = 'open'
        stack.append(node)
        for target in sorted(graph[node]):
            if state.get(target) == 'open':
                return stack[stack.index(target):] + [target]
            if target not in state:
                cycle = visit(target)
                if cycle:
                    return cycle
        stack.pop()
        state[node] = 'done'
        return None

    for node in sorted(graph):
        if node not in state:
            cycle = visit(node)
            if cycle:
                return cycle
    return None


def test_the_graph_sees_function_level_and_relative_imports():
    graph = import_graph()
    # linalg imports the compiled Gram matrix inside gram_matrix, relatively.
    assert 'dgmod_ros.core.kernels.dgmod' in graph['dgmod_ros.core.linalg']
    assert 'dgmod_ros.core.streaming.contract' in graph['dgmod_ros.core.streaming']


def test_find_cycle_reports_a_circle_and_none_without_one():
    assert find_cycle({'a': {'b'}, 'b': {'c'}, 'c': {'a'}}) == ['a', 'b', 'c', 'a']
    assert find_cycle({'a': {'b', 'c'}, 'b': {'c'}, 'c': set()}) is None


def test_the_package_imports_without_a_circle():
    cycle = find_cycle(import_graph())
    assert cycle is None, 'import circle: ' + ' -> '.join(cycle)


@pytest.mark.parametrize('module', sorted(WARMUP_IMPORTERS))
def test_the_warmup_importers_are_modules_of_the_package(module):
    assert module in import_graph()


def test_only_the_entry_points_import_the_warmup():
    graph = import_graph()
    assert WARMUP in graph
    importers = {name for name, targets in graph.items() if WARMUP in targets}
    assert importers <= WARMUP_IMPORTERS, sorted(importers - WARMUP_IMPORTERS)
