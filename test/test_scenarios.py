# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The scenario suite: determinism, exact ground truth, scripted behaviour, layout, accuracy."""

import json
import subprocess
import sys

import cv2
from dgmod_ros.core.metrics import ConfusionCounts, PersonCounts
import numpy as np
import pytest

SHORT = 0.1     # the tests' suite: lingering and still spans at a tenth (the 60 s stand: 6 s)


@pytest.fixture(scope='module')
def material(data_dir):
    from dgmod_ros.scenarios import load_material
    return load_material(data_dir)


@pytest.fixture(scope='module')
def suite(material):
    from dgmod_ros.scenarios import build_scenario, SCENARIO_NAMES
    return {n: build_scenario(n, material, seed=0, duration_scale=SHORT) for n in SCENARIO_NAMES}


def _blobs(truth, min_area=100):
    count, _, stats, centroids = cv2.connectedComponentsWithStats(
        (truth == 255).astype(np.uint8), connectivity=8)
    keep = [i for i in range(1, count) if stats[i, cv2.CC_STAT_AREA] >= min_area]
    return stats[keep], centroids[keep]


def test_same_seed_same_frames_other_seed_other_frames(material):
    from dgmod_ros.scenarios import build_scenario
    first = build_scenario('crossing', material, seed=3, duration_scale=SHORT)
    again = build_scenario('crossing', material, seed=3, duration_scale=SHORT)
    other = build_scenario('crossing', material, seed=4, duration_scale=SHORT)
    assert len(first) == len(again)
    for k in (0, len(first) // 3, len(first) // 2, len(first) - 1):
        image, truth = first.render(k)
        image_again, truth_again = again.render(k)
        assert np.array_equal(image, image_again) and np.array_equal(truth, truth_again)
    k = min(len(first), len(other)) // 2
    assert not np.array_equal(first.render(k)[0], other.render(k)[0])


def test_background_and_people_come_from_the_people_clips(material):
    from dgmod_ros.scenarios.material import PEOPLE_CLIPS
    assert set(material.backgrounds) <= set(PEOPLE_CLIPS)
    assert len(material.backgrounds) >= 4 and len(material.tracks) >= 4 and material.close_ups
    for background in material.backgrounds.values():
        assert background.unseen_fraction <= 0.02
        assert background.image.dtype == np.float32
        assert 0 <= background.image.min() and background.image.max() <= 255
    for track in material.tracks:
        assert all(c.clip == track.clip for c in track.cutouts)
        assert np.all(np.diff([c.frame for c in track.cutouts]) == 1)


@pytest.mark.parametrize('name', ['in_view', 'stops', 'close_up', 'crossing', 'close_in_view'])
def test_ground_truth_is_the_pasted_alpha(suite, name):
    from dgmod_ros.scenarios.compose import BAND_ALPHA
    scenario = suite[name]
    checked = 0
    for k in np.linspace(0, len(scenario) - 1, 7).astype(int):
        image, truth = scenario.render(k)
        alpha = scenario.coverage(k)
        assert set(np.unique(truth)) <= {0, 170, 255}
        assert np.array_equal(truth == 255, alpha > 0.5)
        assert np.array_equal(truth == 170, (alpha > BAND_ALPHA) & (alpha <= 0.5))
        # away from the people the frame is the background under the camera's gain and noise
        clean, _ = scenario._compose(k, with_image=True)
        assert np.array_equal(clean[alpha == 0], scenario.background.image[alpha == 0])
        if (truth == 255).any():
            checked += 1
            # the soft band is a thin rim around the people
            band = truth == 170
            assert band.any()
            # (the feather's kernel reaches 4 pixels; a finger thinner than the
            # feather has a band and no 255 pixel, hence a share)
            rim = cv2.dilate((truth == 255).astype(np.uint8), np.ones((9, 9), np.uint8)) > 0
            assert np.mean(rim[band]) > 0.98
    assert checked >= 3


def test_one_person_pasted_where_the_script_says(suite):
    scenario = suite['stops']
    actor = scenario.actors[0]
    k = scenario.phases['still'][0] + 5
    rgb, alpha, top, left = actor.sprite(k)
    expected = np.zeros(scenario.shape, np.float32)
    rows, cols = scenario.shape
    y0, x0 = max(top, 0), max(left, 0)
    y1, x1 = min(top + alpha.shape[0], rows), min(left + alpha.shape[1], cols)
    expected[y0:y1, x0:x1] = alpha[y0 - top:y1 - top, x0 - left:x1 - left]
    assert np.array_equal(scenario.coverage(k), expected)
    # feet on the scripted row and centred on the scripted column
    ys, xs = np.nonzero(scenario.coverage(k) > 0.5)
    assert abs(ys.max() - actor.y[k]) <= 1
    assert abs(0.5 * (xs.min() + xs.max()) - actor.x[k]) <= 1.5


def test_the_still_person_does_not_move_over_the_still_span(suite):
    scenario = suite['stops']
    first, last = scenario.phases['still']
    assert last - first + 1 == round(60 * scenario.fps * SHORT)
    actor = scenario.actors[0]
    span = slice(first, last + 1)
    for column in (actor.x, actor.y, actor.height, actor.pose):
        assert np.all(column[span] == column[first])
    reference = scenario.render(first)[1]
    for k in (first + 1, (first + last) // 2, last):
        assert np.array_equal(scenario.render(k)[1], reference)
    # it walked in (moved before the span) and leaves (nobody in the last frame)
    assert np.ptp(actor.x[:first][actor.pose[:first] >= 0]) > 20
    assert not (scenario.render(0)[1] == 255).any()
    assert not (scenario.render(len(scenario) - 1)[1] == 255).any()


def test_in_view_people_are_there_from_the_first_frame_and_stay_near(suite):
    scenario = suite['in_view']
    first = scenario.render(0)[1]
    stats, _ = _blobs(first)
    assert len(stats) == 2
    for actor in scenario.actors:
        assert np.all(actor.pose >= 0)
        width = actor.cutouts[0].mask.shape[1] * actor.height.max() / actor.source_height
        assert np.ptp(actor.x) <= 1.0 * width
        assert np.ptp(actor.x) > 0


def test_close_up_covers_30_to_60_percent_of_the_view(suite):
    scenario = suite['close_up']
    first, last = scenario.phases['close']
    assert not (scenario.render(0)[1] == 255).any()
    shares = [np.mean(scenario.coverage(k) > 0.5) for k in np.linspace(first, last, 9).astype(int)]
    assert 0.3 <= min(shares) and max(shares) <= 0.6
    # cut by the frame's bottom: the body continues below the view
    truth = scenario.render(first)[1]
    assert (truth[-1] == 255).any()


def test_close_in_view_is_close_up_from_the_first_frame(suite):
    scenario = suite['close_in_view']
    assert scenario.phases['close'] == (0, len(scenario) - 1)
    assert np.all(scenario.actors[0].pose >= 0)
    shares = [np.mean(scenario.coverage(k) > 0.5)
              for k in np.linspace(0, len(scenario) - 1, 9).astype(int)]
    assert 0.3 <= min(shares) and max(shares) <= 0.6
    assert (scenario.render(0)[1][-1] == 255).any()
    # moving about: the middle of the body is never uncovered, its sides are
    covered = [scenario.coverage(k) > 0.5 for k in range(len(scenario))]
    always, ever = np.logical_and.reduce(covered), np.logical_or.reduce(covered)
    assert always.any() and (ever & ~always).any()


def test_crossing_people_pass_each_other(suite):
    scenario = suite['crossing']
    a, b = scenario.actors
    both = (a.pose >= 0) & (b.pose >= 0)
    order = np.sign(a.x[both] - b.x[both])
    assert (order > 0).any() and (order < 0).any()
    assert a.y[both].mean() != b.y[both].mean()


def test_written_layout_is_what_the_tools_read(suite, tmp_path, data_dir):
    from dgmod_ros.evaluation import load_dataset
    from dgmod_ros.inputs import read_frames
    from dgmod_ros.scenarios import write_sequence
    scenario = suite['close_up']
    folder = write_sequence(scenario, tmp_path / 'close_up')
    count = len(scenario)
    assert sorted(p.name for p in (folder / 'input').iterdir())[0] == 'in000001.png'
    assert len(list((folder / 'groundtruth').glob('gt*.png'))) == count
    assert (folder / 'temporalROI.txt').read_text().split() == ['1', str(count)]
    assert (cv2.imread(str(folder / 'ROI.bmp'), cv2.IMREAD_GRAYSCALE) == 255).all()
    assert json.loads((folder / 'scenario.json').read_text())['frames'] == count
    dataset = load_dataset(folder)
    assert (dataset.first, dataset.last) == (0, count - 1)
    frames = list(read_frames(folder))
    k = count // 2
    rgb, truth = scenario.render(k)
    assert np.array_equal(frames[k].image[:, :, ::-1], rgb)          # read as BGR, lossless
    assert np.array_equal(cv2.imread(str(dataset.truths[k]), cv2.IMREAD_GRAYSCALE), truth)
    # the planner's view agrees with the shared tool on the same masks
    tool = data_dir.parent / 'tools' / 'object_recall.py'
    masks = tmp_path / 'masks'
    masks.mkdir()
    counts = PersonCounts()
    for j in range(count):
        truth = cv2.imread(str(dataset.truths[j]), cv2.IMREAD_GRAYSCALE)
        mask = np.zeros_like(truth)
        mask[(truth == 255) & (np.arange(truth.shape[1]) < truth.shape[1] * (j % 3) / 2)] = 255
        mask[:12, :12] = 255
        cv2.imwrite(str(masks / f'bin{j + 1:06d}.png'), mask)
        counts.add(mask, truth)
    report = json.loads(subprocess.run([sys.executable, str(tool), str(folder), str(masks),
                                        '--json'], capture_output=True, text=True,
                                       check=True).stdout)
    assert report['person_recall'] == pytest.approx(counts.person_recall)
    assert report['false_blobs_per_frame'] == pytest.approx(counts.false_blobs_per_frame)


def test_command_line_writes_the_suite(material, data_dir, tmp_path, monkeypatch):
    from dgmod_ros.scenarios import __main__ as command
    read = []
    monkeypatch.setattr(command, 'load_material', lambda path: read.append(path) or material)
    assert command.main(['--out', str(tmp_path), '--data', str(data_dir), '--only', 'close_up',
                         '--duration-scale', '0.05']) == 0
    assert read == [str(data_dir)]
    monkeypatch.undo()
    main = command.main
    assert (tmp_path / 'close_up' / 'temporalROI.txt').is_file()
    assert main(['--out', str(tmp_path), '--data', str(tmp_path / 'nowhere')]) == 2


# The streaming detector at the package defaults on the short suite (seed 0):
# (F floor, person recall floor), each about 0.03 below the figure measured on
# the same frames (docs/results.md, "The scenario suite"). Low where the
# detector is known to fail (issue 22): people in view from the first frame
# (at this scale close_in_view is 45 frames, most of them while the window
# still fills with consecutive frames: the figures are those of a first start).
SCENARIO_FLOORS = {
    'in_view': (0.59, 0.52),        # measured F 0.621, person recall 0.558 (0.616, 0.558
                                    # before a level the model misses by in every column
                                    # was read as its offset; 0.593, 0.492
                                    # before the fill bridged outlines; 0.565, 0.383 before
                                    # it held out a body that came in; 0.524, 0.308 before
                                    # the first frame counted as settled)
    'stops': (0.96, 0.97),          # measured 0.995, 1.000
    'close_up': (0.97, 0.97),       # measured 0.997, 1.000 (0.959, 1.000 before the fill
                                    # closed a body cut by one side of the frame; 0.495,
                                    # 0.176 with every fit whole)
    'crossing': (0.96, 0.97),       # measured 0.989, 1.000
    'close_in_view': (0.63, 0.57),  # measured 0.661, 0.600 (0.654, 0.622 before the offset
                                    # level; 0.601, 0.578 before the fill
                                    # bridged outlines; 0.581, 0.578 before it closed a body
                                    # cut by one side; 0.554, 0.444; 0.517, 0.289)
}


@pytest.mark.parametrize('name', list(SCENARIO_FLOORS))
def test_streaming_detector_on_the_scenarios(suite, name):
    from dgmod_ros import config
    from dgmod_ros.sequence import stream_results
    scenario = suite[name]
    counts, people = ConfusionCounts(), PersonCounts()
    for frame, mask, _, _ in stream_results(scenario.frames(), dict(config.DEFAULTS)):
        truth = scenario.render(frame.index)[1]
        counts.add(mask, truth)
        people.add(mask, truth)
    floor_f, floor_recall = SCENARIO_FLOORS[name]
    assert counts.fmeasure > floor_f
    assert people.person_recall > floor_recall


def test_a_person_in_view_from_the_start_is_not_taken_for_noise(suite):
    # in_view's people stand in the first window's columns, and the masks call
    # their pixels foreground there: the level of all the columns is their own
    # change across the window. Read from consecutive columns (doubtful_floor
    # 0.5) the levels let them through sooner. Measured on these frames, 0.5
    # against 1 (the level of all the columns): F 0.593 / 0.559, person recall
    # 0.492 / 0.317, precision 0.746 / 0.743 (before the fill held out a body
    # that came in: F 0.565 / 0.530, recall 0.383 / 0.300; docs/results.md).
    from dgmod_ros import config
    from dgmod_ros.sequence import stream_results
    scenario = suite['in_view']
    scores = {}
    for floor in (config.DEFAULTS['doubtful_floor'], 1.0):
        counts, people = ConfusionCounts(), PersonCounts()
        values = dict(config.DEFAULTS, doubtful_floor=floor)
        for frame, mask, _, _ in stream_results(scenario.frames(), values):
            truth = scenario.render(frame.index)[1]
            counts.add(mask, truth)
            people.add(mask, truth)
        scores[floor] = counts, people
    assert config.DEFAULTS['doubtful_floor'] < 1.0
    (counts, people), (whole, whole_people) = scores[config.DEFAULTS['doubtful_floor']], \
        scores[1.0]
    assert counts.fmeasure > whole.fmeasure + 0.012
    assert people.person_recall > whole_people.person_recall + 0.04
    assert counts.precision > whole.precision - 0.05
