# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
``sensor_msgs/Image`` <-> numpy without cv_bridge and without importing ROS.

Also ``sensor_msgs/CompressedImage`` (JPEG, PNG) and depth images to numpy.

Works on any object with the message's fields (``height``, ``width``,
``encoding``, ``is_bigendian``, ``step``, ``data``), so it is tested without
ROS. Rows are read through ``step`` (padding honoured) and multi-byte pixels
in the byte order ``is_bigendian`` states, as cv_bridge's ``imgmsg_to_cv2``
does; numpy 2 has no ``ndarray.newbyteorder``, so the dtype carries the order.
"""

import cv2
import numpy as np

from .core.preprocess import to_uint8

#: encoding -> (numpy dtype, channels, channel order of colour images)
ENCODINGS = {
    'mono8': (np.uint8, 1, None),
    '8UC1': (np.uint8, 1, None),
    'mono16': (np.uint16, 1, None),
    '16UC1': (np.uint16, 1, None),
    '32FC1': (np.float32, 1, None),
    'rgb8': (np.uint8, 3, 'rgb'),
    'bgr8': (np.uint8, 3, 'bgr'),
    'rgba8': (np.uint8, 4, 'rgb'),
    'bgra8': (np.uint8, 4, 'bgr'),
}


class ImageConversionError(ValueError):
    """
    A message that cannot be turned into an image.

    ``reason`` is a short stable key for counters (``'encoding'``, ``'size'``,
    ``'step'``, ``'data_length'``, ``'too_large'``, ``'non_finite'``, and for
    compressed images ``'decode'``).
    """

    def __init__(self, reason, message):
        super().__init__(message)
        self.reason = reason


def stamp_ns(header):
    """Return a ``std_msgs/Header``'s stamp in integer nanoseconds."""
    return header.stamp.sec * 1_000_000_000 + header.stamp.nanosec


def image_to_array(msg, max_pixels=None, allow_non_finite=False):
    """
    Return the pixels of an Image message as a new ``(h, w)`` or ``(h, w, c)`` array.

    Parameters
    ----------
    msg : sensor_msgs.msg.Image or any object with its fields
        The message; its buffer is copied, never aliased.
    max_pixels : int or None
        Refuse images with more pixels than this.
    allow_non_finite : bool
        Accept NaN and Inf in float images (depth marks "no reading" so).

    Returns
    -------
    image : ndarray
        Native byte order.
    channel_order : {'rgb', 'bgr'} or None
        For colour encodings.

    Raises
    ------
    ImageConversionError
        With a ``reason`` key and a sentence naming the problem.

    """
    encoding = msg.encoding
    if encoding not in ENCODINGS:
        raise ImageConversionError(
            'encoding', f'unsupported encoding {encoding!r} (supported: '
                        f'{", ".join(sorted(ENCODINGS))})')
    base, channels, order = ENCODINGS[encoding]
    height, width, step = int(msg.height), int(msg.width), int(msg.step)
    if height <= 0 or width <= 0:
        raise ImageConversionError('size', f'empty image: {width} x {height}')
    if max_pixels is not None and height * width > max_pixels:
        raise ImageConversionError(
            'too_large', f'{width} x {height} = {width * height} pixels exceeds the limit '
                         f'of {max_pixels}')
    dtype = np.dtype(base).newbyteorder('>' if msg.is_bigendian else '<')
    row_bytes = width * channels * dtype.itemsize
    if step < row_bytes:
        raise ImageConversionError(
            'step', f'step {step} is smaller than one row of {width} {encoding} pixels '
                    f'({row_bytes} bytes)')
    data = msg.data
    size = len(data)
    if size != step * height:
        raise ImageConversionError(
            'data_length', f'data holds {size} bytes, step x height = {step * height}')
    try:
        raw = np.frombuffer(data, dtype=np.uint8)     # bytes, array.array('B'), memoryview
    except TypeError:
        raw = np.asarray(data, dtype=np.uint8)        # a plain list of ints
    rows = raw.reshape(height, step)[:, :row_bytes]
    image = np.ascontiguousarray(rows).view(dtype).reshape(height, width, channels)
    image = image.astype(dtype.newbyteorder('='), copy=True)
    if channels == 1:
        image = image[:, :, 0]
    if not allow_non_finite and image.dtype.kind == 'f' and not np.all(np.isfinite(image)):
        raise ImageConversionError('non_finite', f'{encoding} image contains NaN or Inf')
    return image, order


