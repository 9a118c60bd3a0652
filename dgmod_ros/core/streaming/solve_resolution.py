# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The window solve at a capped size, and the full-size background carried from it.

A solve costs about its pixel count times its columns and channels, so a solve
of 640 x 480 frames costs four times one of 320 x 240 ones, while the
per-frame path (projection, decision) costs far less at any size. Above
``solve_pixels`` pixels a frame, the window is solved downscaled
(:func:`solve_shape`) and the full-size background is carried from the
solve's temporal factors (:func:`carry_backgrounds`): the solve fixes how the
background changes over the window (its right singular vectors, the frames'
mixing of a few background images), and each full-size pixel's own time series
fixes its share of each, wherever the solve did not call that pixel foreground.
The carried background stays in factored form (:class:`CarriedBackground`),
and the window's noise levels are read at one full-size pixel per solved one
(:class:`PixelSample`): what follows the capped solve then costs a fraction
of the solve, where at full size it had cost more than the solve itself.
"""

import cv2
import numpy as np

from .fast_path import background_basis
from .kernels.solve_resolution import normal_equations
from .noise_levels import magnitude_noise
from ..linalg import thin_svd
from ..preprocess import shape_within

# Most channels one cv2.resize call takes: OpenCV 5's CV_CN_MAX, and 4 for
# area averaging at a ratio that is not an integer (an integer one takes all:
# one call of 30 channels cost a fifth of eight calls of 4 and their copies).
_AREA_CHANNELS = 4
_MAX_CHANNELS = 128
# Noise levels of the solve's residual above which an entry is held out of the
# full-size fit (a short solve's S holds much of the noise too, so S's own
# support would hold out nearly every entry).
_HELD_OUT_SIGMAS = 3.0


def solve_shape(shape, max_pixels, scale=1.0):
    """
    Return the (rows, cols, C) a window of frames of ``shape`` is solved at.

    ``shape`` scaled by ``scale`` in both directions, and further down, by one
    factor in both directions, to at most ``max_pixels`` pixels (at least
    1 x 1), so the rule follows any camera's aspect; ``shape`` itself at
    ``scale`` 1 when a frame has at most ``max_pixels`` pixels.
    """
    rows, cols = shape[:2]
    max_pixels = min(max_pixels, int(scale * scale * rows * cols + 1e-6))
    return shape_within(rows, cols, max_pixels) + tuple(shape[2:])


def resample_columns(columns, shape, new_shape, interpolation):
    """
    Return an (n, m) matrix of frame columns resampled from ``shape`` to ``new_shape``.

    Each column is one (rows, cols) image; the matrix is read as images of
    as many channels as one OpenCV call takes.
    """
    rows, cols = shape[:2]
    new_rows, new_cols = new_shape[:2]
    if (rows, cols) == (new_rows, new_cols):
        return columns
    width = columns.shape[1]
    image = columns.reshape(rows, cols, width)
    out = np.empty((new_rows, new_cols, width), dtype=columns.dtype)
    integer = rows % new_rows == 0 and cols % new_cols == 0
    group = (_AREA_CHANNELS if interpolation == cv2.INTER_AREA and not integer
             else _MAX_CHANNELS)
    for start in range(0, width, group):
        part = np.ascontiguousarray(image[:, :, start:start + group])
        resized = cv2.resize(part, (new_cols, new_rows), interpolation=interpolation)
        out[:, :, start:start + group] = resized.reshape(new_rows, new_cols, -1)
    return out.reshape(new_rows * new_cols, width)


def resample_frames(frames, shape, new_shape, interpolation):
    """
    Return frames-major rows (m, n) resampled from ``shape`` to ``new_shape``, (m, n') float32.

    Each row is one (rows, cols) image, resized by one OpenCV call: the
    window is frames-major in memory (:meth:`~.results.WindowSnapshot.window`),
    where a row is contiguous and an image of ``m`` channels is not.
    """
    rows, cols = shape[:2]
    new_rows, new_cols = new_shape[:2]
    out = np.empty((frames.shape[0], new_rows * new_cols), dtype=np.float32)
    for row, image in zip(out, frames):
        image = np.ascontiguousarray(image, dtype=np.float32).reshape(rows, cols)
        row[:] = cv2.resize(image, (new_cols, new_rows), interpolation=interpolation).ravel()
    return out


def downsample_window(data, shape, small_shape):
    """
    Return the window (C, n, m) at ``small_shape`` (area averaging, as frames are scaled).

    Each channel of the result is F-ordered, an ``n x m`` view of its
    frames-major ``(m, n)`` rows: what the fused solver works on
    (:func:`~dgmod_ros.core.linalg.frames_major`), so that it copies nothing.
    """
    small = np.stack([resample_frames(channel.T, shape, small_shape, cv2.INTER_AREA)
                      for channel in data])                                # (C, m, n')
    return small.transpose(0, 2, 1)


class ColumnCache:
    """
    Each buffered column's copy at the solve size and at the noise levels' pixels, made once.

    A capped solve reads its whole window downscaled and at a
    :class:`PixelSample` of pixels, a pass over 27 MB at 640 x 480 each time,
    while between two solves one column in the window's thirty is new (one
    admission per ``memory_spacing`` frames, one solve per ``stride``).
    Buffered columns are never written (:meth:`~.buffer.FrameWindow.columns`),
    so each column's downscaled and sampled copies are made the first time a
    solve asks and kept while the column is in a solved window. Every copy is
    the same arithmetic as :func:`downsample_window` and :func:`take_pixels`
    on the stacked window, per column. A solve thread reads and fills the
    cache; a detector's solves run one at a time, and one left running by a
    reset works on the cache of its own snapshot.
    """

    def __init__(self):
        self._entries = {}      # id(column) -> (column, {key: copy})

    def _copy(self, column, key, make):
        entry = self._entries.get(id(column))
        if entry is None or entry[0] is not column:     # an id reused by a new column
            entry = self._entries[id(column)] = (column, {})
        copy = entry[1].get(key)
        if copy is None:
            copy = entry[1][key] = make(column)
        return copy

    def keep(self, columns):
        """Forget the copies of every column not in ``columns``."""
        alive = {id(column) for column in columns}
        for key in list(self._entries):
            if key not in alive:
                self._entries.pop(key, None)

    def small_window(self, columns, shape, small_shape):
        """Return the window of ``columns`` (C, n) at ``small_shape``, as downsample_window."""
        key = ('area', tuple(shape[:2]), tuple(small_shape[:2]))
        small = np.stack([self._copy(column, key, lambda c: resample_frames(
            c, shape, small_shape, cv2.INTER_AREA)) for column in columns], axis=1)
        return small.transpose(0, 2, 1)                                    # (C, n', m)

    def sampled_window(self, columns, sample):
        """Return the window of ``columns`` (C, n) at ``sample``'s pixels, as its ``take``."""
        key = ('sample', sample.shape, sample.small_shape)
        picked = np.stack([self._copy(column, key, lambda c: np.take(c, sample.pixels, axis=1))
                           for column in columns])                         # (m, C, k)
        return np.ascontiguousarray(np.moveaxis(picked, 0, -1))


