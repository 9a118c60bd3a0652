# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Every tunable parameter in one table, shared by the node and the command line.

The node declares a ROS parameter for each entry (with its description and
range), the command line offers each as an option and reads the node's YAML
parameter file, and :func:`build_detector` turns a full set of values into core
objects. No ROS import here.
"""

from dataclasses import dataclass
import sys

import yaml

from .core.baselines.frpcag import FRPCAG
from .core.baselines.ialm import InexactALM
from .core.baselines.lago import LAGO
from .core.baselines.median import TemporalMedian
from .core.baselines.spcp import SplitSPCP
from .core.baselines.spgl1 import SPGL1RPCA
from .core.dgmod import DualGraphMOD
from .core.masks import MaskRule
from .core.streaming import SlidingWindowDetector
from .core.subtractors import OpenCVSubtractor, OpenCVWindowModel
from .core.validation import options


#: Where a parameter can be read: the node, ``dgmod --mode stream`` (the node's
#: streaming detector offline), ``dgmod --mode batch`` (windows tiling a sequence).
NODE, STREAM, BATCH = 'node', 'stream', 'batch'
STREAMING = (NODE, STREAM)
EVERYWHERE = (NODE, STREAM, BATCH)
OFFLINE = (STREAM, BATCH)
NODE_ONLY = (NODE,)

#: Methods that update a per-pixel model with every frame instead of solving windows.
_OPENCV_METHODS = ('mog2', 'knn')
#: Window methods: the sliding window, its solves and the per-pixel decision.
_WINDOW_METHODS = ('dgmod', 'lago', 'spcp', 'spgl1', 'ialm', 'frpcag', 'median')


class Not:
    """An ``active_when`` value: the parameter acts while the other is none of ``values``."""

    def __init__(self, *values):
        self.values = values

    def __contains__(self, value):
        return value not in self.values

    def __eq__(self, other):
        return isinstance(other, Not) and other.values == self.values

    def __hash__(self):
        return hash(self.values)

    def __repr__(self):
        return 'Not(' + ', '.join(map(repr, self.values)) + ')'


def _allowed(value):
    """Normalise one ``active_when`` value: a :class:`Not`, or a tuple of the allowed values."""
    return value if isinstance(value, (Not, tuple)) else (value,)


def _choices(owner, name):
    """Return the values ``owner`` accepts for ``name``: the choices the core declares."""
    return options(owner._parameter_constraints[name])


#: ``active_when`` shorthands: the dual-graph model's own weights and solver; a
#: sliding-window detector; its per-pixel decisions; one global threshold.
_DGMOD = {'method': 'dgmod'}
_WINDOW = {'method': Not(*_OPENCV_METHODS)}
_PER_PIXEL = {'decision': ('adaptive', 'uniform')}
_GLOBAL = {'decision': 'global'}
_DEPTH = ({'use_depth': True}, {'depth_only': True})


@dataclass(frozen=True)
class Parameter:
    """
    One parameter: name, default, description, the range ROS enforces, where it acts.

    ``acts`` names where it is read (:data:`NODE`, :data:`STREAM`, :data:`BATCH`;
    the node declares only those with :data:`NODE`, the command line offers the
    others). ``advanced`` marks a solver internal: the defaults are measured
    (docs/solver.md, docs/results.md), and ``config/detector.yaml`` and
    ``--help`` list them apart. ``active_when`` says when the parameter has an
    effect at all: a mapping ``{other parameter: value or tuple of values or
    Not(values)}`` (all must hold), or a tuple of such mappings (any); a
    condition on a parameter that is not read where this one is read (say
    ``decision`` in batch mode) holds, one on a parameter that is read there
    but has no effect itself does not. :func:`inert_parameters` reads it; the
    descriptions the node, the YAML file and ``--help`` show say it.
    """

    name: str
    default: object
    description: str
    low: object = None
    high: object = None
    step: int = 1
    choices: tuple = ()
    read_only: bool = False
    acts: tuple = STREAMING
    advanced: bool = False
    active_when: object = ()

    def __post_init__(self):
        # One canonical form, hashable: a tuple of alternatives, each a tuple of
        # (name, allowed) pairs.
        when = self.active_when
        alternatives = (when,) if isinstance(when, dict) else tuple(when)
        object.__setattr__(self, 'active_when', tuple(
            tuple((name, _allowed(value)) for name, value in alternative.items())
            for alternative in alternatives))
        unknown = set(self.acts) - set(EVERYWHERE)
        if unknown or not self.acts:
            raise ValueError(f'{self.name}: acts must name some of {EVERYWHERE}')

    @property
    def where(self):
        """'node' (the node only), 'offline' (the command line only) or 'both'."""
        if NODE not in self.acts:
            return 'offline'
        return 'both' if set(self.acts) & set(OFFLINE) else 'node'


#: Every parameter. A new one is one entry: name, default, description, range
#: (low, high[, step]) or choices, and where they differ from the defaults
#: ``acts`` (default: the streaming detector, node and stream mode),
#: ``active_when``, ``advanced``, ``read_only``.
PARAMETERS = (
    # Method and window.
    Parameter('method', 'dgmod', 'separation method: dgmod (the dual-graph model); the '
              "paper's comparators lago, spcp, spgl1 (fastRPCA); ialm (classical PCP); frpcag "
              '(graphs without the nuclear norm); median (temporal median); OpenCV mog2 / knn '
              'run per frame. Comparators use their documented defaults.',
              choices=_WINDOW_METHODS + _OPENCV_METHODS, acts=EVERYWHERE),
    Parameter('window', 30, 'frames m in the sliding window (streaming: the consecutive frames '
              'it fills with, then memory_columns spaced memory_spacing apart)', 2, 300,
              acts=EVERYWHERE),
    Parameter('stride', 10, 'buffered frames between window solves (<= window)', 1, 300),
    Parameter('scale', 0.5, 'processing scale of frames for the per-frame path (projection, '
              'decision) and the window, up to processing_pixels; masks come back at input '
              'size. The window solve runs at this size up to solve_pixels', 0.05, 1.0,
              acts=EVERYWHERE),
    Parameter('processing_pixels', 25600, 'largest frame (pixels) the per-frame path and the '
              'window run at: a larger one (after scale) is scaled down to this, same aspect, '
              'so that the per-frame rules, which reach over a fixed number of pixels, see a '
              'scene alike at any camera resolution (25600: the largest processing size the '
              'defaults were chosen at; a 640 x 480 camera runs at 184 x 138)', 64, 100000000,
              acts=EVERYWHERE, advanced=True),
    Parameter('color', 'rgb', 'gray: one luma channel; rgb: each channel solved, fused by '
              'the largest magnitude', choices=_choices(SlidingWindowDetector, 'color'),
              acts=EVERYWHERE),
    Parameter('min_frames', 5, 'frames before the first solve (<= window); until then masks '
              'use the per-pixel median of the buffer', 2, 300, active_when=_WINDOW),
    Parameter('basis_rank', 2, 'background components the per-frame fast path projects on',
              1, 20, active_when=_WINDOW),
    Parameter('global_change_fraction', 0.7, 'foreground share of two consecutive frames '
              'that restarts the window (light switched, exposure jump); 1.0 disables',
              0.01, 1.0, active_when=_WINDOW),
    Parameter('memory_spacing', 10, 'frames between admissions to the full window, which '
              'then spans memory_columns * memory_spacing frames; 1 = consecutive frames', 1,
              1000, active_when=_WINDOW),
    Parameter('memory_columns', 10, 'columns the full window settles to (at most window): '
              "after the window's first, consecutive frames each admission drops the oldest "
              'column, and one more while the window holds more; each column weighs 1 / '
              'memory_columns in the solve', 2, 300, active_when=_WINDOW),
    Parameter('conditional_update', True, 'admit frames with their foreground replaced by the '
              'background, so that a person who stops stays foreground', active_when=_WINDOW),
    Parameter('hold_changes', False, 'the conditional update also keeps out the pixels over '
              'pixel_k / 2 noise levels from the background that change as much within 5 '
              'frames or have been away for fewer than still_frames frames (something '
              'passing that the mask missed)',
              active_when={'conditional_update': True, **_PER_PIXEL}),
    Parameter('absorb_frames', 5400, 'foreground older than this many frames enters the '
              'window as it is (a left object then joins the background; 5400 = 3 min at 30 '
              'frames/s: a person who waits stays foreground, the planner decides what is '
              'parked); the depth background holds a still person as long', 1, 1000000,
              active_when={'conditional_update': True}),
    Parameter('motion_threshold', 0.0, 'frames whose mean absolute change to the last '
              'buffered frame is below this are masked but not buffered; 0 buffers all',
              0.0, 1.0, active_when=_WINDOW),
    Parameter('value_range', 0.0, 'pixel value meaning full scale (for example 5000.0 for '
              '16UC1 depth in mm); 0 uses the type range (floats: 1.0)', 0.0, 1e9,
              acts=EVERYWHERE),
    # Model (Algorithm 1).
    Parameter('lambda1', 0.0, 'weight of the weighted nuclear norm; 0 = automatic, lambda2 '
              '* sqrt(max(n, m)) (as in the core; the model without the term is frpcag)',
              0.0, 1e6, acts=EVERYWHERE, active_when=_DGMOD),
    Parameter('lambda2', 0.5, 'weight of ||S||_1; below 1 so that S takes the foreground',
              1e-6, 0.999, acts=EVERYWHERE, active_when=_DGMOD),
    Parameter('gamma1', 0.5, 'weight of the spatial graph term', 0.0, 1e3, acts=EVERYWHERE,
              active_when=_DGMOD),
    Parameter('gamma2', 0.5, 'weight of the temporal graph term', 0.0, 1e3, acts=EVERYWHERE,
              active_when=_DGMOD),
    Parameter('rho1', 20.0, 'ADMM penalty of U = L', 1e-3, 1e6, acts=EVERYWHERE,
              active_when=_DGMOD, advanced=True),
    Parameter('rho2', 20.0, 'ADMM penalty of V = D - L - S', 1e-3, 1e6, acts=EVERYWHERE,
              active_when=_DGMOD, advanced=True),
    Parameter('weight_scale', 0.0, 'scale s of the weights exp(-sigma^2/s^2); 0 = 0.1 * '
              'largest singular value of the window', 0.0, 1e9, acts=EVERYWHERE,
              active_when=_DGMOD),
    Parameter('h_s', 0.0, 'spatial filtering parameter; 0 = median patch distance', 0.0, 1e9,
              acts=EVERYWHERE, active_when=_DGMOD),
    Parameter('h_t', 0.0, 'temporal filtering parameter; 0 = median frame distance',
              0.0, 1e9, acts=EVERYWHERE, active_when=_DGMOD),
    Parameter('patch_size', 3, 'odd side p of the patches of the spatial graph', 1, 15, 2,
              acts=EVERYWHERE, active_when=_DGMOD),
    Parameter('smoothing_sigma', 0.0, 'Gaussian pre-smoothing (pixels) before patch '
              'distances; 0 = off', 0.0, 10.0, acts=EVERYWHERE, active_when=_DGMOD),
    Parameter('temporal_neighbors', 4, 'frames joined to each frame in the temporal graph',
              2, 20, acts=EVERYWHERE, active_when=_DGMOD),
    Parameter('l_step', 'gradient', 'L-step: gradient (paper) or exact (block CG in the '
              'temporal eigenbasis)', choices=_choices(DualGraphMOD, 'l_step'), acts=EVERYWHERE,
              active_when=_DGMOD, advanced=True),
    Parameter('inner_iter', 1, 'gradient steps or CG iterations per L-step (T_in)', 1, 50,
              acts=EVERYWHERE, active_when=_DGMOD, advanced=True),
    Parameter('tol', 1e-3, 'stop when relative changes and residuals are below this',
              1e-8, 0.1, acts=EVERYWHERE, active_when=_DGMOD, advanced=True),
    Parameter('max_iter', 300, 'ADMM sweeps per window solve at most (T_out) in batch mode '
              '(streaming solves take stream_max_iter)', 1, 10000, acts=(BATCH,),
              active_when=_DGMOD, advanced=True),
    Parameter('solve_lag', 5, 'frames between the window snapshot of a solve and its install '
              '(at most stride): the solve runs beside that many frames of per-frame work, and '
              'the masks do not depend on its speed (sync mode and offline; async installs a '
              'solve when it ends, about 5 frames at 30 frames/s)', 0, 300,
              active_when={**_WINDOW, 'solve_mode': 'sync'}, advanced=True),
    Parameter('solve_pixels', 19200, 'largest frame (pixels) the window solve runs at: a '
              'larger one (after solve_scale) is solved scaled down to this, same aspect, and '
              "its full-size background fit from the solve's temporal factors (19200 = 160 x "
              '120: binds only where processing_pixels is raised above 320 x 240)', 64, 100000000,
              active_when=_WINDOW, advanced=True),
    Parameter('solve_scale', 0.5, 'scale of the window solve against the processing size '
              '(before the solve_pixels cap); the full-size background is fit from the '
              "solve's temporal factors", 0.05, 1.0, active_when=_WINDOW),
    Parameter('refit_background', True, "the background is each pixel's own series fit on "
              "the solve's leading temporal factors, the solve's foreground held out, also "
              "when the solve runs at the processing size; false: the solve's own L there",
              active_when=_WINDOW, advanced=True),
    Parameter('stream_max_iter', 3, 'ADMM sweeps per window solve while streaming (node, '
              "stream mode), from the window's data (or, with warm_start, from the last "
              'solve, so that sweeps add up over overlapping windows)', 1, 10000,
              active_when=_DGMOD, advanced=True),
    Parameter('warm_start', False, "start each window solve from the last solve's iterates "
              "instead of from the window's data: sweeps add up, and so does what the first "
              'windows learnt (a person in view from the first frame)', active_when=_WINDOW,
              advanced=True),
    Parameter('solve_threads', 1, "threads of the window solve's compiled kernels where it "
              'runs beside the per-frame work (the async node, stream mode); 1 leaves the other '
              'cores to the image callback, DDS and the camera driver; 0 = one per core. The '
              'masks do not depend on it', 0, 1024, read_only=True, active_when=_WINDOW),
    # Masks.
    Parameter('decision', 'adaptive', 'adaptive: each pixel against pixel_k times its own noise '
              "level from the window's residual; uniform: one level for all pixels; global: "
              'the mask_* rule (one threshold, morphology)',
              choices=_choices(SlidingWindowDetector, 'decision'), active_when=_WINDOW),
    Parameter('noise_source', 'solve', "residual of the window that gives each pixel's noise "
              "level: solve: the solve's D - L; projection / least_squares: each frame against "
              "its robust / least-squares projection on the fast path's basis (what the per-frame "
              'decision thresholds); max: the larger of the solve and projection levels',
              choices=_choices(SlidingWindowDetector, 'noise_source'), active_when=_PER_PIXEL,
              advanced=True),
    Parameter('doubtful_floor', 0.5, "a pixel the window's masks called foreground in more "
              'than half of its columns (a person in view while the window filled) reads its '
              'noise level from the differences of consecutive columns where that is lower '
              'than the level of all its columns, but not below this share of it; 1 = the '
              'level of all its columns', 0.0, 1.0, active_when=_PER_PIXEL),
    Parameter('ghost_test', True, 'drop still blobs, and still parts of blobs, whose outline '
              'is an edge of the background rather than of the frame (ghosts of what has '
              'left); they heal the window',
              active_when=_PER_PIXEL),
    Parameter('still_frames', 15, 'drop pixels that have been in a still blob (at most 1 % '
              'of it, or one pixel, changed by pixel_k / 2 noise levels over 5 frames) for '
              'this many frames, unless the blob was seen to come in (most of its pixels '
              'moved while foreground): ghosts that uncover texture; they heal the window; '
              '0 = off', 0, 1000000,
              active_when=_PER_PIXEL),
    Parameter('line_pixels', 100, 'a blob with no 3 x 3 square of foreground at the '
              'processing size is a line (the rim of a light that grew with the exposure, a '
              "cable's shadow), not a body: one that covers at least this many of the camera's "
              'pixels leaves the published mask (the window still keeps it out); 0 = off. '
              'Also the fewest pixels of a body that the filling window holds out where it came '
              'in under a model (0: every blob)', 0, 100000000,
              active_when=(_PER_PIXEL, {'conditional_update': True})),
    Parameter('fill_holes', True, "close the published mask with the field's 5 x 5 "
              'neighbourhood (a gap it opened in an outline is bridged) and fill its holes: '
              "background enclosed by a body's outline, or by it and one side of the frame (a "
              'flat coat whose colour the window has seen there, a body cut by the edge); '
              "background that reaches two sides or a corner is the scene's; the window keeps "
              'the unfilled decision',
              active_when=_PER_PIXEL),
    Parameter('mrf_beta', 2.0, 'coupling of 5 x 5 neighbours in the Potts field that decides '
              'the per-pixel mask (log-odds per neighbour, mean field); 0 = threshold and '
              'median filter (median_size)', 0.0, 100.0, active_when=_PER_PIXEL),
    Parameter('pixel_k', 6.0, 'multiple of the noise level that makes a pixel foreground '
              "(and of the level of a pixel's steps between window columns past which its "
              'level is an offset of the model, not noise)', 0.1, 100.0, active_when=_PER_PIXEL),
    Parameter('median_size', 5, 'median filter of the thresholded per-pixel decision at the '
              'processing size (odd; 1 = off)', 1, 15, 2,
              active_when={**_PER_PIXEL, 'mrf_beta': 0.0}),
    Parameter('chroma_cue', True, 'a change of light (shadow, reflection) keeps the '
              'chromaticity: pixels whose chromaticity distortion stays within pixel_k noise '
              'levels may be taken for one (rgb)', active_when=_PER_PIXEL),
    Parameter('texture_cue', True, 'a change of light keeps the local texture: pixels whose '
              'LBSP descriptor stays within texture_bits of the background may be taken for '
              'one', active_when=_PER_PIXEL),
    Parameter('texture_bits', 8, 'largest LBSP Hamming distance (of 16 bits per channel) of a '
              'change of light', 0, 48, active_when={'texture_cue': True}),
    Parameter('moving_texture_k', 2.0, 'pixels whose LBSP texture changed (moving_texture_bits '
              'or more) and that moved over 5 frames are foreground from this multiple of the '
              'noise level instead of pixel_k (a person whose colour matches what is behind); '
              '0 = off', 0.0, 100.0, active_when=_PER_PIXEL),
    Parameter('moving_texture_bits', 16, 'fewest differing LBSP bits (of 16 per channel) of a '
              'changed texture for moving_texture_k', 0, 48,
              active_when={'moving_texture_k': Not(0.0)}),
    Parameter('mask_threshold', 0.0, 'fixed threshold on |S| for data in [0, 1]; 0 = auto '
              '(max(mask_min_threshold, mask_k * robust sigma of D - L))', 0.0, 1.0,
              acts=EVERYWHERE, active_when=_GLOBAL),
    Parameter('mask_k', 5.0, 'multiple of the robust noise level of the auto threshold',
              0.1, 100.0, acts=EVERYWHERE, active_when={**_GLOBAL, 'mask_threshold': 0.0}),
    Parameter('mask_min_threshold', 0.1, 'floor of the auto threshold', 0.0, 1.0,
              acts=EVERYWHERE, active_when={**_GLOBAL, 'mask_threshold': 0.0}),
    Parameter('morph_size', 3, 'kernel of the morphological opening and closing; 0 = off',
              0, 15, acts=EVERYWHERE, active_when=(_GLOBAL, {'method': _OPENCV_METHODS})),
    # Node only (no command-line option).
    Parameter('solve_mode', 'async', 'async: solves run in a worker thread while frames are '
              'masked; sync: in the image callback (deterministic, for replays)',
              choices=('async', 'sync'), acts=NODE_ONLY),
    Parameter('max_pixels', 4096 * 4096, 'refuse images with more pixels than this',
              1, 1 << 30, acts=NODE_ONLY),
    Parameter('publish_overlay', False, 'publish foreground_overlay (rgb8) for rviz',
              acts=NODE_ONLY),
    Parameter('diagnostics_period', 1.0, 'seconds between /diagnostics messages', 0.1, 60.0,
              acts=NODE_ONLY),
    Parameter('solve_timeout', 10.0, 'diagnostics warn when a window solve has been due '
              'this many seconds with none finished while frames arrive (a frozen '
              'background); 0 = never', 0.0, 3600.0, acts=NODE_ONLY),
    Parameter('foreground_jump', 0.3, 'diagnostics warn when the foreground share of the '
              'frame changes by more than this between consecutive frames (camera moved, '
              'lights); 1.0 disables', 0.01, 1.0, acts=NODE_ONLY),
    Parameter('input_transport', 'raw', 'raw: subscribe image (sensor_msgs/Image); '
              'compressed: subscribe image/compressed (sensor_msgs/CompressedImage, JPEG or '
              'PNG, as image_transport offers it)', choices=('raw', 'compressed'),
              read_only=True, acts=NODE_ONLY),
    Parameter('autostart', True, 'configure and activate the lifecycle node at start-up; '
              'false waits for a lifecycle manager', read_only=True, acts=NODE_ONLY),
    # Depth (people in 3-D for planners).
    Parameter('use_depth', False, 'also subscribe depth/image_rect (16UC1 mm or 32FC1 m, '
              'registered to image) and depth/camera_info, and publish foreground_points and '
              'foreground_depth/image_rect + camera_info for every paired frame',
              read_only=True, acts=NODE_ONLY),
    Parameter('depth_slop', 0.02, 'largest stamp difference (seconds) of a colour frame and '
              'the depth image paired with it', 0.0, 1.0, acts=NODE_ONLY,
              active_when=_DEPTH),
    Parameter('cloud_pixel_step', 2, 'foreground_points takes every n-th pixel in both '
              'directions (1 = every foreground pixel)', 1, 16, acts=NODE_ONLY,
              active_when=_DEPTH),
    # Depth background and fusion (issue 23): depth decides where it can tell.
    Parameter('depth_background', True, "learn the static scene's depth per pixel and decide "
              'with it: nearer by more than depth_noise_k noise levels is foreground, at its '
              'depth background, whatever the colour says; no reading: the colour mask. '
              'false: the colour mask back-projected as it is', acts=NODE_ONLY,
              active_when=_DEPTH),
    Parameter('depth_fuse_mask', True, 'foreground_mask carries the fused mask too (published '
              "when the frame's depth partner arrives; at once while no depth comes)",
              acts=NODE_ONLY,
              active_when=_DEPTH),
    Parameter('depth_only', False, 'no colour subscription: masks, points and masked depth '
              'from the depth background alone (a dark scene, a depth-only sensor)',
              read_only=True, acts=NODE_ONLY),
    Parameter('depth_noise_base', 0.002, 'depth noise (m, standard deviation) at zero '
              'distance: sigma(z) = depth_noise_base + depth_noise_quadratic * z^2',
              0.0001, 1.0, acts=NODE_ONLY,
              active_when=_DEPTH),
    Parameter('depth_noise_quadratic', 0.005, 'growth of the depth noise with distance squared '
              '(1/m); 0.004 for a RealSense D435 at 640 x 480 (subpixel 0.08, 50 mm baseline), '
              'about half for a 95 mm baseline', 0.0, 1.0, acts=NODE_ONLY,
              active_when=_DEPTH),
    Parameter('depth_noise_k', 4.0, 'multiple of the depth noise that makes a pixel nearer '
              "than the static scene (foreground); within it, at the scene's depth",
              0.5, 100.0, acts=NODE_ONLY,
              active_when=_DEPTH),
    Parameter('depth_learn_frames', 10, "readings at the scene's depth before a pixel's depth "
              'decides (until then the colour mask does)', 1, 100000, acts=NODE_ONLY,
              advanced=True, active_when=_DEPTH),
    Parameter('depth_reveal_frames', 5, 'consistent readings behind the learnt depth that move '
              'it back (the scene uncovered by what stood there)', 1, 100000, acts=NODE_ONLY,
              advanced=True, active_when=_DEPTH),
    Parameter('depth_change_fraction', 0.25, 'share of the judged pixels behind the learnt '
              'depth in one frame that restarts the depth background and the window (the '
              'camera moved); 1.0 disables', 0.01, 1.0, acts=NODE_ONLY,
              advanced=True, active_when=_DEPTH),
)

BY_NAME = {p.name: p for p in PARAMETERS}
DEFAULTS = {p.name: p.default for p in PARAMETERS}


def reads(context):
    """Return the parameters read in ``context`` (:data:`NODE`, :data:`STREAM`, :data:`BATCH`)."""
    return tuple(p for p in PARAMETERS if context in p.acts)


def is_active(name, values, context):
    """
    Tell whether parameter ``name`` has an effect under ``values`` in ``context``.

    Read from the table: ``acts`` and ``active_when`` (see :class:`Parameter`).
    """
    spec = BY_NAME[name]
    if context not in spec.acts:
        return False
    return not spec.active_when or any(
        all(_condition_holds(other, allowed, values, context) for other, allowed in alternative)
        for alternative in spec.active_when)


def _condition_holds(name, allowed, values, context):
    if context not in BY_NAME[name].acts:
        return True                 # not read here, so it decides nothing here
    return values[name] in allowed and is_active(name, values, context)


def _text(value):
    return _yaml_scalar(value) if isinstance(value, bool) else str(value)


def _condition_text(name, allowed):
    if isinstance(allowed, Not):
        return f'{name} not {"|".join(map(_text, allowed.values))}'
    return f'{name}={"|".join(map(_text, allowed))}'


def conditions_text(spec, contexts=EVERYWHERE):
    """
    Return ``spec.active_when`` in words ('decision=global and mask_threshold=0.0'), or ''.

    Only the conditions on parameters read in one of ``contexts``: the command
    line does not mention the node's ``solve_mode``.
    """
    alternatives = [[(name, allowed) for name, allowed in alternative
                     if set(BY_NAME[name].acts) & set(contexts)]
                    for alternative in spec.active_when]
    if not all(alternatives):           # one alternative always holds there
        return ''
    return ', or with '.join(' and '.join(_condition_text(name, allowed)
                                          for name, allowed in alternative)
                             for alternative in alternatives)


def describe(spec, contexts=EVERYWHERE):
    """Return the description the node, the YAML file and ``--help`` show: when it acts too."""
    conditions = conditions_text(spec, contexts)
    if not conditions:
        return spec.description
    return f'{spec.description.rstrip(".")}. Acts only with {conditions}.'


_CONTEXT_NAMES = {NODE: 'the node', STREAM: 'dgmod --mode stream', BATCH: 'dgmod --mode batch'}


def inert_reason(name, values, context):
    """Return, in words, why ``name`` has no effect under ``values`` in ``context``; else None."""
    spec = BY_NAME[name]
    if context not in spec.acts:
        return 'it is read only by ' + ' and '.join(_CONTEXT_NAMES[c] for c in spec.acts)
    if is_active(name, values, context):
        return None
    controllers = list(dict.fromkeys(other for alternative in spec.active_when
                                     for other, _ in alternative
                                     if context in BY_NAME[other].acts))
    reason = f'it acts only with {conditions_text(spec)} (' + ', '.join(
        f'{other} is {_text(values[other])}' for other in controllers) + ')'
    # Every value as asked, yet inert: a parameter it depends on has no effect itself.
    for alternative in spec.active_when:
        named = [(other, allowed) for other, allowed in alternative
                 if context in BY_NAME[other].acts]
        if all(values[other] in allowed for other, allowed in named):
            other = next(o for o, _ in named if not is_active(o, values, context))
            return f'{reason}, and {other} has no effect: ' + \
                inert_reason(other, values, context)[len('it '):]
    return reason


def inert_parameters(values, names, context):
    """Return ``{name: reason}`` for those of ``names`` that have no effect, in table order."""
    names = set(names)
    reasons = {spec.name: inert_reason(spec.name, values, context) for spec in PARAMETERS
               if spec.name in names}
    return {name: reason for name, reason in reasons.items() if reason is not None}


def parse_bool(text):
    """Return the boolean a user typed: true/false, yes/no, on/off, 1/0 (any case)."""
    word = str(text).strip().lower()
    if word in ('true', 'yes', 'on', '1'):
        return True
    if word in ('false', 'no', 'off', '0'):
        return False
    raise ValueError(f'expected true or false (yes/no, on/off, 1/0), got {text!r}')


def parse_value(name, text):
    """Return ``text`` as a value of parameter ``name`` (its default's type)."""
    kind = type(BY_NAME[name].default)
    return parse_bool(text) if kind is bool else kind(text)


def _auto(value):
    """Map the ROS-friendly 0.0 for 'automatic' to None."""
    return None if value == 0 else value


_KINDS = {bool: 'true or false', int: 'an integer', float: 'a number', str: 'a string'}


def check_value(name, value):
    """Raise ``ValueError`` when ``value`` is of another type, or outside the choices or range."""
    spec = BY_NAME[name]
    kind = type(spec.default)
    # An int for a float is fine here (the command line converts; ROS refuses it itself).
    accepted = (int, float) if kind is float else kind
    if isinstance(value, bool) != (kind is bool) or not isinstance(value, accepted):
        raise ValueError(f'{name} must be {_KINDS[kind]}, got {value!r}')
    if spec.choices and value not in spec.choices:
        raise ValueError(f'{name} must be one of {", ".join(spec.choices)}, got {value!r}')
    if spec.low is not None and not spec.low <= value <= spec.high:
        raise ValueError(f'{name} must be in [{spec.low}, {spec.high}], got {value!r}')


def build_model(values, streaming=False):
    """Return the :class:`DualGraphMOD` the values describe (for streaming or batch)."""
    return DualGraphMOD(
        lambda1=_auto(values['lambda1']), lambda2=values['lambda2'],
        gamma1=values['gamma1'], gamma2=values['gamma2'], rho1=values['rho1'],
        rho2=values['rho2'], weight_scale=_auto(values['weight_scale']),
        h_s=_auto(values['h_s']), h_t=_auto(values['h_t']), patch_size=values['patch_size'],
        smoothing_sigma=values['smoothing_sigma'],
        temporal_neighbors=values['temporal_neighbors'], l_step=values['l_step'],
        inner_iter=values['inner_iter'], tol=values['tol'],
        max_iter=values['stream_max_iter' if streaming else 'max_iter'])


def build_mask_rule(values):
    """Return the :class:`MaskRule` the values describe."""
    threshold = values['mask_threshold'] if values['mask_threshold'] > 0 else 'auto'
    return MaskRule(threshold=threshold, k=values['mask_k'],
                    min_threshold=values['mask_min_threshold'], morph_size=values['morph_size'])


#: Window methods other than dgmod, built with their documented defaults.
COMPARATORS = {'lago': LAGO, 'spcp': SplitSPCP, 'spgl1': SPGL1RPCA, 'ialm': InexactALM,
               'frpcag': FRPCAG, 'median': TemporalMedian}
#: Parameters of the node itself: changing them leaves the detector untouched.
NODE_PARAMETERS = tuple(p.name for p in PARAMETERS if p.acts == NODE_ONLY)


def window_model(values, streaming=False):
    """Return the estimator that separates one window by ``values['method']``."""
    method = values['method']
    if method == 'dgmod':
        return build_model(values, streaming)
    if method in _OPENCV_METHODS:
        return OpenCVWindowModel(method)
    if method not in COMPARATORS:
        raise ValueError(f'unknown method {method!r}')
    return COMPARATORS[method]()


def detector_class(values):
    """Return the streaming detector class that runs ``values['method']``."""
    return OpenCVSubtractor if values['method'] in _OPENCV_METHODS else SlidingWindowDetector


def _say_on_stderr(message):
    print(message, file=sys.stderr, flush=True)


def load_kernels(values, log=None, pending=None, should_stop=None):
    """
    Load the compiled kernels that ``values['method']`` runs (numba's disk cache).

    Once per process: a start-up cost like the imports. Loaded lazily, they
    would stall the first frame (the node lost the frames after its first to
    its input queue meanwhile: docs/node.md), and a caller timing the frames
    would count them. OpenCV's subtractors need none. A cache not ready for
    this install is filled by a child process first (``pending``, if one was
    started already), which ``log`` announces and a signal or
    ``should_stop()`` interrupts (:func:`~dgmod_ros.core.kernel_cache.ensure_ready`);
    without ``log`` (the command line) on stderr.
    """
    if detector_class(values) is SlidingWindowDetector:
        from .core.kernel_cache import ensure_ready
        ensure_ready(log or _say_on_stderr, pending, should_stop)
        from .core.warmup import compile_all        # numba: imported when needed
        compile_all()


def detector_settings(values):
    """Return the keyword arguments of the streaming detector the values describe."""
    if detector_class(values) is OpenCVSubtractor:
        return {'kind': values['method'], 'scale': values['scale'],
                'processing_pixels': values['processing_pixels'], 'color': values['color'],
                'morph_size': values['morph_size'], 'stride': values['stride']}
    return {'model': window_model(values, streaming=True), 'window': values['window'],
            'stride': values['stride'], 'scale': values['scale'],
            'processing_pixels': values['processing_pixels'], 'color': values['color'],
            'mask_rule': build_mask_rule(values),
            'motion_threshold': values['motion_threshold'],
            'min_frames': values['min_frames'], 'basis_rank': values['basis_rank'],
            'global_change_fraction': values['global_change_fraction'],
            'memory_spacing': values['memory_spacing'],
            'memory_columns': values['memory_columns'],
            'conditional_update': values['conditional_update'],
            'hold_changes': values['hold_changes'],
            'absorb_frames': values['absorb_frames'], 'decision': values['decision'],
            'noise_source': values['noise_source'],
            'doubtful_floor': values['doubtful_floor'],
            'pixel_k': values['pixel_k'], 'median_size': values['median_size'],
            'ghost_test': values['ghost_test'], 'still_frames': values['still_frames'],
            'line_pixels': values['line_pixels'], 'fill_holes': values['fill_holes'],
            'mrf_beta': values['mrf_beta'], 'chroma_cue': values['chroma_cue'],
            'texture_cue': values['texture_cue'], 'texture_bits': values['texture_bits'],
            'moving_texture_k': values['moving_texture_k'],
            'moving_texture_bits': values['moving_texture_bits'],
            'solve_lag': values['solve_lag'], 'solve_pixels': values['solve_pixels'],
            'solve_scale': values['solve_scale'],
            'refit_background': values['refit_background'],
            'warm_start': values['warm_start']}


def validate(values):
    """
    Check a complete set of values, ranges and cross-field rules alike.

    Returns the values; raises ``ValueError`` with the first problem found.
    """
    missing = set(DEFAULTS) - set(values)
    if missing:
        raise ValueError(f'missing parameters: {", ".join(sorted(missing))}')
    for name, value in values.items():
        if name not in BY_NAME:
            raise ValueError(f'unknown parameter {name!r}')
        check_value(name, value)
    detector_class(values)(**detector_settings(values)).validate()
    # The model's own checks, for every method (the table holds dgmod's values).
    build_model(values).check_parameters()
    return values


def build_detector(values):
    """Return a validated streaming detector for a complete set of values."""
    validate(values)
    return detector_class(values)(**detector_settings(values)).validate()


def update_detector(detector, values, previous):
    """
    Return the streaming detector for ``values``, given the one running with ``previous``.

    Only node parameters changed: ``detector`` itself, untouched. The method
    needs another detector class: a new detector. Otherwise ``detector``
    reconfigured (it keeps what it can, see its ``configure``). Either way a
    solve started before the change is discarded when it comes back.
    """
    if all(values[name] == previous[name] for name in DEFAULTS
           if name not in NODE_PARAMETERS):
        return detector
    if type(detector) is not detector_class(values):
        return build_detector(values)
    return detector.configure(**detector_settings(values))


def load_parameter_file(path):
    """
    Read the ``ros__parameters`` of a ROS parameter YAML file.

    Accepts the node's own layout (``/detector: ros__parameters: ...``), any
    node name (``/**`` included), or a flat mapping. Unknown keys are refused.
    """
    with open(path, encoding='utf-8') as handle:
        content = yaml.safe_load(handle) or {}
    if not isinstance(content, dict):
        raise ValueError(f'{path}: expected a mapping at the top level')
    params = content
    for value in content.values():
        if isinstance(value, dict) and 'ros__parameters' in value:
            params = value['ros__parameters'] or {}
            break
    unknown = set(params) - set(DEFAULTS)
    if unknown:
        raise ValueError(f'{path}: unknown parameters: {", ".join(sorted(unknown))}')
    return dict(params)


#: Section titles, at the first parameter of each section (the table's order).
_SECTIONS = {'method': 'Method and sliding window',
             'lambda1': 'Model (Algorithm 1); 0.0 means automatic where stated',
             'decision': 'Masks', 'solve_mode': 'Node',
             'use_depth': 'Depth: the foreground in 3-D for planners'}
ADVANCED_TITLE = 'Advanced: solver internals (defaults measured: docs/solver.md, docs/results.md)'


def parameter_groups(specs):
    """
    Return ``[(title, [Parameter, ...]), ...]``: ``specs`` by section, the advanced ones last.

    One layout for ``config/detector.yaml`` and ``dgmod --help``; empty groups left out.
    """
    wanted = {spec.name for spec in specs}
    groups, advanced = [], []
    for spec in PARAMETERS:
        if spec.name in _SECTIONS:
            groups.append((_SECTIONS[spec.name], []))
        if spec.name in wanted:
            (advanced if spec.advanced else groups[-1][1]).append(spec)
    groups.append((ADVANCED_TITLE, advanced))
    return [(title, members) for title, members in groups if members]


def _yaml_scalar(value):
    if isinstance(value, bool):
        return 'true' if value else 'false'
    return repr(value) if isinstance(value, float) else str(value)


def _commented(spec, indent):
    import textwrap
    allowed = (' {' + ', '.join(spec.choices) + '}' if spec.choices
               else f' [{spec.low}, {spec.high}]' if spec.low is not None else '')
    text = describe(spec, NODE_ONLY if NODE in spec.acts else OFFLINE)
    return [f'{indent}# ' + line for line in textwrap.wrap(text + allowed, 88)]


def parameter_file_text():
    """Return ``config/detector.yaml``: every node parameter, its default and description."""
    lines = ['# Parameters of the dgmod_ros detector node, with their defaults.',
             '# Use: ros2 run dgmod_ros detector --ros-args --params-file <this file>',
             '# The offline command reads the same file: dgmod separate INPUT --config <file>',
             '# Write floats with a decimal point (1.0, not 1): ROS refuses an int for a double.',
             '# "Acts only with ...": the parameter has no effect otherwise (the node warns).',
             '# Generated by `python -m dgmod_ros.config`; a test keeps it in step with the code.',
             '/detector:', '  ros__parameters:']
    for title, specs in parameter_groups(reads(NODE)):
        lines.append(f'    # --- {title}')
        for spec in specs:
            lines += _commented(spec, '    ')
            lines.append(f'    {spec.name}: {_yaml_scalar(spec.default)}')
    offline = [spec for spec in PARAMETERS if spec.where == 'offline']
    if offline:
        lines.append('# Not node parameters: read by the offline command only '
                     '(dgmod ... --config <file>, or as options)')
        for spec in offline:
            lines += _commented(spec, '')
            lines.append(f'#   {spec.name}: {_yaml_scalar(spec.default)}')
    return '\n'.join(lines) + '\n'


if __name__ == '__main__':
    print(parameter_file_text(), end='')
