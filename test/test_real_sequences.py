# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Accuracy on the shared real sequences, scored against their ground truth."""

import cv2
from dgmod_ros.core.dgmod import DualGraphMOD
from dgmod_ros.core.metrics import ConfusionCounts
from dgmod_ros.core.pipeline import batch_separate
import pytest


def _read(folder):
    inputs = sorted((folder / 'input').iterdir())
    truths = sorted((folder / 'groundtruth').iterdir())
    assert len(inputs) == len(truths) > 0
    return [cv2.imread(str(p)) for p in inputs], [cv2.imread(str(p), 0) for p in truths]


@pytest.fixture(scope='module')
def ibm(data_dir):
    return _read(data_dir / 'sbi_IBMtest2')


def _opencv_fmeasure(subtractor, frames, truths):
    counts = ConfusionCounts()
    for frame, truth in zip(frames, truths):
        counts.add(subtractor.apply(frame) == 255, truth)    # 127 = shadow, not foreground
    return counts.fmeasure


def test_dgmod_beats_opencv_subtractors_on_ibmtest2(ibm):
    frames, truths = ibm
    counts = ConfusionCounts()
    for index, mask, _, _ in batch_separate(frames, DualGraphMOD(tol=1e-3), window=45,
                                            scale=0.5, channel_order='bgr'):
        counts.add(mask, truths[index])
    mog2 = _opencv_fmeasure(cv2.createBackgroundSubtractorMOG2(), frames, truths)
    knn = _opencv_fmeasure(cv2.createBackgroundSubtractorKNN(), frames, truths)
    # Measured on this machine: dgmod F 0.922 (Pr 0.954, Re 0.892) with the
    # default mask rule; OpenCV defaults on the colour frames: MOG2 0.830,
    # KNN 0.563. The floor 0.88 leaves room for BLAS rounding differences only.
    assert counts.fmeasure > max(mog2, knn)
    assert counts.fmeasure > 0.88


# The streaming detector as the node runs it (package defaults), on a segment
# of each shared sequence: (first frame fed, frames fed, F floor). Segments
# keep the suite short (about 700 frames in all); the figures on the whole
# clips are in docs/results.md. Each floor is about 0.03 below the F
# measured on the same segment (docs/results.md, "Accuracy tests"; measured
# again 2026-12-05 with the fill bridging outlines).
STREAM_SEGMENTS = {
    'sbi_IBMtest2': (0, 90, 0.92),            # measured 0.953
    'sbi_CAVIAR2': (0, 150, 0.88),            # measured 0.906
    'sbi_CAVIAR1': (0, 150, 0.83),            # measured 0.856
    'sbi_Candela_m1.10': (0, 200, 0.93),      # measured 0.958 (the person sits from ~40)
    # Frames 470-649 scored. Started at frame 400, the trees are calm in its
    # first two frames and sway from about frame 450: specks of leaves.
    # Every blob held out while the window filled: 0.911 (leaves never learnt).
    'cdnet_highway': (400, 250, 0.92),        # measured 0.948
}


@pytest.mark.parametrize('name', list(STREAM_SEGMENTS))
def test_streaming_detector_on_real_sequences(data_dir, name):
    from dgmod_ros import config
    from dgmod_ros.evaluation import load_dataset
    from dgmod_ros.inputs import read_frames
    from dgmod_ros.sequence import stream_results
    first, count, floor = STREAM_SEGMENTS[name]
    dataset = load_dataset(data_dir / name)
    frames = list(read_frames(dataset.path))[first:first + count]
    counts = ConfusionCounts()
    for frame, mask, _, _ in stream_results(frames, dict(config.DEFAULTS)):
        if dataset.first <= frame.index <= dataset.last:
            truth = cv2.imread(str(dataset.truths[frame.index]), cv2.IMREAD_GRAYSCALE)
            counts.add(mask, truth, dataset.roi)
    assert counts.fmeasure > floor


