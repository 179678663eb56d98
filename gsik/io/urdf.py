"""URDF robot descriptions: parse the kinematic tree (links and joints).

This is the file-format layer only: it reads ``<link>`` names and
``<joint>`` elements (type, parent, child, origin, axis, limits) into plain,
read-only data and checks that they form one tree. Visuals, collisions,
inertials, transmissions and other elements are ignored.

Malformed input raises :class:`~gsik.errors.UrdfError` naming the element
and the offending value (and the XML parser's line number for broken XML).
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from collections import Counter
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from gsik.errors import UrdfError, choices, show_value
from gsik.io.files import read_bytes
from gsik.io.urdf_xml import children, link_ref, local_tag, only_child, scalar_attr, vector_attr
from gsik.validate import finite_array

#: Joint types this module parses (prismatic is parsed; conversion may reject it).
JOINT_TYPES = ("revolute", "continuous", "fixed", "prismatic")
# Valid URDF, but with more than one DOF: named separately in the error message.
_UNSUPPORTED_TYPES = ("floating", "planar")
_LIMITED_TYPES = ("revolute", "prismatic")

#: Largest URDF file read [bytes] (a URDF names its meshes; it does not hold them).
MAX_URDF_BYTES = 16 * 1024 * 1024

#: Most ``<link>`` and most ``<joint>`` elements a robot may have (as many frames as a gsik skeleton may have).
MAX_URDF_ELEMENTS = 8192


def _frozen_vector(v, what: str) -> np.ndarray:
    return finite_array(v, (3,), what, UrdfError)


@dataclass(frozen=True, eq=False)
class UrdfJoint:
    """One ``<joint>`` element.

    Attributes:
        name: Joint name.
        type: ``"revolute"``, ``"continuous"``, ``"fixed"`` or ``"prismatic"``.
        parent: Parent link name.
        child: Child link name.
        origin_xyz: (3,) child frame position in the parent link frame [m].
        origin_rpy: (3,) fixed roll, pitch, yaw [rad] of the child frame
            (see :func:`matrix_from_rpy`).
        axis: (3,) unit axis in the joint (child) frame; ``(1, 0, 0)`` when
            the file has none.
        lower: Lower limit ([rad], or [m] for prismatic); ``None`` for
            continuous and fixed joints.
        upper: Upper limit, like ``lower``.
    """

    name: str
    type: str
    parent: str
    child: str
    origin_xyz: np.ndarray
    origin_rpy: np.ndarray
    axis: np.ndarray
    lower: float | None = None
    upper: float | None = None

    def __post_init__(self) -> None:
        if self.type not in JOINT_TYPES:
            raise UrdfError(f"joint {self.name!r}: unknown type {self.type!r}; expected one of {choices(JOINT_TYPES)}")
        object.__setattr__(self, "origin_xyz", _frozen_vector(self.origin_xyz, f"joint {self.name!r} origin_xyz"))
        object.__setattr__(self, "origin_rpy", _frozen_vector(self.origin_rpy, f"joint {self.name!r} origin_rpy"))
        axis = _frozen_vector(self.axis, f"joint {self.name!r} axis")
        scale = float(np.max(np.abs(axis)))
        if scale == 0.0:
            raise UrdfError(f"joint {self.name!r}: axis is zero")
        scaled = axis / scale  # components near 1e308 would overflow the norm
        scaled_norm = float(np.linalg.norm(scaled))
        if abs(scaled_norm * scale - 1.0) > 1e-12:
            axis = _frozen_vector(scaled / scaled_norm, f"joint {self.name!r} axis")
        object.__setattr__(self, "axis", axis)
        for attr in ("lower", "upper"):
            value = getattr(self, attr)
            if value is not None:
                value = float(value)
                if not np.isfinite(value):
                    raise UrdfError(f"joint {self.name!r}: {attr} limit {value} is not finite")
                object.__setattr__(self, attr, value)
        if self.lower is not None and self.upper is not None and self.lower > self.upper:
            raise UrdfError(f"joint {self.name!r}: lower limit {self.lower} > upper limit {self.upper}")

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, UrdfJoint):
            return NotImplemented
        return (
            (self.name, self.type, self.parent, self.child, self.lower, self.upper)
            == (other.name, other.type, other.parent, other.child, other.lower, other.upper)
            and np.array_equal(self.origin_xyz, other.origin_xyz)
            and np.array_equal(self.origin_rpy, other.origin_rpy)
            and np.array_equal(self.axis, other.axis)
        )

    __hash__ = None  # type: ignore[assignment]  # holds arrays

    @property
    def origin_rotation(self) -> np.ndarray:
        """(3, 3) fixed rotation of the child frame in the parent link frame."""
        return matrix_from_rpy(self.origin_rpy)


@dataclass(frozen=True, eq=False)
class UrdfRobot:
    """The kinematic tree of a URDF robot.

    Attributes:
        name: The ``<robot name>`` (empty if absent).
        links: Link names in file order.
        joints: Joints in file order (see :meth:`joints_in_tree_order`).
        root_link: The one link that is no joint's child.
    """

    name: str
    links: tuple[str, ...]
    joints: tuple[UrdfJoint, ...]
    root_link: str

    def __post_init__(self) -> None:
        object.__setattr__(self, "links", tuple(self.links))
        object.__setattr__(self, "joints", tuple(self.joints))
        root = _check_tree(self.links, self.joints)
        if root != self.root_link:
            raise UrdfError(f"root_link is {self.root_link!r} but the tree's root is {root!r}")

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, UrdfRobot):
            return NotImplemented
        return (self.name, self.links, self.joints, self.root_link) == (
            other.name,
            other.links,
            other.joints,
            other.root_link,
        )

    __hash__ = None  # type: ignore[assignment]

    @cached_property
    def _by_name(self) -> dict[str, UrdfJoint]:
        return {j.name: j for j in self.joints}

    @cached_property
    def _by_child(self) -> dict[str, UrdfJoint]:
        return {j.child: j for j in self.joints}

    @cached_property
    def _by_parent(self) -> dict[str, tuple[UrdfJoint, ...]]:
        out: dict[str, list[UrdfJoint]] = {}
        for j in self.joints:
            out.setdefault(j.parent, []).append(j)
        return {link: tuple(js) for link, js in out.items()}

    @cached_property
    def _link_set(self) -> frozenset[str]:
        return frozenset(self.links)

    def joint(self, name: str) -> UrdfJoint:
        """The joint called ``name``."""
        try:
            return self._by_name[name]
        except KeyError:
            raise UrdfError(f"robot {self.name!r} has no joint {name!r}; joints: {choices(self._by_name)}") from None

    def parent_joint(self, link: str) -> UrdfJoint | None:
        """The joint whose child is ``link``; ``None`` for the root link."""
        if link not in self._link_set:
            raise UrdfError(f"robot {self.name!r} has no link {link!r}; links: {choices(self.links)}")
        return self._by_child.get(link)

    def child_joints(self, link: str) -> tuple[UrdfJoint, ...]:
        """Joints whose parent is ``link``, in file order."""
        return self._by_parent.get(link, ())

    def joints_in_tree_order(self) -> tuple[UrdfJoint, ...]:
        """All joints depth-first from the root link (parent before child, siblings in file order)."""
        return tuple(_preorder(self.root_link, self.child_joints))


def _preorder(root: str, child_joints) -> list[UrdfJoint]:
    out: list[UrdfJoint] = []
    stack = list(reversed(child_joints(root)))
    while stack:
        joint = stack.pop()
        out.append(joint)
        stack.extend(reversed(child_joints(joint.child)))
    return out


# ---------------------------------------------------------------------------
# Rotations
# ---------------------------------------------------------------------------


def matrix_from_rpy(rpy) -> np.ndarray:
    """Rotation matrix of URDF roll, pitch, yaw: ``R = Rz(yaw) @ Ry(pitch) @ Rx(roll)``.

    Args:
        rpy: (..., 3) roll, pitch, yaw [rad] (fixed axes X, then Y, then Z).

    Returns:
        (..., 3, 3) rotation matrices.
    """
    rpy = np.asarray(rpy, dtype=float)
    if rpy.shape[-1:] != (3,):
        raise UrdfError(f"rpy must have shape (..., 3), got {rpy.shape}")
    cr, cp, cy = np.cos(rpy[..., 0]), np.cos(rpy[..., 1]), np.cos(rpy[..., 2])
    sr, sp, sy = np.sin(rpy[..., 0]), np.sin(rpy[..., 1]), np.sin(rpy[..., 2])
    R = np.empty(rpy.shape[:-1] + (3, 3))
    R[..., 0, 0] = cy * cp
    R[..., 0, 1] = cy * sp * sr - sy * cr
    R[..., 0, 2] = cy * sp * cr + sy * sr
    R[..., 1, 0] = sy * cp
    R[..., 1, 1] = sy * sp * sr + cy * cr
    R[..., 1, 2] = sy * sp * cr - cy * sr
    R[..., 2, 0] = -sp
    R[..., 2, 1] = cp * sr
    R[..., 2, 2] = cp * cr
    return R


# ---------------------------------------------------------------------------
# Parsing
# ---------------------------------------------------------------------------


def _parse_links(robot: ET.Element) -> tuple[str, ...]:
    names: list[str] = []
    seen: set[str] = set()
    for i, link in enumerate(children(robot, "link")):
        name = link.get("name")
        if not name:
            raise UrdfError(f"<link> number {i + 1} has no name attribute")
        if name in seen:
            raise UrdfError(f"duplicate link name {name!r}")
        seen.add(name)
        names.append(name)
    return tuple(names)


def _parse_limits(elem: ET.Element, jtype: str, where: str) -> tuple[float | None, float | None]:
    if jtype not in _LIMITED_TYPES:
        return None, None  # continuous and fixed joints have no position limits
    limit = only_child(elem, "limit", where)
    if limit is None:
        raise UrdfError(f"{where}: a {jtype} joint needs <limit lower=... upper=...>")
    missing = [a for a in ("lower", "upper") if limit.get(a) is None]
    if missing:
        raise UrdfError(f"{where}: <limit> has no {' or '.join(missing)} attribute")
    lower = scalar_attr(limit, "lower", f"{where} <limit>")
    upper = scalar_attr(limit, "upper", f"{where} <limit>")
    if lower > upper:
        raise UrdfError(f"{where} <limit>: lower={limit.get('lower')!r} is greater than upper={limit.get('upper')!r}")
    return lower, upper


def _parse_joint(elem: ET.Element, index: int, links: set[str]) -> UrdfJoint:
    name = elem.get("name")
    if not name:
        raise UrdfError(f"<joint> number {index + 1} has no name attribute")
    where = f"joint {name!r}"
    jtype = elem.get("type")
    if not jtype:
        raise UrdfError(f"{where} has no type attribute")
    if jtype in _UNSUPPORTED_TYPES:
        raise UrdfError(f"{where}: joint type {jtype!r} is not supported; supported: {choices(JOINT_TYPES)}")
    if jtype not in JOINT_TYPES:
        raise UrdfError(f"{where}: unknown joint type {jtype!r}; expected one of {choices(JOINT_TYPES)}")
    parent = link_ref(elem, "parent", where, links)
    child = link_ref(elem, "child", where, links)
    if parent == child:
        raise UrdfError(f"{where} connects link {parent!r} to itself")
    origin = only_child(elem, "origin", where)
    xyz = vector_attr(origin, "xyz", (0.0, 0.0, 0.0), f"{where} <origin>")
    rpy = vector_attr(origin, "rpy", (0.0, 0.0, 0.0), f"{where} <origin>")
    axis_elem = only_child(elem, "axis", where)
    axis = vector_attr(axis_elem, "xyz", (1.0, 0.0, 0.0), f"{where} <axis>")
    if not np.any(axis):
        if jtype != "fixed":
            raise UrdfError(f"{where} <axis xyz={axis_elem.get('xyz')!r}>: axis must not be zero")
        axis = np.array([1.0, 0.0, 0.0])  # exporters write "0 0 0" on fixed joints; the axis is unused
    lower, upper = _parse_limits(elem, jtype, where)
    return UrdfJoint(
        name=name,
        type=jtype,
        parent=parent,
        child=child,
        origin_xyz=xyz,
        origin_rpy=rpy,
        axis=axis,
        lower=lower,
        upper=upper,
    )


def _check_tree(links: tuple[str, ...], joints: tuple[UrdfJoint, ...]) -> str:
    """Check that links and joints form one tree; return the root link."""
    link_set = _check_links(links)
    parent_of = _parent_of(joints, link_set)
    root = _root_link(links, parent_of)
    # One root and one parent per link: whatever the root cannot reach lies on a cycle.
    reached = _reachable(root, joints)
    for n in links:
        if n not in reached:
            raise UrdfError(f"the joints form a cycle: {_a_cycle(n, parent_of)}")
    return root


def _check_links(links: tuple[str, ...]) -> set[str]:
    """At least one link, each named once; returns the names as a set."""
    if not links:
        raise UrdfError("robot has no <link>")
    link_set = set(links)
    if len(link_set) != len(links):
        dup = next(n for n, count in Counter(links).items() if count > 1)
        raise UrdfError(f"duplicate link name {dup!r}")
    return link_set


def _parent_of(joints: tuple[UrdfJoint, ...], link_set: set[str]) -> dict[str, UrdfJoint]:
    """``{child link: its joint}``; joints named once, between known links, one parent per link."""
    joint_names: set[str] = set()
    parent_of: dict[str, UrdfJoint] = {}
    for j in joints:
        if j.name in joint_names:
            raise UrdfError(f"duplicate joint name {j.name!r}")
        joint_names.add(j.name)
        for role, link in (("parent", j.parent), ("child", j.child)):
            if link not in link_set:
                raise UrdfError(f"joint {j.name!r} references unknown link {link!r} as {role}")
        if j.child in parent_of:
            raise UrdfError(
                f"link {j.child!r} has two parents: joints {parent_of[j.child].name!r} and {j.name!r}"
            )
        parent_of[j.child] = j
    return parent_of


def _root_link(links: tuple[str, ...], parent_of: dict[str, UrdfJoint]) -> str:
    """The one link that is no joint's child."""
    roots = [n for n in links if n not in parent_of]
    if len(roots) > 1:
        raise UrdfError(f"more than one root link (links that are no joint's child): {choices(roots)}")
    if not roots:
        cycle = _a_cycle(links[0], parent_of)
        raise UrdfError(f"no root link: every link is some joint's child, so the joints form a cycle: {cycle}")
    return roots[0]


