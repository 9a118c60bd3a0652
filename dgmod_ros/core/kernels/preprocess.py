# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
A frame to float columns at half size in one compiled pass (the default robot camera's path).

:func:`~dgmod_ros.core.preprocess.frame_columns` converts a frame to float32
in [0, 1] at full size, averages 2 x 2 areas (OpenCV's ``INTER_AREA``) and
transposes the result into per-channel columns: four passes over a 640 x 480
frame in the per-frame path. For an 8- or 16-bit colour frame of even size
at ``scale`` 0.5, :func:`half_columns` does the same arithmetic in one pass
over the frame and writes the columns directly: each value scaled and
clipped as :func:`~dgmod_ros.core.preprocess.to_float_channels` does, and
the area ``(((a + b) + c) + d) * 0.25`` in the order of OpenCV's
integer-ratio area resize, so the columns are the same bit for bit: those
of the general path's numpy and OpenCV steps, :func:`half_columns_reference`
(``test/test_compiled_passes.py``, ``test/test_per_frame_kernels.py``).
numba's process-wide settings come with ``njit`` from
:mod:`~dgmod_ros.core.numba_setup`; the pass is serial and ``nogil``
(the image callback's).
"""

import cv2
import numpy as np

from ..numba_setup import njit, register_pass


@njit(cache=True, nogil=True)
def _half_columns(image, scale, reverse, out):
    rows, cols = image.shape[0] // 2, image.shape[1] // 2
    quarter = np.float32(0.25)
    one = np.float32(1.0)
    zero = np.float32(0.0)
    for channel in range(out.shape[0]):
        source = out.shape[0] - 1 - channel if reverse else channel
        for i in range(rows):
            top = image[2 * i]
            bottom = image[2 * i + 1]
            row = out[channel, i * cols:(i + 1) * cols]
            for j in range(cols):
                a = min(max(np.float32(top[2 * j, source]) * scale, zero), one)
                b = min(max(np.float32(top[2 * j + 1, source]) * scale, zero), one)
                c = min(max(np.float32(bottom[2 * j, source]) * scale, zero), one)
                d = min(max(np.float32(bottom[2 * j + 1, source]) * scale, zero), one)
                row[j] = (((a + b) + c) + d) * quarter


def half_columns(image, scale, reverse):
    """
    Return the (3, n) float32 columns of a uint8 or uint16 (h, w, >= 3) frame at half its size.

    ``scale`` is the float32 factor to [0, 1] (``1 / value_range``);
    ``reverse`` takes the first three channels in reverse order (BGR input).
    ``h`` and ``w`` must be even.
    """
    rows, cols = image.shape[0] // 2, image.shape[1] // 2
    out = np.empty((3, rows * cols), dtype=np.float32)
    # C-contiguous, the layout compiled at start-up (a padded image row is a
    # strided view): another layout would compile in the image callback.
    _half_columns(np.ascontiguousarray(image), np.float32(scale), bool(reverse), out)
    return out


def half_columns_reference(image, scale, reverse):
    """
    Return :func:`half_columns`'s columns through the general path's steps.

    As :func:`~dgmod_ros.core.preprocess.frame_columns` converts any frame:
    to float32 times ``scale``, the first three channels (reversed with
    ``reverse``) clipped to [0, 1], OpenCV's area resize to half size, then
    one row per channel.
    """
    data = np.asarray(image).astype(np.float32) * np.float32(scale)
    data = data[:, :, 2::-1] if reverse else data[:, :, :3]
    data = np.clip(data, 0.0, 1.0, out=np.ascontiguousarray(data))
    rows, cols = image.shape[0] // 2, image.shape[1] // 2
    small = cv2.resize(data, (cols, rows), interpolation=cv2.INTER_AREA)
    return np.ascontiguousarray(small.reshape(rows * cols, 3).T)


def _examples():
    """
    Return frames of 8 and 16 bits, writeable and read-only, in both channel orders.

    Writeable and read-only frames both (a frame viewing a message's bytes
    is read-only), since numba compiles each apart; and four-channel frames
    with a smaller value range than the type's (values clipped to 1), which
    compile nothing more.
    """
    rng = np.random.default_rng(0)
    examples = []
    for dtype in (np.uint8, np.uint16):
        top = np.iinfo(dtype).max
        for writeable in (True, False):
            frame = rng.integers(0, top, (24, 32, 3), endpoint=True).astype(dtype)
            frame.setflags(write=writeable)
            examples.extend((frame, 1.0 / top, reverse) for reverse in (False, True))
        frame = rng.integers(0, top, (24, 32, 4), endpoint=True).astype(dtype)
        examples.extend((frame, 1.0 / (0.8 * top), reverse) for reverse in (False, True))
    return examples


register_pass(half_columns, _examples, reference=half_columns_reference)
