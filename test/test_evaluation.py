# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""``dgmod evaluate`` on a small CDnet-style dataset the test writes."""

import json

import cv2
from dgmod_ros import config
from dgmod_ros.core.preprocess import to_float_channels
from dgmod_ros.core.synthetic import synthetic_scene
from dgmod_ros.evaluation import evaluate, load_dataset, reference_background, write_composite
from dgmod_ros.inputs import read_frames
import numpy as np
import pytest


@pytest.fixture(scope='module')
def dataset(tmp_path_factory):
    scene = synthetic_scene(n_frames=30, shape=(48, 64), seed=9)
    root = tmp_path_factory.mktemp('cdnet') / 'synthetic'
    (root / 'input').mkdir(parents=True)
    (root / 'groundtruth').mkdir()
    for index, (frame, mask) in enumerate(zip(scene.frames, scene.masks)):
        cv2.imwrite(str(root / 'input' / f'in{index + 1:06d}.png'),
                    cv2.cvtColor(frame, cv2.COLOR_RGB2BGR))
        cv2.imwrite(str(root / 'groundtruth' / f'gt{index + 1:06d}.png'), mask)
    (root / 'temporalROI.txt').write_text('11 30\n')
    return scene, root


def test_reference_background_is_the_luma_of_the_true_background(dataset):
    scene, root = dataset
    data = load_dataset(root)
    assert (data.first, data.last) == (10, 29)
    reference = reference_background(list(read_frames(root)), data)
    truth = np.median([to_float_channels(b, 'rgb', 'gray')[:, :, 0]
                       for b in scene.backgrounds[10:]], axis=0)
    # Noise and light drift only: within a few grey levels (measured 0.01).
    assert np.median(np.abs(reference - truth)) < 0.03


def test_evaluate_scores_every_method_and_writes_its_outputs(dataset, tmp_path):
    _, root = dataset
    values = dict(config.DEFAULTS, window=10, stride=5)
    rows = evaluate([root], ['median', 'mog2'], values, 'stream', tmp_path)
    assert [r['method'] for r in rows] == ['median', 'mog2']
    assert all(r['scored_frames'] == 20 and r['re'] is not None for r in rows)
    # Measured on this short scene: F 0.68 (median: a 10-frame window holds
    # the shape) and 0.58 (mog2), RE of the mean background 0.10 and 0.12.
    assert rows[0]['fmeasure'] > 0.6 and rows[1]['fmeasure'] > 0.5
    assert all(r['re'] < 0.15 for r in rows)
    assert json.loads((tmp_path / 'results.json').read_text()) == rows
    for name in ('results.md', 'figure1_backgrounds_synthetic.png',
                 'figure2_foregrounds_synthetic.png'):
        assert (tmp_path / name).is_file()


def test_a_composite_copies_the_truth_and_passes_each_frame_through_in_order(dataset, tmp_path):
    _, root = dataset
    seen = []

    def transform(index, image):
        seen.append(index)
        return 255 - image

    out = tmp_path / 'composite'
    assert write_composite(root, out, transform, suffix='.png') == 30
    assert seen == list(range(30))
    assert (out / 'temporalROI.txt').read_text() == (root / 'temporalROI.txt').read_text()
    assert sorted(p.name for p in (out / 'groundtruth').iterdir()) == \
        sorted(p.name for p in (root / 'groundtruth').iterdir())
    first = cv2.imread(str(root / 'input' / 'in000001.png'))
    assert np.array_equal(cv2.imread(str(out / 'input' / 'in000001.png')), 255 - first)
    assert (load_dataset(out).first, load_dataset(out).last) == (10, 29)