def _reachable(root: str, joints: tuple[UrdfJoint, ...]) -> set[str]:
    """The links reached from ``root`` through the joints."""
    reached = {root}
    child_links: dict[str, list[str]] = {}
    for j in joints:
        child_links.setdefault(j.parent, []).append(j.child)
    stack = [root]
    while stack:
        for c in child_links.get(stack.pop(), ()):
            if c not in reached:
                reached.add(c)
                stack.append(c)
    return reached


def _a_cycle(start: str, parent_of: dict[str, UrdfJoint]) -> str:
    """Describe the cycle reached by walking up from ``start`` (each link has a parent)."""
    path = [start]
    seen = {start: 0}
    link = start
    while True:
        link = parent_of[link].parent
        if link in seen:
            loop = path[seen[link]:] + [link]
            return " <- ".join(repr(n) for n in loop)
        seen[link] = len(path)
        path.append(link)


#: Deepest nesting of XML elements (a URDF needs 4: robot, joint, limit... ).
MAX_XML_DEPTH = 256

_XML_CHUNK = 1 << 16


def _xml_root(data: str | bytes, source: str) -> ET.Element:
    """The parsed XML, fed in chunks: past :data:`MAX_URDF_ELEMENTS` links or joints, or
    :data:`MAX_XML_DEPTH` levels, the rest of the file is never parsed."""
    try:
        parser = ET.XMLPullParser(events=("start", "end"))
        depth, counts, roots = 0, {"link": 0, "joint": 0}, []
        for at in range(0, len(data), _XML_CHUNK):
            parser.feed(data[at:at + _XML_CHUNK])
            depth = _count_events(parser, depth, counts, roots, source)
        parser.close()
        _count_events(parser, depth, counts, roots, source)
        return roots[0]
    except ET.ParseError as exc:
        line = exc.position[0] if getattr(exc, "position", None) else None
        raise UrdfError(f"{source}:{line}: malformed XML: {exc}") from None
    except LookupError as exc:  # an encoding declaration Python does not know
        raise UrdfError(f"{source}: cannot decode the XML: {show_value(str(exc))}") from None
    except UnicodeError as exc:  # text holding lone surrogates cannot be encoded for the parser
        raise UrdfError(f"{source}: cannot encode the XML text: {exc.reason} at character {exc.start}") from None


