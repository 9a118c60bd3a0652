# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Frame preprocessing: grey or colour channels, [0, 1] scaling, downscaling, still frames."""

import math

import cv2
import numpy as np

# ITU-R BT.601 luma, the weights OpenCV's RGB2GRAY uses.
_LUMA = np.array([0.299, 0.587, 0.114], dtype=np.float32)
# Pixel types whose channels OpenCV's cvtColor swaps.
_SWAPPABLE = (np.uint8, np.uint16, np.float32)


def unit_scale(dtype):
    """Return the value that maps to 1.0 for ``dtype`` (floats are taken as [0, 1])."""
    dtype = np.dtype(dtype)
    if dtype.kind == 'u' or dtype.kind == 'i':
        return float(np.iinfo(dtype).max)
    if dtype.kind == 'f':
        return 1.0
    raise ValueError(f'unsupported pixel type {dtype}')


def to_float_channels(image, channel_order='rgb', color='gray', value_range=None):
    """
    Turn one frame into float32 channels in [0, 1].

    Parameters
    ----------
    image : ndarray (h, w) or (h, w, c) with c in {1, 3, 4}
        The frame, integer or float.
    channel_order : {'rgb', 'bgr'}
        Order of the first three channels of a colour image; alpha is ignored.
    color : {'gray', 'rgb'}
        'gray' returns (h, w, 1) luma; 'rgb' returns (h, w, 3) in R, G, B order
        (a grey input is replicated).
    value_range : float or None
        The pixel value that means full scale; None uses the dtype's maximum
        (floats are taken to be in [0, 1] already). Values are clipped to [0, 1].

    """
    image = np.asarray(image)
    if image.ndim == 2:
        image = image[:, :, None]
    if image.ndim != 3 or image.shape[2] not in (1, 3, 4):
        raise ValueError(f'expected an (h, w), (h, w, 1), (h, w, 3) or (h, w, 4) image, '
                         f'got shape {image.shape}')
    if channel_order not in ('rgb', 'bgr'):
        raise ValueError(f"channel_order must be 'rgb' or 'bgr', got {channel_order!r}")
    scale = unit_scale(image.dtype) if value_range is None else float(value_range)
    if not scale > 0:
        raise ValueError(f'value_range must be positive, got {value_range!r}')
    if (channel_order == 'bgr' and color == 'rgb' and image.shape[2] >= 3
            and image.dtype in _SWAPPABLE):
        # OpenCV's swap gives the values of the reversed view below, contiguous:
        # copying the reversed float view took ten times as long (docs/results.md).
        image = cv2.cvtColor(image, cv2.COLOR_BGR2RGB if image.shape[2] == 3
                             else cv2.COLOR_BGRA2RGB)
        channel_order = 'rgb'
    data = image.astype(np.float32) * np.float32(1.0 / scale)
    if data.shape[2] >= 3:
        data = data[:, :, :3]
        if channel_order == 'bgr':
            data = data[:, :, ::-1]
        if color == 'gray':
            data = (data @ _LUMA)[:, :, None]
    elif color == 'rgb':
        data = np.repeat(data, 3, axis=2)
    elif color != 'gray':
        raise ValueError(f"color must be 'gray' or 'rgb', got {color!r}")
    return np.clip(data, 0.0, 1.0, out=np.ascontiguousarray(data))


def to_uint8(image):
    """Return a [0, 1] float image as uint8 0-255, rounded and clipped."""
    return np.clip(np.asarray(image) * 255.0 + 0.5, 0, 255).astype(np.uint8)


def shape_within(rows, cols, max_pixels):
    """
    Return (rows, cols) scaled down by one factor in both directions to at most ``max_pixels``.

    A frame of at most ``max_pixels`` pixels keeps its size; at least 1 x 1.
    The camera's aspect is kept.
    """
    if rows * cols <= max_pixels:
        return rows, cols
    factor = math.sqrt(max_pixels / (rows * cols))
    # The small epsilon keeps an exact factor (0.25 of 640 x 480 for 160 x 120) exact.
    return max(1, int(rows * factor + 1e-6)), max(1, int(cols * factor + 1e-6))


