# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Run a script in a fresh Python: what other tests imported cannot hide what it imports."""

from pathlib import Path
import subprocess
import sys

REPO = Path(__file__).resolve().parents[1]


def fresh_python(script, env=None):
    """Run ``script`` in this interpreter from the repository root (in ``env``); return stdout."""
    return subprocess.run([sys.executable, '-c', script], capture_output=True, text=True,
                          env=env, cwd=str(REPO), check=True).stdout
