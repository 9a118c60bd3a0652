# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The robust dual-graph regularized separation model and its ADMM solver."""

from dataclasses import dataclass, replace
from numbers import Integral

import numpy as np

from .graphs import (banded_matrix, diagonal_bands, spatial_laplacian_bands,
                     temporal_laplacian)
from .linalg import (drop_oldest, frames_major, gram_eigh, gram_matrix, mixing_factors,
                     relative_change, row_median, shrink, singular_value_map,
                     top_singular_value)
from .runtime import limit_blas_threads
from .validation import (Interval, NON_NEGATIVE, Options, POSITIVE, POSITIVE_INTEGER,
                         validate_params)
from .window_data import check_window_data


@dataclass
class ADMMState:
    """
    Every iterate of Algorithm 1; the unit a warm start hands over.

    All arrays are ``n x m`` float32 except ``weights`` (length m).
    """

    background: np.ndarray      # L
    foreground: np.ndarray      # S
    low_rank: np.ndarray        # U, the split copy of L
    noise: np.ndarray           # V = D - L - S
    dual_low_rank: np.ndarray   # Y1, scaled dual of U = L
    dual_noise: np.ndarray      # Y2, scaled dual of D - L - S = V
    weights: np.ndarray         # w of the weighted nuclear norm

    @property
    def frames(self):
        """Return how many frames the state spans."""
        return self.background.shape[1]

    def shifted(self, count, fill_column=None):
        """
        State of a window that dropped its ``count`` oldest frames.

        The new columns start from ``fill_column`` (background and low-rank
        copy; None: the newest background column) with zero foreground, noise
        and duals: the solver only needs a close start.
        """
        if count <= 0:
            return self
        if fill_column is None:
            fill_column = self.background[:, -1]
        fill = fill_column[:, None]
        arrays = {name: drop_oldest(getattr(self, name), count,
                                    fill if name in ('background', 'low_rank') else 0.0)
                  for name in ('background', 'foreground', 'low_rank', 'noise',
                               'dual_low_rank', 'dual_noise')}
        return replace(self, **arrays)