def test_a_person_who_stops_dead_stays_foreground(data_dir):
    # The scenario suite's person who walks in and stands perfectly still
    # (6 s at duration scale 0.1, longer than still_frames): before the rule
    # that a blob seen to come in is never still, the masks kept 0.07 of the
    # person's pixels over the still span; now 0.97 (docs/results.md).
    from dgmod_ros import config
    from dgmod_ros.scenarios import build_scenario, load_material
    from dgmod_ros.sequence import stream_results
    scenario = build_scenario('stops', load_material(data_dir), seed=0, duration_scale=0.1)
    first, last = scenario.phases['still']
    counts = ConfusionCounts()
    for frame, mask, _, _ in stream_results(scenario.frames(last + 1), dict(config.DEFAULTS)):
        if frame.index >= first:
            counts.add(mask, scenario.render(frame.index)[1])
    assert counts.recall > 0.95


def test_the_place_a_person_stood_on_from_the_first_frame_clears_as_he_walks_off(data_dir):
    # sbi_CaVignal: the person stands from the first frame (he is the window's
    # background) and walks off from about frame 140; his old place and he are
    # one blob until about frame 183. Scored over frames 140-199: F 0.813
    # (Pr 0.774) with the ghost test on the still parts of blobs, 0.722
    # (Pr 0.624) with whole blobs only (docs/results.md).
    from dgmod_ros import config
    from dgmod_ros.evaluation import load_dataset
    from dgmod_ros.inputs import read_frames
    from dgmod_ros.sequence import stream_results
    dataset = load_dataset(data_dir / 'sbi_CaVignal')
    frames = list(read_frames(dataset.path))[:200]
    counts = ConfusionCounts()
    for frame, mask, _, _ in stream_results(frames, dict(config.DEFAULTS)):
        if frame.index >= 140:
            truth = cv2.imread(str(dataset.truths[frame.index]), cv2.IMREAD_GRAYSCALE)
            counts.add(mask, truth, dataset.roi)
    assert counts.fmeasure > 0.78


def test_a_vga_camera_sees_a_scene_as_its_native_size_does(data_dir):
    # sbi_HumanBody2's first 150 frames as they are (320 x 240) and upsampled
    # to a robot camera's 640 x 480, masks scored at the native size: F 0.829
    # native, 0.822 at 640 x 480 (processed at 184 x 138 by
    # processing_pixels), 0.805 processed at 320 x 240 as scale 0.5 alone
    # gave (docs/results.md).
    from dgmod_ros import config
    from dgmod_ros.evaluation import load_dataset
    from dgmod_ros.inputs import read_frames
    dataset = load_dataset(data_dir / 'sbi_HumanBody2')
    frames = list(read_frames(dataset.path))[:150]
    fmeasures = []
    for size in (None, (640, 480)):
        detector = config.build_detector(dict(config.DEFAULTS))
        counts = ConfusionCounts()
        for frame in frames:
            image = frame.image if size is None else cv2.resize(frame.image, size,
                                                                interpolation=cv2.INTER_CUBIC)
            result, _ = detector.process(image, frame.channel_order)
            truth = cv2.imread(str(dataset.truths[frame.index]), cv2.IMREAD_GRAYSCALE)
            counts.add(cv2.resize(result.mask, truth.shape[::-1],
                                  interpolation=cv2.INTER_NEAREST), truth, dataset.roi)
        fmeasures.append(counts.fmeasure)
    native, vga = fmeasures
    assert native > 0.80
    assert vga > native - 0.015


