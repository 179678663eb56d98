"""Tests for gsik.io.bvh: the clip's own forward kinematics and round-trip properties."""

from __future__ import annotations

import numpy as np
from bvh_cases import AXIS_MATRIX, DATA, rx, ry, rz
from hypothesis import given, settings
from hypothesis import strategies as st

from gsik.io.bvh import (
    CHANNEL_NAMES,
    BvhClip,
    BvhJoint,
    bvh_forward_kinematics,
    bvh_local_rotations,
    bvh_local_translations,
    format_bvh,
    parse_bvh,
    read_bvh,
)

# ---------------------------------------------------------------------------
# Forward kinematics
# ---------------------------------------------------------------------------

CHAIN = """\
HIERARCHY
ROOT A
{
  OFFSET 1 2 3
  CHANNELS 3 Zrotation Xrotation Yrotation
  JOINT B
  {
    OFFSET 1 0 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 0 2 0
    }
  }
}
MOTION
Frames: 2
Frame Time: 0.1
0 0 0 0 0 0
90 0 0 0 90 0
"""


def test_fk_two_joint_chain_exact():
    R, p = bvh_forward_kinematics(parse_bvh(CHAIN))
    # Rest: offsets add up.
    np.testing.assert_array_equal(p[0], [[1, 2, 3], [2, 2, 3], [2, 4, 3]])
    np.testing.assert_array_equal(R[0], np.broadcast_to(np.eye(3), (3, 3, 3)))
    # A turns 90 deg about Z: B's offset (1,0,0) becomes (0,1,0).
    # B turns 90 deg about X: the tip's (0,2,0) becomes (0,0,2), then Rz keeps it.
    np.testing.assert_array_equal(p[1], [[1, 2, 3], [1, 3, 3], [1, 3, 5]])
    np.testing.assert_array_equal(R[1, 0], [[0, -1, 0], [1, 0, 0], [0, 0, 1]])
    np.testing.assert_array_equal(R[1, 1], [[0, 0, 1], [1, 0, 0], [0, 1, 0]])
    np.testing.assert_array_equal(R[1, 2], R[1, 1])  # the End Site has no rotation of its own


def test_fk_position_channels_replace_offset():
    text = CHAIN.replace("CHANNELS 3 Zrotation Xrotation Yrotation\n  JOINT",
                         "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n  JOINT")
    text = text.replace("0 0 0 0 0 0\n90 0 0 0 90 0", "5 6 7 0 0 0 0 0 0\n5 6 7 90 0 0 0 90 0")
    R, p = bvh_forward_kinematics(parse_bvh(text))
    np.testing.assert_array_equal(p[:, 0], [[5, 6, 7], [5, 6, 7]])  # not offset + position
    np.testing.assert_array_equal(p[1, 2], [5, 7, 9])


def test_fk_partial_position_channels():
    text = CHAIN.replace("CHANNELS 3 Zrotation Xrotation Yrotation\n  JOINT", "CHANNELS 1 Yposition\n  JOINT")
    text = text.replace("0 0 0 0 0 0\n90 0 0 0 90 0", "0 0 0 0\n10 0 0 0")
    t = bvh_local_translations(parse_bvh(text))
    np.testing.assert_array_equal(t[:, 0], [[1, 0, 3], [1, 10, 3]])


def single_joint_clip(channels: tuple[str, ...], values) -> BvhClip:
    return BvhClip(
        (BvhJoint("j", -1, (0, 0, 0), channels), BvhJoint("j_end", 0, (1, 0, 0), (), is_end_site=True)),
        0.1,
        np.array([values], dtype=float),
    )


def test_channel_order_matters():
    angles = (30.0, 40.0, 50.0)  # first, second, third channel in file order
    zxy = ("Zrotation", "Xrotation", "Yrotation")
    xyz = ("Xrotation", "Yrotation", "Zrotation")
    R_zxy = bvh_local_rotations(single_joint_clip(zxy, angles))[0, 0]
    R_xyz = bvh_local_rotations(single_joint_clip(xyz, angles))[0, 0]
    np.testing.assert_allclose(R_zxy, rz(30) @ rx(40) @ ry(50), atol=1e-14)
    np.testing.assert_allclose(R_xyz, rx(30) @ ry(40) @ rz(50), atol=1e-14)
    assert not np.allclose(R_zxy, R_xyz, atol=1e-3)


def test_rotations_exact_at_quarter_turns():
    R = bvh_local_rotations(single_joint_clip(("Zrotation",), [-270.0]))[0, 0]
    np.testing.assert_array_equal(R, [[0, -1, 0], [1, 0, 0], [0, 0, 1]])
    R = bvh_local_rotations(single_joint_clip(("Yrotation",), [180.0]))[0, 0]
    np.testing.assert_array_equal(R, [[-1, 0, 0], [0, 1, 0], [0, 0, -1]])


