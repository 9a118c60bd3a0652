# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The detector keeps publishing correct masks through bad input, faults and bursts."""

from dgmod_ros.core.metrics import iou
from dgmod_ros.core.streaming import SlidingWindowDetector
from dgmod_ros.core.synthetic import synthetic_scene
import numpy as np
import pytest
from rclpy.parameter import Parameter
from ros_harness import DetectorHarness, image_message, mask_array

SHAPE = (96, 128)


@pytest.fixture(scope='module')
def scene():
    return synthetic_scene(n_frames=80, shape=SHAPE, seed=21)


@pytest.fixture
def harness():
    with DetectorHarness(max_pixels=200_000) as h:
        yield h


def _malformed(kind, frame):
    msg = image_message(frame, 'rgb8')
    if kind == 'encoding':
        msg.encoding = 'yuv422'
    elif kind == 'data_length':
        msg.data = bytes(msg.data)[:-5]
    elif kind == 'step':
        msg.step = 10
        msg.data = bytes(10 * msg.height)
    elif kind == 'size':
        msg.width = 0
        msg.data = b''
        msg.step = 0
    elif kind == 'too_large':
        big = np.zeros((500, 500, 3), np.uint8)
        msg = image_message(big, 'rgb8')
    elif kind == 'non_finite':
        values = np.full(SHAPE, 0.5, np.float32)
        values[3, 4] = np.nan
        msg = image_message(values, '32FC1')
    return msg


