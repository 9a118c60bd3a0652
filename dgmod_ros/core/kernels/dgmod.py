# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Fused, multi-threaded kernels of one ADMM sweep of :class:`DualGraphMOD`.

A sweep of the numpy formulation is about 25 single-threaded passes over
``n x m`` float32 arrays. Here it is one pass, threaded over blocks of pixels
(:func:`primal_pass`): the gradient L-step (spatial and temporal
Laplacians applied as diagonal bands), the S- and V-shrinkages, the dual
update of ``Y2``, the next SVT input ``Lh`` and the sums of squares behind the
stopping rule. ``Y1`` is never stored (``Y1 = U - Lh`` after every U-step),
and V, ``Y2`` and ``Lh`` are updated in place, so the pass moves as few
arrays as the sweep needs (docs/solver.md, "Fused sweep").
:func:`squared_gap` gives the primal residual ``||U - L||`` where the next
pass cannot wait for it.

The pass runs on the **frames-major** transposes ``(m, n)`` of the matrices
(:func:`~dgmod_ros.core.linalg.frames_major`): a frame's pixels are one contiguous row, so each
step is a long unit-stride loop over a block's pixels that the compiler
vectorises. In the ``n x m`` layout a row holds a pixel's ``m`` = 30 frames,
too few for the vector loop to start, and the pass ran scalar
(docs/solver.md, "Frames-major sweep").

The pass also does the SVT's two n x m products on each block while it is in
cache, on the pass's threads: before updating a block it forms the block's
``U = Lh (left right_t)`` from the last SVT's rank-k factors (the SVT keeps a
few of ``m`` components), and after, it adds the block's part of the next
Gram matrix ``Lh Lh^T``. As BLAS products between passes, on one thread
(OpenBLAS must not spin beside the kernels), they read ``Lh`` twice more and
wrote ``U`` for the pass to read back. Only the eigendecomposition of the
m x m Gram matrix runs between passes. Within a block, ``U``'s two small
products are BLAS calls (single-threaded, below: each kernel thread makes
its own) and the Gram matrix is summed by register tiles: the sweep of the
converged solve is bound by its arithmetic, not by memory (docs/solver.md,
"Where a converged sweep's time goes").

