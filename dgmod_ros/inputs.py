# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Frame sources for the command line: image folders, video files, rosbag2 bags.

Each source yields :class:`Frame` objects in order. A frame that cannot be
decoded is yielded as a :class:`BadInput` (one sentence naming it), so that a
caller can stop or skip it and go on; an input that cannot be opened at all
raises :class:`BadInput`. rosbag2 is read with ``rosbags`` (pure Python), so
no ROS installation is needed.
"""

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from .image_conversion import image_to_array, ImageConversionError

IMAGE_SUFFIXES = {'.png', '.jpg', '.jpeg', '.bmp', '.tif', '.tiff', '.ppm', '.pgm'}
VIDEO_SUFFIXES = {'.mp4', '.avi', '.mkv', '.mov', '.m4v', '.mpg', '.mpeg', '.webm'}
BAG_SUFFIXES = {'.mcap', '.db3'}


class BadInput(ValueError):
    """An input, or one frame of it, that cannot be read."""


@dataclass
class Frame:
    """One decoded frame and where it came from."""

    index: int
    stem: str                   # output file name without suffix
    image: np.ndarray
    channel_order: str          # 'rgb' or 'bgr' for colour images


def _folder_images(folder):
    root = folder / 'input' if (folder / 'input').is_dir() else folder
    files = sorted(p for p in root.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES)
    if not files:
        raise BadInput(f'no image files ({", ".join(sorted(IMAGE_SUFFIXES))}) in {root}')
    return files


def _read_folder(folder):
    for index, path in enumerate(_folder_images(folder)):
        image = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
        if image is None or image.size == 0:
            yield BadInput(f'cannot decode image {path}')
            continue
        if image.ndim == 3 and image.shape[2] == 4:
            image = image[:, :, :3]
        yield Frame(index, path.stem, image, 'bgr')


def _read_video(path):
    capture = cv2.VideoCapture(str(path))
    if not capture.isOpened():
        raise BadInput(f'OpenCV cannot open the video {path}')
    index = 0
    try:
        while True:
            ok, image = capture.read()
            if not ok:
                break
            yield Frame(index, f'{index:06d}', image, 'bgr')
            index += 1
    finally:
        capture.release()
    if index == 0:
        raise BadInput(f'the video {path} holds no readable frame')


def _bag_reader(path):
    try:
        from rosbags.rosbag2 import Reader
    except ImportError as error:        # pragma: no cover - rosbags is a dependency
        raise BadInput(f'reading rosbag2 needs the rosbags package: {error}') from error
    try:
        return Reader(path)
    except Exception as error:  # noqa: B902 - rosbags raises several unrelated types
        raise BadInput(f'cannot open the rosbag2 {path}: {error}') from error


def _read_bag(path, topic):
    from rosbags.typesys import get_typestore, Stores
    store = get_typestore(Stores.ROS2_JAZZY)
    reader = _bag_reader(path)
    try:
        reader.open()
    except Exception as error:  # noqa: B902
        raise BadInput(f'cannot open the rosbag2 {path}: {error}') from error
    try:
        images = [c for c in reader.connections if c.msgtype == 'sensor_msgs/msg/Image']
        if topic is not None:
            images = [c for c in images if c.topic == topic]
            if not images:
                raise BadInput(f'no sensor_msgs/msg/Image topic {topic!r} in {path}')
        elif len({c.topic for c in images}) != 1:
            topics = sorted({c.topic for c in images}) or ['none']
            raise BadInput(f'{path} has image topics {", ".join(topics)}: choose one with '
                           f'--topic')
        for index, (connection, stamp, raw) in enumerate(reader.messages(connections=images)):
            try:
                msg = store.deserialize_cdr(raw, connection.msgtype)
                image, order = image_to_array(msg)
            except ImageConversionError as error:
                yield BadInput(f'message {index} of {connection.topic} (t={stamp} ns): {error}')
                continue
            except Exception as error:  # noqa: B902 - a corrupt CDR buffer
                yield BadInput(f'message {index} of {connection.topic} (t={stamp} ns) cannot '
                               f'be decoded: {error}')
                continue
            yield Frame(index, f'{index:06d}', image, order or 'rgb')
    finally:
        reader.close()


def input_kind(path):
    """Return 'folder', 'video' or 'bag' for an input path; raise BadInput otherwise."""
    path = Path(path)
    if not path.exists():
        raise BadInput(f'input {path} does not exist')
    if path.is_dir():
        return 'bag' if (path / 'metadata.yaml').is_file() else 'folder'
    suffix = path.suffix.lower()
    if suffix in BAG_SUFFIXES:
        return 'bag'
    if suffix in VIDEO_SUFFIXES:
        return 'video'
    raise BadInput(f'cannot tell what {path} is: expected a folder of images, a video '
                   f'({", ".join(sorted(VIDEO_SUFFIXES))}) or a rosbag2')


def read_frames(path, topic=None):
    """
    Yield the frames of an input in order (a :class:`BadInput` for an unreadable one).

    Parameters
    ----------
    path : str or Path
        A folder of frames (plain, or CDnet-style with ``input/``), a video file
        OpenCV reads, or a rosbag2 (folder with ``metadata.yaml``, ``.mcap``,
        ``.db3``).
    topic : str or None
        Image topic of a bag; needed when it holds several.

    """
    path = Path(path)
    kind = input_kind(path)
    if kind == 'folder':
        return _read_folder(path)
    if kind == 'video':
        return _read_video(path)
    return _read_bag(path, topic)


def count_frames(path, topic=None):
    """Return the number of frames an input announces, or None when unknown."""
    try:
        kind = input_kind(path)
        if kind == 'folder':
            return len(_folder_images(Path(path)))
        if kind == 'video':
            capture = cv2.VideoCapture(str(path))
            total = int(capture.get(cv2.CAP_PROP_FRAME_COUNT))
            capture.release()
            return total if total > 0 else None
        reader = _bag_reader(Path(path))
        reader.open()
        try:
            return sum(c.msgcount for c in reader.connections
                       if c.msgtype == 'sensor_msgs/msg/Image'
                       and (topic is None or c.topic == topic)) or None
        finally:
            reader.close()
    except Exception:  # noqa: B902 - counting is best effort; reading reports errors
        return None
