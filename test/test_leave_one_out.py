# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The leave-one-out benchmark's choice, summary and cache, on made-up scores (no data)."""

from benchmark_modules import load
import pytest


@pytest.fixture(scope='module')
def loo():
    return load('leave_one_out')


SEQUENCES = ['a', 'b', 'c', 'd']


def _scores(table):
    return {value: {s: {'fmeasure': f} for s, f in zip(SEQUENCES, row)}
            for value, row in table.items()}


def test_each_held_out_sequence_gets_the_value_best_on_the_others(loo):
    # pixel_k's default is 6.0; 7.5 is best on a, b, c; 4.5 only on d, by far
    scores = _scores({4.5: [0.5, 0.5, 0.5, 0.99], 6.0: [0.8, 0.8, 0.8, 0.8],
                      7.5: [0.9, 0.9, 0.9, 0.1]})
    summary = loo.leave_one_out('pixel_k', scores, SEQUENCES, gap=0.005)
    held = {s: (h['chosen'], h['fmeasure']) for s, h in summary['held_out'].items()}
    # without d, 7.5 wins (0.9 against 0.8); without a, the means are 0.663 / 0.8 / 0.633: 6.0
    assert held['d'] == (7.5, 0.1)
    assert held['a'] == (6.0, 0.8)
    assert held['b'] == (6.0, 0.8) and held['c'] == (6.0, 0.8)
    assert summary['loo_mean'] == pytest.approx((0.8 * 3 + 0.1) / 4)
    assert summary['all_seven_choice'] == 6.0
    assert summary['all_seven_mean'] == pytest.approx(0.8)
    # the default leads on the mean yet is beaten on every sequence (7.5 on a, b, c; 4.5 on d)
    assert summary['default_wins'] == 0
    assert 'FEW WINS' in summary['flags'] and 'LOO GAP' in summary['flags']


def test_ties_keep_the_default_and_a_sound_default_is_not_flagged(loo):
    scores = _scores({10: [0.8, 0.7, 0.6, 0.5], 15: [0.8, 0.7, 0.6, 0.5],
                      25: [0.79, 0.69, 0.59, 0.49]})
    summary = loo.leave_one_out('still_frames', scores, SEQUENCES, gap=0.005)
    assert all(h['chosen'] == 15 for h in summary['held_out'].values())
    assert summary['loo_mean'] == pytest.approx(summary['default_mean'])
    assert summary['default_wins'] == 4 and summary['flags'] == []


def test_missing_scores_give_no_summary(loo):
    scores = _scores({15: [0.8, 0.7, 0.6, 0.5], 25: [0.8, 0.7, 0.6, 0.5]})
    del scores[25]['d']
    assert loo.leave_one_out('still_frames', scores, SEQUENCES, gap=0.005) is None


def test_cache_reuses_scores_of_the_same_mask_code_only(loo, tmp_path):
    path = tmp_path / 'cache.json'
    cache = loo.ScoreCache(path, 'code1', 'abc', any_code=False)
    key = loo.cache_key('pixel_k', 6.0, 'a', None)
    assert key == loo.cache_key('still_frames', 15, 'a', None)      # one defaults run
    assert key != loo.cache_key('pixel_k', 6.0, 'a', 300)
    cache.put(key, {'fmeasure': 0.5})
    assert loo.ScoreCache(path, 'code1', 'def', False).get(key)['fmeasure'] == 0.5
    assert loo.ScoreCache(path, 'code2', 'abc', False).get(key) is None
    assert loo.ScoreCache(path, 'code2', 'abc', True).get(key)['fmeasure'] == 0.5


def test_mask_code_follows_the_detector_not_the_scoring(loo, tmp_path):
    package = tmp_path / 'dgmod_ros'
    (package / 'core').mkdir(parents=True)
    (package / 'core' / 'masks.py').write_text('a = 1\n')
    (package / 'core' / 'metrics.py').write_text('b = 1\n')
    before = loo.mask_code(tmp_path)
    (package / 'core' / 'metrics.py').write_text('b = 2\n')
    assert loo.mask_code(tmp_path) == before
    (package / 'core' / 'masks.py').write_text('a = 2\n')
    assert loo.mask_code(tmp_path) != before