Each pass has its numpy reference below it (:func:`primal_pass_reference`,
:func:`frames_gram_reference`, :func:`squared_gap_reference`), which
``test/test_compiled_passes.py`` holds it to on its warm-up examples; the
solver's own numpy engine (``DualGraphMOD(engine='numpy')``) is the literal
formulation on n x m arrays (``test/test_kernels.py``).
numba's process-wide settings (cache folder, threading layer, one OpenBLAS
thread) come with ``njit`` from :mod:`~dgmod_ros.core.numba_setup`.
"""

import numpy as np

from ..numba_setup import BLOCK_PIXELS, FAST_MATH, njit, prange, register_pass


@njit(cache=True, inline='always')
def _shrink(x, t):
    # x - clip(x, -t, t): branch-free, so the row loops vectorise.
    return x - min(max(x, -t), t)


# nogil on the passes below: a pass takes milliseconds, and the node's image
# callback must not wait for the solve thread's kernels.
@njit(cache=True, inline='always', fastmath=FAST_MATH)
def _add_product(weights, values, out):
    """``out += weights * values`` over three equally long rows."""
    for i in range(out.size):
        out[i] += weights[i] * values[i]


@njit(cache=True, inline='always', fastmath=FAST_MATH)
def _add_scaled(weight, values, out):
    """``out += weight * values`` over two equally long rows."""
    for i in range(out.size):
        out[i] += weight * values[i]


@njit(cache=True, inline='always', fastmath=FAST_MATH)
def _gradient_step(d, bg, u, lh, s, v, y2, spatial, temporal, l_new, coefficients):
    """Take one gradient L-step over a row segment into ``l_new`` (``Y1 = U - Lh``)."""
    g1, g2, c = coefficients[0], coefficients[1], coefficients[2]
    rho1, rho2, step = coefficients[3], coefficients[4], coefficients[5]
    for i in range(d.size):
        rhs = rho1 * (u[i] + (u[i] - lh[i])) + rho2 * (d[i] - s[i] - v[i] + y2[i])
        grad = c * bg[i] - rhs + g1 * spatial[i] + g2 * temporal[i]
        l_new[i] = bg[i] - step * grad


@njit(cache=True, inline='always', fastmath=FAST_MATH)
def _shrink_steps(d, bg, u, lh, s, v, y2, l_new, s_new, t_s, t_v, sums):
    """
    Take the S- and V-steps, ``Y2`` and the next ``Lh`` over a row segment; add up its sums.

    Row segments of one frame are contiguous: the loop has no stride and
    no aliasing the compiler must rule out, so it vectorises (the pixel-major
    rows of ``m`` entries were too short for that, docs/solver.md).
    """
    d_l = n_l = d_s = n_s = r_u = r_v = np.float32(0.0)
    for i in range(d.size):
        dual = u[i] - lh[i]
        gap = u[i] - bg[i]
        r_u += gap * gap
        background = l_new[i]
        residual = d[i] - background
        foreground = _shrink(residual - v[i] + y2[i], t_s)
        noise = _shrink(residual - foreground + y2[i], t_v)
        gap = residual - foreground - noise
        y2[i] += gap
        r_v += gap * gap
        s_new[i] = foreground
        v[i] = noise
        lh[i] = background - dual
        delta = background - bg[i]
        d_l += delta * delta
        n_l += bg[i] * bg[i]
        delta = foreground - s[i]
        d_s += delta * delta
        n_s += s[i] * s[i]
    sums[0] += d_l
    sums[1] += n_l
    sums[2] += d_s
    sums[3] += n_s
    sums[4] += r_u
    sums[5] += r_v


# Not inlined, as _add_block_gram below: compiled apart, they keep the
# parallel pass's compile time (a cold install's first start) near what it
# was without them.
@njit(cache=True, nogil=True)
def _block_u(rows, lo, hi, svt_left, svt_right):
    """Return ``svt_right (svt_left rows[:, lo:hi])`` (m x block)."""
    # Two small matrix products: BLAS (one thread, numba_setup's docstring)
    # runs them faster than a compiled loop here (docs/solver.md).
    return np.dot(svt_right, np.dot(svt_left, np.ascontiguousarray(rows[:, lo:hi])))


@njit(cache=True, inline='always', fastmath=FAST_MATH)
def _add_times(x, u0, u1, u2, u3, s0, s1, s2, s3):
    """Return ``(s0 + x u0, ..., s3 + x u3)``: one row of a Gram tile's update."""
    return s0 + x * u0, s1 + x * u1, s2 + x * u2, s3 + x * u3


@njit(cache=True, inline='always')
def _add_tile(gram, a, c, count, sums):
    """Add the tile ``sums`` (3 rows of 4) to ``gram[a:a + 3, c:c + count]`` inside ``gram``."""
    for r in range(3):
        if a + r < gram.shape[0]:
            for k in range(count):
                gram[a + r, c + k] += sums[4 * r + k]


@njit(cache=True, nogil=True, fastmath=FAST_MATH)
def _add_block_gram(rows, lo, hi, gram):
    """
    Add the upper triangle of ``rows[:, lo:hi] rows[:, lo:hi]^T`` to ``gram``, by 3 x 4 tiles.

    Twelve products per seven loads: the loop is bound by loads, and twelve
    accumulators and seven values still fit the vector registers. A tile
    that reaches below the diagonal adds there too; the caller keeps the
    upper triangle only.
    """
    m = rows.shape[0]
    for a in range(0, m, 3):
        x0 = rows[a, lo:hi]
        x1 = rows[min(a + 1, m - 1), lo:hi]
        x2 = rows[min(a + 2, m - 1), lo:hi]
        c = a
        while c < m:
            count = min(4, m - c)
            r0 = rows[c, lo:hi]
            r1 = rows[c + min(1, count - 1), lo:hi]
            r2 = rows[c + min(2, count - 1), lo:hi]
            r3 = rows[c + min(3, count - 1), lo:hi]
            s00 = s01 = s02 = s03 = np.float32(0.0)
            s10 = s11 = s12 = s13 = np.float32(0.0)
            s20 = s21 = s22 = s23 = np.float32(0.0)
            for i in range(hi - lo):
                u0, u1, u2, u3 = r0[i], r1[i], r2[i], r3[i]
                s00, s01, s02, s03 = _add_times(x0[i], u0, u1, u2, u3, s00, s01, s02, s03)
                s10, s11, s12, s13 = _add_times(x1[i], u0, u1, u2, u3, s10, s11, s12, s13)
                s20, s21, s22, s23 = _add_times(x2[i], u0, u1, u2, u3, s20, s21, s22, s23)
            _add_tile(gram, a, c, count,
                      (s00, s01, s02, s03, s10, s11, s12, s13, s20, s21, s22, s23))
            c += count


