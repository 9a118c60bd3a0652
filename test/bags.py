# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Write small rosbag2 files of Image messages with rosbags, as a camera driver would."""

from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import get_typestore, Stores


def write_image_bag(path, frames, topic='/camera/image_raw', encoding='rgb8',
                    storage='mcap', period_ns=33_333_333, frame_id='camera'):
    """Write ``frames`` (uint8 arrays in ``encoding``'s layout) as a rosbag2 at ``path``."""
    store = get_typestore(Stores.ROS2_JAZZY)
    Image = store.types['sensor_msgs/msg/Image']
    Header = store.types['std_msgs/msg/Header']
    Time = store.types['builtin_interfaces/msg/Time']
    plugin = StoragePlugin.MCAP if storage == 'mcap' else StoragePlugin.SQLITE3
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        connection = writer.add_connection(topic, Image.__msgtype__, typestore=store)
        for index, frame in enumerate(frames):
            stamp = 1_700_000_000 * 10**9 + index * period_ns
            channels = 1 if frame.ndim == 2 else frame.shape[2]
            msg = Image(header=Header(stamp=Time(sec=stamp // 10**9, nanosec=stamp % 10**9),
                                      frame_id=frame_id),
                        height=frame.shape[0], width=frame.shape[1], encoding=encoding,
                        is_bigendian=0, step=frame.shape[1] * channels * frame.itemsize,
                        data=frame.reshape(-1).view('uint8'))
            writer.write(connection, stamp, store.serialize_cdr(msg, Image.__msgtype__))
    return path


def write_message_bag(path, entries, storage='mcap'):
    """
    Write rclpy messages as a rosbag2: ``entries`` are ``(topic, message, time_ns)``.

    The messages are serialized by rclpy and written by rosbags, as a
    recorder would store them.
    """
    from rclpy.serialization import serialize_message

    store = get_typestore(Stores.ROS2_JAZZY)
    plugin = StoragePlugin.MCAP if storage == 'mcap' else StoragePlugin.SQLITE3
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        connections = {}
        for topic, msg, time_ns in entries:
            if topic not in connections:
                msgtype = f'{type(msg).__module__.split(".")[0]}/msg/{type(msg).__name__}'
                connections[topic] = writer.add_connection(topic, msgtype, typestore=store)
            writer.write(connections[topic], time_ns, serialize_message(msg))
    return path


def read_message_bag(path):
    """Yield ``(topic, rclpy message)`` from a rosbag2 in recorded order."""
    from importlib import import_module

    from rclpy.serialization import deserialize_message
    from rosbags.rosbag2 import Reader

    with Reader(path) as reader:
        for connection, _, raw in reader.messages():
            package, _, name = connection.msgtype.split('/')
            msg_type = getattr(import_module(f'{package}.msg'), name)
            yield connection.topic, deserialize_message(raw, msg_type)
