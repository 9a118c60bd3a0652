# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The node's parameter rules without ROS: changes, parameters set, inert warnings."""

from types import SimpleNamespace

from dgmod_ros import config, node_parameters


def test_only_the_tables_parameters_are_changes():
    parameters = [SimpleNamespace(name='window', value=40),
                  SimpleNamespace(name='qos_overrides./image.subscription.depth', value=3)]
    assert node_parameters.table_changes(parameters) == {'window': 40}


def test_a_value_equal_to_the_default_is_not_set():
    values = dict(config.DEFAULTS, window=config.DEFAULTS['window'], tol=5e-4)
    assert node_parameters.set_by_user(values) == {'tol'}


def test_an_inert_parameter_is_warned_with_its_reason():
    values = dict(config.DEFAULTS, method='knn', tol=5e-4)
    assert node_parameters.inert_warnings(values, {'tol', 'window'}) == [
        'tol=0.0005 has no effect: it acts only with method=dgmod (method is knn)']


def test_a_change_warns_of_what_it_made_inert():
    previous = dict(config.DEFAULTS, tol=5e-4)
    values = dict(previous, method='knn')
    assert node_parameters.change_warnings(previous, values, {'method': 'knn'}) == [
        'tol=0.0005 has no effect: it acts only with method=dgmod (method is knn)']
    # Already inert before: not repeated.
    assert node_parameters.change_warnings(values, dict(values, window=40),
                                           {'window': 40}) == []


def test_an_offline_parameter_given_to_the_node_is_named():
    lines = node_parameters.not_node_warnings(['max_iter', 'window', 'use_sim_time'],
                                              lambda name: name == 'window', config.DEFAULTS)
    assert len(lines) == 1 and lines[0].startswith('max_iter is not a node parameter: ')


def test_the_log_lines():
    assert node_parameters.change_line({'window': 40, 'tol': 5e-4}) == \
        'parameters changed: tol=0.0005, window=40'
    line = node_parameters.configured_line(config.DEFAULTS, None, None)
    assert line.startswith(f"detector configured: method {config.DEFAULTS['method']}, ")
    assert line.endswith(f"input depth only ({config.DEFAULTS['input_transport']}), depth off")