def test_malformed_frames_are_dropped_counted_and_masks_stay_right(harness, scene):
    kinds = ['encoding', 'data_length', 'step', 'size', 'too_large', 'non_finite']
    sent = {k: 0 for k in kinds}
    ious = []
    for index, frame in enumerate(scene.frames[:60]):
        if index % 4 == 3:
            kind = kinds[(index // 4) % len(kinds)]
            sent[kind] += 1
            harness.send(_malformed(kind, frame), expect_mask=False)
        mask = mask_array(harness.send(image_message(frame, 'rgb8'), settle=True))
        if index >= 30:
            ious.append(iou(mask, scene.masks[index]))
    figures = harness.node.statistics()
    assert {k: figures.get(f'dropped_{k}', 0) for k in kinds} == sent
    assert figures['masks_out'] == 60
    assert figures['frames_in'] == figures['masks_out'] + figures['frames_dropped']
    # The malformed frames changed nothing: IoU as on clean input (measured 0.93).
    assert np.mean(ious) > 0.85


def test_encoding_change_restarts_the_window(harness, scene):
    for frame in scene.frames[:10]:
        harness.send(image_message(frame, 'rgb8'))
    for frame in scene.frames[10:20]:
        grey = (frame.mean(axis=2) * 257).astype(np.uint16)
        mask = mask_array(harness.send(image_message(grey, 'mono16')))
        assert mask.shape == SHAPE
    assert harness.node.statistics()['window_resets'] == 1


def test_burst_then_silence_then_frames_again(harness, scene):
    # A burst: 200 frames published without waiting. The subscription's
    # sensor-data queue (depth 5) drops the oldest in transport; everything the
    # node receives is masked or counted, and nothing queues up. The last
    # frame is a marker: it is the newest, so the queue keeps it, and once its
    # mask is out every frame received before it has been handled.
    marker = 1_234_567_890
    for index in range(200):
        harness.publisher.publish(image_message(scene.frames[index % 80], 'rgb8', index))
    harness.publisher.publish(image_message(scene.frames[0], 'rgb8', marker))
    assert harness.spin_until(lambda: any(
        m.header.stamp.sec * 10**9 + m.header.stamp.nanosec == marker for m in harness.masks))
    harness.wait_for_solves()
    figures = harness.node.statistics()
    assert figures['frames_in'] == figures['masks_out'] + figures['frames_dropped']
    assert 0 < figures['frames_in'] <= 201
    # Frames again after any silence: the node has no timer of its own, so a
    # stall is no frames, and masks resume with the next frame.
    before = figures['masks_out']
    for frame in scene.frames[:5]:
        assert mask_array(harness.send(image_message(frame, 'rgb8'))).shape == SHAPE
    assert harness.node.statistics()['masks_out'] == before + 5


def test_scale_and_window_changes_at_run_time_keep_masking(harness, scene):
    for frame in scene.frames[:20]:
        harness.send(image_message(frame, 'rgb8'), settle=True)
    results = harness.node.set_parameters([Parameter('scale', value=0.25),
                                           Parameter('window', value=20)])
    assert all(r.successful for r in results)
    assert len(harness.node._detector.buffer_) == 20           # nothing lost
    ious = []
    for index, frame in enumerate(scene.frames[20:60], start=20):
        mask = mask_array(harness.send(image_message(frame, 'rgb8'), settle=True))
        assert mask.shape == SHAPE
        if index >= 35:
            ious.append(iou(mask, scene.masks[index]))
    harness.wait_for_solves()
    assert harness.node._detector.shape_[:2] == (24, 32)
    # Measured 0.706 (0.713 before the first frame after the rescale counted
    # as settled; the comment said 0.85 since an earlier default).
    assert np.mean(ious) > 0.65


class _FailingOnce:
    """A window model that breaks on its second fit, then recovers."""

    def __init__(self, model):
        self.model = model
        self.calls = 0
        self.cold_after_failure = None

    def fit(self, data, frame_shape, init=None):
        self.calls += 1
        if self.calls == 2:
            data = np.full_like(data, np.nan)
            return self.model.fit(data, frame_shape, init)       # raises ValueError
        if self.calls == 3:
            self.cold_after_failure = init is None
        return self.model.fit(data, frame_shape, init)


def test_solver_failure_keeps_the_previous_model_and_restarts_cold(scene):
    # Grey: one fit per solve, so the model's second fit is the second solve.
    detector = SlidingWindowDetector(window=20, stride=5, color='gray')
    failures = []
    for index, frame in enumerate(scene.frames[:40]):
        if index == 0:
            detector.process(frame)
            wrapper = _FailingOnce(detector.model_)
            detector.model_ = wrapper
            continue
        result, solved = detector.process(frame)
        if result.solve_error:
            failures.append(index)
            assert detector.background_model_ is not None       # previous model kept
        assert result.mask.shape == SHAPE
    assert len(failures) == 1 and wrapper.cold_after_failure is True
    assert wrapper.calls >= 6


def test_node_reports_a_failed_solve_and_goes_on(harness, scene):
    for frame in scene.frames[:8]:
        harness.send(image_message(frame, 'rgb8'), settle=True)
    harness.wait_for_solves()
    with harness.node._lock:
        harness.node._detector.model_ = _FailingOnce(harness.node._detector.model_)
        harness.node._detector.model_.calls = 1                 # the next fit fails
    for frame in scene.frames[8:40]:
        harness.send(image_message(frame, 'rgb8'), settle=True)
    harness.wait_for_solves()
    figures = harness.node.statistics()
    assert figures['solve_failures'] == 1 and 'NaN' in figures['last_solve_error']
    # Solves at frames 4, 14 (fails), 24 (cold) and 34.
    assert figures['solves'] == 3 and figures['masks_out'] == 40


# Frames after the jump whose mask is over half foreground. Measured 0 for all
# three: a gain jump (the projection absorbs a gain); light over 85% or over half
# of the view (the lighting test of the decision takes the lit part for light,
# while the scene-change rule, which counts every change above the noise, light
# included, restarts the window within two frames). Bounds: 0 for a gain;
# otherwise the 2 frames the scene-change rule needs.
@pytest.mark.parametrize('change, bound', [('gain', 0), ('most', 2), ('half', 2)])
def test_illumination_jump_blinds_for_a_bounded_number_of_frames(scene, change, bound):
    frames = scene.frames.astype(np.float32)
    jumped = frames.copy()
    if change == 'gain':                      # auto-exposure: everything 40% brighter
        jumped[40:] *= 1.4
    elif change == 'most':                    # the room lights, but for one corner
        jumped[40:, :, SHAPE[1] * 3 // 20:] += 70.0
    else:                                     # a light switched on over half the room
        jumped[40:, :, SHAPE[1] // 2:] += 70.0
    jumped = np.clip(jumped, 0, 255).astype(np.uint8)
    detector = SlidingWindowDetector(window=30, stride=10)
    blind = []
    for index, frame in enumerate(jumped):
        result, _ = detector.process(frame)
        if index >= 40 and np.count_nonzero(result.mask) > 0.5 * result.mask.size:
            blind.append(index)
    assert len(blind) <= bound and all(i < 40 + max(bound, 1) for i in blind)
    assert iou(result.mask, scene.masks[-1]) > 0.5             # and then right again
