"""Import a BVH file with Blender's own importer and print what Blender made of it, as JSON.

Runs inside a Python that has ``bpy`` (Blender as a Python module), always in its own process: bpy
must never share a process with Qt/VTK or the test runner. Usage::

    python tests/blender/blender_bvh.py FILE.bvh [--frames 1,3,5] [--options '{"axis_up": "Z"}']

``--frames`` are Blender scene frames (float allowed, e.g. ``2.5``); with the importer's defaults
(``frame_start=1``, ``use_fps_scale=False``) BVH frame ``k`` (0-based) lands on scene frame ``1 + k``.
``--options`` are keyword arguments of ``bpy.ops.import_anim.bvh`` (axis_forward, axis_up,
global_scale, rotate_mode, frame_start, use_fps_scale, ...).

The result is one line ``GSIK_BLENDER_JSON {...}`` on stdout (Blender prints its own chatter
around it). On success: ``ok`` true, ``bones`` (names in Blender's order), ``parents`` (parent
bone name or null), ``rest_heads`` / ``rest_tails`` (world, Blender units), ``rotation_modes``,
``global_matrix`` (3x3 the importer used for the axis options), ``frame_range`` of the action and
``heads``: for each requested frame (key: the frame as given) the world head of every pose bone,
``armature.matrix_world @ pose_bone.head``. On failure: ``ok`` false and ``error``, the last line of
Blender's exception text (e.g. ``KeyError: (0, 1, None)``), and ``error_text``, all of it.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import sys

MARKER = "GSIK_BLENDER_JSON "


def _vec(v) -> list[float]:
    return [float(x) for x in v]


def _import(path: str, options: dict):
    """Armature object the importer made from ``path`` in an empty factory scene."""
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    with contextlib.redirect_stdout(sys.stderr):  # the importer prints progress
        bpy.ops.import_anim.bvh(filepath=path, **options)
    armatures = [ob for ob in bpy.context.scene.objects if ob.type == "ARMATURE"]
    if len(armatures) != 1:
        raise RuntimeError(f"expected one armature after import, found {len(armatures)}")
    return armatures[0]


def _global_matrix(options: dict) -> list[list[float]]:
    from bpy_extras.io_utils import axis_conversion

    m = axis_conversion(from_forward=options.get("axis_forward", "-Z"), from_up=options.get("axis_up", "Y"))
    return [_vec(row) for row in m]


def _heads_at(armature, frame: float) -> list[list[float]]:
    import bpy

    whole = math.floor(frame)
    bpy.context.scene.frame_set(int(whole), subframe=float(frame - whole))
    world = armature.matrix_world
    return [_vec(world @ pb.head) for pb in armature.pose.bones]


def describe(path: str, frames: list[float], options: dict) -> dict:
    """What Blender imported from ``path``: see the module docstring for the keys."""
    try:
        armature = _import(path, options)
    except Exception as exc:  # noqa: BLE001 - the error text is the result
        text = str(exc)
        # Operator errors end with "Location: .../bpy/ops.py:N" after the Python exception line.
        lines = [line.strip() for line in text.splitlines() if line.strip() and not line.startswith("Location:")]
        return {"ok": False, "error": lines[-1] if lines else type(exc).__name__, "error_text": text}
    bones = armature.data.bones
    world = armature.matrix_world
    action = armature.animation_data.action if armature.animation_data else None
    return {
        "ok": True,
        "bones": [b.name for b in bones],
        "parents": [b.parent.name if b.parent else None for b in bones],
        "rest_heads": [_vec(world @ b.head_local) for b in bones],
        "rest_tails": [_vec(world @ b.tail_local) for b in bones],
        "rotation_modes": [pb.rotation_mode for pb in armature.pose.bones],
        "global_matrix": _global_matrix(options),
        "frame_range": _vec(action.frame_range) if action else None,
        "heads": {repr(f): _heads_at(armature, f) for f in frames},
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("path")
    parser.add_argument("--frames", default="", help="comma-separated scene frames, e.g. 1,3,5")
    parser.add_argument("--options", default="{}", help="JSON object of import_anim.bvh keyword arguments")
    args = parser.parse_args(argv)
    frames = [float(f) for f in args.frames.split(",") if f.strip()]
    result = describe(args.path, frames, json.loads(args.options))
    sys.stdout.write(MARKER + json.dumps(result) + "\n")
    sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
