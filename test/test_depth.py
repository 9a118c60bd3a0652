# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Depth decoding, back-projection and the PointCloud2 layout, without ROS."""

from types import SimpleNamespace

import cv2
from dgmod_ros.core.depth import (back_project, depth_in_metres, invalidate_background,
                                  PinholeIntrinsics)
from dgmod_ros.image_conversion import (array_to_image_fields, compressed_image_to_array,
                                        depth_image_to_array, ImageConversionError)
from dgmod_ros.point_cloud import point_cloud_fields, point_cloud_to_array
import numpy as np
import pytest

K = [200.0, 0.0, 80.0, 0.0, 210.0, 60.0, 0.0, 0.0, 1.0]


def test_sixteen_bit_millimetres_and_float_metres_give_the_same_metres():
    millimetres = np.array([[0, 1000], [2500, 65535]], np.uint16)
    metres = np.array([[np.nan, 1.0], [2.5, 65.535]], np.float32)
    for depth in (millimetres, metres):
        out = depth_in_metres(depth)
        assert out.dtype == np.float32 and np.isnan(out[0, 0])
        assert np.allclose(out[~np.isnan(out)], [1.0, 2.5, 65.535])
    floats = depth_in_metres(np.array([[np.inf, -np.inf, 0.0, -1.0, 3.0]], np.float32))
    assert np.isnan(floats[0, :4]).all() and floats[0, 4] == 3.0
    with pytest.raises(ValueError, match='uint16'):
        depth_in_metres(np.zeros((2, 2), np.int32))


def test_background_is_set_invalid_in_the_input_encoding():
    mask = np.array([[1, 0], [0, 1]], bool)
    mm = invalidate_background(np.full((2, 2), 1500, np.uint16), mask)
    assert mm.dtype == np.uint16 and mm.tolist() == [[1500, 0], [0, 1500]]
    m = invalidate_background(np.full((2, 2), 1.5, np.float32), mask)
    assert m.dtype == np.float32 and np.isnan(m[0, 1]) and np.isnan(m[1, 0]) and m[0, 0] == 1.5
    # A half-resolution mask is scaled to the depth image by nearest neighbour.
    big = invalidate_background(np.full((4, 4), 7, np.uint16), mask)
    assert big[:2, :2].min() == 7 and big[:2, 2:].max() == 0


def test_back_projection_inverts_the_pinhole_projection():
    intrinsics = PinholeIntrinsics.from_k(K)
    rng = np.random.default_rng(0)
    depth = rng.uniform(0.5, 4.0, (120, 160)).astype(np.float32)
    depth[10, 20] = np.nan
    mask = np.zeros((120, 160), bool)
    mask[5:40, 10:50] = True
    points = back_project(depth, mask, intrinsics)
    assert points.dtype == np.float32 and points.shape == (35 * 40 - 1, 3)
    assert np.all(np.isfinite(points))
    # Projecting the points back lands on the foreground pixels at their depth.
    u = points[:, 0] * 200.0 / points[:, 2] + 80.0
    v = points[:, 1] * 210.0 / points[:, 2] + 60.0
    cols, rows = np.rint(u).astype(int), np.rint(v).astype(int)
    assert np.allclose(u, cols, atol=1e-3) and np.allclose(v, rows, atol=1e-3)
    assert mask[rows, cols].all()
    assert np.allclose(points[:, 2], depth[rows, cols])
    # The principal point maps onto the optical axis.
    depth[60, 80] = 2.0
    centre = np.zeros_like(mask)
    centre[60, 80] = True
    assert np.allclose(back_project(depth, centre, intrinsics), [[0.0, 0.0, 2.0]])


def test_subsampling_takes_every_step_th_pixel_in_both_directions():
    intrinsics = PinholeIntrinsics.from_k(K)
    depth = np.full((120, 160), 1.0, np.float32)
    mask = np.ones((120, 160), bool)
    full = back_project(depth, mask, intrinsics)
    every_fourth = back_project(depth, mask, intrinsics, step=4)
    assert every_fourth.shape[0] == 30 * 40
    rows = {tuple(p) for p in full.tolist()}
    assert all(tuple(p) in rows for p in every_fourth.tolist())
    assert back_project(depth, np.zeros_like(mask), intrinsics).shape == (0, 3)
    with pytest.raises(ValueError, match='step'):
        back_project(depth, mask, intrinsics, step=0)