def array_to_image_fields(image, encoding):
    """
    Return the ``height, width, encoding, is_bigendian, step, data`` of an Image.

    ``image`` must already have the dtype and channel count of ``encoding``.
    """
    base, channels, _ = ENCODINGS[encoding]
    image = np.ascontiguousarray(image, dtype=np.dtype(base).newbyteorder('='))
    if image.ndim == 2:
        image = image[:, :, None]
    if image.shape[2] != channels:
        raise ValueError(f'{encoding} needs {channels} channels, got {image.shape[2]}')
    height, width = image.shape[:2]
    return {'height': height, 'width': width, 'encoding': encoding,
            'is_bigendian': int(not np.little_endian),
            'step': width * channels * image.dtype.itemsize, 'data': image.tobytes()}


def fill_image(msg, image, encoding, header=None):
    """
    Fill an Image message (or any object with its fields) from an array; return it.

    The one place that builds ``sensor_msgs/Image`` messages: the node's
    outputs, the demo's camera, the benchmarks and the tests all use it.

    Parameters
    ----------
    msg : sensor_msgs.msg.Image
        A new message; its pixel fields are replaced.
    image : ndarray
        Pixels with the dtype and channel count of ``encoding``.
    encoding : str
        One of :data:`ENCODINGS`.
    header : std_msgs.msg.Header or None
        Copied into the message when given.

    """
    for name, value in array_to_image_fields(image, encoding).items():
        setattr(msg, name, value)
    if header is not None:
        msg.header = header
    return msg


#: Depth encodings (REP 118): 16-bit millimetres or 32-bit float metres.
def background_fields(image):
    """Return ``(pixels, encoding)`` of a float [0, 1] (h, w, C) image: mono8, or rgb8 (C 3)."""
    pixels = to_uint8(image)
    if pixels.shape[2] == 1:
        pixels = pixels[:, :, 0]
    return pixels, 'mono8' if pixels.ndim == 2 else 'rgb8'


DEPTH_ENCODINGS = ('16UC1', 'mono16', '32FC1')


def depth_image_to_array(msg, max_pixels=None):
    """
    Return a depth Image's pixels: uint16 millimetres or float32 metres (NaN allowed).

    Raises
    ------
    ImageConversionError
        As :func:`image_to_array`; reason ``'encoding'`` for an encoding that
        is not a depth encoding.

    """
    if msg.encoding not in DEPTH_ENCODINGS:
        raise ImageConversionError(
            'encoding', f'unsupported depth encoding {msg.encoding!r} (supported: '
                        f'{", ".join(DEPTH_ENCODINGS)})')
    return image_to_array(msg, max_pixels, allow_non_finite=True)[0]


def compressed_image_to_array(msg, max_pixels=None):
    """
    Decode a CompressedImage (JPEG or PNG, as image_transport publishes it).

    Parameters
    ----------
    msg : sensor_msgs.msg.CompressedImage or any object with ``format`` and ``data``
        ``format`` is ``'jpeg'``, ``'png'`` or image_transport's
        ``'<encoding>; jpeg compressed <encoding>'``; the bytes decide.
    max_pixels : int or None
        Refuse images with more pixels than this.

    Returns
    -------
    image : ndarray (h, w) or (h, w, c)
        uint8 (or uint16 for a 16-bit PNG); colour in B, G, R(, A) order.
    channel_order : {'bgr'} or None

    Raises
    ------
    ImageConversionError
        ``'encoding'`` for compressedDepth (its own header, not an image
        file), ``'data_length'`` for no bytes, ``'decode'`` for bytes OpenCV
        cannot decode, ``'too_large'``.

    """
    if 'compresseddepth' in str(msg.format).lower().replace(' ', ''):
        raise ImageConversionError(
            'encoding', f'compressedDepth is not supported (format {msg.format!r})')
    data = msg.data
    try:
        raw = np.frombuffer(data, dtype=np.uint8)
    except TypeError:
        raw = np.asarray(data, dtype=np.uint8)
    if raw.size == 0:
        raise ImageConversionError('data_length', 'compressed image holds no bytes')
    image = cv2.imdecode(raw, cv2.IMREAD_UNCHANGED)
    if image is None or image.size == 0:
        raise ImageConversionError(
            'decode', f'{raw.size} bytes of format {msg.format!r} are no JPEG or PNG image '
                      'OpenCV can decode')
    height, width = image.shape[:2]
    if max_pixels is not None and height * width > max_pixels:
        raise ImageConversionError(
            'too_large', f'{width} x {height} = {width * height} pixels exceeds the limit '
                         f'of {max_pixels}')
    return image, ('bgr' if image.ndim == 3 else None)
