"""``gsik humanoid FILE``: which joint of a rig is which humanoid bone, how sure, by what, and what was ignored."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import TextIO

from gsik.anim.retarget_map import read_mapping
from gsik.cli.common import load_any_skeleton
from gsik.humanoid import HUMANOID_BONES, Recognition, Rig, recognise, rig_from_clip, rig_from_skeleton
from gsik.humanoid.bones import BIPED_FRAMES
from gsik.io.bvh import read_bvh


def add_command(add) -> None:
    """Register ``humanoid``; ``add(name, help, description)`` makes a sub-parser."""
    p = add("humanoid", "recognise a rig's humanoid bones (hips, spine, head, arms, legs) and print them",
            "Read a BVH clip's rig or a skeleton (bundled name, YAML, URDF) and find its humanoid bones "
            "(VRM / Unity Humanoid names: hips, spine, chest, upperChest, neck, head, per side shoulder (the "
            "clavicle), upper and lower arm, hand, upper and lower leg, foot, toes): by name for the common rig "
            "conventions, by the tree's shape where names fail. Prints each bone's joint, confidence and method, "
            "the bones not found and the joints ignored (twist, share, roll, finger, face, end, helper, other).")
    p.add_argument("file", metavar="FILE", help="a .bvh clip, a skeleton .yaml, a .urdf robot or a bundled skeleton")
    p.add_argument("--map", metavar="MAP.yaml", help="bone: joint entries that override the recognition")
    p.add_argument("--json", action="store_true", help="print JSON instead of text")
    p.set_defaults(run=cmd_humanoid)


def load_rig(spec: str) -> Rig:
    """The rig of a BVH clip (its joints and End Sites) or of any skeleton gsik loads (its joints and sites)."""
    if Path(spec).suffix.lower() == ".bvh":
        return rig_from_clip(read_bvh(spec))
    return rig_from_skeleton(load_any_skeleton(spec))


def _overrides(path: str | None) -> dict[str, str]:
    """A mapping file's entries by canonical bone (the biped's frame names of older files translated)."""
    by_frame = {f: b for b, f in BIPED_FRAMES.items()}
    return {by_frame.get(k, k): v for k, v in read_mapping(path).items()} if path else {}


def _as_dict(r: Recognition) -> dict:
    return {"bones": {b: {"joint": j, "confidence": r.confidence[b], "method": r.method[b]} for b, j in
                      r.bones.items()},
            "missing": [b for b in HUMANOID_BONES if b not in r.bones], "ignored": dict(r.ignored),
            "up": r.up.tolist(), "forward": r.forward.tolist(), "height": r.height}


def format_recognition(r: Recognition, n_joints: int) -> str:
    """The table: bone, joint, confidence, method; then the bones not found and the ignored joints by reason."""
    lines = [f"{n_joints} joints; rest pose up {_axis(r.up)}, facing {_axis(r.forward)}, "
             f"{r.height:.4g} units tall",
             f"{'bone':14} {'joint':32} {'confidence':>10}  method"]
    lines += [f"{b:14} {j:32} {r.confidence[b]:10.2f}  {r.method[b]}" for b, j in r.bones.items()]
    lines.append("not found: " + (", ".join(b for b in HUMANOID_BONES if b not in r.bones) or "none"))
    by_reason: dict[str, list[str]] = {}
    for joint, why in r.ignored.items():
        by_reason.setdefault(why, []).append(joint)
    lines.append(f"ignored: {len(r.ignored)} joints" + ("" if r.ignored else " (none)"))
    lines += [f"  {why} ({len(js)}): {', '.join(js)}" for why, js in sorted(by_reason.items())]
    return "\n".join(lines)


def _axis(v) -> str:
    """``+y`` for an axis, else the vector."""
    k = int(abs(v).argmax())
    return f"{'+' if v[k] > 0 else '-'}{'xyz'[k]}" if abs(abs(v[k]) - 1.0) < 1e-9 else str(v.round(3).tolist())


def cmd_humanoid(args: argparse.Namespace, out: TextIO) -> int:
    rig = load_rig(args.file)
    r = recognise(rig, _overrides(args.map))
    print(json.dumps(_as_dict(r), indent=2) if args.json else format_recognition(r, rig.n_joints), file=out)
    return 0
