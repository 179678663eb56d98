"""URDF -> gsik: a robot description as a skeleton.

:mod:`gsik.io.urdf` parses the file; this module builds the
:class:`~gsik.skeleton.Skeleton`.

Naming and mapping:

* Each URDF ``<joint>`` becomes a gsik joint **named after the URDF joint**:
  offset = ``origin xyz``, fixed orientation = ``origin rpy``, and for a
  revolute or continuous joint one rotation about its ``axis`` (any
  direction), labelled ``"q"`` (DOF name ``"<joint>.q"``). So its local
  transform is ``Trans(xyz) @ Rot(rpy) @ RotAxis(axis, q)``, as URDF defines.
* Each **link** becomes a site **named after the link**, at the link's frame
  (the child frame of its joint, zero offset): every link can be an effector
  or the IK root by its name. If a link has the name of a joint, its site is
  ``"<link>_link"``.
* The root link's frame is the skeleton's top joint, a fixed frame named
  ``"<root link>_root"`` (made unique if taken), at the origin.
* Limits: revolute joints keep theirs; continuous joints get
  ``[-continuous_limit, continuous_limit]`` (default 2 pi, so the solver can
  turn through +-pi); the rest angle is 0 clamped into the limits.
* Fixed joints are fixed frames; prismatic joints are rejected
  (:class:`~gsik.errors.UrdfError`), gsik has only rotations.
* Effectors: by default the sites of the leaf links (links without child
  joints); the IK root: by default the root link's site.
* Segments: one per link, drawn from the link to each child link.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence

import numpy as np

from gsik.errors import UrdfError, choices
from gsik.skeleton import JointSpec, RotationSpec, SegmentSpec, SiteSpec, Skeleton, build_skeleton
from gsik.io.names import unique_name
from gsik.io.urdf import UrdfJoint, UrdfRobot, read_urdf

#: Label of a URDF joint's one rotation: DOF names are ``"<joint>.q"``.
DOF_LABEL = "q"


def link_site_names(robot: UrdfRobot) -> dict[str, str]:
    """``{link: site name}``: the link's own name, or ``"<link>_link"`` where a joint has that name."""
    taken = {j.name for j in robot.joints}
    out = {}
    for link in robot.links:
        name = unique_name(link if link not in taken else f"{link}_link", taken)
        taken.add(name)
        out[link] = name
    return out


def skeleton_from_urdf(
    robot_or_path: UrdfRobot | str | os.PathLike,
    effectors: Sequence[str] | None = None,
    root: str | None = None,
    continuous_limit: float = 2.0 * math.pi,
) -> Skeleton:
    """A URDF robot as a gsik skeleton (see the module's naming rules).

    Args:
        robot_or_path: A parsed :class:`~gsik.io.urdf.UrdfRobot` or a path to a URDF file.
        effectors: Link names to use as effectors (their sites; site names
            work too); default the leaf links.
        root: The IK root: a link, site or joint name; default the root link.
        continuous_limit: Limit [rad] (> 0) of continuous joints, both ways.

    Raises:
        UrdfError: a prismatic joint, an unknown effector or root (listing
            the valid links), or a bad ``continuous_limit``.
        GsikFileError: the file cannot be read.
    """
    robot = robot_or_path if isinstance(robot_or_path, UrdfRobot) else read_urdf(robot_or_path)
    continuous_limit = _check_continuous_limit(continuous_limit)
    site_of = link_site_names(robot)
    top = unique_name(f"{robot.root_link}_root", set(site_of.values()) | {j.name for j in robot.joints})
    specs, joint_of_link = _joint_specs(robot, top, continuous_limit)
    sites = [SiteSpec(site_of[link], joint_of_link[link], (0.0, 0.0, 0.0)) for link in robot.links]
    names = _Names(robot, site_of, set(joint_of_link.values()))
    if effectors is None:
        chosen = [site_of[link] for link in robot.links if not robot.child_joints(link)]
    else:
        chosen = names.effectors(effectors)
    root_name = site_of[robot.root_link] if root is None else names.resolve(root, "root")
    return build_skeleton(robot.name or "robot", specs, sites, _segments(robot, site_of), effectors=chosen,
                          root=root_name, source=f"<urdf {robot.name}>")


def _check_continuous_limit(value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not (math.isfinite(value) and value > 0):
        raise UrdfError(f"continuous_limit must be a positive angle [rad], got {value!r}")
    return float(value)


def _joint_specs(robot: UrdfRobot, top: str, continuous_limit: float) -> tuple[list[JointSpec], dict[str, str]]:
    """The joint specs, the fixed ``top`` first, and ``{link: the joint whose frame it is}``."""
    joint_of_link = {robot.root_link: top}
    specs = [JointSpec(top, None, (0.0, 0.0, 0.0))]
    for j in robot.joints_in_tree_order():
        orientation = None if not np.any(j.origin_rpy) else j.origin_rotation
        specs.append(JointSpec(j.name, joint_of_link[j.parent], tuple(j.origin_xyz), _rotations(j, continuous_limit),
                               orientation))
        joint_of_link[j.child] = j.name
    return specs, joint_of_link


def _rotations(j: UrdfJoint, continuous_limit: float) -> tuple[RotationSpec, ...]:
    """The one rotation of a revolute or continuous joint; none for a fixed one."""
    if j.type == "prismatic":
        raise UrdfError(f"prismatic joint {j.name!r} is not supported: gsik joints only rotate "
                        "(make it fixed to pose the rest of the robot)")
    if j.type not in ("revolute", "continuous"):
        return ()
    lo, hi = (float(j.lower), float(j.upper)) if j.type == "revolute" else (-continuous_limit, continuous_limit)
    return (RotationSpec(tuple(j.axis), lo, hi, min(max(0.0, lo), hi), DOF_LABEL),)


def _segments(robot: UrdfRobot, site_of: dict[str, str]) -> list[SegmentSpec]:
    """One segment per link with children, drawn from the link to each child link."""
    segments = []
    for link in robot.links:
        ends = tuple(site_of[j.child] for j in robot.child_joints(link))
        if ends:
            segments.append(SegmentSpec(link, site_of[link], ends))
    return segments


class _Names:
    """Effector and root names as the user gives them (links, sites, joints) → site or joint names."""

    def __init__(self, robot: UrdfRobot, site_of: dict[str, str], joints: set[str]) -> None:
        self.robot, self.site_of, self.sites, self.joints = robot, site_of, set(site_of.values()), joints

    def resolve(self, name: str, what: str) -> str:
        if name in self.site_of:
            return self.site_of[name]
        if name in self.sites:
            return name
        if what == "root" and name in self.joints:
            return name
        raise UrdfError(f"robot {self.robot.name!r} has no link {name!r} to use as {what}; "
                        f"links: {choices(self.robot.links)}")

    def effectors(self, effectors: Sequence[str] | str) -> list[str]:
        effectors = [effectors] if isinstance(effectors, str) else effectors
        chosen = [self.resolve(e, "an effector") for e in effectors]
        if len(set(chosen)) != len(chosen):
            raise UrdfError(f"effectors are listed twice: {list(effectors)}")
        return chosen


__all__ = ["DOF_LABEL", "link_site_names", "skeleton_from_urdf"]
