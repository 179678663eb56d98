"""Run Blender's own BVH importer on a file, in a subprocess, and return what it made.

bpy (Blender as a Python module, ``pip install 'bpy==4.5.*'``, Python 3.11 only) never runs in the
test process: it would clash with Qt/VTK. The interpreter that has it is ``$GSIK_BLENDER_PYTHON``
(``.ci/run`` sets it to its ``.venv-blender``), else the test process's own Python when ``bpy`` is
installed there (``pip install -r tests/blender/requirements.txt``). Without either, callers are
skipped with the reason.
"""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path

import pytest

HARNESS = Path(__file__).with_name("blender_bvh.py")
_MARKER = "GSIK_BLENDER_JSON "


def blender_python() -> tuple[str | None, str]:
    """(interpreter that can ``import bpy`` or None, why that one or why none)."""
    env = os.environ.get("GSIK_BLENDER_PYTHON")
    if env:
        return env, f"GSIK_BLENDER_PYTHON={env}"
    if importlib.util.find_spec("bpy") is not None:  # find, never import, in this process
        return sys.executable, f"bpy installed for {sys.executable}"
    return None, (
        f"bpy (Blender as a Python module) is not installed for {sys.executable} "
        f"(Python {sys.version_info.major}.{sys.version_info.minor}; bpy==4.5.* needs 3.11): "
        "pip install -r tests/blender/requirements.txt, or set GSIK_BLENDER_PYTHON to a Python that has it"
    )


def blender_import(
    path: str | os.PathLike, frames: Sequence[float] = (), timeout: float = 120.0, **options: object
) -> dict:
    """Import ``path`` with ``bpy.ops.import_anim.bvh(**options)`` and sample the pose.

    Args:
        path: BVH file.
        frames: Blender scene frames to sample (BVH frame k is scene frame ``frame_start + k``
            with the default ``use_fps_scale=False``).
        timeout: seconds before the Blender process is killed [s].
        **options: importer keywords (axis_forward, axis_up, global_scale, rotate_mode, ...).

    Returns:
        The harness's JSON as a dict (see ``blender_bvh.py``); ``heads`` keyed by float frame,
        each a list of (3,) world positions in Blender units, one per bone in ``bones`` order.
        ``ok`` is False with ``error`` when Blender refused the file.
    """
    python, why = blender_python()
    if python is None:
        pytest.skip(why)
    cmd = [python, str(HARNESS), os.fspath(path), "--frames", ",".join(repr(float(f)) for f in frames),
           "--options", json.dumps(options)]
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    lines = [line for line in done.stdout.splitlines() if line.startswith(_MARKER)]
    if done.returncode != 0 or len(lines) != 1:
        raise RuntimeError(f"Blender harness failed ({why}), exit {done.returncode}:\n{done.stderr[-2000:]}")
    result = json.loads(lines[0][len(_MARKER):])
    if result["ok"]:
        result["heads"] = {float(k): v for k, v in result["heads"].items()}
    return result
