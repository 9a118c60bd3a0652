# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The scenario suite: five scripted behaviours on real backgrounds with real people.

=====================  =========================================================
``in_view``            two people in view from the first frame, each moving
                       about within a small area (half a body width) for the
                       whole clip: the background behind them is never seen
                       whole (20 s)
``stops``              a person walks in, stands perfectly still (same pose,
                       same place) for 60 s, then walks out (about 66 s)
``close_up``           a person close to the camera, the body cut by the
                       frame's bottom, covering 30-60% of the view, entering
                       after 1 s and moving about (15 s)
``crossing``           two people at different depths enter from opposite
                       sides, linger, cross each other (the near one hides the
                       far one), linger on the other side, leave (about 22 s)
``close_in_view``      ``close_up``'s person in view from the first frame,
                       moving about (15 s): the background behind the middle
                       of the body is never seen (a robot that starts up
                       beside someone)
=====================  =========================================================

Frame rate 30 frames/s, the robot camera's: the detector's rules count frames
(``still_frames``, ``absorb_frames``), so a scenario's frames mean what they
mean on the robot, and the 60 s stand is 1800 frames. ``duration_scale``
shortens the lingering and still spans (the tests' short suite); the walking
speed stays that of a person (0.75 body heights per second).

Everything random (background, people, positions, paths, light, noise) is
drawn from ``seed``; the same seed and data give the same frames bit for bit.
"""

import numpy as np

from .compose import Actor, flicker, Scenario, Script
from .material import load_material

FPS = 30.0
WALK_SPEED = 0.75 / FPS     # body heights per frame
SCENARIO_NAMES = ('in_view', 'stops', 'close_up', 'crossing', 'close_in_view')
CLOSE_UP_COVERAGE = (0.35, 0.5)


def _frames(seconds, scale):
    return max(int(round(seconds * FPS * scale)), 2)


def _person_backgrounds(material):
    return sorted(clip for clip, b in material.backgrounds.items() if b.perspective is not None)


def _pick_track(tracks, target_height, rng, exclude=()):
    """Pick a track tall enough not to be enlarged much (else one of the tallest)."""
    tracks = [t for t in tracks if id(t) not in exclude] or tracks
    tall = [t for t in tracks if t.height >= 0.6 * target_height]
    if not tall:
        tallest = max(t.height for t in tracks)
        tall = [t for t in tracks if t.height >= 0.8 * tallest]
    return tall[rng.integers(len(tall))]


def _feet_row(background, rng):
    _, _, low, high = background.perspective
    return float(rng.uniform(low, high))


def _width(track, height):
    """Width (pixels) of the track's person drawn ``height`` tall."""
    cutout = track.cutouts[0]
    return cutout.mask.shape[1] * height / track.height


def in_view(material, rng, scale):
    """Script two people in view from the first frame, each moving about a small area."""
    background = material.backgrounds[rng.choice(_person_backgrounds(material))]
    rows, cols = background.image.shape[:2]
    count = _frames(20, scale)
    actors, used = [], set()
    for centre in (0.3, 0.7):
        y = _feet_row(background, rng)
        height = background.person_height(y)
        track = _pick_track(material.tracks, height, rng, used)
        used.add(id(track))
        x = cols * (centre + rng.uniform(-0.05, 0.05))
        script = Script(x, y, FPS, len(track), rng)
        script.linger(count, 0.5 * _width(track, height), 0.02 * rows)
        actors.append(script.actor(track.cutouts, track.height, background.person_height, count))
    return background, actors, count, {'in_view': (0, count - 1)}, \
        'two people in view from the first frame, moving about within half a body width'


def stops(material, rng, scale):
    """Script a person who walks in, stands still for 60 s, walks out."""
    background = material.backgrounds[rng.choice(_person_backgrounds(material))]
    cols = background.image.shape[1]
    y = _feet_row(background, rng)
    height = background.person_height(y)
    track = _pick_track(material.tracks, height, rng)
    outside = 0.6 * _width(track, height) + 2
    side = rng.choice((-1, 1))
    start, end = (-outside, cols + outside) if side > 0 else (cols + outside, -outside)
    script = Script(start, y, FPS, len(track), rng)
    script.away(_frames(1, scale))
    script.walk(cols * (0.5 + rng.uniform(-0.15, 0.15)), WALK_SPEED * height)
    first = len(script)
    still = _frames(60, scale)
    # a standing pose: the track's most upright cut-out (tallest for its width)
    script.still(still, int(np.argmax([c.height / c.mask.any(axis=0).sum()
                                       for c in track.cutouts])))
    script.walk(end, WALK_SPEED * height)
    script.away(_frames(1, scale))
    count = len(script)
    actor = script.actor(track.cutouts, track.height, background.person_height, count)
    return background, [actor], count, {'still': (first, first + still - 1)}, \
        f'a person walks in, stands still for {still / FPS:.0f} s, walks out'


def _close_up_height(background, track, x, coverage):
    """Height that makes the cut-off person cover ``coverage`` of the frame at column ``x``."""
    rows, cols = background.image.shape[:2]
    height = track.height * np.sqrt(coverage * rows * cols / np.median(
        [c.area for c in track.cutouts]))
    for _ in range(4):
        probe = Actor(track.cutouts[:1], track.height, np.array([x]), np.array([rows - 1.0]),
                      np.array([height]), np.array([0]))
        rgb, alpha, top, left = probe.sprite(0)
        y0, x0 = max(top, 0), max(left, 0)
        y1, x1 = min(top + alpha.shape[0], rows), min(left + alpha.shape[1], cols)
        area = float((alpha[y0 - top:y1 - top, x0 - left:x1 - left] > 0.5).sum())
        height *= np.sqrt(coverage * rows * cols / max(area, 1.0))
    return float(height)


def _close_person(material, rng):
    """Draw a background, a close-up track, its column, height and feet row."""
    clips = sorted(material.backgrounds)
    background = material.backgrounds[rng.choice(clips)]
    rows, cols = background.image.shape[:2]
    tallest = max(t.height for t in material.close_ups)
    tracks = [t for t in material.close_ups if t.height >= 0.8 * tallest]
    track = tracks[rng.integers(len(tracks))]
    centre = cols * (0.5 + rng.uniform(-0.08, 0.08))
    height = _close_up_height(background, track, centre, rng.uniform(*CLOSE_UP_COVERAGE))
    # the head stays in view: a person taller than the frame is cut lower
    feet = rows - 1.0 + max(height - 0.97 * rows, 0.0)
    return background, track, centre, height, feet


def close_up(material, rng, scale):
    """Script a person close to the camera covering 30-60% of the view, moving about."""
    background, track, centre, height, feet = _close_person(material, rng)
    cols = background.image.shape[1]
    width = _width(track, height)
    side = rng.choice((-1, 1))
    script = Script(-side * (0.6 * width) + (cols if side < 0 else 0), feet, FPS, len(track), rng)
    script.away(_frames(1, scale))
    script.walk(centre, 2 * WALK_SPEED * height)
    first = len(script)
    script.linger(_frames(14, scale), 0.12 * cols, 0.0)
    count = len(script)
    actor = script.actor(track.cutouts, track.height, lambda _: height, count)
    return background, [actor], count, {'close': (first, count - 1)}, \
        'a person close to the camera, cut by the frame, moving about'


def close_in_view(material, rng, scale):
    """Script ``close_up``'s person in view from the first frame, moving about."""
    background, track, centre, height, feet = _close_person(material, rng)
    cols = background.image.shape[1]
    script = Script(centre, feet, FPS, len(track), rng)
    script.linger(_frames(15, scale), 0.12 * cols, 0.0)
    count = len(script)
    actor = script.actor(track.cutouts, track.height, lambda _: height, count)
    return background, [actor], count, {'close': (0, count - 1)}, \
        'a person close to the camera, cut by the frame, in view from the first frame'


def crossing(material, rng, scale):
    """Script two people who enter from opposite sides, linger, cross, linger, leave."""
    background = material.backgrounds[rng.choice(_person_backgrounds(material))]
    rows, cols = background.image.shape[:2]
    _, _, low, high = background.perspective
    rows_of = sorted(rng.uniform(low, high, 2))
    if rows_of[1] - rows_of[0] < 0.3 * (high - low):
        rows_of = [low + 0.2 * (high - low), high - 0.1 * (high - low)]
    scripts, used = [], set()
    for k, side in enumerate((1, -1)):
        y = rows_of[k]
        height = background.person_height(y)
        track = _pick_track(material.tracks, height, rng, used)
        used.add(id(track))
        outside = 0.6 * _width(track, height) + 2
        start, end = (-outside, cols + outside) if side > 0 else (cols + outside, -outside)
        script = Script(start, y, FPS, len(track), rng)
        script.away(_frames(0.5 + k * 0.7, scale))
        near, far = (0.3, 0.72) if side > 0 else (0.7, 0.28)
        speed = WALK_SPEED * height
        script.walk(cols * near, speed)
        script.linger(_frames(4, scale), 0.3 * _width(track, height), 0.01 * rows)
        script.walk(cols * far, speed)
        script.linger(_frames(4, scale), 0.3 * _width(track, height), 0.01 * rows)
        script.walk(end, speed)
        scripts.append((script, track))
    count = max(len(s) for s, _ in scripts) + _frames(1, scale)
    actors = [s.actor(t.cutouts, t.height, background.person_height, count) for s, t in scripts]
    return background, actors, count, {}, \
        'two people at different depths linger and cross each other'


BUILDERS = {'in_view': in_view, 'stops': stops, 'close_up': close_up, 'crossing': crossing,
            'close_in_view': close_in_view}


def build_scenario(name, material, seed=0, duration_scale=1.0):
    """Return the :class:`Scenario` ``name`` (one of :data:`SCENARIO_NAMES`) for ``seed``."""
    if name not in BUILDERS:
        raise ValueError(f'unknown scenario {name!r}; choose from {", ".join(SCENARIO_NAMES)}')
    code = SCENARIO_NAMES.index(name)
    rng = np.random.default_rng((seed, code))
    background, actors, count, phases, description = BUILDERS[name](material, rng,
                                                                    duration_scale)
    return Scenario(name, description, background, actors, count, FPS, seed, code,
                    flicker(count, FPS, rng), phases)


def build_suite(data_dir, seed=0, duration_scale=1.0, names=SCENARIO_NAMES, material=None):
    """Return the suite's scenarios built from the shared data under ``data_dir``."""
    material = load_material(data_dir) if material is None else material
    return [build_scenario(n, material, seed, duration_scale) for n in names]
