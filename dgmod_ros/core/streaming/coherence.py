# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Spatial coherence of the foreground decision: a Markov random field by mean field.

A pixel's distance to its background in units of its own noise level,
``z = d / sigma_p``, is what the per-pixel rule thresholds at ``k``. Read as a
likelihood, background noise makes ``z`` Gaussian (log-likelihood
``-z^2 / 2``) while foreground makes it anything (flat), so the log-odds of
foreground for one pixel alone are ``u = (z^2 - k^2) / 2``: zero at the
``k``-sigma threshold, so that a pixel with no neighbours decides as the
per-pixel rule does. People are regions, noise is not: a Potts prior adds
``beta`` to the log-odds for every foreground neighbour in the
``(2 r + 1)^2`` neighbourhood and takes ``beta`` off for every background
one. A few mean-field sweeps (each pixel's probability of foreground
recomputed from its unary term and its neighbours' current probabilities,
all pixels at once) approximate the field's marginals; the mask is where
they exceed one half.

Against the majority vote of a median filter, the field weighs how far a
pixel is from its threshold: a pixel well above it (the quadratic unary
grows fast) stays foreground alone, so small far people survive, while a
pixel just above it with background around it goes, and one just below it
inside a silhouette comes in.

References
----------
.. [1] S. Geman, D. Geman, "Stochastic relaxation, Gibbs distributions, and
   the Bayesian restoration of images", IEEE TPAMI 6(6), 1984.
.. [2] P. Kraehenbuehl, V. Koltun, "Efficient inference in fully connected
   CRFs with Gaussian edge potentials", NIPS 2011 (mean-field updates as
   filtering).

"""

import numpy as np

from .kernels.coherence import mean_field_spins, mean_field_spins_reference
from ..numba_setup import reference_unless

#: Mean-field sweeps; the masks change little after 5 (``docs/results.md``).
SWEEPS = 5
#: Radius ``r`` of the neighbourhood: 5 x 5, the median filter's support.
RADIUS = 2
# Distances beyond this multiple of k carry no more evidence (keeps exp finite).
_Z_CAP = 3.0
# Log-odds beyond this are certain (float32 exp overflows near 88).
_LOGIT_CAP = 50.0


def mean_field_mask(distance, noise, k, beta, shape, sweeps=SWEEPS, radius=RADIUS):
    """
    Return the foreground (rows, cols) uint8 0/255 of the Potts field over the k-sigma rule.

    The sweeps compiled (:mod:`~dgmod_ros.core.streaming.kernels.coherence`),
    the numpy reference's spins bit for bit, the reference itself where the
    pass cannot promise them.

    Parameters
    ----------
    distance : ndarray (n,) or (rows, cols)
        Each pixel's distance to its background.
    noise : ndarray (n,) or float
        Each pixel's noise level.
    k : float or ndarray (n,)
        Multiple of the noise level at which a pixel alone is even odds
        (one for all pixels or each pixel's own).
    beta : float
        Coupling of neighbours (log-odds per neighbour); 0 gives the plain rule.
    shape : tuple (rows, cols, ...)
        Processing shape.
    sweeps : int
        Mean-field sweeps.
    radius : int
        Neighbourhood radius ``r`` (square of side ``2 r + 1``).

    """
    rows, cols = shape[:2]
    spin = reference_unless(mean_field_spins, mean_field_spins_reference, distance, noise, k,
                            beta, rows, cols, sweeps, radius, _Z_CAP, _LOGIT_CAP)
    return np.where(spin > 0, np.uint8(255), np.uint8(0))


def mean_field_mask_reference(distance, noise, k, beta, shape, sweeps=SWEEPS, radius=RADIUS):
    """Return :func:`mean_field_mask` computed in numpy and OpenCV (the tests' reference)."""
    rows, cols = shape[:2]
    spin = mean_field_spins_reference(distance, noise, k, beta, rows, cols, sweeps, radius,
                                      _Z_CAP, _LOGIT_CAP)
    return np.where(spin > 0, np.uint8(255), np.uint8(0))