def processing_shape(frame_shape, scale, max_pixels=None):
    """
    Return the (rows, cols) of a frame after downscaling by ``scale`` (at least 1 x 1).

    With ``max_pixels``, a frame that has more pixels than that after
    ``scale`` is scaled down further, by one factor in both directions, to
    at most ``max_pixels`` (the camera's aspect kept).
    """
    if not 0 < scale <= 1:
        raise ValueError(f'scale must be in (0, 1], got {scale!r}')
    rows, cols = frame_shape[:2]
    small = max(1, int(round(rows * scale))), max(1, int(round(cols * scale)))
    if max_pixels is None or small[0] * small[1] <= max_pixels:
        return small
    return shape_within(rows, cols, max_pixels)


def resize(image, shape, interpolation=cv2.INTER_AREA):
    """Resize an (h, w) or (h, w, c) float image to ``shape`` = (rows, cols)."""
    if image.shape[:2] == tuple(shape):
        return image
    out = cv2.resize(image, (shape[1], shape[0]), interpolation=interpolation)
    return out.reshape(shape + image.shape[2:]) if image.ndim == 3 else out


def frame_columns(frame, scale, color='gray', channel_order='rgb', value_range=None,
                  max_pixels=None):
    """
    Return one frame as per-channel pixel columns at the processing size.

    The one conversion every window method uses (streaming and batch):
    :func:`to_float_channels`, then :func:`resize` to :func:`processing_shape`
    (``scale``, at most ``max_pixels`` pixels).

    Returns
    -------
    columns : ndarray float32 (C, rows * cols)
        One row per channel, pixels in row-major order.
    shape : tuple (rows, cols, C)

    """
    frame = np.asarray(frame)
    if frame.ndim < 2 or frame.shape[0] == 0 or frame.shape[1] == 0:
        raise ValueError(f'frame must be a non-empty image, got shape {frame.shape}')
    rows, cols = processing_shape(frame.shape[:2], scale, max_pixels)
    if (color == 'rgb' and frame.ndim == 3 and frame.shape[2] in (3, 4)
            and frame.dtype in (np.uint8, np.uint16) and frame.shape[:2] == (2 * rows, 2 * cols)
            and channel_order in ('rgb', 'bgr')):
        # A colour camera at scale 0.5: the same columns in one pass (halving_kernel).
        full_scale = unit_scale(frame.dtype) if value_range is None else float(value_range)
        if full_scale > 0:
            from .kernels.preprocess import half_columns        # numba: loaded on first use
            return (half_columns(frame, np.float32(1.0 / full_scale), channel_order == 'bgr'),
                    (rows, cols, 3))
    channels = to_float_channels(frame, channel_order, color, value_range)
    small = resize(channels, (rows, cols)).reshape(rows, cols, -1)
    return small.reshape(rows * cols, -1).T.copy(), (rows, cols, small.shape[2])


def moving_frames(columns, threshold):
    """
    Return the indices of the frames kept by the paper's motionless-frame rule.

    A frame is dropped when the mean absolute difference (the l1 norm of the
    column difference divided by the pixel count, so that ``threshold`` does
    not depend on resolution) to the last kept frame is below ``threshold``.
    The first frame is always kept. ``threshold <= 0`` keeps every frame.
    """
    columns = np.asarray(columns)
    m = columns.shape[1]
    if threshold <= 0 or m == 0:
        return np.arange(m)
    kept = [0]
    for j in range(1, m):  # a loop over frames, each step one vectorised column op
        if np.mean(np.abs(columns[:, j] - columns[:, kept[-1]])) >= threshold:
            kept.append(j)
    return np.asarray(kept)