def take_pixels(array, pixels, grid=None):
    """
    Return ``array`` (n, m) or (C, n, m) at ``pixels`` of its second-to-last axis, C-ordered.

    A frames-major window (pixels the faster axis in memory,
    :meth:`~.results.WindowSnapshot.window`) is gathered along its rows and
    the small result transposed: a gather across its frames' strides cost
    several times as much. ``grid`` = (rows, cols, picked rows, picked
    columns), where ``pixels`` is that grid's row-major product, gathers the
    rows and then the columns of each frame: half the time of a gather of
    single pixels, the same values.
    """
    frames = np.moveaxis(array, -1, 0)                  # (m, ..., n)
    if array.ndim > 1 and frames.flags.c_contiguous:
        # np.take of a strided array copies it whole first: take from the rows.
        if grid is None:
            picked = np.take(frames.reshape(-1, frames.shape[-1]), pixels, axis=1)
        else:
            rows, cols, picked_rows, picked_cols = grid
            images = frames.reshape(-1, rows, cols)
            picked = np.take(np.take(images, picked_rows, axis=1), picked_cols, axis=2)
        return np.ascontiguousarray(np.moveaxis(picked.reshape(frames.shape[:-1] + (-1,)), 0, -1))
    return np.take(array, pixels, axis=-2)