def test_fk_fixture_matches_chain_products():
    """World transforms of a real file equal the explicit product along each chain."""
    clip = read_bvh(DATA / "walk_zxy.bvh")
    R, p = bvh_forward_kinematics(clip)
    f, j = 2, clip.joint_index("LeftForeArm_end")
    chain = []
    while j >= 0:
        chain.append(j)
        j = clip.joints[j].parent
    world_R, world_p = np.eye(3), np.zeros(3)
    for k in reversed(chain):
        joint = clip.joints[k]
        vals = dict(zip(joint.channels, clip.motion[f, clip.channel_index(k)]))
        t = np.array([vals.get(a + "position", joint.offset[i]) for i, a in enumerate("XYZ")])
        local = np.eye(3)
        for c in joint.channels:
            if c.endswith("rotation"):
                local = local @ AXIS_MATRIX[c[0]](vals[c])
        world_p = world_p + world_R @ t
        world_R = world_R @ local
    np.testing.assert_allclose(p[f, chain[0]], world_p, atol=1e-12)
    np.testing.assert_allclose(R[f, chain[0]], world_R, atol=1e-12)


# ---------------------------------------------------------------------------
# Properties
# ---------------------------------------------------------------------------

decimal_angles = st.integers(-720_000_000, 720_000_000).map(lambda n: n / 1e6)  # 6 decimals
decimal_lengths = st.integers(-10_000_000, 10_000_000).map(lambda n: n / 1e6)


@settings(max_examples=60, deadline=None)
@given(
    channels=st.lists(st.sampled_from(CHANNEL_NAMES), unique=True, max_size=6).flatmap(st.permutations),
    data=st.data(),
)
def test_random_channel_orders_round_trip(channels, data):
    channels = tuple(channels)
    n_frames = data.draw(st.integers(0, 3))
    values = data.draw(
        st.lists(st.lists(decimal_angles, min_size=len(channels), max_size=len(channels)),
                 min_size=n_frames, max_size=n_frames)
    )
    offset = data.draw(st.tuples(decimal_lengths, decimal_lengths, decimal_lengths))
    clip = BvhClip(
        (BvhJoint("j", -1, offset, channels), BvhJoint("j_end", 0, (1, 0, 0), (), is_end_site=True)),
        data.draw(st.sampled_from([1 / 30, 1 / 120, 0.04, 0.0083333])),
        np.array(values, dtype=float).reshape(n_frames, len(channels)),
    )
    again = parse_bvh(format_bvh(clip))
    assert again == clip
    # The local rotation is the product of the rotation channels in file order.
    R = bvh_local_rotations(again)
    for f in range(n_frames):
        expected = np.eye(3)
        for c, v in zip(channels, values[f]):
            if c.endswith("rotation"):
                expected = expected @ AXIS_MATRIX[c[0]](v)
        np.testing.assert_allclose(R[f, 0], expected, atol=1e-12)


@st.composite
def random_clips(draw) -> BvhClip:
    """A random hierarchy in depth-first order with random channels and motion."""
    n = draw(st.integers(1, 8))
    joints: list[BvhJoint] = []
    stack: list[int] = []
    for i in range(n):
        if i == 0:
            parent = -1
        else:
            depth = draw(st.integers(1, len(stack)))
            del stack[depth:]
            parent = stack[-1]
        ends_here = i > 0 and draw(st.booleans())
        if ends_here:
            name = f"{joints[parent].name}_end"
            if any(j.name == name for j in joints):
                ends_here = False
        if not ends_here:
            name = draw(st.from_regex(r"[A-Za-z][A-Za-z0-9_:.\-]{0,8}", fullmatch=True))
            if any(j.name == name for j in joints) or name.endswith("_end"):
                name = f"j{i}"
                while any(j.name == name for j in joints):  # a drawn name may already be "j<i>"
                    name += "x"
        channels = () if ends_here else tuple(
            draw(st.lists(st.sampled_from(CHANNEL_NAMES), unique=True, max_size=6).flatmap(st.permutations))
        )
        offset = draw(st.tuples(decimal_lengths, decimal_lengths, decimal_lengths))
        joints.append(BvhJoint(name, parent, offset, channels, is_end_site=ends_here))
        if not ends_here:
            stack.append(i)
    n_channels = sum(len(j.channels) for j in joints)
    n_frames = draw(st.integers(0, 3))
    motion = draw(st.lists(decimal_angles, min_size=n_frames * n_channels, max_size=n_frames * n_channels))
    return BvhClip(tuple(joints), 0.04, np.array(motion, dtype=float).reshape(n_frames, n_channels))


@settings(max_examples=60, deadline=None)
@given(random_clips())
def test_random_hierarchies_round_trip(clip):
    text = format_bvh(clip)
    again = parse_bvh(text)
    assert again == clip
    assert format_bvh(again) == text
    R, p = bvh_forward_kinematics(again)
    assert R.shape == (clip.n_frames, clip.n_joints, 3, 3) and p.shape == (clip.n_frames, clip.n_joints, 3)
    np.testing.assert_allclose(R @ np.swapaxes(R, -1, -2), np.broadcast_to(np.eye(3), R.shape), atol=1e-12)