@njit(parallel=True, cache=True, fastmath=FAST_MATH, nogil=True)
def primal_pass(data, L, U, Lh, S, V, Y2,
                s_offsets, s_bands, t_offsets, t_bands, coefficients, l_given,
                L_new, S_new, svt_left, svt_right, u_from_svt):
    """
    Run one sweep but the SVT, fused, threaded over blocks of pixels.

    Every matrix is **frames-major**, ``(m, n)``: the transpose of the
    solver's ``n x m`` window, one contiguous row of pixels per frame
    (:func:`~dgmod_ros.core.linalg.frames_major`). For each block of pixels and each frame ``j``:
    the L-step (one gradient step into ``L_new``; with ``l_given`` the caller
    computed ``L_new`` in numpy), the S-step into ``S_new``, and in place the
    V-step, ``Y2 += D - L - S - V`` and the next SVT input ``Lh = L_new - Y1``.
    The dual ``Y1`` is not stored: after every U-step ``Y1 = U - Lh`` exactly
    (``Y1 + U - L`` with ``Lh = L - Y1``). ``L`` and ``S`` keep the previous
    iterate (the L-step reads neighbouring pixels and frames of ``L``; the
    solver falls back on both when an iterate is not finite).
    ``coefficients`` = (g1, g2, c, rho1, rho2, step, lam2 / rho2, 1 / rho2).
    ``s_bands[k, i] = Phi_s[i, i + s_offsets[k]]`` and
    ``t_bands[k, j] = Phi_t[j, j + t_offsets[k]]``
    (:func:`~dgmod_ros.core.graphs.diagonal_bands`).
    With ``u_from_svt``, ``U`` is not read: each block forms its own
    ``U = svt_right (svt_left Lh)`` (``svt_left`` k x m, ``svt_right`` m x k,
    the last SVT's factors) from its ``Lh`` before updating it, in cache,
    instead of an n x m product between passes that the pass then reads.

    Returns the float64 sums ``(||L_new - L||^2, ||L||^2, ||S_new - S||^2,
    ||S||^2, ||U - L||^2, ||D - L_new - S_new - V_new||^2)``: the fifth is the
    previous sweep's primal residual of ``U = L`` (``U`` is that sweep's SVT);
    and the next SVT's Gram matrix ``Lh Lh^T`` (m x m, float64), each block's
    part summed right after the block's new ``Lh`` is written
    (:func:`_add_block_gram`) instead of in a BLAS pass over ``Lh``.
    """
    m, n = data.shape
    coefficients = coefficients.astype(np.float32)
    t_s = coefficients[6]
    t_v = coefficients[7]
    n_blocks = (n + BLOCK_PIXELS - 1) // BLOCK_PIXELS
    sums = np.zeros((n_blocks, 6), dtype=np.float64)
    grams = np.zeros((n_blocks, m, m), dtype=np.float64)
    for b in prange(n_blocks):
        lo = b * BLOCK_PIXELS
        hi = min(n, lo + BLOCK_PIXELS)
        spatial = np.empty(hi - lo, dtype=np.float32)
        temporal = np.empty(hi - lo, dtype=np.float32)
        block_sums = np.zeros(6, dtype=np.float64)
        # The block's U, formed from the SVT's factors or copied from U: the
        # steps below read one kind of row (a contiguous one).
        if u_from_svt:
            block_u = _block_u(Lh, lo, hi, svt_left, svt_right)
        else:
            block_u = np.ascontiguousarray(U[:, lo:hi])
        for j in range(m):
            u = block_u[j]
            if not l_given:
                spatial[:] = 0.0
                temporal[:] = 0.0
                for k in range(s_offsets.size):
                    # (Phi_s L)[i] = sum_k bands[k, i] L[i + off]; the band is
                    # zero where i + off leaves the frame, so the range is cut.
                    off = s_offsets[k]
                    first = max(lo, -off)
                    last = min(hi, n - off)
                    if first < last:
                        _add_product(s_bands[k, first:last], L[j, first + off:last + off],
                                     spatial[first - lo:last - lo])
                for k in range(t_offsets.size):
                    # (L Phi_t)[j] = sum_k L[j + off] Phi_t[j + off, j], Phi_t symmetric.
                    other = j + t_offsets[k]
                    if 0 <= other < m:
                        _add_scaled(t_bands[k, j], L[other, lo:hi], temporal)
                _gradient_step(data[j, lo:hi], L[j, lo:hi], u, Lh[j, lo:hi],
                               S[j, lo:hi], V[j, lo:hi], Y2[j, lo:hi], spatial, temporal,
                               L_new[j, lo:hi], coefficients)
            _shrink_steps(data[j, lo:hi], L[j, lo:hi], u, Lh[j, lo:hi], S[j, lo:hi],
                          V[j, lo:hi], Y2[j, lo:hi], L_new[j, lo:hi], S_new[j, lo:hi],
                          t_s, t_v, block_sums)
        sums[b] = block_sums
        _add_block_gram(Lh, lo, hi, grams[b])
    return sums.sum(axis=0), _symmetric_sum(grams)


