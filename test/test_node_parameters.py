# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The node's parameters: it declares what it reads and warns of what does nothing."""

from dgmod_ros import config
import pytest
from rclpy.impl.rcutils_logger import RcutilsLogger
from rclpy.parameter import Parameter
from ros_harness import DetectorHarness


@pytest.fixture
def warnings(monkeypatch):
    said = []
    original = RcutilsLogger.warning

    def record(logger, message, **kwargs):
        said.append(message)
        return original(logger, message, **kwargs)
    monkeypatch.setattr(RcutilsLogger, 'warning', record)
    return said


def test_the_node_declares_only_what_it_reads_and_warns_of_inert_parameters(warnings):
    harness = DetectorHarness(mask_k=4.0, max_iter=50, median_size=3)
    try:
        node = harness.node
        declared = {name for name in config.BY_NAME if node.has_parameter(name)}
        assert declared == {spec.name for spec in config.reads(config.NODE)}
        assert 'max_iter' not in declared
        assert 'Acts only with decision=global' in node.describe_parameter('mask_k').description
        assert warnings == [            # one line each, in the table's order
            'median_size=3 has no effect: it acts only with decision=adaptive|uniform and '
            'mrf_beta=0.0 (decision is adaptive, mrf_beta is 2.0)',
            'mask_k=4.0 has no effect: it acts only with decision=global and '
            'mask_threshold=0.0 (decision is adaptive, mask_threshold is 0.0)',
            'max_iter is not a node parameter: it is read only by dgmod --mode batch']
        del warnings[:]
        # Now median_size acts, and a change that does something says nothing more.
        assert node.set_parameters([Parameter('mrf_beta', value=0.0)])[0].successful
        assert warnings == []
        # decision=global makes mask_k act, and median_size and mrf_beta (both set) inert.
        assert node.set_parameters([Parameter('decision', value='global')])[0].successful
        assert warnings == ['mrf_beta=0.0 has no effect: it acts only with '
                            'decision=adaptive|uniform (decision is global)',
                            'median_size=3 has no effect: it acts only with '
                            'decision=adaptive|uniform and mrf_beta=0.0 (decision is global, '
                            'mrf_beta is 0.0)']
        del warnings[:]
        assert node.set_parameters([Parameter('pixel_k', value=4.0)])[0].successful
        assert len(warnings) == 1 and warnings[0].startswith('pixel_k=4.0 has no effect')
    finally:
        harness.close()
