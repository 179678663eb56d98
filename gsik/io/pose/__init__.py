"""Poses as YAML files: joint angles, the pinned root and every effector target.

A pose file is plain YAML, readable and editable by hand::

    # gsik pose
    format: 1                   # version of this format
    skeleton: biped             # the skeleton's name, or its file's path (relative to this file)
    root: right_foot            # the IK root: a joint or site, pinned to the world
    root_transform:             # world transform of the root frame
      position: [0.09, 0.0505, 0.0]        # [m]
      orientation: [1.0, 0.0, 0.0, 0.0]    # unit quaternion (w, x, y, z)
    joints:                     # every degree of freedom by name, angle [rad]
      waist.x: 0.0
      waist.y: 0.0
      # ... one line per DOF, all of them (see Skeleton.dof_names)
    targets:                    # every effector of this root (all effector sites but the root)
      left_hand:
        position: [-0.19, 0.049, 0.753]    # world position [m]
        orientation: [1.0, 0.0, 0.0, 0.0]  # world orientation, unit quaternion (w, x, y, z)
        enabled: true           # optional, default true: false leaves the effector free
        weight: 1.0             # optional, default 1.0: relative importance, >= 0
        position_only: false    # optional, default false: true ignores the orientation
        priority: 0             # optional, default 0: strict priority level (0 the most important)
      # ... one entry per effector
    library:                    # optional: named poses (the studio's pose library)
      - name: reach             # unique
        root: right_foot        # ... and root_transform, joints, targets as above
    keys:                       # optional: keyed poses of a timeline
      fps: 30.0                 # optional, default 30: frames per second (0 < fps <= 1000)
      length: 61                # optional, default last key + 1: frames in the sequence
      poses:
        - frame: 0              # whole number, unique, below 100000
          root: right_foot      # ... and root_transform, joints, targets as above
    poles:                      # optional: pole targets (where a knee or elbow points)
      left_knee:                # a joint of the skeleton
        position: [0.1, 0.3, 0.5]          # world position [m]
        enabled: true           # optional, default true
    clip:                       # optional: a motion kept with the pose (a walk, an imported BVH clip)
      name: walk.bvh
      frame_time: 0.03333333333333333      # seconds per frame [s] (> 0)
      dofs: [waist.x, waist.y]  # every DOF of the skeleton, in its order: the columns of `angles`
      frames:                   # one entry per frame, at least one
        - root: right_foot      # the IK root in this frame (any joint or site)
          world_from_root: [[1.0, 0.0, 0.0, 0.09], [0.0, 1.0, 0.0, 0.05], [0.0, 0.0, 1.0, 0.0]]
                                # rows of the root's world transform: rotation | position [m]
          angles: [0.0, 0.0]    # [rad], one per DOF (not clamped: the clip is kept as it came)

Rules:

- Angles are radians, lengths metres, in the skeleton's world frame
  (for the bundled biped: z up, facing +y, right side +x).
- ``format``, ``skeleton``, ``root``, ``root_transform``, ``joints`` and
  ``targets`` are required; so are every DOF of the skeleton and every
  effector of the root, each with ``position`` and ``orientation``.
- The file is read once by :func:`gsik.io.yaml_safe.load_yaml` (bounded: no
  alias bombs, no deep nesting, no huge numbers, no tags). Target positions
  lie within ``MAX_COORDINATE`` of the origin, weights within ``MAX_WEIGHT``.
- Unknown keys, unknown joints or effectors, a target for the root itself,
  NaN or infinite numbers and quaternions that are not of unit norm
  (within 1 %) are errors (:class:`gsik.PoseError`, naming the file, the
  line, the field and the value). A quaternion a little off unit norm is
  normalised.
- An angle outside its joint's limits is clamped into them and reported as
  a warning in :attr:`PoseRead.warnings` (never silently).
- A file may also hold a ``library``: a list of named poses, each a mapping
  of ``name`` (unique) and the four pose fields above (``root``,
  ``root_transform``, ``joints``, ``targets``), read into
  :attr:`PoseRead.library`. A file without it is a single pose, as before.
- ``keys``, ``poles`` and ``clip`` (each optional) are what the studio's
  timeline and pole targets keep, read into :attr:`PoseRead.keys`,
  :attr:`PoseRead.poles` and :attr:`PoseRead.clip`. A clip's frames are
  written in full (angles and root transforms exactly), so a document reopens
  as it was saved without its BVH file; the whole file stays within the
  bounded reader's limits (a save that would exceed them is refused, naming
  the clip). A rotation must be orthonormal within 1e-6.
- Numbers are written with Python's shortest exact ``repr``, so writing a
  pose and reading it back gives exactly the same numbers.

:func:`write_pose` replaces the file atomically: a failed save leaves an
existing file untouched. This module needs NumPy and PyYAML only.
"""

from gsik.io.pose.model import (LIMIT_TOLERANCE, POSE_FORMAT, QUATERNION_NORM_TOLERANCE, SKELETON_FILE_SUFFIXES, Clip,
                                KeySequence, Pole, Pose, PoseRead)
from gsik.io.pose.read import (PoseDocument, parse_pose, pose_from_document, pose_from_yaml, read_pose,
                               read_pose_document)
from gsik.io.pose.write import pose_to_yaml, write_pose

__all__ = ["LIMIT_TOLERANCE", "POSE_FORMAT", "QUATERNION_NORM_TOLERANCE", "SKELETON_FILE_SUFFIXES", "Clip",
           "KeySequence", "Pole", "Pose", "PoseDocument",
           "PoseRead", "parse_pose", "pose_from_document", "pose_from_yaml", "pose_to_yaml", "read_pose",
           "read_pose_document", "write_pose"]
