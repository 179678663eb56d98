"""Humanoid characters for the glTF tests, made by Blender (tests/blender/blender_gltf.py) in several namings.

A character is a :class:`Spec`: a naming convention, a rest pose (T or A), extra bones or not, a mesh resolution.
:func:`make_character` has Blender build and export it once per spec and test session (cached in a tmp folder).
"""

from __future__ import annotations

import json
import math
import os
import subprocess
from pathlib import Path
from typing import NamedTuple

import pytest
from blender import blender_python

HARNESS = Path(__file__).with_name("blender_gltf.py")
MARKER = "GSIK_BLENDER_JSON "

#: The layout: canonical bone -> (parent, head, tail) in Blender's world (z up, facing -y, metres), left side +x.
#: Arm bones are listed for the T-pose; the A-pose turns each arm 40 degrees down about its shoulder.
LAYOUT = {
    "hips": (None, (0.0, 0.0, 0.98), (0.0, 0.0, 1.08)),
    "spine": ("hips", (0.0, 0.0, 1.08), (0.0, 0.0, 1.22)),
    "chest": ("spine", (0.0, 0.0, 1.22), (0.0, 0.0, 1.36)),
    "upperChest": ("chest", (0.0, 0.0, 1.36), (0.0, 0.0, 1.48)),
    "neck": ("upperChest", (0.0, 0.0, 1.48), (0.0, 0.0, 1.58)),
    "head": ("neck", (0.0, 0.0, 1.58), (0.0, 0.0, 1.80)),
}
for side, sx in (("left", 1.0), ("right", -1.0)):
    S = side
    LAYOUT.update({
        f"{S}Shoulder": ("upperChest", (0.03 * sx, 0.0, 1.44), (0.17 * sx, 0.0, 1.44)),
        f"{S}UpperArm": (f"{S}Shoulder", (0.17 * sx, 0.0, 1.44), (0.45 * sx, 0.0, 1.44)),
        f"{S}LowerArm": (f"{S}UpperArm", (0.45 * sx, 0.0, 1.44), (0.71 * sx, -0.01, 1.44)),
        f"{S}Hand": (f"{S}LowerArm", (0.71 * sx, -0.01, 1.44), (0.81 * sx, -0.01, 1.44)),
        f"{S}UpperLeg": ("hips", (0.10 * sx, 0.0, 0.95), (0.10 * sx, -0.02, 0.52)),
        f"{S}LowerLeg": (f"{S}UpperLeg", (0.10 * sx, -0.02, 0.52), (0.10 * sx, 0.0, 0.09)),
        f"{S}Foot": (f"{S}LowerLeg", (0.10 * sx, 0.0, 0.09), (0.10 * sx, -0.13, 0.03)),
        f"{S}Toes": (f"{S}Foot", (0.10 * sx, -0.13, 0.03), (0.10 * sx, -0.20, 0.03)),
    })

_LIMBS = ("Shoulder", "UpperArm", "LowerArm", "Hand", "UpperLeg", "LowerLeg", "Foot", "Toes")
_TORSO = ("hips", "spine", "chest", "upperChest", "neck", "head")


def _naming(torso: str, limbs: str, limb_name: str, sides: tuple[str, str]):
    """A canonical bone -> name function: ``torso``/``limbs`` are space-separated names in the orders of
    :data:`_TORSO`/:data:`_LIMBS`; ``limb_name`` formats a limb from ``{limb}`` and ``{side}`` (one of ``sides``)."""
    torso_of, limb_of = dict(zip(_TORSO, torso.split())), dict(zip(_LIMBS, limbs.split()))

    def name(bone: str) -> str:
        if bone in torso_of:
            return torso_of[bone]
        side = "left" if bone.startswith("left") else "right"
        return limb_name.format(limb=limb_of[bone[len(side):]], side=sides[side == "right"])

    return name


def _vrm(bone: str) -> str:
    return bone[0].upper() + bone[1:]


NAMINGS = {
    "mixamo": _naming("mixamorig:Hips mixamorig:Spine mixamorig:Spine1 mixamorig:Spine2 mixamorig:Neck mixamorig:Head",
                      "Shoulder Arm ForeArm Hand UpLeg Leg Foot ToeBase", "mixamorig:{side}{limb}", ("Left", "Right")),
    "unreal": _naming("pelvis spine_01 spine_02 spine_03 neck_01 head",
                      "clavicle upperarm lowerarm hand thigh calf foot ball", "{limb}_{side}", ("l", "r")),
    "vrm": _vrm,
    "rigify": _naming("DEF-spine DEF-spine.001 DEF-spine.002 DEF-spine.003 DEF-spine.004 DEF-spine.006",
                      "shoulder upper_arm forearm hand thigh shin foot toe", "DEF-{limb}.{side}", ("L", "R")),
}


