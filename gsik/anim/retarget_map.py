"""Which clip joint drives which biped frame: name heuristics for common rigs, or a mapping file.

Names are compared normalised (:func:`normalise`): namespace dropped
(``mixamorig:LeftArm`` -> ``LeftArm``), lower case, without ``_ - . `` and
spaces. A side is a ``left``/``l`` or ``right``/``r`` before or after the part
(``LeftUpLeg``, ``l_thigh``, ``Thigh_R``). The first alias present in the clip
wins, so ``Spine`` beats ``Spine1`` for the waist.

A mapping file (YAML) names clip joints for biped frames where the heuristics
miss; it overrides them one entry at a time::

    format: 1
    map:                    # biped frame: clip joint (as written in the file)
      left_hip: Bip01_L_Thigh
      left_knee: Bip01_L_Calf
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from pathlib import Path

from gsik.errors import RetargetError, choices, show_value
from gsik.io.files import read_text
from gsik.io.yaml_safe import MAX_BYTES, load_yaml

#: The keys a mapping file may have, and its format number.
MAP_KEYS = ("format", "map")
MAP_FORMAT = 1

#: Aliases (normalised) of the biped's frames without a side.
CENTRE_ALIASES = {
    "pelvis": ("hips", "hip", "pelvis", "root"),
    "waist": ("spine", "spine0", "abdomen", "lowerback", "spine1", "chest"),
    "neck": ("neck", "neck1", "lowerneck", "upperneck"),
    "atlas": ("head",),
    "head_top": ("headend", "headtop", "headtopend", "headsite", "head1"),
}
#: Aliases (normalised, without the side) of the biped's frames on each side.
SIDE_ALIASES = {
    "hip": ("upleg", "thigh", "upperleg", "femur", "hip"),
    "knee": ("leg", "shin", "knee", "calf", "lowerleg", "tibia", "shank"),
    "ankle": ("ankle", "foot"),
    "toe": ("toebase", "toe", "toes", "ball", "footend"),
    "shoulder": ("arm", "upperarm", "humerus"),
    "elbow": ("forearm", "elbow", "lowerarm", "radius"),
    "hand": ("hand", "wrist"),
}
SIDES = {"left": ("left", "l"), "right": ("right", "r")}


def normalise(name: str) -> str:
    """``name`` without its namespace, in lower case, without ``_ - .`` and spaces."""
    return re.sub(r"[\s_\-.]", "", name.rsplit(":", 1)[-1]).lower()


def _aliases() -> dict[str, tuple[str, ...]]:
    """Every biped frame and its aliases, normalised, in order of preference."""
    out = dict(CENTRE_ALIASES)
    for side, prefixes in SIDES.items():
        for part, names in SIDE_ALIASES.items():
            out[f"{side}_{part}"] = tuple(a for n in names for p in prefixes for a in (p + n, n + p))
    return out


def guess_mapping(clip_names: Sequence[str], frame_names: Sequence[str]) -> dict[str, str]:
    """Biped frame -> clip joint, for every frame in ``frame_names`` a clip name matches by alias."""
    by_norm: dict[str, str] = {}
    for name in clip_names:
        by_norm.setdefault(normalise(name), name)
    out = {}
    for frame, aliases in _aliases().items():
        if frame not in frame_names:
            continue
        hit = next((by_norm[a] for a in aliases if a in by_norm), None)
        if hit is not None and hit not in out.values():
            out[frame] = hit
    return out


def read_mapping(path: str | Path) -> dict[str, str]:
    """A mapping file's ``map`` (biped frame -> clip joint); see the module docstring."""
    # The one bounded reader every other format uses: size, depth and alias expansion limited, lines named.
    doc = load_yaml(read_text(path, "mapping file", limit=MAX_BYTES), str(path), RetargetError)
    data = doc.data
    if not isinstance(data, dict) or not isinstance(data.get("map"), dict):
        raise RetargetError(f"{path}: a mapping file needs a 'map:' of biped frame: clip joint, got "
                            f"{show_value(data)}")
    for key, value in data.items():
        if key not in MAP_KEYS:
            raise RetargetError(f"{path}:{doc.lines.get((key,), 1)}: unknown key {show_value(key)}; keys: "
                                f"{choices(MAP_KEYS)}")
    fmt = data.get("format", MAP_FORMAT)
    if type(fmt) is not int or fmt != MAP_FORMAT:
        raise RetargetError(f"{path}:{doc.lines.get(('format',), 1)}: format: {show_value(fmt)}; the mapping "
                            f"format is {MAP_FORMAT}")
    for frame, joint in data["map"].items():
        if not (_is_name(frame) and _is_name(joint)):
            raise RetargetError(f"{path}:{doc.lines.get(('map', frame), 1)}: map: {show_value(frame)}: "
                                f"{show_value(joint)}: expected biped frame: clip joint, both names")
    return {str(k): str(v) for k, v in data["map"].items()}


def _is_name(value) -> bool:
    """A name as YAML reads it: text, or a whole number (a joint named ``1``)."""
    return isinstance(value, str) or (isinstance(value, int) and not isinstance(value, bool))


def resolve_mapping(clip_names: Sequence[str], frame_names: Sequence[str],
                    overrides: Mapping[str, str] | None = None) -> dict[str, str]:
    """The heuristic mapping with ``overrides`` applied (checked against both name lists)."""
    mapping = guess_mapping(clip_names, frame_names)
    for frame, joint in (overrides or {}).items():
        if frame not in frame_names:
            raise RetargetError(f"mapping names biped frame {frame!r}, which does not exist; "
                                f"valid: {choices(frame_names)}")
        if joint not in clip_names:
            raise RetargetError(f"mapping names clip joint {joint!r} for {frame!r}, which is not in the clip; "
                                f"valid: {choices(clip_names)}")
        mapping[frame] = joint
    return mapping