def _count_events(parser: ET.XMLPullParser, depth: int, counts: dict[str, int], roots: list[ET.Element],
                  source: str) -> int:
    """Follow the parser's new events: the element depth after them (the document's element is put in
    ``roots``); refuses past the bounds."""
    for event, elem in parser.read_events():
        if event == "end":
            depth -= 1
            continue
        depth += 1
        if depth == 1:
            roots.append(elem)
        if depth > MAX_XML_DEPTH:
            raise UrdfError(f"{source}: XML elements nested deeper than {MAX_XML_DEPTH:,}; the limit is "
                            f"{MAX_XML_DEPTH:,}")
        tag = local_tag(elem.tag)
        if depth == 2 and tag in counts:
            counts[tag] += 1
            if counts[tag] > MAX_URDF_ELEMENTS:
                raise UrdfError(f"{source}: more than {MAX_URDF_ELEMENTS:,} <{tag}> elements; the limit is "
                                f"{MAX_URDF_ELEMENTS:,}")
    return depth


def _robot_from_xml(root: ET.Element, source: str) -> UrdfRobot:
    try:
        if local_tag(root.tag) != "robot":
            raise UrdfError(f"root element is <{local_tag(root.tag)}>, expected <robot>")
        links = _parse_links(root)
        link_set = set(links)
        joints: list[UrdfJoint] = []
        seen: set[str] = set()
        for i, elem in enumerate(children(root, "joint")):
            joint = _parse_joint(elem, i, link_set)
            if joint.name in seen:
                raise UrdfError(f"duplicate joint name {joint.name!r}")
            seen.add(joint.name)
            joints.append(joint)
        root_link = _check_tree(links, tuple(joints))
        return UrdfRobot(name=root.get("name", ""), links=links, joints=tuple(joints), root_link=root_link)
    except UrdfError as exc:
        raise UrdfError(f"{source}: {exc}") from None


def parse_urdf(text: str, source: str = "<string>") -> UrdfRobot:
    """Parse URDF XML text into its kinematic tree.

    Only direct children of ``<robot>`` count, so the ``<joint>`` inside a
    ``<transmission>`` is not mistaken for a kinematic joint.

    Args:
        text: The whole file.
        source: Path or label used in error messages.

    Returns:
        The robot; its arrays are read-only.

    Raises:
        UrdfError: malformed XML (``source:line:`` from the XML parser) or an
            invalid robot (message names the element and value).
    """
    return _robot_from_xml(_xml_root(text.removeprefix("\ufeff"), source), source)


def read_urdf(path: str | os.PathLike) -> UrdfRobot:
    """Read and parse a URDF file (the XML parser honours its encoding declaration).

    Raises:
        UrdfError: malformed file (message starts with the path).
        GsikFileError: the file cannot be read.
    """
    source = os.fspath(path)
    data = read_bytes(path, "URDF file", MAX_URDF_BYTES)  # bytes: the XML parser decodes them as declared
    return _robot_from_xml(_xml_root(data, source), source)


__all__ = ["JOINT_TYPES", "UrdfJoint", "UrdfRobot", "matrix_from_rpy", "parse_urdf", "read_urdf"]
