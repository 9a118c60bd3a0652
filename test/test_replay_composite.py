# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The replay composite's frame order and the folder it writes, on made-up frames (no data)."""

from benchmark_modules import load
import cv2
from dgmod_ros.evaluation import load_dataset
import numpy as np
import pytest


@pytest.fixture(scope='module')
def replay():
    return load('replay_composite')


def test_the_stretch_plays_forward_and_back_and_ends_forward(replay):
    order = replay.replay_order(8, 2, 4, 9)
    assert order == [0, 1, 2, 3, 4, 4, 3, 2, 2, 3, 4, 5, 6, 7]
    with pytest.raises(ValueError):
        replay.replay_order(8, 4, 4, 9)


def test_the_copy_pairs_each_frame_with_its_own_truth_and_scores_from_the_sources_first(
        replay, tmp_path):
    source = tmp_path / 'source'
    (source / 'input').mkdir(parents=True)
    (source / 'groundtruth').mkdir()
    for index in range(6):
        image = np.full((4, 5, 3), 10 * index, np.uint8)
        cv2.imwrite(str(source / 'input' / f'in{index + 1:06d}.png'), image)
        cv2.imwrite(str(source / 'groundtruth' / f'gt{index + 1:06d}.png'), image[:, :, 0])
    (source / 'temporalROI.txt').write_text('3 6\n')    # frames 3-6 scored (1-based)
    out = tmp_path / 'out'
    assert replay.main([str(source), str(out), '--start', '1', '--end', '3',
                        '--frames', '7']) == 0
    copy = load_dataset(out)
    frames = sorted((out / 'input').iterdir())
    values = [int(cv2.imread(str(path))[0, 0, 0]) // 10 for path in frames]
    truths = [int(cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)[0, 0]) // 10
              for path in copy.truths]
    assert values == truths == replay.replay_order(6, 1, 3, 7)
    assert values[copy.first] == 2 and copy.last == len(values) - 1
