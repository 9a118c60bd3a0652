# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Message conversion, tested without ROS on plain objects with the Image fields."""

from types import SimpleNamespace

from dgmod_ros.image_conversion import (array_to_image_fields, ENCODINGS, image_to_array,
                                        ImageConversionError)
from hypothesis import given, settings, strategies as st
import numpy as np
import pytest


def message(array, encoding, pad=0, big_endian=False):
    """Lay out ``array`` as an Image message would, with ``pad`` bytes after each row."""
    dtype = np.dtype(ENCODINGS[encoding][0]).newbyteorder('>' if big_endian else '<')
    rows = np.ascontiguousarray(array, dtype=dtype).reshape(array.shape[0], -1).view(np.uint8)
    padded = np.concatenate([rows, np.full((rows.shape[0], pad), 0xAB, np.uint8)], axis=1)
    return SimpleNamespace(height=array.shape[0], width=array.shape[1], encoding=encoding,
                           is_bigendian=int(big_endian), step=padded.shape[1],
                           data=padded.tobytes())


def sample(encoding, shape=(4, 5), seed=0):
    base, channels, _ = ENCODINGS[encoding]
    rng = np.random.default_rng(seed)
    full = shape + ((channels,) if channels > 1 else ())
    if np.dtype(base).kind == 'f':
        return rng.random(full).astype(base)
    return rng.integers(0, np.iinfo(base).max, full, endpoint=True).astype(base)


@pytest.mark.parametrize('encoding', sorted(ENCODINGS))
@pytest.mark.parametrize('pad', [0, 3])
@pytest.mark.parametrize('big_endian', [False, True])
def test_round_trip_with_padding_and_byte_order(encoding, pad, big_endian):
    array = sample(encoding)
    image, order = image_to_array(message(array, encoding, pad, big_endian))
    assert image.dtype == np.dtype(ENCODINGS[encoding][0])       # native order
    assert np.array_equal(image, array)
    assert order == ENCODINGS[encoding][2]


def test_output_fields_are_exact():
    fields = array_to_image_fields(np.arange(6, dtype=np.uint16).reshape(2, 3), 'mono16')
    assert (fields['height'], fields['width'], fields['step']) == (2, 3, 6)
    back, _ = image_to_array(SimpleNamespace(**fields))
    assert np.array_equal(back, np.arange(6).reshape(2, 3))


def test_buffer_is_copied_not_aliased():
    data = bytearray(np.arange(6, dtype=np.uint8).tobytes())
    msg = SimpleNamespace(height=2, width=3, encoding='mono8', is_bigendian=0, step=3, data=data)
    image, _ = image_to_array(msg)
    data[0] = 99
    assert image[0, 0] == 0


@pytest.mark.parametrize('change, reason', [
    ({'encoding': 'yuv422'}, 'encoding'),
    ({'width': 0}, 'size'),
    ({'height': 0}, 'size'),
    ({'step': 4}, 'step'),
    ({'data': bytes(14)}, 'data_length'),
    ({'data': bytes(16)}, 'data_length'),
])
def test_malformed_messages_name_the_reason(change, reason):
    msg = message(sample('mono8'), 'mono8')
    for name, value in change.items():
        setattr(msg, name, value)
    with pytest.raises(ImageConversionError) as error:
        image_to_array(msg)
    assert error.value.reason == reason


def test_size_limit_and_non_finite_floats():
    with pytest.raises(ImageConversionError) as error:
        image_to_array(message(sample('mono8'), 'mono8'), max_pixels=19)
    assert error.value.reason == 'too_large'
    array = sample('32FC1')
    array[1, 2] = np.nan
    with pytest.raises(ImageConversionError) as error:
        image_to_array(message(array, '32FC1'))
    assert error.value.reason == 'non_finite'


encodings = st.sampled_from(sorted(ENCODINGS) + ['yuv422', 'bayer_rggb8', '', '64FC1'])


@settings(max_examples=300, deadline=None)
@given(encoding=encodings, height=st.integers(-2, 12), width=st.integers(-2, 12),
       step=st.integers(-4, 120), big_endian=st.booleans(),
       data=st.binary(max_size=400))
def test_random_messages_convert_or_raise_conversion_error(encoding, height, width, step,
                                                           big_endian, data):
    msg = SimpleNamespace(height=height, width=width, encoding=encoding,
                          is_bigendian=int(big_endian), step=step, data=data)
    try:
        image, _ = image_to_array(msg, max_pixels=100)
    except ImageConversionError as error:
        assert error.reason in {'encoding', 'size', 'step', 'data_length', 'too_large',
                                'non_finite'}
        return
    # Anything accepted is a well-formed image of the stated size.
    assert image.shape[:2] == (height, width)
    assert height * width <= 100 and len(data) == step * height
    if image.dtype.kind == 'f':
        assert np.all(np.isfinite(image))


@settings(max_examples=100, deadline=None)
@given(encoding=st.sampled_from(sorted(ENCODINGS)), height=st.integers(1, 9),
       width=st.integers(1, 9), pad=st.integers(0, 7), big_endian=st.booleans(),
       seed=st.integers(0, 1000))
def test_random_valid_images_round_trip(encoding, height, width, pad, big_endian, seed):
    array = sample(encoding, (height, width), seed)
    image, _ = image_to_array(message(array, encoding, pad, big_endian))
    assert np.array_equal(image, array)
