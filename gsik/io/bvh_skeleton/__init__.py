"""BVH <-> gsik: export poses and motions as BVH clips, import a clip as a skeleton and its motion.

:mod:`gsik.io.bvh` reads and writes the file format; this module converts
between a :class:`~gsik.io.bvh.BvhClip` and a gsik :class:`~gsik.skeleton.Skeleton`
with its :class:`~gsik.anim.motion.Motion`.

Conventions of the export (:func:`motion_to_bvh`, :func:`pose_to_bvh`,
:func:`write_motion_bvh`):

* **Hierarchy.** The skeleton's own joint tree, rooted at its top joint (the
  biped's ``hips``), whatever IK root each frame used: one consistent
  hierarchy for a walk whose root alternates between the feet.
* **Root.** The ROOT has ``OFFSET 0 0 0`` and six channels: ``Xposition
  Yposition Zposition`` then three rotations, carrying the top joint's world
  position and orientation in each frame, computed by forward kinematics from
  that frame's ``(q, root, world_from_root)``. (A zero root OFFSET means
  readers that add the OFFSET to the position channels and readers that
  replace it agree.) The rotation order is :data:`EULER_ORDER` of the up axis:
  ``Zrotation Xrotation Yrotation`` for z up, ``Yrotation Xrotation
  Zrotation`` for y up (the vertical turn outermost, so a character turning
  round never meets gimbal lock).
* **Joints.** Every other gsik joint is a ``JOINT`` with its definition offset.
  A joint whose rotation axes are coordinate axes (after the up-axis change)
  and that has no fixed ``orientation`` gets its one-DOF rotations as
  channels, in its own order, angles in degrees (the biped's hip is
  ``Xrotation Yrotation Zrotation``). A joint with one or two such rotations
  gets three rotation channels all the same (``pad_rotations=True``, the
  default; Blender's importer accepts only 0 or 3): the missing axes locked
  at 0, placed where the skeleton's usual order puts them if the joint's own
  axes keep that order, else after them (the biped's knee is ``CHANNELS 3
  Xrotation Yrotation Zrotation`` z-up, the 0s changing nothing). Any other
  joint (a fixed ``orientation``, oblique axes) gets three channels in
  :data:`EULER_ORDER`, decomposed from its local rotation matrix, unwrapped
  over the frames so the angles are continuous. A joint without rotations
  gets ``CHANNELS 0``.
* **Sites.** Every site becomes a zero-channel ``JOINT`` named after the site,
  at the site's offset, holding an ``End Site`` with a zero offset. This keeps
  the sites' names (``left_hand``, ``head`` ...) in the file, so a re-imported
  clip has the same effectors; readers that draw bones show the forearm ending
  at the hand. A site's fixed orientation is not written (BVH has no place for
  it). A joint with neither child joints nor sites gets a zero ``End Site``.
  With ``end_sites=True`` a site that is its joint's only child is written as
  that joint's ``End Site`` instead (no extra bone in Blender, but the name is
  lost: a re-import calls it ``<joint>_end``).
* **Units.** ``units="cm"`` (the default: most animation tools expect
  centimetres) or ``"m"``.
* **Up axis.** ``up="z"`` (the default, gsik's own world) or ``"y"``: the
  world is turned by -90 degrees about x (:data:`Z_UP_TO_Y_UP`), applied to
  offsets, positions and rotations alike, so the rest pose stands along +y and
  the biped, which faces +y in gsik, faces -z. Coordinate-axis rotations stay
  exact: gsik x, y, z become ``Xrotation``, ``Zrotation`` (angle negated) and
  ``Yrotation``.
* Names with whitespace or braces (not allowed in BVH) have them replaced by ``_``.

Conventions of the import (:func:`import_bvh`, :func:`skeleton_from_bvh`):

* **Names** are kept as written (``mixamorig:Hips``); ``strip_namespace=True``
  drops everything up to the last ``:``. DOFs are named ``"<joint>.<axis>"``
  after the file's channel (``"mixamorig:Spine.z"`` for ``Zrotation``).
* **Joints.** The ROOT becomes the skeleton's top joint, a fixed frame: all
  its channels go into the Motion's ``world_from_root`` (per frame, with the
  top joint as the root); its definition offset and orientation are those of
  the first frame. Every other joint with rotation channels gets one one-DOF
  rotation per channel, in the file's channel order, so any order (ZXY, ZYX,
  XYZ ...) reproduces the file's forward kinematics exactly. A joint without
  channels is a fixed joint.
* **Position channels** on a non-root joint replace its offset. gsik has no
  sliding joints, so the first frame's value is used; where the value changes
  over the clip, the import reports it in ``warnings`` (and only frames with
  the first frame's value are reproduced exactly).
* **Sites.** Each ``End Site`` becomes a site named ``"<parent>_end"`` (the
  parser's name). A zero-channel ``JOINT`` without child joints whose End
  Sites all have a zero offset (what the export writes for a site) becomes a
  site named after the ``JOINT``.
* **Effectors.** By default every site, plus a site ``"<root>_site"`` at the
  top joint's origin when no site is there already (the pelvis). An explicit
  list names sites or joints; a joint gets a site ``"<joint>_site"`` at its
  origin. The skeleton's IK root is the top joint unless ``root`` says
  otherwise.
* **Units.** ``scale`` is metres per file unit. By default it is detected from
  the size of the rest pose (the hierarchy's offsets, root offset excluded):
  up to 10 units across is metres, up to 1000 centimetres, more millimetres.
* **Up axis.** ``up="auto"`` (the default) judges the whole clip
  (:func:`detect_up_reason`): the axis along which the body is tallest in the
  median frame, gravity (the lowest point keeps its height along the up axis)
  deciding close calls; a y-up file is turned to gsik's z-up world (the
  inverse of the export's turn), so an export with either ``up`` re-imports
  exactly.
* **Angles** are unwrapped per channel: a channel that jumps by about 360
  degrees between frames (-178 to +180) continues past 180 instead, so the
  motion's angles are continuous and the solver never meets a limit the clip
  only crosses by wrapping.
* **Limits.** ``limits="wide"``: [-pi, pi] for each angle; an (unwrapped)
  angle that goes further gets half a turn of room beyond the clip's range on
  both sides, so a spinning joint never meets a limit the clip does not;
  ``"from_motion"``: the clip's range of each
  angle plus ``margin`` on both sides. Either way every frame of the clip lies
  within the limits. The rest angle is 0 (the file's rest pose), clamped into
  the limits.

Writing a solved motion back (:func:`clip_with_motion`): the clip a motion
was imported from, its motion numbers replaced, so the output keeps the
input's names (namespaces included), End Sites, root OFFSET and channels,
channel orders, units, up axis, frame time and frame count.

Conversion errors raise :class:`~gsik.errors.BvhError`.
"""

from gsik.io.bvh_skeleton.conventions import (
    EULER_ORDER, LIMIT_MODES, UNITS_PER_METRE, UP_AXES, Z_UP_TO_Y_UP, BvhImportWarning, euler_from_matrix,
    matrix_from_euler,
)
from gsik.io.bvh_skeleton.export import motion_to_bvh, pose_to_bvh, write_motion_bvh
from gsik.io.bvh_skeleton.keep import clip_with_motion
from gsik.io.bvh_skeleton.importer import (BvhImport, detect_scale, detect_up, detect_up_reason, import_bvh,
                                          skeleton_from_bvh)

__all__ = [
    "EULER_ORDER",
    "LIMIT_MODES",
    "UNITS_PER_METRE",
    "UP_AXES",
    "Z_UP_TO_Y_UP",
    "BvhImport",
    "BvhImportWarning",
    "clip_with_motion",
    "detect_scale",
    "detect_up",
    "detect_up_reason",
    "euler_from_matrix",
    "import_bvh",
    "matrix_from_euler",
    "motion_to_bvh",
    "pose_to_bvh",
    "skeleton_from_bvh",
    "write_motion_bvh",
]
