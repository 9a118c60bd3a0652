# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
from pathlib import Path

from dgmod_ros import config
from dgmod_ros.config import BATCH, NODE, STREAM
from dgmod_ros.core.streaming import StreamingDetector
from dgmod_ros.core.synthetic import synthetic_scene
from dgmod_ros.inputs import Frame
from dgmod_ros.sequence import stream_results
import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[1]


def test_parameter_file_lists_every_parameter_with_its_default():
    path = REPO / 'config' / 'detector.yaml'
    assert path.read_text() == config.parameter_file_text(), \
        'regenerate with: python -m dgmod_ros.config > config/detector.yaml'
    values = config.load_parameter_file(path)
    # The node's parameters, each once; the offline-only ones are comments there.
    assert values == {spec.name: spec.default for spec in config.reads(NODE)}
    assert all(type(values[k]) is type(config.DEFAULTS[k]) for k in values)
    config.validate(dict(config.DEFAULTS, **values))
    assert 'max_iter' not in values and '#   max_iter: 300' in path.read_text()


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


def _condition_parameters(spec):
    return [(name, allowed) for alternative in spec.active_when for name, allowed in alternative]


@pytest.mark.parametrize('spec', config.PARAMETERS, ids=lambda spec: spec.name)
def test_every_entry_says_where_it_acts_and_when(spec):
    assert spec.where in ('node', 'offline', 'both') and set(spec.acts) <= set(config.EVERYWHERE)
    config.check_value(spec.name, spec.default)

    def check(current, path):        # conditions name known parameters, without a cycle
        for name, allowed in _condition_parameters(current):
            assert name in config.BY_NAME and name not in path, f'{spec.name}: {path + (name,)}'
            other = config.BY_NAME[name]
            named = allowed.values if isinstance(allowed, config.Not) else allowed
            for value in named:          # a value the other parameter can take
                config.check_value(name, type(other.default)(value))
            check(other, path + (name,))
    check(spec, (spec.name,))
    if spec.active_when:                 # the descriptions say when
        assert 'Acts only with ' + config.conditions_text(spec) in config.describe(spec)


def test_solver_internals_are_advanced_and_the_integrators_parameters_are_not():
    advanced = {spec.name for spec in config.PARAMETERS if spec.advanced}
    assert {'rho1', 'rho2', 'inner_iter', 'l_step', 'noise_source', 'solve_lag',
            'stream_max_iter', 'solve_pixels', 'refit_background'} <= advanced
    assert not advanced & {'method', 'window', 'stride', 'scale', 'pixel_k', 'decision',
                           'use_depth'}
    groups = config.parameter_groups(config.PARAMETERS)
    assert groups[-1] == (config.ADVANCED_TITLE, [s for s in config.PARAMETERS if s.advanced])
    assert sorted(s.name for _, specs in groups for s in specs) == sorted(config.BY_NAME)


@pytest.mark.parametrize('name, change, context, inert', [
    ('mask_k', {}, STREAM, True),
    ('mask_k', {'decision': 'global'}, STREAM, False),
    ('mask_k', {'decision': 'global', 'mask_threshold': 0.2}, NODE, True),
    ('mask_k', {}, BATCH, False),                     # batch always thresholds |S|
    ('mask_threshold', {}, NODE, True),
    ('median_size', {}, STREAM, True),
    ('median_size', {'mrf_beta': 0.0}, STREAM, False),
    ('median_size', {'mrf_beta': 0.0, 'decision': 'global'}, STREAM, True),
    ('morph_size', {}, STREAM, True),
    ('morph_size', {'method': 'mog2'}, STREAM, False),
    ('morph_size', {'decision': 'global'}, NODE, False),
    ('morph_size', {}, BATCH, False),
    ('texture_bits', {'decision': 'global'}, STREAM, True),     # through texture_cue
    ('texture_bits', {}, STREAM, False),
    ('moving_texture_bits', {'moving_texture_k': 0.0}, STREAM, True),
    ('max_iter', {}, STREAM, True),
    ('max_iter', {}, NODE, True),
    ('max_iter', {}, BATCH, False),
    ('max_iter', {'method': 'median'}, BATCH, True),
    ('stream_max_iter', {}, BATCH, True),
    ('lambda2', {'method': 'lago'}, BATCH, True),
    ('pixel_k', {'method': 'knn'}, NODE, True),
    ('solve_lag', {}, NODE, True),                    # async installs a solve when it ends
    ('solve_lag', {'solve_mode': 'sync'}, NODE, False),
    ('solve_lag', {}, STREAM, False),
    ('depth_slop', {}, NODE, True),
    ('depth_slop', {'use_depth': True}, NODE, False),
])
def test_inert_parameters_follow_the_table(name, change, context, inert):
    reasons = config.inert_parameters(dict(config.DEFAULTS, **change), [name], context)
    assert (name in reasons) == inert
    if inert:
        assert reasons[name].startswith('it ')


