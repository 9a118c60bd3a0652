# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Changes that light explains: shadows, reflections, highlights.

A shadow or a reflection on a polished floor scales the background's colour
and leaves its texture in place; a person changes the colour's direction
(chromaticity), the local pattern of shades, or the brightness by more than
light plausibly does. Horprasert et al. split a pixel's colour difference
``I - E`` (frame ``I``, background ``E``, RGB vectors) into a part along
``E`` and a part across it. With ``alpha = <I, E> / <E, E>``:

- brightness ratio ``alpha`` (1: unchanged; a shadow is below 1, a
  reflection above);
- chromaticity distortion ``c = |I - alpha E|``, in the units of the data.

A candidate pixel (its distance above ``k`` noise levels) is a change of
light when all the enabled cues agree
(:func:`~dgmod_ros.core.streaming.kernels.photometric.distortion` computes both):

- chromaticity: ``c`` within ``k`` times the pixel's own chromaticity noise
  level (:func:`chroma_noise`: read from the window's ``D`` and ``L`` the way
  :func:`~dgmod_ros.core.streaming.noise_levels.pixel_noise` reads the level of
  the channel-wise difference);
- texture: the LBSP descriptor distance to the background
  (:mod:`~dgmod_ros.core.streaming.kernels.texture`) at most ``texture_bits``;
- brightness: ``|alpha - 1|`` within LBSP's relative threshold
  (:data:`~dgmod_ros.core.streaming.kernels.texture.RELATIVE_THRESHOLD`), the one
  share of a value below which both cues call two values similar.

References
----------
T. Horprasert, D. Harwood, L. S. Davis, "A statistical approach for real-time
robust background subtraction and shadow detection", IEEE ICCV Frame-Rate
Workshop, 1999.

"""

from .kernels.photometric import (explained_pixels, explained_pixels_reference, window_chroma,
                                  window_chroma_reference)
from .noise_levels import magnitude_noise
from ..numba_setup import reference_unless


def chroma_noise(data, residual, shape, observed=None, uniform=False, sample=None):
    """
    Return each pixel's chromaticity noise level (n,) float32 from a window solve.

    Parameters
    ----------
    data : ndarray (C, n, m)
        The window ``D``; with ``sample``, its sampled pixels only (C, k, m).
    residual : ndarray (C, n, m)
        ``D - L``, at the same pixels as ``data``.
    shape : tuple (rows, cols, C)
        Processing shape.
    observed : ndarray (n, m) bool or None
        Entries the level counts, as for
        :func:`~dgmod_ros.core.streaming.noise_levels.pixel_noise` (with
        ``sample``: (k, m)); None: all.
    uniform : bool
        Give every pixel the typical level.
    sample : PixelSample or None
        Read the levels at ``sample``'s pixels and upsample them
        (:func:`~dgmod_ros.core.streaming.noise_levels.pixel_noise`); None: every pixel.

    """
    chroma = reference_unless(window_chroma, window_chroma_reference, data, residual)
    return magnitude_noise(chroma, shape, observed, uniform, sample)   # a distance: >= 0


class LightingTest:
    """
    Tell which candidate foreground pixels are changes of light.

    Parameters
    ----------
    chroma : bool, default=True
        Use the chromaticity cue.
    texture : bool, default=True
        Use the LBSP texture cue.
    texture_bits : int, default=8
        Largest LBSP Hamming distance (of ``16 C`` bits) that a change of
        light may have.

    """

    def __init__(self, chroma=True, texture=True, texture_bits=8):
        self.chroma = chroma
        self.texture = texture
        self.texture_bits = texture_bits

    def explains(self, columns, background, noise, k, shape, candidates, chroma_level=None):
        """
        Return, for every pixel, whether it is a candidate whose change light explains.

        Parameters
        ----------
        columns, background : ndarray (C, n)
            The frame and its background.
        noise : ndarray (n,) or float
            Each pixel's noise level.
        k : float
            Multiple of the noise level that counts as a change.
        shape : tuple (rows, cols, C)
            Processing shape.
        candidates : ndarray (n,) bool
            Pixels whose distance is above ``k`` noise levels.
        chroma_level : ndarray (n,) or None
            Each pixel's chromaticity noise level (:func:`chroma_noise`);
            None: ``noise`` (an upper bound: ``c <= |I - E|``).

        Returns
        -------
        ndarray (n,) bool

        Notes
        -----
        Computed in one compiled pass over the candidates
        (:mod:`~dgmod_ros.core.streaming.kernels.photometric`), with the answers
        of :meth:`explains_reference` bit for bit.

        """
        return reference_unless(explained_pixels, explained_pixels_reference, columns,
                                background, noise, k, shape, candidates, chroma_level,
                                self.chroma, self.texture, self.texture_bits)

    def explains_reference(self, columns, background, noise, k, shape, candidates,
                           chroma_level=None):
        """Return :meth:`explains` computed in numpy (what the tests compare with)."""
        return explained_pixels_reference(columns, background, noise, k, shape, candidates,
                                          chroma_level, self.chroma, self.texture,
                                          self.texture_bits)