class PixelSample:
    """
    One full-size pixel for each pixel of the solve's grid: where a carried window's noise is read.

    A noise level is a median over the window's columns at each pixel, as
    costly at 640 x 480 as the solve itself once that is capped. Read at the
    full-size pixel nearest each solve-size pixel's centre (a picked pixel,
    not an area average, whose noise would be lower by the averaging), the
    levels are those of full-size pixels, upsampled bilinearly; they are
    smoothed over 5 x 5 pixels afterwards anyway
    (:func:`~dgmod_ros.core.streaming.noise_levels.pixel_noise`).

    Parameters
    ----------
    shape, small_shape : tuple (rows, cols, ...)
        Full and solve frame sizes.

    Attributes
    ----------
    pixels : ndarray (k,) intp
        Row-major full-size indices of the picked pixels, in the solve grid's order.

    """

    def __init__(self, shape, small_shape):
        self.shape, self.small_shape = tuple(shape[:2]), tuple(small_shape[:2])
        (rows, cols), (small_rows, small_cols) = self.shape, self.small_shape
        picked_rows = ((np.arange(small_rows) + 0.5) * (rows / small_rows)).astype(np.intp)
        picked_cols = ((np.arange(small_cols) + 0.5) * (cols / small_cols)).astype(np.intp)
        picked_rows = np.minimum(picked_rows, rows - 1)
        picked_cols = np.minimum(picked_cols, cols - 1)
        self.pixels = (picked_rows[:, None] * cols + picked_cols[None, :]).ravel()
        self._grid = (rows, cols, picked_rows, picked_cols)

    def take(self, array):
        """Return ``array``'s picked pixels (:func:`take_pixels`, by rows and columns)."""
        return take_pixels(array, self.pixels, self._grid)

    def upsample(self, levels):
        """Return (n,) float32 levels bilinearly upsampled from one per picked pixel (k,)."""
        small = np.asarray(levels, dtype=np.float32).reshape(self.small_shape)
        return cv2.resize(small, self.shape[::-1], interpolation=cv2.INTER_LINEAR).ravel()


def solve_spd(gram, rhs):
    """
    Return ``x`` (r, k) of the k symmetric positive definite r x r systems ``gram x = rhs``.

    ``gram`` is (r, r, k) and ``rhs`` (r, k): each system one column, so the
    elimination (no pivoting, which a positive definite matrix does not
    need) runs over contiguous rows of k, with loops over r only.
    ``np.linalg.solve`` on (k, r, r) pays a per-matrix overhead that cost
    more than the arithmetic of 2 x 2 systems at 640 x 480.
    """
    upper = np.array(gram, dtype=np.float32)
    x = np.array(rhs, dtype=np.float32)
    r = x.shape[0]
    for i in range(r):
        for j in range(i + 1, r):
            factor = upper[j, i] / upper[i, i]
            upper[j, i:] -= factor * upper[i, i:]
            x[j] -= factor * x[i]
    for i in reversed(range(r)):
        x[i] -= np.einsum('jk,jk->k', upper[i, i + 1:], x[i + 1:])
        x[i] /= upper[i, i]
    return x


class CarriedBackground:
    """
    The full-size backgrounds of a carried window solve, as factors ``L_c = A_c V_c^T``.

    ``L_c`` itself (n x m a channel) is formed only where a caller needs all
    of it (:meth:`residuals` without pixels): the newest and mean columns,
    the fast path's basis and the residual at a sample of pixels come from
    the factors.

    Parameters
    ----------
    factors : list of (ndarray (n, r) float32, ndarray (m, r) float32)
        Each channel's ``A`` and orthonormal ``V``.

    """

    def __init__(self, factors):
        self.factors = factors

    def bases(self, rank):
        """
        Return each channel's fast-path basis (n, r'): the left singular vectors of ``L``.

        With ``V`` orthonormal, ``A = U S W^T`` gives ``L = U S (V W)^T``: the
        SVD of ``A`` (n x r) is that of ``L`` (n x m), at r / m of the cost.
        """
        return [background_basis(coef, rank) for coef, _ in self.factors]

    def newest(self):
        """Return the newest column of each channel's background (n, C)."""
        return np.stack([coef @ temporal[-1] for coef, temporal in self.factors], axis=1)

    def mean(self):
        """Return each channel's mean background column (n, C)."""
        return np.stack([coef @ temporal.mean(axis=0) for coef, temporal in self.factors],
                        axis=1)

    def residuals(self, data, pixels=None):
        """
        Return ``D - L`` (C, n, m), or at ``pixels`` only (C, k, m).

        ``data`` is the window, or with ``pixels`` the window at those pixels
        (:func:`take_pixels`), which the caller reads for more than this.
        """
        out = np.empty(data.shape, dtype=np.float32)
        for channel, (coef, temporal) in enumerate(self.factors):
            coef = coef if pixels is None else coef[pixels]
            np.subtract(data[channel], coef @ temporal.T, out=out[channel])
        return out