def test_an_inert_reason_names_the_choice_that_makes_it_inert():
    values = dict(config.DEFAULTS, decision='global')
    assert config.inert_reason('texture_bits', values, STREAM) == (
        'it acts only with texture_cue=true (texture_cue is true), and texture_cue has no '
        'effect: acts only with decision=adaptive|uniform (decision is global)')
    assert config.inert_reason('mask_k', dict(config.DEFAULTS), NODE) == (
        'it acts only with decision=global and mask_threshold=0.0 (decision is adaptive, '
        'mask_threshold is 0.0)')


# What the table's active_when claims, checked against the detector: under each of these
# choices, every parameter the table calls inert leaves the masks byte for byte.
_CHOICES = [{}, {'decision': 'global'}, {'mrf_beta': 0.0, 'moving_texture_k': 0.0,
                                         'texture_cue': False, 'conditional_update': False},
            {'method': 'median'}, {'method': 'mog2'}]


def _other_value(spec, values):
    """Return a value of ``spec`` other than the current one that passes validation."""
    current = values[spec.name]
    if isinstance(current, bool):
        candidates = [not current]
    elif spec.choices:
        candidates = [c for c in spec.choices if c != current]
    else:
        step = spec.step if isinstance(current, int) else 0
        candidates = [current + 2 * step if step else current * 2, current + (step or 0.1),
                      spec.high, spec.low]
    for value in candidates:
        value = type(current)(value)
        if value != current:
            try:
                return value, config.validate(dict(values, **{spec.name: value}))
            except ValueError:
                continue
    raise AssertionError(f'no other valid value of {spec.name}')


def _stream_masks(values, frames):
    return [mask for _, mask, _, _ in stream_results(frames, values)]


@pytest.fixture(scope='module')
def short_stream():
    scene = synthetic_scene(n_frames=40, shape=(48, 64), seed=5)
    return [Frame(index, f'{index:06d}', frame, 'rgb') for index, frame in enumerate(scene.frames)]


def _choice_id(choice):
    return ','.join(f'{name}={value}' for name, value in choice.items()) or 'defaults'


@pytest.mark.parametrize('choice', _CHOICES, ids=_choice_id)
def test_what_the_table_calls_inert_leaves_the_masks_unchanged(choice, short_stream):
    values = config.validate(dict(config.DEFAULTS, window=12, stride=4, memory_spacing=1,
                                  **choice))
    reference = _stream_masks(values, short_stream)
    inert = config.inert_parameters(values, [s.name for s in config.reads(STREAM)], STREAM)
    assert inert or choice == {}, 'each choice makes something inert'
    for name in sorted(inert):
        value, changed = _other_value(config.BY_NAME[name], values)
        masks = _stream_masks(changed, short_stream)
        assert all(np.array_equal(a, b) for a, b in zip(reference, masks)), \
            f'{name}={value} changed the masks under {choice or "the defaults"}'
