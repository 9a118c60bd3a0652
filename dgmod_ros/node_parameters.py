# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The detector node's parameter rules (no ROS import).

Which of the table's parameters a set of ROS parameters changes, which ones
the user set, and the warnings about parameters that do nothing here
(:func:`dgmod_ros.config.inert_parameters`); the node declares the
parameters and logs the lines.
"""

from . import config


def table_changes(parameters):
    """
    Return ``{name: value}`` of the table's parameters among ``parameters``.

    ``parameters``: objects with ``name`` and ``value`` (rclpy's
    ``Parameter``); others (``qos_overrides.*``) are left out.
    """
    return {p.name: p.value for p in parameters if p.name in config.BY_NAME}


def set_by_user(values):
    """Return the node parameters whose value is not the default (a full file repeats them)."""
    return {spec.name for spec in config.reads(config.NODE)
            if values[spec.name] != spec.default}


def inert_warnings(values, names):
    """Return one warning line for each of ``names`` that has no effect with ``values``."""
    return [f'{name}={values[name]} has no effect: {reason}'
            for name, reason in config.inert_parameters(values, names, config.NODE).items()]


def not_node_warnings(overrides, declared, values):
    """
    Return one warning line for each override of a table parameter the node does not read.

    ``overrides``: the names given at start-up; ``declared(name)``: whether
    the node declared it.
    """
    return [f'{name} is not a node parameter: '
            f'{config.inert_reason(name, values, config.NODE)}'
            for name in overrides if name in config.BY_NAME and not declared(name)]


def change_warnings(previous, values, changed):
    """
    Return the warnings after ``changed`` turned ``previous`` into ``values``.

    The changed parameters that do nothing, and those set before that this
    change made inert.
    """
    before = config.inert_parameters(previous, set_by_user(previous), config.NODE)
    return inert_warnings(values, set(changed) | (set_by_user(values) - set(before)))


def change_line(changed):
    """Return the log line of the parameters ``changed`` (``{name: value}``)."""
    return 'parameters changed: ' + ', '.join(
        f'{name}={value}' for name, value in sorted(changed.items()))


def configured_line(values, input_topic, depth):
    """Return the log line of a configured node (``input_topic`` None: depth only)."""
    return (f"detector configured: method {values['method']}, window "
            f"{values['window']}, stride {values['stride']}, scale "
            f"{values['scale']}, solve_mode {values['solve_mode']}, input "
            f"{input_topic or 'depth only'} "
            f"({values['input_transport']}), depth "
            f"{'on' if depth else 'off'}")


def processing_line(image_shape, encoding, processing_size, values):
    """
    Return the log line of a first frame: its size and the size its masks are computed at.

    The configured line names ``scale``; what a camera's frames are processed
    at also depends on ``processing_pixels`` and is known only once a frame came.
    """
    rows, cols = processing_size
    return (f'frames of {image_shape[1]} x {image_shape[0]} {encoding}: masks computed at '
            f"{cols} x {rows} (scale {values['scale']}, processing_pixels "
            f"{values['processing_pixels']})")
