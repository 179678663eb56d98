"""BVH motion-capture files: parse, write, and the clip's own forward kinematics.

This module is the file-format layer only: it turns BVH text into plain,
read-only data (:class:`BvhClip`) and back, without converting to a gsik
skeleton.

BVH semantics used throughout:

* A joint's local rotation is the product of its rotation channels in the
  order they are listed: ``CHANNELS 3 Zrotation Xrotation Yrotation`` gives
  ``R = Rz @ Rx @ Ry`` (angles in degrees).
* A joint's local translation is its ``OFFSET``, except that each position
  channel (``Xposition`` ...) replaces the matching offset component.
* ``End Site`` blocks become joints with no channels, named after their
  parent with an ``_end`` suffix (made unique if that name is taken).

Malformed input raises :class:`~gsik.errors.BvhError` naming the problem, the
1-based line number and the source; file-system failures raise
:class:`~gsik.errors.GsikFileError`.
"""

from gsik.io.bvh.clip import CHANNEL_NAMES, BvhClip, BvhJoint
from gsik.io.bvh.fk import bvh_forward_kinematics, bvh_local_rotations, bvh_local_translations
from gsik.io.bvh.parse import parse_bvh, read_bvh
from gsik.io.bvh.write import format_bvh, write_bvh

__all__ = [
    "CHANNEL_NAMES",
    "BvhClip",
    "BvhJoint",
    "bvh_forward_kinematics",
    "bvh_local_rotations",
    "bvh_local_translations",
    "format_bvh",
    "parse_bvh",
    "read_bvh",
    "write_bvh",
]