def test_the_rims_of_ceiling_lights_are_no_obstacles(data_dir):
    # sbi_HumanBody2's first 120 frames: as people come near, the camera's
    # exposure moves and the rims of the ceiling lights change in bands one or
    # two pixels wide. Measured: 1.20 false blobs a frame without the line rule
    # (line_pixels 0), 0.37 with it; person recall 0.874 both (docs/results.md).
    from dgmod_ros import config
    from dgmod_ros.core.metrics import PersonCounts
    from dgmod_ros.evaluation import load_dataset
    from dgmod_ros.inputs import read_frames
    from dgmod_ros.sequence import stream_results
    dataset = load_dataset(data_dir / 'sbi_HumanBody2')
    frames = list(read_frames(dataset.path))[:120]
    counts = {}
    for line_pixels in (config.DEFAULTS['line_pixels'], 0):
        counts[line_pixels] = PersonCounts()
        values = dict(config.DEFAULTS, line_pixels=line_pixels)
        for frame, mask, _, _ in stream_results(frames, values):
            counts[line_pixels].add(mask, cv2.imread(str(dataset.truths[frame.index]),
                                                     cv2.IMREAD_GRAYSCALE))
    rule, off = counts[config.DEFAULTS['line_pixels']], counts[0]
    assert rule.false_blobs_per_frame < 0.5
    assert off.false_blobs_per_frame > 2 * rule.false_blobs_per_frame
    assert rule.person_recall > 0.84
    assert rule.person_recall == off.person_recall


def test_what_a_moving_outline_encloses_is_published_whole(data_dir):
    # sbi_HumanBody2's first 120 frames: people in flat clothes whose colour
    # the window has seen where they walk are detected by their outlines, and
    # the fill publishes what the outlines enclose, gaps the field opened in
    # them bridged. Measured with the fill and without (fill_holes False): F
    # 0.879 / 0.858, pixel recall 0.908 / 0.854, precision 0.852 / 0.862,
    # people found 137 / 132 of 151, false blobs 26 / 28 in 120 frames. The
    # precision lost is the floor between a walker's legs where they are cut
    # by the frame's bottom edge, closed with it, and the notches the closing
    # fills (docs/results.md).
    from dgmod_ros import config
    from dgmod_ros.core.metrics import ConfusionCounts, PersonCounts
    from dgmod_ros.evaluation import load_dataset
    from dgmod_ros.inputs import read_frames
    from dgmod_ros.sequence import stream_results
    dataset = load_dataset(data_dir / 'sbi_HumanBody2')
    frames = list(read_frames(dataset.path))[:120]
    counts, people = {}, {}
    for fill in (True, False):
        counts[fill], people[fill] = ConfusionCounts(), PersonCounts()
        for frame, mask, _, _ in stream_results(frames, dict(config.DEFAULTS, fill_holes=fill)):
            truth = cv2.imread(str(dataset.truths[frame.index]), cv2.IMREAD_GRAYSCALE)
            counts[fill].add(mask, truth, dataset.roi)
            people[fill].add(mask, truth)
    assert config.DEFAULTS['fill_holes']
    assert counts[True].fmeasure > counts[False].fmeasure + 0.015
    assert counts[True].recall > counts[False].recall + 0.04
    assert counts[True].precision >= counts[False].precision - 0.015
    assert people[True].found >= people[False].found
    assert people[True].false_blobs <= people[False].false_blobs


def test_a_small_ghost_with_one_noisy_pixel_still_heals(data_dir):
    # sbi_HumanBody2 started at frame 120 (40 %), a man standing at the table
    # in its first frame: the place his legs uncover by the table's leg is a
    # ghost of about 40 processing pixels, where one pixel past the still
    # test's level every few frames restarted its count (a share of 0.01 of 40
    # pixels allows none). Measured with one pixel allowed / without: false
    # blobs 0.26 / 0.50 a frame, person recall 0.851 both (docs/results.md).
    from dgmod_ros import config
    from dgmod_ros.core.metrics import PersonCounts
    from dgmod_ros.evaluation import load_dataset
    from dgmod_ros.inputs import read_frames
    from dgmod_ros.sequence import stream_results
    dataset = load_dataset(data_dir / 'sbi_HumanBody2')
    frames = list(read_frames(dataset.path))[120:300]
    people = PersonCounts()
    for frame, mask, _, _ in stream_results(frames, dict(config.DEFAULTS)):
        people.add(mask, cv2.imread(str(dataset.truths[frame.index]), cv2.IMREAD_GRAYSCALE))
    assert people.false_blobs_per_frame < 0.35
    assert people.person_recall > 0.82
