"""Writing BVH text: standard layout, tab indentation, one frame per line."""

from __future__ import annotations

import os

from gsik import validate
from gsik.errors import BvhError
from gsik.io.bvh.clip import BvhClip, BvhJoint
from gsik.io.files import atomic_write_text




def format_bvh(clip: BvhClip, precision: int = 6) -> str:
    """Format a clip as standard BVH text (tab indentation, one frame per line).

    Offsets and motion values are written with ``precision`` decimals, the
    frame time exactly, so ``parse_bvh(format_bvh(c))`` reproduces ``c``
    to the printed precision (End Site names are always regenerated).

    Args:
        clip: The clip.
        precision: Decimal places for offsets and motion values (>= 0).

    Returns:
        The text, ending with a newline.
    """
    validate.whole(precision, "precision", BvhError)
    if not isinstance(clip, BvhClip):
        raise BvhError(f"format_bvh needs a BvhClip, got {type(clip).__name__}")
    fmt = f"{{:.{int(precision)}f}}".format
    out = ["HIERARCHY", *_hierarchy_lines(clip, fmt)]
    out += ["MOTION", f"Frames: {clip.n_frames}", f"Frame Time: {clip.frame_time!r}"]
    out += [" ".join(fmt(v) for v in row) for row in clip.motion.tolist()]
    return "\n".join(out) + "\n"


def _hierarchy_lines(clip: BvhClip, fmt) -> list[str]:
    """The hierarchy's lines, each block indented by one tab per level."""
    out: list[str] = []
    open_blocks: list[int] = []  # joints whose '}' is still to be written

    def close_until(parent: int) -> None:
        while open_blocks and open_blocks[-1] != parent:
            open_blocks.pop()
            out.append("\t" * len(open_blocks) + "}")

    for i, joint in enumerate(clip.joints):
        close_until(joint.parent)
        out += _joint_lines(joint, i == 0, "\t" * len(open_blocks), fmt)
        open_blocks.append(i)
    close_until(-1)
    return out


def _joint_lines(joint: BvhJoint, is_root: bool, pad: str, fmt) -> list[str]:
    """A joint's head, ``{``, OFFSET and (but for an End Site) CHANNELS lines."""
    head = "End Site" if joint.is_end_site else ("ROOT " if is_root else "JOINT ") + joint.name
    lines = [pad + head, pad + "{", pad + "\tOFFSET " + " ".join(fmt(v) for v in joint.offset.tolist())]
    if not joint.is_end_site:
        lines.append(pad + f"\tCHANNELS {len(joint.channels)}" + "".join(" " + c for c in joint.channels))
    return lines


def write_bvh(path: str | os.PathLike, clip: BvhClip, precision: int = 6) -> None:
    """Write ``clip`` to ``path`` atomically (see :func:`gsik.io.files.atomic_write_text`).

    The text is formatted before the file system is touched, so a clip that
    cannot be formatted never affects an existing file.

    Raises:
        BvhError: ``clip`` or ``precision`` is invalid.
        GsikFileError: the file cannot be written.
    """
    atomic_write_text(path, format_bvh(clip, precision))