@njit(cache=True, nogil=True)
def _symmetric_sum(grams):
    """Return the sum of the blocks' upper triangles (blocks, m, m), made symmetric."""
    gram = grams.sum(axis=0)
    for a in range(gram.shape[0]):
        for c in range(a):
            gram[a, c] = gram[c, a]
    return gram


@njit(parallel=True, cache=True, nogil=True)
def frames_gram(rows):
    """
    Return ``rows rows^T`` (m x m, float64) of a C-contiguous float32 ``rows`` (m, n).

    The Gram matrix of a frames-major window, by the pass's blocks and tiles
    (:func:`_add_block_gram`), threaded: faster than BLAS's float32 product
    at the solver's sizes, even on one thread (docs/solver.md), and summed in
    float64 across the blocks.
    """
    m, n = rows.shape
    n_blocks = (n + BLOCK_PIXELS - 1) // BLOCK_PIXELS
    grams = np.zeros((n_blocks, m, m), dtype=np.float64)
    for b in prange(n_blocks):
        _add_block_gram(rows, b * BLOCK_PIXELS, min(n, (b + 1) * BLOCK_PIXELS), grams[b])
    return _symmetric_sum(grams)


@njit(parallel=True, cache=True, fastmath=FAST_MATH, nogil=True)
def squared_gap(a, b):
    """Return ``||a - b||_F^2`` of two C-contiguous arrays in float64, threaded over blocks."""
    a = a.ravel()
    b = b.ravel()
    n = a.size
    n_blocks = (n + BLOCK_PIXELS - 1) // BLOCK_PIXELS
    sums = np.zeros(n_blocks, dtype=np.float64)
    for blk in prange(n_blocks):
        total = np.float32(0.0)
        for i in range(blk * BLOCK_PIXELS, min(n, (blk + 1) * BLOCK_PIXELS)):
            gap = a[i] - b[i]
            total += gap * gap
        sums[blk] = total
    return sums.sum()


# The numpy references of the three passes: the same arguments, the same
# results. The passes sum in float32 by blocks and are compiled with
# fastmath (reassociated, contracted sums): no numpy formulation gives
# their rounding, so the references sum in float64 and agree to a float32
# rounding (the tolerances registered below).
def _shrink_reference(x, t):
    return x - np.clip(x, -t, t)