class DualGraphMOD:
    r"""
    Robust dual-graph regularized moving-object detection (Algorithm 1).

    Separates a window ``D`` (n pixels x m frames, values in [0, 1]) into a
    low-rank background ``L`` and a sparse foreground ``S`` by solving

    .. math::

        \min_{L,S} \|D - L - S\|_1 + \lambda_1 \|L\|_{W,*} + \lambda_2 \|S\|_1
        + \frac{\gamma_1}{2} \mathrm{tr}(L^T \Phi_s L)
        + \frac{\gamma_2}{2} \mathrm{tr}(L \Phi_t L^T)

    with ADMM on the splitting ``U = L``, ``V = D - L - S``. The weighted
    nuclear norm uses ``w_i = exp(-sigma_i^2 / s^2)`` recomputed from the last
    U-step, so large (background) singular values are barely penalised.
    ``Phi_s`` and ``Phi_t`` are the normalised Laplacians of the 4-neighbour
    patch-similarity pixel graph and of the nearest-frames graph
    (:mod:`dgmod_ros.core.graphs`). The steps are those of
    ``docs/solver.md`` (one ADMM sweep), which corrects the paper's printed S-
    and V-steps.

    Because both the fidelity and the foreground terms are l1, the optimum puts
    the whole residual ``D - L`` into ``S`` when ``lambda2 < 1`` and into
    ``V`` when ``lambda2 > 1``; keep ``lambda2 < 1`` for a foreground.

    Parameters
    ----------
    lambda1 : float or None, default=None
        Weight of the weighted nuclear norm. None or 0: automatic,
        ``lambda2 * sqrt(max(n, m))``, the balance of classical PCP (0 means
        automatic in the node's parameter table too). The model without the
        term is :class:`~dgmod_ros.core.baselines.frpcag.FRPCAG`.
    lambda2 : float, default=0.5
        Weight of ``||S||_1``; must be below 1 (see above).
    gamma1 : float, default=0.5
        Weight of the spatial graph term.
    gamma2 : float, default=0.5
        Weight of the temporal graph term.
    rho1, rho2 : float, default=20.0
        ADMM penalties of the two constraints (affect speed, not the optimum).
    weight_scale : float or None, default=None
        ``s`` in the weights. None: ``0.1 * sigma_1(D)``, so components with a
        tenth of the window's energy or more are left almost unshrunk.
    h_s, h_t : float or None, default=None
        Graph filtering parameters; None is the data-driven median edge distance.
    patch_size : int, default=3
        Patch side ``p`` of the spatial similarity.
    smoothing_sigma : float, default=0.0
        Gaussian pre-smoothing (pixels) before patch distances; 0 is off.
    temporal_neighbors : int, default=4
        Frames joined to each frame in the temporal graph.
    l_step : {'gradient', 'exact'}, default='gradient'
        'gradient' takes the paper's ``inner_iter`` gradient steps of size
        ``step_size``; 'exact' diagonalises ``Phi_t`` and solves the shifted
        sparse systems by warm-started block conjugate gradients. With the
        default penalties the subproblem's condition number is about 1.05,
        so one gradient step is nearly exact: both need the same number of
        sweeps and the gradient step is cheaper (docs/solver.md).
    inner_iter : int, default=1
        ``T_in``: CG iterations per L-step ('exact') or gradient steps ('gradient').
    step_size : float or None, default=None
        Gradient step; None is ``1 / Lipschitz`` of the L-subproblem.
    svd : {'gram', 'full'}, default='gram'
        'gram' takes the thin SVD through the m x m Gram matrix; 'full' calls
        LAPACK on the tall matrix (the literal reference).
    engine : {'fused', 'numpy'}, default='fused'
        'fused' runs a sweep as one compiled, multi-threaded pass and the
        BLAS products of the SVT (:mod:`dgmod_ros.core.kernels.dgmod`); 'numpy' is
        the literal formulation, one numpy expression per step, which the
        tests compare it with. Both give the same iterates to float32
        rounding. ``svd='full'`` (the literal reference) always runs the
        numpy formulation.
    tol : float, default=1e-4
        Stop when the relative changes of L and S and the relative primal
        residuals ``||U - L|| / ||D||``, ``||D - L - S - V|| / ||D||`` are all
        below ``tol``.
    max_iter : int, default=300
        ``T_out``, the limit on ADMM sweeps.

    Attributes
    ----------
    background_ : ndarray (n, m)
        ``L``.
    foreground_ : ndarray (n, m)
        ``S``.
    state_ : ADMMState
        All iterates, for a warm start of the next overlapping window.
    n_iter_ : int
        ADMM sweeps run.
    info_ : int
        0 converged; ``> 0`` stopped at ``max_iter`` (value = sweeps run);
        ``-1`` a non-finite iterate appeared (results are the last finite ones).
    history_ : dict of lists
        Per sweep: 'change_L', 'change_S', 'residual_U', 'residual_V', 'rank'.
    h_s_, h_t_, lambda1_, weight_scale_ : float
        The parameters actually used after data-driven defaults.
    singular_values_ : ndarray
        Singular values of the last ``L - Y1``.

    References
    ----------
    .. [1] J. Qin, R. Shen, R. Zhu, B. Xie, "Robust Dual-Graph Regularized
       Moving Object Detection", arXiv:2204.11939, 2022.
    .. [2] S. Gu, L. Zhang, W. Zuo, X. Feng, "Weighted Nuclear Norm Minimization
       with Application to Image Denoising", CVPR 2014.

    """

    #: Whether the objective has the weighted nuclear norm (FRPCAG's has not).
    _nuclear_norm = True

    #: The parameters' constraints (:mod:`~dgmod_ros.core.validation`), in checking order.
    _parameter_constraints = {
        'lambda2': POSITIVE, 'rho1': POSITIVE, 'rho2': POSITIVE, 'tol': POSITIVE,
        'gamma1': NON_NEGATIVE, 'gamma2': NON_NEGATIVE, 'smoothing_sigma': NON_NEGATIVE,
        'lambda1': (None, *NON_NEGATIVE),
        'weight_scale': (None, *POSITIVE), 'h_s': (None, *POSITIVE),
        'h_t': (None, *POSITIVE), 'step_size': (None, *POSITIVE),
        'l_step': [Options('gradient', 'exact')], 'svd': [Options('gram', 'full')],
        'engine': [Options('fused', 'numpy')],
        'patch_size': [Interval(Integral, 1, None, odd=True)],
        'inner_iter': POSITIVE_INTEGER, 'max_iter': POSITIVE_INTEGER,
        'temporal_neighbors': POSITIVE_INTEGER,
    }

    def __init__(self, lambda1=None, lambda2=0.5, gamma1=0.5, gamma2=0.5, rho1=20.0, rho2=20.0,
                 weight_scale=None, h_s=None, h_t=None, patch_size=3, smoothing_sigma=0.0,
                 temporal_neighbors=4, l_step='gradient', inner_iter=1, step_size=None,
                 svd='gram', engine='fused', tol=1e-4, max_iter=300):
        self.lambda1 = lambda1
        self.lambda2 = lambda2
        self.gamma1 = gamma1
        self.gamma2 = gamma2
        self.rho1 = rho1
        self.rho2 = rho2
        self.weight_scale = weight_scale
        self.h_s = h_s
        self.h_t = h_t
        self.patch_size = patch_size
        self.smoothing_sigma = smoothing_sigma
        self.temporal_neighbors = temporal_neighbors
        self.l_step = l_step
        self.inner_iter = inner_iter
        self.step_size = step_size
        self.svd = svd
        self.engine = engine
        self.tol = tol
        self.max_iter = max_iter

    # ------------------------------------------------------------------ checks
    def check_parameters(self):
        """Raise ``ValueError`` naming the first unusable parameter; return self."""
        validate_params(self)
        return self

    def _validate(self, data, frame_shape):
        self.check_parameters()
        return check_window_data(data, frame_shape)

    # ------------------------------------------------------------------ steps
    def _initial_state(self, data):
        median = row_median(data)[:, None]
        background = np.empty_like(data)        # in the memory order of data
        background[...] = median
        zeros = np.zeros_like(data)
        return ADMMState(background=background, foreground=data - background,
                         low_rank=background.copy(), noise=zeros, dual_low_rank=zeros.copy(),
                         dual_noise=zeros.copy(),
                         weights=np.ones(data.shape[1], dtype=np.float32))

    def _weighted_svt(self, matrix, weights, threshold):
        """Return ``A diag(shrink(sigma, w * t)) B^T``, the singular values and the rank kept."""
        if threshold == 0:          # no nuclear norm (FRPCAG): the prox is the identity
            return matrix.copy(), np.zeros(matrix.shape[1]), matrix.shape[1]
        if self.svd == 'full':
            left, sigma, right_t = np.linalg.svd(matrix, full_matrices=False)
            shrunk = np.maximum(sigma - weights[:sigma.size] * threshold, 0)
            keep = shrunk > 0
            result = (left[:, keep] * shrunk[keep]) @ right_t[keep]
            return result.astype(np.float32), sigma, int(np.count_nonzero(keep))
        # U = Lh B diag(shrunk / sigma) B^T needs only the m x m eigenproblem.
        return singular_value_map(matrix, lambda sigma: np.maximum(
            sigma - weights[:sigma.size] * threshold, 0.0))

    def _l_step(self, rhs, background, ops, c):
        """Minimise the Lagrangian over L: ``g1 Phi_s L + g2 L Phi_t + c L = rhs``."""
        g1, g2 = self.gamma1, self.gamma2
        phi_s = ops['phi_s']
        if self.l_step == 'gradient':
            # The subproblem's Hessian has spectrum in [c, c + 2 g1 + 2 g2].
            step = self.step_size or 1.0 / (2.0 * g1 + 2.0 * g2 + c)
            x = background
            for _ in range(self.inner_iter):
                grad = x * c
                grad -= rhs
                if g1 > 0:
                    grad += g1 * (phi_s @ x)
                if g2 > 0:
                    grad += g2 * (x @ ops['phi_t'])
                grad *= -step
                grad += x
                x = grad
            return x
        # Exact: in the eigenbasis Q of Phi_t, column j of L Q solves the SPD
        # system (g1 Phi_s + (g2 mu_j + c) I) z = (rhs Q)_j, condition number
        # at most (2 g1 + c) / c; block CG runs the m systems together with
        # per-column step sizes, warm-started from the previous L.
        basis = ops['basis']
        shifts = (g2 * ops['mu'] + c).astype(np.float32)
        b = rhs @ basis
        if g1 == 0:
            b /= shifts
            return b @ basis.T
        z = background @ basis
        r = b
        r -= shifts * z
        r -= g1 * (phi_s @ z)
        p = r.copy()
        rr = np.einsum('ij,ij->j', r, r)
        for _ in range(self.inner_iter):
            ap = phi_s @ p
            ap *= g1
            ap += shifts * p
            pap = np.einsum('ij,ij->j', p, ap)
            alpha = np.divide(rr, pap, out=np.zeros_like(rr), where=pap > 0)
            z += alpha * p
            ap *= alpha
            r -= ap
            rr_new = np.einsum('ij,ij->j', r, r)
            beta = np.divide(rr_new, rr, out=np.zeros_like(rr), where=rr > 0)
            p *= beta
            p += r
            rr = rr_new
        return z @ basis.T

    def _record(self, history, change_L, change_S, residual_U, residual_V, rank):
        """Append one sweep's figures to ``history``; return True when the stopping rule holds."""
        for key, value in (('change_L', change_L), ('change_S', change_S),
                           ('residual_U', residual_U), ('residual_V', residual_V),
                           ('rank', rank)):
            history[key].append(value)
        return max(change_L, change_S, residual_U, residual_V) < self.tol

    def _run_numpy(self, data, ops, iterates, history, data_norm):
        """Sweep with one numpy expression per step (the literal formulation)."""
        L, S, U, V = iterates['L'], iterates['S'], iterates['U'], iterates['V']
        Y1, Y2, weights, sigma = (iterates['Y1'], iterates['Y2'], iterates['weights'],
                                  iterates['sigma'])
        rho1, rho2 = float(self.rho1), float(self.rho2)
        # Scratch buffers: a sweep is ~25 passes over n x m arrays, and
        # allocating each temporary would cost as much as the arithmetic.
        rhs = np.empty_like(data)
        work = np.empty_like(data)
        residual = np.empty_like(data)
        S_new = np.empty_like(data)
        V_new = np.empty_like(data)
        for _ in range(self.max_iter):
            # 1. L-step, right-hand side rho1 (U + Y1) + rho2 (D - S - V + Y2).
            self._l_rhs(data, U, Y1, S, V, Y2, rhs, work)
            L_new = self._l_step(rhs, L, ops, rho1 + rho2)
            # 2. S-step.
            np.subtract(data, L_new, out=residual)                    # D - L
            np.subtract(residual, V, out=work)
            work += Y2
            shrink(work, self.lambda2 / rho2, out=S_new)
            # 3. U-step (weights from the previous sweep), then new weights.
            np.subtract(L_new, Y1, out=work)
            U_new, sigma, rank = self._weighted_svt(work, weights, self.lambda1_ / rho1)
            # 4. V-step.
            np.subtract(residual, S_new, out=work)
            work += Y2
            shrink(work, 1.0 / rho2, out=V_new)
            if not (np.isfinite(sigma).all() and np.isfinite(U_new).all()
                    and np.isfinite(S_new).all()):
                self.info_ = -1
                break
            weights = np.exp(-(sigma / self.weight_scale_) ** 2).astype(np.float32)
            change_L = relative_change(L_new, L)
            change_S = relative_change(S_new, S)
            S, S_new = S_new, S
            V, V_new = V_new, V
            L, U = L_new, U_new
            # 5. Dual updates with the primal residuals.
            np.subtract(U, L, out=work)
            residual_U = float(np.linalg.norm(work)) / data_norm
            Y1 += work
            residual -= S
            residual -= V                                             # D - L - S - V
            residual_V = float(np.linalg.norm(residual)) / data_norm
            Y2 += residual
            # 6. Stop.
            if self._record(history, change_L, change_S, residual_U, residual_V, rank):
                self.info_ = 0
                break
        iterates.update(L=L, S=S, U=U, V=V, Y1=Y1, Y2=Y2, weights=weights, sigma=sigma)

    def _l_rhs(self, data, U, Y1, S, V, Y2, rhs, work):
        """Write the L-step's right-hand side ``rho1 (U + Y1) + rho2 (D - S - V + Y2)``."""
        np.add(U, Y1, out=rhs)
        rhs *= self.rho1
        np.subtract(data, S, out=work)
        work -= V
        work += Y2
        work *= self.rho2
        rhs += work
        return rhs

    def _run_fused(self, data, ops, iterates, history, data_norm):
        """
        Sweep with the compiled pass of :mod:`dgmod_ros.core.kernels.dgmod`.

        The same steps as :meth:`_run_numpy` in the same order, the same
        iterates and the same stopping sweep. The primal pass also sums the
        Gram matrix of the next ``Lh = L - Y1``, and forms the last SVT's
        ``U = (Lh left) right_t`` block by block from its rank-k factors; BLAS
        forms the whole product only where ``U`` itself is read (the stopping
        test, a numpy L-step, the state handed back). ``Y1`` lives as
        ``U - Lh`` (kernels.dgmod's docstring) and is formed once, at the end.
        The pass runs on the frames-major transposes of the iterates
        (:func:`~dgmod_ros.core.linalg.frames_major`); the iterates handed back are ``n x m``
        views of them (F-ordered), so a warm start from them needs no
        transpose. The given L, S, U and Y1 are read, never written: the
        caller's state needs no copy.
        """
        from .kernels import dgmod as kernels   # numba compiles or loads its cache on first use
        # Again at every solve: an OpenBLAS loaded since (scipy.linalg's) must
        # not spin beside the kernels either (numba_setup's docstring).
        limit_blas_threads(1)

        D = frames_major(data)
        # L, S and U are read only (the given ones may be the caller's
        # state); V and Y2 are updated in place, so the pass gets copies.
        L, S, U = (frames_major(iterates[k]) for k in ('L', 'S', 'U'))
        V, Y2 = (frames_major(iterates[k]).copy() for k in ('V', 'Y2'))
        given_L = L                 # the first sweep swaps it, and the given S, out
        Lh = U - frames_major(iterates['Y1'])   # so that U - Lh is the given Y1
        # After a sweep's SVT, U = (left right_t)^T Lh is kept as its factors:
        # the next pass forms it block by block (kernels.primal_pass), and the
        # n x m product is formed only where U itself is read.
        svt = None                  # (left^T, right_t^T) float32, or None: U is formed
        m = data.shape[1]
        no_svt = (np.zeros((0, m), np.float32), np.zeros((m, 0), np.float32))

        def formed_u():
            # U^T = (left right_t)^T Lh^T, frames-major, through the k x n factor.
            left_t, right = svt
            return np.matmul(right, left_t @ Lh)

        weights, sigma = iterates['weights'], iterates['sigma']
        rho1, rho2 = float(self.rho1), float(self.rho2)
        g1, g2, c = float(self.gamma1), float(self.gamma2), rho1 + rho2
        step = self.step_size or 1.0 / (2.0 * g1 + 2.0 * g2 + c)
        coefficients = np.array([g1, g2, c, rho1, rho2, step, self.lambda2 / rho2, 1.0 / rho2])
        s_offsets, s_bands = ops['phi_s_bands']
        # The kernel reads Phi_t[j, j + off]; Phi_t is symmetric, so its own bands serve.
        t_offsets, t_bands = ops['phi_t_bands']
        # Other L-steps than one gradient step run in numpy and hand L_new over.
        l_given = not (self.l_step == 'gradient' and self.inner_iter == 1)
        L_new, S_new = np.empty_like(D), np.empty_like(D)
        rhs = work = Y1 = None
        threshold = self.lambda1_ / rho1
        # A sweep's residual ||U - L|| needs its SVT, so the next pass sums it;
        # only when every other figure of the rule is already below tol is it
        # summed at once (the pass updates V, Y2 and Lh in place: it must not
        # run past the stopping sweep).
        pending = None      # (change_L, change_S, residual_V, rank) of the last sweep

        def finish(squared_gap):
            change_L, change_S, residual_V, rank = pending
            return self._record(history, change_L, change_S,
                                float(np.sqrt(squared_gap)) / data_norm, residual_V, rank)

        for _ in range(self.max_iter):
            if svt is not None and (l_given or (pending is not None
                                                and max(pending[:3]) < self.tol)):
                U, svt = formed_u(), None
            if pending is not None and max(pending[:3]) < self.tol:
                stop = finish(kernels.squared_gap(U, L))
                pending = None
                if stop:
                    self.info_ = 0
                    break
            if l_given:     # the numpy steps on n x m views of the frames-major arrays
                if rhs is None:
                    rhs, work, Y1 = (np.empty_like(D) for _ in range(3))
                np.subtract(U, Lh, out=Y1)
                self._l_rhs(data, U.T, Y1.T, S.T, V.T, Y2.T, rhs.T, work.T)
                np.copyto(L_new.T, self._l_step(rhs.T, L.T, ops, c))
            sums, gram = kernels.primal_pass(     # (U unread with the SVT's factors: D)
                D, L, D if svt is not None else U, Lh, S, V, Y2, s_offsets, s_bands,
                t_offsets, t_bands, coefficients, l_given, L_new, S_new,
                *(svt or no_svt), svt is not None)
            if pending is not None:
                finish(sums[4])     # not below tol: pending's own figures are not
                pending = None
            if not (np.isfinite(gram).all() and np.isfinite(sums[:4]).all()):
                # L and S are the last finite iterate; V, Y2 and Lh were
                # overwritten in place: the state restarts U, V and the duals
                # (U = L, V = Y1 = Y2 = 0) instead of handing them over.
                self.info_ = -1
                U, svt = L.copy(), None
                Lh[...] = L
                V[...] = 0.0
                Y2[...] = 0.0
                break
            if threshold == 0:      # no nuclear norm (FRPCAG): the prox is the identity
                left = right_t = np.eye(m, dtype=np.float32)
                sigma, rank = np.zeros(m), m
            else:
                left, right_t, sigma, rank = mixing_factors(gram, lambda values: np.maximum(
                    values - weights[:values.size] * threshold, 0.0))
            weights = np.exp(-(sigma / self.weight_scale_) ** 2).astype(np.float32)
            L, L_new = L_new, L
            S, S_new = S_new, S
            if L_new is given_L:        # the given L and S: the next sweep writes new ones
                L_new, S_new = np.empty_like(D), np.empty_like(D)
            # The SVT keeps k components of m (the background a few): U
            # through its k x n factor, 2 k m n multiply-adds.
            svt = (np.ascontiguousarray(left.T, dtype=np.float32),
                   np.ascontiguousarray(right_t.T, dtype=np.float32))
            pending = (_ratio(sums[0], sums[1]), _ratio(sums[2], sums[3]),
                       float(np.sqrt(sums[5])) / data_norm, rank)
        if svt is not None:
            U = formed_u()
        if pending is not None and finish(kernels.squared_gap(U, L)):
            self.info_ = 0          # the last sweep's residual, after the loop
        Y1 = np.subtract(U, Lh, out=Lh)
        iterates.update(L=L.T, S=S.T, U=U.T, V=V.T, Y1=Y1.T, Y2=Y2.T,
                        weights=weights, sigma=sigma)

    # ------------------------------------------------------------------ public
    def build_operators(self, data, frame_shape):
        """
        Graph Laplacians (the temporal eigenbasis on demand) and the data's Gram matrix.

        ``phi_s_bands`` and ``phi_t_bands`` hold the Laplacians' diagonal bands
        (what the fused sweep applies); ``phi_t`` is dense (m x m). The sparse
        ``phi_s`` of the numpy steps and ``Phi_t``'s eigenbasis (the exact
        L-step) are formed on first use only (:class:`_Operators`).
        """
        offsets, bands, self.h_s_ = spatial_laplacian_bands(
            data, frame_shape, self.patch_size, self.h_s, self.smoothing_sigma)
        gram = gram_matrix(data)
        phi_t, self.h_t_ = temporal_laplacian(data, self.temporal_neighbors, self.h_t, gram)
        phi_t_float32 = phi_t.astype(np.float32)
        return _Operators(phi_s_bands=(offsets, bands), phi_t=phi_t_float32,
                          phi_t_bands=diagonal_bands(phi_t_float32),
                          phi_t_float64=phi_t, data_gram=gram)

    def objective(self, data, frame_shape):
        """
        Return the model's objective at the fitted ``L`` and ``S``.

        ``||D - L - S||_1 + lambda1 ||L||_{W,*} + lambda2 ||S||_1 + g1/2 tr(L^T Phi_s L)
        + g2/2 tr(L Phi_t L^T)`` in float64, with the weights taken from the
        singular values of ``L`` itself (the fixed point of the reweighting),
        so that solutions reached by different sweeps are scored alike.
        """
        data = self._validate(data, frame_shape)
        L = self.background_.astype(np.float64)
        S = self.foreground_.astype(np.float64)
        ops = self.build_operators(data, frame_shape)
        sigma = gram_eigh(L, vectors=False)
        weights = np.exp(-(sigma / self.weight_scale_) ** 2)
        return float(np.abs(data - L - S).sum() + self.lambda1_ * (weights * sigma).sum()
                     + self.lambda2 * np.abs(S).sum()
                     + 0.5 * self.gamma1 * (L * (ops['phi_s'] @ L)).sum()
                     + 0.5 * self.gamma2 * (L * (L @ ops['phi_t'])).sum())

    def fit(self, data, frame_shape, init=None):
        """
        Separate one window.

        Parameters
        ----------
        data : array-like (n, m)
            Frames as columns, values in [0, 1], pixels in row-major order.
        frame_shape : tuple (n1, n2)
            Rows and columns of one frame; ``n1 * n2 == n``.
        init : ADMMState or None
            Warm start (for example ``previous.state_.shifted(stride, column)``);
            None starts from the per-pixel temporal median.

        Returns
        -------
        self

        """
        data = self._validate(data, frame_shape)
        n, m = data.shape
        if init is not None and init.background.shape != data.shape:
            raise ValueError(f'init state has shape {init.background.shape}, data {data.shape}')
        if not self._nuclear_norm:
            self.lambda1_ = 0.0
        else:       # None and 0 both mean automatic, as in the parameter table
            self.lambda1_ = self.lambda1 or self.lambda2 * np.sqrt(max(n, m))
        ops = self.build_operators(data, frame_shape)
        data_norm = float(np.linalg.norm(data)) or 1.0
        if self.weight_scale is None:
            self.weight_scale_ = 0.1 * top_singular_value(data, ops['data_gram']) or 1.0
        else:
            self.weight_scale_ = float(self.weight_scale)

        fused = self.engine == 'fused' and self.svd == 'gram'
        if fused:
            # The compiled pass runs frames-major; ``data`` becomes an n x m
            # view of the transpose, so that the state's arithmetic below
            # runs in one memory order (linalg.frames_major).
            data = frames_major(data).T
        state = self._initial_state(data) if init is None else replace(init)
        # The numpy steps update every iterate in place, so they start from
        # copies, in the state's own memory order (a copy of the fused
        # solver's frames-major state into C order would be a strided
        # transpose); the fused sweep copies what it updates in place itself.
        own = (lambda array: array) if fused else (lambda array: array.copy(order='K'))
        L = own(state.background)
        # A warm start's new columns know nothing of the new frames: putting
        # the whole residual into S satisfies D = L + S + V exactly.
        if init is not None:
            S = np.subtract(data, L, out=np.empty_like(L))
            S -= state.noise
        else:
            S = own(state.foreground)
        U, V = own(state.low_rank), own(state.noise)
        Y1, Y2 = own(state.dual_low_rank), own(state.dual_noise)
        iterates = {'L': L, 'S': S, 'U': U, 'V': V, 'Y1': Y1, 'Y2': Y2,
                    'weights': state.weights, 'sigma': np.zeros(m)}
        history = {k: [] for k in ('change_L', 'change_S', 'residual_U', 'residual_V', 'rank')}
        self.info_ = self.max_iter
        if fused:
            self._run_fused(data, ops, iterates, history, data_norm)
        else:
            self._run_numpy(data, ops, iterates, history, data_norm)
        L, S, U, V = iterates['L'], iterates['S'], iterates['U'], iterates['V']
        Y1, Y2, weights, sigma = (iterates['Y1'], iterates['Y2'], iterates['weights'],
                                  iterates['sigma'])
        self.n_iter_ = len(history['change_L'])
        self.history_ = history
        self.singular_values_ = sigma
        self.state_ = ADMMState(background=L, foreground=S, low_rank=U, noise=V,
                                dual_low_rank=Y1, dual_noise=Y2, weights=weights)
        self.background_ = L
        self.foreground_ = S
        return self


class _Operators(dict):
    """
    A window's operators; what only some L-steps read is formed when first read.

    The sparse ``phi_s`` (the numpy steps) from its bands, and the
    eigendecomposition of ``Phi_t`` (``mu`` and ``basis``, the exact L-step).
    """

    def __missing__(self, key):
        if key == 'phi_s':
            self['phi_s'] = banded_matrix(*self['phi_s_bands'])
        elif key in ('mu', 'basis'):
            mu, basis = np.linalg.eigh(self['phi_t_float64'])
            self['mu'], self['basis'] = mu, basis.astype(np.float32)
        else:
            raise KeyError(key)
        return self[key]


def _ratio(squared_change, squared_norm):
    """``sqrt(a / b)`` as :func:`relative_change` from sums of squares (0 / 0 is 0)."""
    if squared_norm == 0.0:
        return 0.0 if squared_change == 0.0 else np.inf
    return float(np.sqrt(squared_change / squared_norm))
