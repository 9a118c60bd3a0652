# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Run one method over a sequence of frames, in stream or batch mode (no ROS import)."""

from concurrent.futures import ThreadPoolExecutor

import cv2

from . import config
from .core.numba_setup import use_threads
from .core.pipeline import batch_separate


def _at_input_size(background, frame):
    return cv2.resize(background, frame.image.shape[1::-1]).reshape(
        frame.image.shape[:2] + (-1,))


def stream_results(frames, values):
    """
    Yield ``(frame, mask, background, window)`` the way the node computes them.

    ``background`` (float [0, 1], input size, (h, w, C)) is given where the
    detector announces a new one (the node publishes it there), ``window`` (a
    dict with ``seconds`` and ``iterations``) where a window was solved; both
    are None elsewhere. The solves run in a worker thread beside the per-frame
    work (started as soon as their window is final, installed ``solve_lag``
    frames after they are due); the install rule of the streaming contract
    makes the masks those of solving in line (the node's sync mode). The
    worker's kernels run on ``solve_threads`` threads, as the node's do.
    """
    detector = config.build_detector(values)
    value_range = values['value_range'] or None
    with ThreadPoolExecutor(max_workers=1, thread_name_prefix='dgmod-solve',
                            initializer=use_threads,
                            initargs=(values['solve_threads'],)) as executor:
        for frame in frames:
            result, solved = detector.process(frame.image, frame.channel_order, value_range,
                                              executor=executor)
            window = None
            if solved is not None:
                window = {'first_frame': solved.first_id, 'last_frame': solved.last_id,
                          'seconds': solved.seconds, 'iterations': solved.iterations,
                          'info': solved.info}
            background = detector.background_image() if result.new_background else None
            yield frame, result.mask, background, window


def batch_results(frames, values):
    """Yield ``(frame, mask, background, window)`` with windows tiling the sequence."""
    frames = list(frames)
    if not frames:
        return
    separated = batch_separate(
        [f.image for f in frames], config.window_model(values), window=values['window'],
        scale=values['scale'], color=values['color'], mask_rule=config.build_mask_rule(values),
        channel_order=frames[0].channel_order, value_range=values['value_range'] or None,
        processing_pixels=values['processing_pixels'])
    for index, mask, background, record in separated:
        frame = frames[index]
        window = None
        if record is not None:
            window = {'first_frame': record.first, 'last_frame': record.last,
                      'seconds': record.seconds, 'iterations': record.iterations}
            background = _at_input_size(background, frame)
        yield frame, mask, background, window


def results(frames, values, mode):
    """Dispatch to :func:`stream_results` or :func:`batch_results`."""
    if mode not in ('stream', 'batch'):
        raise ValueError(f"mode must be 'stream' or 'batch', got {mode!r}")
    return (stream_results if mode == 'stream' else batch_results)(frames, values)
