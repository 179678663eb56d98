"""Tests for gsik.io.urdf: parsing, validation and the RPY convention."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gsik.errors import GsikError, GsikFileError, UrdfError
from gsik.io.urdf import UrdfJoint, UrdfRobot, matrix_from_rpy, parse_urdf, read_urdf

DATA = Path(__file__).resolve().parents[1] / "data"

ARM = """\
<?xml version="1.0"?>
<robot name="arm">
  <link name="base"/>
  <link name="upper"/>
  <link name="lower"/>
  <joint name="shoulder" type="revolute">
    <parent link="base"/>
    <child link="upper"/>
    <origin xyz="0 0 0.1" rpy="0 0 0"/>
    <axis xyz="0 0 1"/>
    <limit lower="-1.5" upper="1.5" effort="1" velocity="1"/>
  </joint>
  <joint name="elbow" type="revolute">
    <parent link="base_placeholder"/>
    <child link="lower"/>
    <origin xyz="0.5 0 0" rpy="0 0 0"/>
    <axis xyz="0 1 0"/>
    <limit lower="-2.5" upper="2.5" effort="1" velocity="1"/>
  </joint>
</robot>
""".replace("base_placeholder", "upper")


def rx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def ry(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def add_before_end(xml: str, snippet: str) -> str:
    return xml.replace("</robot>", snippet + "\n</robot>")


# ---------------------------------------------------------------------------
# Valid files
# ---------------------------------------------------------------------------


def test_humanoid_fixture():
    robot = read_urdf(DATA / "humanoid.urdf")
    assert robot.name == "mini_humanoid"
    assert robot.root_link == "pelvis"
    assert len(robot.links) == 14 and robot.links[:3] == ("pelvis", "torso", "head")
    assert len(robot.joints) == 13  # the <joint> inside <transmission> is not counted
    types = [j.type for j in robot.joints]
    assert types.count("revolute") == 9 and types.count("continuous") == 2 and types.count("fixed") == 2

    waist = robot.joint("waist")
    assert (waist.parent, waist.child) == ("pelvis", "torso")
    np.testing.assert_array_equal(waist.origin_xyz, [0, 0, 0.1])
    np.testing.assert_array_equal(waist.origin_rpy, [0, 0, 0])  # rpy omitted
    np.testing.assert_array_equal(waist.axis, [0, 0, 1])
    assert (waist.lower, waist.upper) == (-0.75, 0.75)

    shoulder = robot.joint("l_shoulder")
    np.testing.assert_array_equal(shoulder.axis, [1, 0, 0])  # URDF default axis
    np.testing.assert_array_equal(shoulder.origin_rpy, [0.3, 0, 0])
    assert shoulder.upper == 1.0  # written "1.0e0"

    neck = robot.joint("neck")
    assert neck.type == "continuous" and neck.lower is None and neck.upper is None
    np.testing.assert_array_equal(neck.axis, [0, 0, 1])  # "0 0 2" normalised

    assert robot.joint("l_wrist").lower is None  # continuous without <limit>
    camera = robot.joint("camera_mount")
    assert camera.type == "fixed" and camera.lower is None
    np.testing.assert_array_equal(camera.axis, [1, 0, 0])  # exporter's "0 0 0" on a fixed joint
    np.testing.assert_array_equal(camera.origin_rpy, [-np.pi / 2, 0, -np.pi / 2])
    # The optical frame: z forward (+x of the head), x right (-y), y down (-z).
    np.testing.assert_allclose(camera.origin_rotation, [[0, 0, 1], [-1, 0, 0], [0, -1, 0]], atol=1e-15)
    assert robot.joint("l_ankle_fixed").type == "fixed"


def test_humanoid_tree_helpers():
    robot = read_urdf(DATA / "humanoid.urdf")
    assert robot.joints[0].name == "l_elbow"  # file order is kept ...
    order = robot.joints_in_tree_order()  # ... and tree order is available
    assert [j.name for j in order] == [
        "waist", "neck", "camera_mount", "l_shoulder", "l_elbow", "l_wrist",
        "r_shoulder", "r_elbow", "l_hip", "l_knee", "l_ankle_fixed", "r_hip", "r_knee",
    ]
    placed = {robot.root_link}
    for j in order:
        assert j.parent in placed
        placed.add(j.child)
    assert placed == set(robot.links)
    assert robot.parent_joint("pelvis") is None
    assert robot.parent_joint("l_hand").name == "l_wrist"
    assert [j.name for j in robot.child_joints("torso")] == ["neck", "l_shoulder", "r_shoulder"]
    with pytest.raises(UrdfError, match="no joint 'tail'"):
        robot.joint("tail")
    with pytest.raises(UrdfError, match="no link 'tail'"):
        robot.parent_joint("tail")


def test_two_link_arm_fixture():
    robot = read_urdf(DATA / "two_link_arm.urdf")
    assert robot.name == "two_link_arm" and robot.root_link == "base"
    assert robot.links == ("base", "upper", "lower", "tool")
    assert [(j.name, j.type, j.parent, j.child) for j in robot.joints] == [
        ("shoulder", "revolute", "base", "upper"),
        ("elbow", "revolute", "upper", "lower"),
        ("tool_mount", "fixed", "lower", "tool"),
    ]
    elbow = robot.joint("elbow")
    np.testing.assert_array_equal(elbow.origin_xyz, [0.5, 0, 0])
    assert (elbow.lower, elbow.upper) == (-2.5, 2.5)


def test_arrays_are_read_only_and_frozen():
    joint = parse_urdf(ARM).joints[0]
    for a in (joint.origin_xyz, joint.origin_rpy, joint.axis):
        assert not a.flags.writeable
        with pytest.raises(ValueError):
            a[0] = 1.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        joint.name = "x"  # type: ignore[misc]


def test_single_link_robot_and_equality():
    robot = parse_urdf('<robot name="r"><link name="only"/></robot>')
    assert robot.root_link == "only" and robot.joints == ()
    assert parse_urdf(ARM) == parse_urdf(ARM)
    assert parse_urdf(ARM) != robot


def test_lenient_inputs():
    # BOM, namespaced root, no XML declaration, no robot name, limits on a
    # prismatic joint, equal lower and upper.
    text = (
        '\ufeff<robot xmlns:xacro="http://www.ros.org/wiki/xacro">'
        '<link name="a"/><link name="b"/><link name="c"/>'
        '<joint name="slide" type="prismatic"><parent link="a"/><child link="b"/>'
        '<limit lower="0" upper="0.2"/></joint>'
        '<joint name="locked" type="revolute"><parent link="b"/><child link="c"/>'
        '<limit lower="0.5" upper="0.5"/></joint>'
        "</robot>"
    )
    robot = parse_urdf(text)
    assert robot.name == "" and robot.root_link == "a"
    assert robot.joint("slide").type == "prismatic" and robot.joint("slide").upper == 0.2
    assert robot.joint("locked").lower == robot.joint("locked").upper == 0.5


def test_read_urdf_with_latin1_declaration(tmp_path):
    path = tmp_path / "latin.urdf"
    path.write_bytes(
        b'<?xml version="1.0" encoding="ISO-8859-1"?>\n'
        + '<robot name="r\u00f6bot"><link name="l"/></robot>'.encode("latin-1")
    )
    assert read_urdf(path).name == "r\u00f6bot"


def test_read_urdf_missing_file(tmp_path):
    with pytest.raises(GsikFileError) as info:
        read_urdf(tmp_path / "nope.urdf")
    assert isinstance(info.value, OSError) and "nope.urdf" in str(info.value)


# ---------------------------------------------------------------------------
# matrix_from_rpy
# ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    "rpy, expected",
    [
        ((0, 0, 0), np.eye(3)),
        ((np.pi / 2, 0, 0), [[1, 0, 0], [0, 0, -1], [0, 1, 0]]),
        ((0, np.pi / 2, 0), [[0, 0, 1], [0, 1, 0], [-1, 0, 0]]),
        ((0, 0, np.pi / 2), [[0, -1, 0], [1, 0, 0], [0, 0, 1]]),
        ((np.pi, 0, 0), [[1, 0, 0], [0, -1, 0], [0, 0, -1]]),
        # Roll first (about fixed X), then yaw (about fixed Z): R = Rz @ Rx.
        ((np.pi / 2, 0, np.pi / 2), [[0, 0, 1], [1, 0, 0], [0, 1, 0]]),
    ],
)
def test_matrix_from_rpy_known(rpy, expected):
    np.testing.assert_allclose(matrix_from_rpy(rpy), expected, atol=1e-15)


@settings(max_examples=100, deadline=None)
@given(st.tuples(*[st.floats(-2 * np.pi, 2 * np.pi, allow_nan=False)] * 3))
def test_matrix_from_rpy_is_rz_ry_rx(rpy):
    r, p, y = rpy
    R = matrix_from_rpy(rpy)
    np.testing.assert_allclose(R, rz(y) @ ry(p) @ rx(r), atol=1e-12)
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(R) == pytest.approx(1.0)


def test_matrix_from_rpy_batch():
    rpy = np.random.default_rng(0).uniform(-3, 3, (4, 5, 3))
    R = matrix_from_rpy(rpy)
    assert R.shape == (4, 5, 3, 3)
    np.testing.assert_allclose(R[2, 3], matrix_from_rpy(rpy[2, 3]))
    with pytest.raises(UrdfError, match="shape"):
        matrix_from_rpy([1.0, 2.0])


# ---------------------------------------------------------------------------
# Validation
# ---------------------------------------------------------------------------

ELBOW_LIMIT = '<limit lower="-2.5" upper="2.5" effort="1" velocity="1"/>'

INVALID = [
    # id, text, message pattern
    ("not-xml", "hello world", r"arm\.urdf:1: malformed XML: syntax error"),
    ("empty", "", r"arm\.urdf:1: malformed XML: no element found"),
    ("mismatched-tag", ARM.replace('<link name="lower"/>', '<link name="lower">'),
     r"arm\.urdf:\d+: malformed XML: mismatched tag"),
    ("mismatched-tag-line", ARM.replace("</joint>\n  <joint", "</jiont>\n  <joint", 1),
     r"arm\.urdf:12: malformed XML: mismatched tag"),
    ("two-documents", ARM + "<robot/>", r"arm\.urdf:21: malformed XML: junk after document element"),
    ("root-not-robot", '<model name="m"><link name="a"/></model>', r"root element is <model>, expected <robot>"),
    ("no-links", '<robot name="r"/>', r"robot has no <link>"),
    ("link-without-name", ARM.replace('<link name="upper"/>', "<link/>"), r"<link> number 2 has no name attribute"),
    ("duplicate-link", ARM.replace('<link name="lower"/>', '<link name="upper"/>'), r"duplicate link name 'upper'"),
    ("joint-without-name", ARM.replace('joint name="elbow"', "joint"), r"<joint> number 2 has no name attribute"),
    ("duplicate-joint", ARM.replace('name="elbow"', 'name="shoulder"'), r"duplicate joint name 'shoulder'"),
    ("joint-without-type", ARM.replace(' type="revolute">\n    <parent link="upper"', '>\n    <parent link="upper"'),
     r"joint 'elbow' has no type attribute"),
    ("unknown-type", ARM.replace('name="elbow" type="revolute"', 'name="elbow" type="hinge"'),
     r"joint 'elbow': unknown joint type 'hinge'; expected one of 'revolute', 'continuous', 'fixed', 'prismatic'"),
    ("floating-type", ARM.replace('name="elbow" type="revolute"', 'name="elbow" type="floating"'),
     r"joint 'elbow': joint type 'floating' is not supported"),
    ("no-parent", ARM.replace('<parent link="upper"/>', ""), r"joint 'elbow' has no <parent link=\.\.\.>"),
    ("no-child", ARM.replace('<child link="lower"/>', ""), r"joint 'elbow' has no <child link=\.\.\.>"),
    ("empty-child", ARM.replace('<child link="lower"/>', '<child link=""/>'),
     r"joint 'elbow' has no <child link=\.\.\.>"),
    ("two-parents-elements", ARM.replace('<parent link="upper"/>', '<parent link="upper"/><parent link="base"/>'),
     r"joint 'elbow' has 2 <parent> elements"),
    ("unknown-parent-link", ARM.replace('<parent link="upper"/>', '<parent link="uper"/>'),
     r"joint 'elbow' references unknown link 'uper' as parent"),
    ("unknown-child-link", ARM.replace('<child link="lower"/>', '<child link="forearm"/>'),
     r"joint 'elbow' references unknown link 'forearm' as child"),
    ("self-loop", ARM.replace('<child link="lower"/>', '<child link="upper"/>'),
     r"joint 'elbow' connects link 'upper' to itself"),
    ("missing-limit", ARM.replace(ELBOW_LIMIT, ""),
     r"joint 'elbow': a revolute joint needs <limit lower=\.\.\. upper=\.\.\.>"),
    ("missing-lower", ARM.replace(ELBOW_LIMIT, '<limit upper="2.5"/>'),
     r"joint 'elbow': <limit> has no lower attribute"),
    ("missing-both", ARM.replace(ELBOW_LIMIT, '<limit effort="1"/>'), r"<limit> has no lower or upper attribute"),
    ("prismatic-missing-limit",
     ARM.replace(ELBOW_LIMIT, "").replace('name="elbow" type="revolute"', 'name="elbow" type="prismatic"'),
     r"a prismatic joint needs <limit"),
    ("lower-above-upper", ARM.replace(ELBOW_LIMIT, '<limit lower="2.5" upper="-2.5"/>'),
     r"joint 'elbow' <limit>: lower='2.5' is greater than upper='-2.5'"),
    ("zero-axis", ARM.replace('<axis xyz="0 1 0"/>', '<axis xyz="0 0 0"/>'),
     r"joint 'elbow' <axis xyz='0 0 0'>: axis must not be zero"),
    ("axis-two-numbers", ARM.replace('<axis xyz="0 1 0"/>', '<axis xyz="0 1"/>'),
     r"joint 'elbow' <axis> xyz='0 1': expected 3 numbers, found 2"),
    ("non-numeric-xyz", ARM.replace('xyz="0.5 0 0"', 'xyz="0.5 0 a"'),
     r"joint 'elbow' <origin> xyz='0.5 0 a': non-numeric value 'a'"),
    ("xacro-expression",
     ARM.replace('rpy="0 0 0"/>\n    <axis xyz="0 1 0"', 'rpy="0 ${pi/2} 0"/>\n    <axis xyz="0 1 0"'),
     r"joint 'elbow' <origin> rpy='0 \$\{pi/2\} 0': non-numeric value '\$\{pi/2\}'"),
    ("nan-rpy", ARM.replace('rpy="0 0 0"/>\n    <axis xyz="0 1 0"', 'rpy="0 nan 0"/>\n    <axis xyz="0 1 0"'),
     r"joint 'elbow' <origin> rpy='0 nan 0': non-finite value 'nan'"),
    ("inf-axis", ARM.replace('<axis xyz="0 1 0"/>', '<axis xyz="0 inf 0"/>'), r"non-finite value 'inf'"),
    ("non-numeric-limit", ARM.replace(ELBOW_LIMIT, '<limit lower="-2.5" upper="big"/>'),
     r"joint 'elbow' <limit> upper='big': non-numeric value 'big'"),
    ("empty-limit", ARM.replace(ELBOW_LIMIT, '<limit lower="" upper="1"/>'), r"<limit> lower='': non-numeric value ''"),
    ("infinite-limit", ARM.replace(ELBOW_LIMIT, '<limit lower="-inf" upper="2.5"/>'),
     r"joint 'elbow' <limit> lower='-inf': non-finite value '-inf'"),
    ("two-parents",
     add_before_end(ARM, '<joint name="extra" type="fixed"><parent link="base"/><child link="lower"/></joint>'),
     r"link 'lower' has two parents: joints 'elbow' and 'extra'"),
    ("two-roots", ARM.replace('<link name="lower"/>', '<link name="lower"/><link name="box"/><link name="ball"/>'),
     r"more than one root link \(links that are no joint's child\): 'base', 'box', 'ball'"),
    ("cycle-no-root",
     add_before_end(ARM, '<joint name="back" type="fixed"><parent link="lower"/><child link="base"/></joint>'),
     r"no root link: every link is some joint's child.*cycle: 'base' <- 'lower' <- 'upper' <- 'base'"),
    ("cycle-detached", add_before_end(
        ARM.replace('<link name="lower"/>', '<link name="lower"/><link name="p"/><link name="q"/>'),
        '<joint name="pq" type="fixed"><parent link="p"/><child link="q"/></joint>'
        '<joint name="qp" type="fixed"><parent link="q"/><child link="p"/></joint>'),
     r"the joints form a cycle: 'p' <- 'q' <- 'p'"),
]


@pytest.mark.parametrize("text, pattern", [c[1:] for c in INVALID], ids=[c[0] for c in INVALID])
def test_invalid_urdf(text, pattern):
    with pytest.raises(UrdfError) as info:
        parse_urdf(text, source="arm.urdf")
    message = str(info.value)
    assert message.startswith("arm.urdf"), message
    assert re.search(pattern, message), message
    assert isinstance(info.value, GsikError) and isinstance(info.value, ValueError)


def test_read_urdf_error_names_path(tmp_path):
    path = tmp_path / "broken.urdf"
    path.write_text(ARM.replace(ELBOW_LIMIT, ""))
    with pytest.raises(UrdfError, match=re.escape(f"{path}: joint 'elbow'")):
        read_urdf(path)


@pytest.mark.parametrize(
    "kwargs, pattern",
    [
        ({"type": "ball"}, r"unknown type 'ball'"),
        ({"axis": (0, 0, 0)}, r"axis is zero"),
        ({"origin_xyz": (0, 0)}, r"origin_xyz must have shape \(3,\)"),
        ({"origin_rpy": (0, np.inf, 0)}, r"origin_rpy .* is not finite"),
        ({"lower": 1.0, "upper": 0.0}, r"lower limit 1.0 > upper limit 0.0"),
    ],
)
def test_joint_construction_is_validated(kwargs, pattern):
    base = dict(name="j", type="revolute", parent="a", child="b", origin_xyz=(0, 0, 0), origin_rpy=(0, 0, 0),
                axis=(1, 0, 0), lower=-1.0, upper=1.0)
    with pytest.raises(UrdfError, match=pattern):
        UrdfJoint(**{**base, **kwargs})


def test_robot_construction_checks_root():
    robot = parse_urdf(ARM)
    with pytest.raises(UrdfError, match="root_link is 'upper' but the tree's root is 'base'"):
        UrdfRobot(robot.name, robot.links, robot.joints, "upper")
