# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Cost per frame of each ingredient of the streaming detector at 640 x 480.

Feeds a synthetic 640 x 480 colour scene through the default detector until
its window is full, then times each stage of one frame on the detector's own
state (median of repeats) and one window solve, divided by the stride for its
share per frame. Prints figures; asserts nothing.

Usage::

    PYTHONPATH=. .venv/bin/python benchmarks/bench_foreground.py [--repeats 30]
        [--set scale=1.0 ...]
"""

import argparse

import cv2
from dgmod_ros import config
from dgmod_ros.core.preprocess import frame_columns
from dgmod_ros.core.streaming.background_memory import conditional_columns
from dgmod_ros.core.streaming.decision import adaptive_mask, moving_texture_k
from dgmod_ros.core.streaming.fast_path import projection_residual, robust_projection
from dgmod_ros.core.streaming.ghost import ghost_blobs
from dgmod_ros.core.streaming.held_foreground import consecutive_frames, still_blob_pixels
from dgmod_ros.core.streaming.noise_levels import pixel_noise
from dgmod_ros.core.streaming.photometric import chroma_noise
from dgmod_ros.core.streaming.upsizing import to_input_size
from dgmod_ros.core.synthetic import synthetic_scene
import numpy as np
from timing import median_ms


def main():
    """Run the detector to a full window, then time each stage."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--repeats', type=int, default=30)
    parser.add_argument('--set', action='append', default=[], metavar='NAME=VALUE',
                        help="a parameter other than its default (the node's name and type)")
    args = parser.parse_args()
    values = dict(config.DEFAULTS)
    for item in args.set:
        name, text = item.split('=', 1)
        values[name] = config.parse_value(name, text)
    detector = config.build_detector(values)
    scene = synthetic_scene(n_frames=60, shape=(480, 640), seed=3)
    frames = list(scene.frames) * 6                      # 360 frames: the window fills up
    for frame in frames:
        detector.process(frame)
    frame = frames[-1]
    model = detector.background_model_
    shape = detector.shape_
    k, stride = detector.pixel_k, detector.stride

    def columns_of(image, color=detector.color, order='rgb'):
        # The detector's conversion: its scale and processing_pixels.
        return frame_columns(image, detector.scale, color, order, None,
                             int(detector.processing_pixels))[0]

    columns = columns_of(frame)
    background = robust_projection(model.basis, columns)
    lighting, chroma_level = detector.lighting_, model.chroma_noise
    mask, distance = adaptive_mask(columns, background, model.noise, k, shape,
                                   detector.median_size, detector.mrf_beta, lighting,
                                   chroma_level)
    candidates = distance.ravel() > k * model.noise
    # A person near the camera: a quarter of the view (the test's cost follows the candidates).
    quarter = np.arange(candidates.size) < candidates.size // 4
    earlier = detector.recent_[0][1]
    weak_k, weak_bits = detector.moving_texture_k, int(detector.moving_texture_bits)
    snapshot = detector.snapshot()
    window = snapshot.window()                  # (C, n, m): the snapshot holds columns
    residual = window - window.mean(axis=2, keepdims=True)
    age = detector.foreground_age_
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5))
    stages = {
        'frame to columns (resize, colour)': lambda: columns_of(frame),
        'IRLS projection on the basis': lambda: robust_projection(model.basis, columns),
        'decision (per-pixel k sigma, Potts field)': lambda: adaptive_mask(
            columns, background, model.noise, k, shape, detector.median_size,
            detector.mrf_beta),
        'lighting test (chroma, brightness, LBSP)': lambda: lighting.explains(
            columns, background, model.noise, k, shape, candidates, chroma_level),
        'moving texture (LBSP at weak moving pixels)': lambda: moving_texture_k(
            columns, background, earlier, model.noise, k, weak_k, weak_bits, shape,
            distance.ravel()),
        'ghost test': lambda: ghost_blobs(mask, columns, background, earlier, model.noise, k),
        'still blobs (held foreground)': lambda: consecutive_frames(age, still_blob_pixels(
            mask, columns, earlier, model.noise, k / 2, 0.01)),
        'mask to input size': lambda: to_input_size(mask, detector.input_shape_),
        'conditional admission (when due)': lambda: conditional_columns(
            columns, background, cv2.dilate(mask, kernel).ravel() > 0, age,
            detector.absorb_frames),
    }
    print(f'640 x 480 input, processing {shape[1]} x {shape[0]} x {shape[2]}, '
          f'window {detector.window}, stride {stride}, memory_spacing {detector.memory_spacing}')
    print(f'  candidates of the lighting test: {candidates.mean():.1%} of the pixels')
    total = 0.0
    for name, function in stages.items():
        ms = median_ms(function, args.repeats)
        total += ms
        print(f'  {name:45s} {ms:7.2f} ms per frame')
    print(f'  {"per-frame path, total":45s} {total:7.2f} ms per frame')
    median_decision = median_ms(lambda: adaptive_mask(
        columns, background, model.noise, k, shape, detector.median_size), args.repeats)
    print(f'  {"instead: k sigma and median filter":45s} {median_decision:7.2f} ms per frame')
    quarter_ms = median_ms(lambda: lighting.explains(columns, background, model.noise, k, shape,
                                                     quarter, chroma_level), args.repeats)
    print(f'  {"lighting test, a quarter of the view candidate":45s} {quarter_ms:7.2f} '
          'ms per frame')
    # Every pixel weak and moving: the moving-texture rule's LBSP over the whole view.
    everywhere_ms = median_ms(lambda: moving_texture_k(
        columns, background, earlier, model.noise, np.inf, 0.0, weak_bits, shape,
        distance.ravel()), args.repeats)
    print(f'  {"moving texture, every pixel weak (worst case)":45s} {everywhere_ms:7.2f} '
          'ms per frame')
    # Decoded files and bgr8 messages come in OpenCV's channel order.
    bgr = np.ascontiguousarray(frame[:, :, ::-1])
    bgr_ms = median_ms(lambda: columns_of(bgr, order='bgr'), args.repeats)
    print(f'  {"frame to columns, BGR input (decoded files)":45s} {bgr_ms:7.2f} ms per frame')
    # The earlier default per-frame path in the same run, as the reference
    # (grey projection on one channel's basis, one threshold, 3 x 3 morphology).
    grey = columns_of(frame, color='gray')
    rule = detector.mask_rule_
    # A model solved for the per-pixel decision carries no global threshold;
    # the detector's own fallback gives one from the noise levels.
    threshold = rule.threshold_from_noise(model.noise)

    def earlier_path():
        residual = grey - robust_projection(model.basis[1:2], grey)
        magnitude = np.abs(residual).max(axis=0).reshape(shape[:2])
        rule.apply(magnitude, threshold, detector.input_shape_)

    print(f'  {"reference: earlier grey path, same run":45s} '
          f'{median_ms(earlier_path, args.repeats):7.2f} ms per frame')
    solve = median_ms(lambda: detector.solve(snapshot), max(3, args.repeats // 10))
    noise = median_ms(lambda: pixel_noise(residual, shape, snapshot.observed),
                      max(3, args.repeats // 10))
    chroma = median_ms(lambda: chroma_noise(window, residual, shape, snapshot.observed),
                       max(3, args.repeats // 10))
    print(f'  {"window solve (3 channels, warm start)":45s} {solve:7.1f} ms per solve, '
          f'{solve / stride:6.2f} ms per frame')
    print(f'  {"  of which per-pixel noise levels":45s} {noise:7.1f} ms per solve, '
          f'{noise / stride:6.2f} ms per frame')
    print(f'  {"  of which chromaticity noise levels":45s} {chroma:7.1f} ms per solve, '
          f'{chroma / stride:6.2f} ms per frame')
    for robust, name in ((True, 'IRLS'), (False, 'least-squares')):
        projected = median_ms(lambda: projection_residual(model.basis, window, robust),
                              max(3, args.repeats // 10))
        print(f'  {"  noise_source residual, " + name + " projection":45s} {projected:7.1f} '
              f'ms per solve, {projected / stride:6.2f} ms per frame')


if __name__ == '__main__':
    main()