class Spec(NamedTuple):
    """One test character: ``naming`` (a key of :data:`NAMINGS`), ``pose`` ("T" or "A"), extra bones or not,
    ``segments`` ([u, v] per ellipsoid) and the file ending (``.glb`` or ``.gltf``)."""

    naming: str
    pose: str = "T"
    extras: bool = False
    segments: tuple[int, int] = (12, 8)
    ending: str = ".glb"

    @property
    def stem(self) -> str:
        extra = "_extras" if self.extras else ""
        return f"{self.naming}_{self.pose}{extra}_{self.segments[0]}x{self.segments[1]}"


def _turn_arm(point, side: float, angle: float):
    """``point`` turned down by ``angle`` about the shoulder joint (the upper arm's head) of its side."""
    sx, sz = 0.17 * side, 1.44
    x, y, z = point
    dx, dz = x - sx, z - sz
    c, s = math.cos(angle), math.sin(angle)
    return (sx + c * dx + side * s * dz, y, sz - side * s * dx + c * dz)


def bones(spec: Spec) -> list:
    """``[name, parent, head, tail]`` of every bone of ``spec``, parents first."""
    name = NAMINGS[spec.naming]
    out = []
    if spec.naming == "unreal":
        out.append(["root", None, (0.0, 0.0, 0.0), (0.0, 0.0, 0.2)])
    for bone, (parent, head, tail) in LAYOUT.items():
        if spec.pose == "A" and ("Arm" in bone or "Hand" in bone):
            side = 1.0 if bone.startswith("left") else -1.0
            head, tail = _turn_arm(head, side, math.radians(40)), _turn_arm(tail, side, math.radians(40))
        parent_name = name(parent) if parent else ("root" if spec.naming == "unreal" else None)
        out.append([name(bone), parent_name, list(head), list(tail)])
    if spec.extras:
        out += _extras(out, name)
    return out


def _extras(made: list, name) -> list:
    """A twist bone on each upper arm, a two-bone index finger per hand, a prop bone in the right hand."""
    where = {b[0]: b for b in made}
    extra = []
    for side in ("left", "right"):
        upper, hand = where[name(f"{side}UpperArm")], where[name(f"{side}Hand")]
        mid = [(a + b) / 2 for a, b in zip(upper[2], upper[3])]
        extra.append([f"{upper[0]}_twist", upper[0], mid, list(upper[3])])
        tip = list(hand[3])
        step = [(b - a) * 0.4 for a, b in zip(hand[2], hand[3])]
        second = [t + s for t, s in zip(tip, step)]
        extra.append([f"{hand[0]}_index1", hand[0], tip, second])
        extra.append([f"{hand[0]}_index2", f"{hand[0]}_index1", second, [t + s for t, s in zip(second, step)]])
    hand = where[name("rightHand")]
    extra.append(["prop_sword", hand[0], list(hand[3]), [hand[3][0], hand[3][1] - 0.3, hand[3][2]]])
    return extra


def make_character(spec: Spec, folder: Path) -> Path:
    """The file Blender makes for ``spec`` in ``folder`` (made once; later calls return it)."""
    out = folder / f"{spec.stem}{spec.ending}"
    if out.exists():
        return out
    python, why = blender_python()
    if python is None:
        pytest.skip(why)
    spec_file = folder / f"{spec.stem}.json"
    spec_file.write_text(json.dumps({"bones": bones(spec), "segments": list(spec.segments)}), encoding="utf-8")
    done = subprocess.run([python, str(HARNESS), "make", str(spec_file), str(out)], capture_output=True, text=True,
                          timeout=600, env={**os.environ, "PYTHONPATH": ""})
    lines = [line for line in done.stdout.splitlines() if line.startswith(MARKER)]
    if done.returncode != 0 or len(lines) != 1 or not out.exists():
        raise RuntimeError(f"Blender could not make {out.name}, exit {done.returncode}:\n{done.stderr[-3000:]}")
    return out


def blender_read(path: Path, times: list[float] | None = None) -> dict:
    """What Blender's glTF importer makes of ``path`` (see tests/blender/blender_gltf.py)."""
    python, why = blender_python()
    if python is None:
        pytest.skip(why)
    args = [python, str(HARNESS), "import", str(path)]
    if times:
        args += ["--times", ",".join(repr(float(t)) for t in times)]
    done = subprocess.run(args, capture_output=True, text=True, timeout=600, env={**os.environ, "PYTHONPATH": ""})
    lines = [line for line in done.stdout.splitlines() if line.startswith(MARKER)]
    if done.returncode != 0 or len(lines) != 1:
        raise RuntimeError(f"Blender could not import {path.name}, exit {done.returncode}:\n{done.stderr[-3000:]}")
    result = json.loads(lines[0][len(MARKER):])
    if result.get("ok") and result.get("heads"):
        result["heads"] = {float(k): v for k, v in result["heads"].items()}
    return result
