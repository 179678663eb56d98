"""Blender's own glTF exporter and importer, for gsik's glTF tests; always run in its own process (bpy).

Two commands, each printing one line ``GSIK_BLENDER_JSON {...}`` on stdout::

    python tests/blender/blender_gltf.py make SPEC.json OUT.glb|OUT.gltf
    python tests/blender/blender_gltf.py import FILE.glb [--times 0,0.5]

``make`` builds a humanoid character the way an artist would: an armature (bones named by the spec's convention,
arms in a T- or A-pose, extra bones if asked) and a body of ellipsoids around the bones, bound by automatic weights
(``ARMATURE_AUTO``; vertices the heat solver leaves unweighted go to their nearest bone), and exports it with
Blender's glTF exporter (``.glb``, or ``.gltf`` with its buffer in a ``.bin`` next to it). The spec is a JSON
object: ``bones`` a list of ``[name, parent or null, head xyz, tail xyz]`` in Blender's world (z up, the
character facing -y, metres), ``segments`` per ellipsoid ``[u, v]`` (vertex resolution).

``import`` reads a file with ``bpy.ops.import_scene.gltf`` and returns ``bones`` (names), ``rest_heads`` and, per
time asked (seconds), ``heads``: the world head of every pose bone at that time (the scene frame
``time * fps``, where the importer places keys) or, without ``--times``, the pose as imported.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import sys

MARKER = "GSIK_BLENDER_JSON "


def _vec(v) -> list[float]:
    return [float(x) for x in v]


def _armature(bones: list) -> object:
    import bpy

    data = bpy.data.armatures.new("Armature")
    obj = bpy.data.objects.new("Armature", data)
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.view_layer.objects.active = obj
    bpy.ops.object.mode_set(mode="EDIT")
    made = {}
    for name, parent, head, tail in bones:
        eb = data.edit_bones.new(name)
        eb.head, eb.tail = head, tail
        if parent is not None:
            eb.parent = made[parent]
            eb.use_connect = False
        made[name] = eb
    bpy.ops.object.mode_set(mode="OBJECT")
    return obj


def _body(bones: list, segments: list[int]) -> object:
    """Ellipsoids around every bone, one mesh."""
    import bmesh
    import bpy
    from mathutils import Matrix, Vector

    bm = bmesh.new()
    for _name, _parent, head, tail in bones:
        h, t = Vector(head), Vector(tail)
        axis = t - h
        length = axis.length
        if length < 1e-6:
            continue
        radius = min(0.09, max(0.025, 0.3 * length))
        rot = axis.to_track_quat("Z", "Y").to_matrix().to_4x4()
        scale = Matrix.Diagonal((radius, radius, 0.6 * length, 1.0))
        matrix = Matrix.Translation((h + t) / 2) @ rot @ scale
        bmesh.ops.create_uvsphere(bm, u_segments=segments[0], v_segments=segments[1], radius=1.0, matrix=matrix)
    mesh = bpy.data.meshes.new("Body")
    bm.to_mesh(mesh)
    bm.free()
    obj = bpy.data.objects.new("Body", mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def _bind(body, armature) -> None:
    """Parent with automatic weights; unweighted vertices get their nearest bone's group at weight 1."""
    import bpy

    bpy.ops.object.select_all(action="DESELECT")
    body.select_set(True)
    armature.select_set(True)
    bpy.context.view_layer.objects.active = armature
    with contextlib.redirect_stdout(sys.stderr):
        bpy.ops.object.parent_set(type="ARMATURE_AUTO")
    bones = armature.data.bones
    for v in body.data.vertices:
        if any(g.weight > 0 for g in v.groups):
            continue
        nearest = min(bones, key=lambda b: ((b.head_local + b.tail_local) / 2 - v.co).length)
        group = body.vertex_groups.get(nearest.name) or body.vertex_groups.new(name=nearest.name)
        group.add([v.index], 1.0, "REPLACE")


def make(spec: dict, out: str) -> dict:
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    armature = _armature(spec["bones"])
    body = _body(spec["bones"], spec.get("segments", [12, 8]))
    _bind(body, armature)
    fmt = "GLB" if out.lower().endswith(".glb") else "GLTF_SEPARATE"
    with contextlib.redirect_stdout(sys.stderr):
        bpy.ops.export_scene.gltf(filepath=out, export_format=fmt, export_skins=True, export_animations=False,
                                  export_yup=True)
    return {"ok": True, "vertices": len(body.data.vertices), "bones": [b.name for b in armature.data.bones]}


def _imported_armature(path: str):
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    with contextlib.redirect_stdout(sys.stderr):
        bpy.ops.import_scene.gltf(filepath=path)
    armatures = [ob for ob in bpy.context.scene.objects if ob.type == "ARMATURE"]
    if len(armatures) != 1:
        raise RuntimeError(f"expected one armature after import, found {len(armatures)}")
    return armatures[0]


def _mesh_points() -> list[list[float]]:
    """World positions of every vertex of every skinned mesh, as evaluated (deformed) at the current frame."""
    import bpy

    depsgraph = bpy.context.evaluated_depsgraph_get()
    points = []
    for ob in bpy.context.scene.objects:
        if ob.type != "MESH" or not any(m.type == "ARMATURE" for m in ob.modifiers):
            continue
        evaluated = ob.evaluated_get(depsgraph)
        mesh = evaluated.to_mesh()
        points += [_vec(evaluated.matrix_world @ v.co) for v in mesh.vertices]
        evaluated.to_mesh_clear()
    return points


def describe(path: str, times: list[float]) -> dict:
    import bpy

    try:
        armature = _imported_armature(path)
    except Exception as exc:  # noqa: BLE001 - the error text is the result
        lines = [line.strip() for line in str(exc).splitlines() if line.strip()]
        return {"ok": False, "error": lines[-1] if lines else type(exc).__name__}
    scene = bpy.context.scene
    fps = scene.render.fps / scene.render.fps_base
    world = armature.matrix_world
    heads = {}
    for t in times:
        frame = t * fps
        scene.frame_set(int(frame), subframe=frame - int(frame))
        heads[repr(t)] = [_vec(world @ pb.head) for pb in armature.pose.bones]
    bpy.context.view_layer.update()
    action = armature.animation_data.action if armature.animation_data else None
    return {
        "ok": True,
        "bones": [pb.name for pb in armature.pose.bones],
        "rest_heads": [_vec(world @ b.head_local) for b in armature.data.bones],
        "pose_heads": [_vec(world @ pb.head) for pb in armature.pose.bones] if not times else None,
        "heads": heads,
        "frame_range": _vec(action.frame_range) if action else None,
        "fps": fps,
        "meshes": [ob.name for ob in scene.objects if ob.type == "MESH"],
        "mesh_points": _mesh_points(),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    m = sub.add_parser("make")
    m.add_argument("spec")
    m.add_argument("out")
    i = sub.add_parser("import")
    i.add_argument("path")
    i.add_argument("--times", default="")
    args = parser.parse_args(argv)
    if args.command == "make":
        with open(args.spec, encoding="utf-8") as f:
            result = make(json.load(f), args.out)
    else:
        result = describe(args.path, [float(t) for t in args.times.split(",") if t.strip()])
    sys.stdout.write(MARKER + json.dumps(result) + "\n")
    sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
