# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
from pathlib import Path

from dgmod_ros import config
from dgmod_ros.core.streaming import StreamingDetector
import pytest

REPO = Path(__file__).resolve().parents[1]


def test_parameter_file_lists_every_parameter_with_its_default():
    path = REPO / 'config' / 'detector.yaml'
    assert path.read_text() == config.parameter_file_text(), \
        'regenerate with: python -m dgmod_ros.config > config/detector.yaml'
    values = config.load_parameter_file(path)
    assert values == config.DEFAULTS
    assert all(type(values[k]) is type(v) for k, v in config.DEFAULTS.items())
    config.validate(values)


@pytest.mark.parametrize('method', config.BY_NAME['method'].choices)
def test_every_method_builds_a_detector(method):
    values = dict(config.DEFAULTS, method=method)
    detector = config.build_detector(values)
    assert isinstance(detector, StreamingDetector)          # the full contract
    assert isinstance(detector, config.detector_class(values))


@pytest.mark.parametrize('change, message', [
    ({'stride': 40}, 'stride must be'),
    ({'min_frames': 31}, 'min_frames must be'),
    ({'method': 'pca'}, 'method must be one of'),
    ({'scale': 0.0}, 'scale must be in'),
    ({'lambda2': 1.5}, 'lambda2 must be in'),
])
def test_invalid_combinations_are_refused(change, message):
    with pytest.raises(ValueError, match=message):
        config.validate(dict(config.DEFAULTS, **change))


def test_unknown_keys_in_a_parameter_file_are_refused(tmp_path):
    path = tmp_path / 'p.yaml'
    path.write_text('/detector:\n  ros__parameters:\n    windw: 3\n')
    with pytest.raises(ValueError, match='unknown parameters: windw'):
        config.load_parameter_file(path)
