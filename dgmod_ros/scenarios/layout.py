# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Write a scenario in the shared data's CDnet layout (read by the anchors tool and benchmarks)."""

import json
from pathlib import Path

import cv2
import numpy as np


def describe(scenario):
    """Return a JSON-ready description of a scenario: its material, script phases, camera."""
    return {
        'name': scenario.name, 'description': scenario.description, 'seed': scenario.seed,
        'frames': len(scenario), 'fps': scenario.fps, 'size': list(scenario.shape[::-1]),
        'background': scenario.background.clip,
        'background_unseen_fraction': scenario.background.unseen_fraction,
        'people': [{'clip': a.cutouts[0].clip,
                    'frames': [int(a.cutouts[0].frame), int(a.cutouts[-1].frame)],
                    'height_px': [float(a.height.min()), float(a.height.max())],
                    'in_view_frames': int((a.pose >= 0).sum())} for a in scenario.actors],
        'phases': {k: [int(v) for v in span] for k, span in scenario.phases.items()},
    }


def write_sequence(scenario, folder):
    """
    Write ``scenario`` under ``folder`` as ``input/inNNNNNN.png`` and ``groundtruth/gtNNNNNN.png``.

    Numbered from 1 as CDnet numbers, with ``temporalROI.txt`` ``1 N`` (every
    frame scored), an all-255 ``ROI.bmp`` and ``scenario.json``
    (:func:`describe`). Returns the folder.
    """
    folder = Path(folder)
    (folder / 'input').mkdir(parents=True, exist_ok=True)
    (folder / 'groundtruth').mkdir(parents=True, exist_ok=True)
    for k in range(len(scenario)):
        rgb, truth = scenario.render(k)
        cv2.imwrite(str(folder / 'input' / f'in{k + 1:06d}.png'),
                    cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))
        cv2.imwrite(str(folder / 'groundtruth' / f'gt{k + 1:06d}.png'), truth)
    (folder / 'temporalROI.txt').write_text(f'1 {len(scenario)}\n')
    cv2.imwrite(str(folder / 'ROI.bmp'), np.full(scenario.shape, 255, np.uint8))
    (folder / 'scenario.json').write_text(json.dumps(describe(scenario), indent=2) + '\n')
    return folder
