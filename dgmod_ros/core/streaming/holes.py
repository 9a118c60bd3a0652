# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Holes in a body: bridged and filled in the published mask.

Where a person's clothes are one flat colour and the window has seen that
colour at a pixel (a coat that covered it in earlier frames, a person in view
from the first frame), the pixel's distance from its background is noise and
the decision leaves it out, while the moving outline around it is far from
the background and stays. What the outline encloses belongs to the body: the
mask a planner receives has the body whole. SuBSENSE (St-Charles et al.,
2015) ends its decision with the same flood fill.

A person close to the camera is cut by the frame's edge, and his outline
encloses his coat together with that edge. The scene's background reaches
the frame's edge round a corner or on two of its sides; what reaches it on
one side only, between two places where the outline meets that side, is
enclosed by the outline and that side, and is filled too. An outline that
meets two sides (a body in a corner) is left open: which of its sides is
the body is not known.

An outline must be whole to enclose. Where a person's edge runs over
background of his own colour, the decision's Potts field (or its median
filter) takes a thin stretch of outline for noise and opens a gap in it, and
through the gap his coat is the scene's. The mask is first closed with a disk
of the field's own neighbourhood (radius ``coherence.RADIUS``): a gap the
field can open, narrower than that neighbourhood, is bridged, and a body's
concave notches of that size with it. A closing joins what is near: a speck
alone stays a speck.

Only what is published is closed and filled. The window keeps its own
decision: a hole the fill closes wrongly (a ring of people, a doughnut of
foreground around real background) must not keep that background out of the
next solves. Measured the other way (the holes kept out of the window too),
mean F was the same within 0.002 and person recall moved both ways from clip
to clip (``docs/results.md``).
"""

import cv2
import numpy as np

from .coherence import RADIUS

# The field's neighbourhood as a disk: a gap it can open is bridged.
_BRIDGE = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * RADIUS + 1, 2 * RADIUS + 1))


def closed_and_filled(mask):
    """
    Return ``mask`` closed by the field's neighbourhood, its holes filled (``mask`` if empty).

    Parameters
    ----------
    mask : ndarray (rows, cols) uint8
        0/255 foreground at the processing size.

    Notes
    -----
    A hole is a 4-connected set of background pixels that touches at most
    one side of the frame, and no corner (a corner is on two sides): the
    4-connected background is the complement of the 8-connected foreground
    the blob rules label, so a blob's outline that touches only diagonally
    still closes it. The holes are those of the closed mask. The closing
    replicates the frame's edge, so a body cut by it is not worn away there.

    """
    if not mask.any():
        return mask
    closed = cv2.morphologyEx(mask, cv2.MORPH_CLOSE, _BRIDGE, borderType=cv2.BORDER_REPLICATE)
    count, labels = cv2.connectedComponents((closed == 0).astype(np.uint8), connectivity=4)
    sides = np.zeros((4, count), bool)
    for side, pixels in enumerate((labels[0], labels[-1], labels[:, 0], labels[:, -1])):
        sides[side, pixels] = True
    holes = sides.sum(axis=0) <= 1
    holes[0] = False                    # label 0 is the foreground
    if not holes.any():
        return closed
    return np.where(holes[labels], np.uint8(255), closed)
