# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Fast Robust PCA on Graphs: the dual-graph model without its nuclear norm."""

from ..dgmod import DualGraphMOD


class FRPCAG(DualGraphMOD):
    r"""
    Fast Robust PCA on Graphs (Shahid et al.), the closest prior art.

    .. math:: \min_L \|D - L\|_1 + \gamma_1 \mathrm{tr}(L^T \Phi_s L)
              + \gamma_2 \mathrm{tr}(L \Phi_t L^T)

    The same graphs, l1 fit and ADMM as :class:`~dgmod_ros.core.dgmod.DualGraphMOD`
    without the weighted nuclear norm (its weight is 0): halving that model's
    objective at ``lambda2 = 0.5`` gives exactly this one, with ``S = D - L``.
    Comparing the two shows what the weighted nuclear norm adds. Parameters
    and defaults are DualGraphMOD's, except ``lambda1``, which does not exist
    here, so the comparison is an ablation. ``docs/evaluation.md`` has the
    measured effect of the graph weights.

    References
    ----------
    .. [1] N. Shahid, V. Kalofolias, X. Bresson, M. Bronstein, P. Vandergheynst,
       "Robust Principal Component Analysis on Graphs", ICCV 2015.
    .. [2] N. Shahid, N. Perraudin, V. Kalofolias, G. Puy, P. Vandergheynst,
       "Fast Robust PCA on Graphs", IEEE J. Sel. Topics Signal Process. 10(4), 2016.

    """

    _nuclear_norm = False

    def __init__(self, lambda2=0.5, gamma1=0.5, gamma2=0.5, rho1=20.0, rho2=20.0, h_s=None,
                 h_t=None, patch_size=3, smoothing_sigma=0.0, temporal_neighbors=4,
                 l_step='gradient', inner_iter=1, step_size=None, tol=1e-4, max_iter=300):
        super().__init__(lambda1=None, lambda2=lambda2, gamma1=gamma1, gamma2=gamma2,
                         rho1=rho1, rho2=rho2, h_s=h_s, h_t=h_t, patch_size=patch_size,
                         smoothing_sigma=smoothing_sigma, temporal_neighbors=temporal_neighbors,
                         l_step=l_step, inner_iter=inner_iter, step_size=step_size, tol=tol,
                         max_iter=max_iter)