def carry_backgrounds(frames, shape, backgrounds, small_residuals, small_shape, rank):
    """
    Return the full-size backgrounds of a window solved at ``small_shape``.

    Each channel's full-size background is ``A V^T``: ``V`` (m x r,
    orthonormal) the solve's leading ``rank`` temporal factors, and each
    full-size pixel's row of ``A`` the weighted least-squares fit of its own
    time series on ``V``, starting from the solve's ``L V`` upsampled (``P``).
    The entries the solve called foreground are weighted out: those whose
    residual ``D - L`` (largest over the channels) exceeds three times the
    pixel's noise level (:func:`~dgmod_ros.core.streaming.noise_levels.pixel_noise`
    of that residual), upsampled, any overlap counting. The fit is of the
    detail ``D - P V^T``, and zero detail counts as a tenth of an observed
    frame (a ridge of ``0.1/m``: it shrinks a fully observed pixel's detail
    by 0.3% at m = 30, and keeps the system of a pixel seen in fewer than r
    frames solvable, that pixel keeping the solve's background).

    With ``W`` the weights and ``G = V^T diag(w) V`` a pixel's r x r matrix,
    that fit ``A = P + (G + rho I)^-1 (W o (D - P V^T)) V`` is
    ``A = (G + rho I)^-1 ((W o D) V + rho P)``: no n x m detail is formed, and
    every pixel solves its system (batched, :func:`solve_spd`), those with
    every entry in (``G = I``) as well, which costs less than gathering the
    others (most pixels have one entry out: 3-sigma exceedances over m
    columns, widened by the upsampling).

    Parameters
    ----------
    frames : sequence of m ndarrays (C, n) float32, or ndarray (m, C, n)
        The window at full size, frame by frame
        (:meth:`~.results.WindowSnapshot.frames`).
    shape, small_shape : tuple (rows, cols, ...)
        Full and solve frame sizes.
    backgrounds : list of ndarray (n_small, m)
        The solve's ``L`` of each channel.
    small_residuals : ndarray (C, n_small, m)
        The solve's ``D - L``.
    rank : int
        Temporal factors carried (the fast path's ``basis_rank``).

    Returns
    -------
    CarriedBackground

    """
    # Frames-major throughout: a frame's pixels are one contiguous row of
    # each frame's channels and of the weights.
    magnitude = np.abs(small_residuals).max(axis=0)                       # (n_small, m)
    noise = magnitude_noise(magnitude, small_shape)
    held_out = (magnitude.T > _HELD_OUT_SIGMAS * noise[None, :]).astype(np.float32)
    held_out = resample_frames(held_out, small_shape, shape, cv2.INTER_LINEAR)  # (m, n)
    ridge = np.float32(0.1 / len(frames))
    temporals = [thin_svd(small, int(rank))[2] for small in backgrounds]  # (m, r) each
    # Systems as columns (r, r, n) and (r, n): the elimination's rows are contiguous.
    systems = normal_equations(frames, held_out, temporals)
    factors = []
    for small, temporal, (gram, rhs) in zip(backgrounds, temporals, systems):
        r = temporal.shape[1]
        start = resample_columns(small @ temporal, small_shape, shape, cv2.INTER_LINEAR)
        gram[np.arange(r), np.arange(r)] += ridge
        rhs += ridge * start.T
        coef = np.ascontiguousarray(solve_spd(gram, rhs).T)               # (n, r)
        factors.append((coef, temporal))
    return CarriedBackground(factors)
