# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
``sensor_msgs/PointCloud2`` <-> numpy for x, y, z float32 clouds, without ROS.

sensor_msgs_py is not available here (and not needed for one fixed layout):
the fields are returned as plain values and dicts that the node copies into
the message, the way :func:`dgmod_ros.image_conversion.array_to_image_fields`
does for images.
"""

import numpy as np

#: sensor_msgs/PointField.FLOAT32
FLOAT32 = 7
#: Bytes per point: three little-endian float32.
POINT_STEP = 12
_XYZ = np.dtype('<f4')


def point_cloud_fields(points):
    """
    Return the fields of an unorganized PointCloud2 holding ``points``.

    Parameters
    ----------
    points : ndarray (n, 3)
        x, y, z; finite (invalid depth is left out, so the cloud is dense).

    Returns
    -------
    fields : dict
        ``height`` (1), ``width`` (n), ``fields`` (three dicts with the
        ``name, offset, datatype, count`` of a PointField), ``is_bigendian``
        (False), ``point_step`` (12), ``row_step``, ``data`` (bytes),
        ``is_dense`` (True). An empty cloud has width 0 and no data.

    """
    points = np.asarray(points)
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError(f'expected (n, 3) points, got shape {points.shape}')
    data = np.ascontiguousarray(points, dtype=_XYZ)
    return {'height': 1, 'width': data.shape[0],
            'fields': [{'name': name, 'offset': 4 * index, 'datatype': FLOAT32, 'count': 1}
                       for index, name in enumerate('xyz')],
            'is_bigendian': False, 'point_step': POINT_STEP,
            'row_step': POINT_STEP * data.shape[0], 'data': data.tobytes(),
            'is_dense': True}


def point_cloud_to_array(msg):
    """
    Return the x, y, z of a PointCloud2 (any object with its fields) as (n, 3) float32.

    Reads float32 ``x``, ``y``, ``z`` fields at any offsets and point step,
    in the byte order the message states.
    """
    offsets = {field.name: field for field in msg.fields}
    missing = [name for name in 'xyz' if name not in offsets]
    if missing:
        raise ValueError(f'cloud has no field {", ".join(missing)}')
    if any(offsets[name].datatype != FLOAT32 for name in 'xyz'):
        raise ValueError('x, y, z must be float32')
    count = int(msg.width) * int(msg.height)
    raw = np.frombuffer(bytes(msg.data), dtype=np.uint8)
    if raw.size < count * int(msg.point_step):
        raise ValueError(f'cloud data holds {raw.size} bytes for {count} points of '
                         f'{msg.point_step} bytes')
    rows = raw[:count * int(msg.point_step)].reshape(count, int(msg.point_step))
    dtype = np.dtype('>f4' if msg.is_bigendian else '<f4')
    columns = [rows[:, offsets[name].offset:offsets[name].offset + 4].copy().view(dtype)[:, 0]
               for name in 'xyz']
    return np.stack(columns, axis=1).astype(np.float32)