def primal_pass_reference(data, L, U, Lh, S, V, Y2,
                          s_offsets, s_bands, t_offsets, t_bands, coefficients, l_given,
                          L_new, S_new, svt_left, svt_right, u_from_svt):
    """Run :func:`primal_pass`'s sweep in numpy, one expression per step over whole frames."""
    m, n = data.shape
    g1, g2, c, rho1, rho2, step, t_s, t_v = coefficients.astype(np.float32)
    if u_from_svt:
        U = np.dot(svt_right, np.dot(svt_left, Lh))
    if not l_given:
        spatial = np.zeros((m, n), dtype=np.float32)      # Phi_s L, band by band
        for off, band in zip(s_offsets, s_bands):
            first, last = max(0, -off), min(n, n - off)
            if first < last:
                spatial[:, first:last] += band[first:last] * L[:, first + off:last + off]
        temporal = np.zeros((m, n), dtype=np.float32)     # L Phi_t, Phi_t symmetric
        for off, band in zip(t_offsets, t_bands):
            first, last = max(0, -off), min(m, m - off)
            if first < last:
                temporal[first:last] += band[first:last, None] * L[first + off:last + off]
        rhs = rho1 * (U + (U - Lh)) + rho2 * (data - S - V + Y2)
        L_new[...] = L - step * (c * L - rhs + g1 * spatial + g2 * temporal)
    dual = U - Lh
    residual = data - L_new
    foreground = _shrink_reference(residual - V + Y2, t_s)
    noise = _shrink_reference(residual - foreground + Y2, t_v)
    gap = residual - foreground - noise
    sums = np.array([squared_gap_reference(L_new, L), squared_gap_reference(L, 0),
                     squared_gap_reference(foreground, S), squared_gap_reference(S, 0),
                     squared_gap_reference(U, L), squared_gap_reference(gap, 0)])
    Y2 += gap
    S_new[...] = foreground
    V[...] = noise
    np.subtract(L_new, dual, out=Lh)
    return sums, frames_gram_reference(Lh)


def frames_gram_reference(rows):
    """Return ``rows rows^T`` (m x m) as :func:`frames_gram`, from the float64 product."""
    rows = np.asarray(rows, dtype=np.float64)
    return rows @ rows.T


def squared_gap_reference(a, b):
    """Return ``||a - b||_F^2`` as :func:`squared_gap`: the float32 gaps, summed in float64."""
    gap = np.subtract(a, b, dtype=np.float32).astype(np.float64).ravel()
    return float(gap @ gap)


def _window(rng, m, n):
    """Return a random frames-major float32 array (m, n), C-ordered, as the solver's."""
    return rng.uniform(-1.0, 1.0, (m, n)).astype(np.float32)


def _sweep_examples():
    """Return the primal pass's arguments on small windows (both L-steps, both U sources)."""
    rng = np.random.default_rng(0)
    m, rows, cols, rank = 7, 30, 40, 2
    n = rows * cols
    s_offsets = np.array([-cols, -1, 0, 1, cols], dtype=np.int64)
    t_offsets = np.array([-1, 0, 1], dtype=np.int64)
    examples = []
    for l_given, u_from_svt in ((False, False), (False, True), (True, True)):
        iterates = [_window(rng, m, n) for _ in range(7)]
        examples.append((*iterates, s_offsets, rng.uniform(0, 1, (5, n)).astype(np.float32),
                         t_offsets, rng.uniform(0, 1, (3, m)).astype(np.float32),
                         np.array([0.1, 0.2, 0.3, 1.0, 1.0, 0.4, 0.05, 0.5]), l_given,
                         _window(rng, m, n), _window(rng, m, n), _window(rng, rank, m),
                         _window(rng, m, rank), u_from_svt))
    return examples


# Measured on the examples: the iterates within 1e-6 of the reference's, the
# sums and the Gram entries (up to 1e3 here) within 2e-4; a wrong step is off
# by far more than these bounds.
register_pass(primal_pass, _sweep_examples, reference=primal_pass_reference,
              atol=5e-4, rtol=1e-5)
register_pass(frames_gram,
              lambda: [(_window(np.random.default_rng(seed), m, 2500),)
                       for seed, m in enumerate((1, 2, 5, 7, 12))],
              reference=frames_gram_reference, atol=5e-4, rtol=1e-5)
register_pass(squared_gap,
              lambda: [(_window(np.random.default_rng(1), 7, 2500),
                        _window(np.random.default_rng(2), 7, 2500))],
              reference=squared_gap_reference, rtol=1e-6)
