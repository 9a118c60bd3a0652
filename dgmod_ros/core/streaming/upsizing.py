# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""A mask at the processing size brought to the input size (the per-frame path's last step)."""

import cv2
import numpy as np


def to_input_size(mask, output_shape):
    """
    Bring a 0/255 mask to ``output_shape`` by bilinear interpolation thresholded at half.

    An exact doubling (the default scale of 0.5) is a copy of each pixel to
    its 2 x 2 block: there every output pixel's bilinear weights are 9/16 on
    its nearest input pixel and 7/16 on the others together (the borders
    replicate), so the interpolation is over half exactly where that pixel
    is 255, within the fixed-point rounding of OpenCV's.
    """
    if mask.shape == tuple(output_shape):
        return mask
    if tuple(output_shape) == (2 * mask.shape[0], 2 * mask.shape[1]):
        return cv2.resize(mask, (output_shape[1], output_shape[0]),
                          interpolation=cv2.INTER_NEAREST)
    smooth = cv2.resize(mask, (output_shape[1], output_shape[0]),
                        interpolation=cv2.INTER_LINEAR)
    return np.where(smooth > 127, np.uint8(255), np.uint8(0))
