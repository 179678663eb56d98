"""Which clip joint drives which skeleton frame: the humanoid recognition of both rigs, or a mapping file.

Both rigs are read by :mod:`gsik.humanoid` (names of every common convention,
the tree's structure where names fail); a canonical bone joins a clip joint
to a skeleton frame. The bundled biped's frames are fixed
(:data:`gsik.humanoid.bones.BIPED_FRAMES`: its ``left_shoulder`` is the arm).
Beyond the canonical bones, the head's top (``headTop``) joins the clip's
head End Site (or ``HeadTop_End``) to the skeleton's ``head_top``.

A mapping file (YAML) names clip joints where the recognition misses; it
overrides it one entry at a time. Keys are canonical bones (VRM names) or,
as in files written for the biped before, the skeleton's frame names::

    format: 1
    map:                    # canonical bone (or skeleton frame): clip joint (as written in the file)
      leftUpperLeg: Bip01_L_Thigh
      left_knee: Bip01_L_Calf
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

from gsik.errors import HumanoidError, RetargetError, choices
from gsik.humanoid import HUMANOID_BONES, Rig, recognise, rig_from_skeleton
from gsik.humanoid.bones import BIPED_FRAMES
from gsik.humanoid.names import label
from gsik.io.files import read_text
from gsik.io.yaml_safe import load_yaml

#: The head's top: not a VRM bone, but a second point that carries the head's orientation.
HEAD_TOP = "headTop"
#: What retargeting cannot do without: the legs place and scale the pelvis, the neck turns it.
REQUIRED_BONES = ("leftUpperLeg", "leftLowerLeg", "leftFoot", "rightUpperLeg", "rightLowerLeg", "rightFoot", "neck")


def read_mapping(path: str | Path) -> dict[str, str]:
    """A mapping file's ``map`` (canonical bone or skeleton frame -> clip joint); see the module docstring."""
    # The one bounded reader every other format uses: size, depth and alias expansion limited, lines named.
    data = load_yaml(read_text(path, "mapping file"), str(path), RetargetError).data
    if not isinstance(data, dict) or not isinstance(data.get("map"), dict):
        raise RetargetError(f"{path}: a mapping file needs a 'map:' of bone (or skeleton frame): clip joint, "
                            f"got {data!r:.80}")
    return {str(k): str(v) for k, v in data["map"].items()}


def _head_top(rig: Rig, head: str | None) -> str | None:
    """The joint above ``head`` that marks its top: a ``HeadTop_End`` or the head's End Site."""
    if head is None:
        return None
    j = rig.names.index(head)
    return next((rig.names[c] for c in rig.children[j] if label(rig.names[c]).kind == "headTop"), None)


def skeleton_bones(skeleton) -> dict[str, str]:
    """Canonical bone (and :data:`HEAD_TOP`) -> the skeleton's frame: the biped's fixed table, else recognised."""
    targets = set(skeleton.target_names)
    if set(BIPED_FRAMES.values()) <= targets:
        out = dict(BIPED_FRAMES)
    else:
        try:
            out = dict(recognise(rig_from_skeleton(skeleton), required=REQUIRED_BONES).bones)
        except HumanoidError as e:
            raise RetargetError(f"skeleton {skeleton.name!r} is no humanoid gsik can retarget onto: {e}") from None
    top = "head_top" if "head_top" in targets else _head_top(rig_from_skeleton(skeleton), out.get("head"))
    if top is not None:
        out[HEAD_TOP] = top
    return {b: f for b, f in out.items() if f in targets}


def _canonical(overrides: Mapping[str, str], frames: Mapping[str, str]) -> dict[str, str]:
    """``overrides`` keyed by canonical bone (a skeleton frame name translated through ``frames``)."""
    by_frame = {f: b for b, f in frames.items()}
    valid = list(HUMANOID_BONES) + [HEAD_TOP] + list(by_frame)
    out = {}
    for key, joint in overrides.items():
        if key not in valid:
            raise RetargetError(f"mapping names bone or frame {key!r}, which does not exist; valid: {choices(valid)}")
        out[by_frame.get(key, key)] = joint
    return out


def resolve_mapping(rig: Rig, frames: Mapping[str, str], overrides: Mapping[str, str] | None = None,
                    clip: str = "clip") -> dict[str, str]:
    """Skeleton frame -> clip joint: the clip ``rig`` recognised (with ``overrides``, canonical bones or skeleton
    frames -> clip joints), joined to the skeleton through ``frames`` (canonical bone -> frame).

    Raises:
        RetargetError: an override names an unknown bone/frame or a joint not in the clip, or the clip lacks
            a bone of :data:`REQUIRED_BONES` (the message names them and the clip's joints).
    """
    wanted = _canonical(overrides or {}, frames)
    for bone, joint in wanted.items():
        if joint not in rig.names:
            raise RetargetError(f"mapping names clip joint {joint!r} for {bone!r}, which is not in the {clip}; "
                                f"valid: {choices(rig.names)}")
    top = wanted.pop(HEAD_TOP, None)
    try:
        bones = dict(recognise(rig, wanted, required=REQUIRED_BONES).bones)
    except HumanoidError as e:
        raise RetargetError(f"cannot retarget {clip}: {e}") from None
    top = top or _head_top(rig, bones.get("head"))
    if top is not None:
        bones[HEAD_TOP] = top
    return {frames[b]: j for b, j in bones.items() if b in frames}


__all__ = ["read_mapping", "resolve_mapping", "skeleton_bones", "REQUIRED_BONES", "HEAD_TOP"]