@pytest.mark.parametrize('k, message', [([0.0] * 9, 'focal'), ([1.0] * 4, '9 finite'),
                                        ([np.nan] + K[1:], '9 finite')])
def test_uncalibrated_camera_matrices_are_refused(k, message):
    with pytest.raises(ValueError, match=message):
        PinholeIntrinsics.from_k(k)


def _depth_message(array, encoding):
    return SimpleNamespace(**array_to_image_fields(array, encoding))


def test_depth_messages_keep_nan_and_refuse_colour():
    metres = np.array([[np.nan, 1.0]], np.float32)
    out = depth_image_to_array(_depth_message(metres, '32FC1'))
    assert np.isnan(out[0, 0]) and out[0, 1] == 1.0
    mm = depth_image_to_array(_depth_message(np.array([[0, 5]], np.uint16), '16UC1'))
    assert mm.dtype == np.uint16 and mm.tolist() == [[0, 5]]
    with pytest.raises(ImageConversionError) as error:
        depth_image_to_array(_depth_message(np.zeros((2, 2, 3), np.uint8), 'rgb8'))
    assert error.value.reason == 'encoding'
    short = _depth_message(np.zeros((2, 2), np.uint16), '16UC1')
    short.data = short.data[:-1]
    with pytest.raises(ImageConversionError) as error:
        depth_image_to_array(short)
    assert error.value.reason == 'data_length'


def test_point_cloud_layout_round_trips():
    points = np.array([[0.1, -0.2, 1.5], [1.0, 2.0, 3.0]], np.float32)
    fields = point_cloud_fields(points)
    assert (fields['height'], fields['width'], fields['point_step'], fields['row_step']) == \
        (1, 2, 12, 24)
    assert fields['is_dense'] and not fields['is_bigendian'] and len(fields['data']) == 24
    assert [(f['name'], f['offset'], f['datatype'], f['count']) for f in fields['fields']] == \
        [('x', 0, 7, 1), ('y', 4, 7, 1), ('z', 8, 7, 1)]
    assert np.frombuffer(fields['data'], '<f4').tolist() == points.reshape(-1).tolist()
    msg = SimpleNamespace(**dict(fields, fields=[SimpleNamespace(**f) for f in fields['fields']]))
    assert np.array_equal(point_cloud_to_array(msg), points)
    empty = point_cloud_fields(np.zeros((0, 3), np.float32))
    assert empty['width'] == 0 and empty['data'] == b'' and empty['row_step'] == 0
    with pytest.raises(ValueError, match=r'\(n, 3\)'):
        point_cloud_fields(np.zeros((4, 2)))


@pytest.mark.parametrize('extension, tolerance', [('.png', 0), ('.jpg', 8)])
def test_compressed_images_decode_to_bgr(extension, tolerance):
    rng = np.random.default_rng(1)
    bgr = cv2.GaussianBlur(rng.integers(0, 255, (48, 64, 3), dtype=np.uint8), (7, 7), 2)
    ok, data = cv2.imencode(extension, bgr, [cv2.IMWRITE_JPEG_QUALITY, 95])
    assert ok
    image, order = compressed_image_to_array(
        SimpleNamespace(format=f'rgb8; {extension[1:]} compressed bgr8', data=data.tobytes()))
    assert order == 'bgr' and image.shape == bgr.shape
    assert np.abs(image.astype(int) - bgr).mean() <= tolerance
    with pytest.raises(ImageConversionError) as error:
        compressed_image_to_array(SimpleNamespace(format='png', data=data.tobytes()),
                                  max_pixels=100)
    assert error.value.reason == 'too_large'


@pytest.mark.parametrize('fmt, data, reason', [
    ('jpeg', b'', 'data_length'),
    ('jpeg', b'\xff\xd8 this is not a jpeg', 'decode'),
    ('png', bytes(range(256)), 'decode'),
    ('16UC1; compressedDepth png', b'\x00' * 40, 'encoding'),
])
def test_malformed_compressed_images_name_the_reason(fmt, data, reason):
    with pytest.raises(ImageConversionError) as error:
        compressed_image_to_array(SimpleNamespace(format=fmt, data=data))
    assert error.value.reason == reason
