"""Pole targets in the model, no window: where they rest, where they aim the joint, the swing they give, Reset."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import gsik
from gsik_studio.model import Document
from gsik_studio.model.pole_places import POLE_DISTANCE, aim_point, limb_of, limbs, rest_place, swing_angle

POLE_JOINTS = {"left_knee", "right_knee", "left_elbow", "right_elbow"}


def settle(doc, frames=600):
    """Step until the document says more frames would not help; True if it did within ``frames``."""
    for _ in range(frames):
        if not doc.needs_solving:
            return True
        doc.step()
    return not doc.needs_solving


@pytest.fixture(scope="module")
def crouched():
    """A document crouched 8 cm (the knees bend), settled, with its pose kept to start each test from."""
    d = Document()
    settle(d)
    d.move_target("pelvis", d.targets["pelvis"].position + (0.0, 0.0, -0.08))
    assert settle(d)
    return d.pose()


@pytest.fixture()
def doc(crouched):
    d = Document()
    d.set_pose(crouched)
    assert settle(d)
    return d


def test_poles_rest_out_in_front_of_the_knees_behind_the_elbows_and_move_nothing(doc):
    # Turning poles on restarts the settled posture's progress (the stall detector holds a creeping posture only
    # until the targets change), so the angles may shuffle in the targets' null space; no joint visibly moves.
    P0 = doc.world_positions().copy()
    doc.controls.set_poles(True)
    assert set(doc.controls.poles) == POLE_JOINTS
    assert settle(doc)
    assert np.linalg.norm(doc.world_positions() - P0, axis=1).max() < 1e-2
    P = P0  # where the poles were placed from
    for joint, pole in doc.controls.poles.items():
        limb = limb_of(doc.skeleton, joint)
        out = pole.position - P[limb.joint]
        length = np.linalg.norm(P[limb.joint] - P[limb.start]) + np.linalg.norm(P[limb.end] - P[limb.joint])
        assert np.linalg.norm(out) == pytest.approx(POLE_DISTANCE * length)
        way = 1.0 if "knee" in joint else -1.0  # the body faces +y
        assert way * out[1] > 0.6 * np.linalg.norm(out), joint
        # The solver aims the joint where it is: the pole lies in the limb's plane, on its bent side.
        np.testing.assert_allclose(doc.solver.targets[joint].position, P[limb.joint], atol=3e-3)


def _expected_swing(limb, P, pole0, pole1):
    """The angle [rad] between two poles seen along the line through the limb's ends."""
    u = P[limb.end] - P[limb.start]
    u /= np.linalg.norm(u)

    def across(p):
        v = p - P[limb.start]
        return v - (v @ u) * u

    a, b = across(pole0), across(pole1)
    return np.arctan2(np.cross(a, b) @ u, a @ b)


@pytest.mark.parametrize("joint, sideways", [("left_knee", -0.12), ("left_knee", 0.12), ("right_elbow", 0.15)])
def test_a_pole_moved_sideways_swings_its_limb_by_the_angle_it_turns_about_the_limb(doc, joint, sideways):
    doc.controls.set_poles(True)
    assert settle(doc)
    limb = limb_of(doc.skeleton, joint)
    ends = {n: T[:3, 3].copy() for n, T in doc.effector_poses().items()}
    start = doc.controls.poles[joint].position.copy()
    for step, to in ((1, start + (sideways, 0.0, 0.0)), (2, start)):  # there and back, each settled: the second
        P0 = doc.world_positions()                                       # after the solver held the first pose
        pole0 = doc.controls.poles[joint].position.copy()
        doc.controls.move_pole(joint, to)
        assert settle(doc), step
        P = doc.world_positions()
        expected = _expected_swing(limb, P0, pole0, to)
        assert np.degrees(abs(expected)) > 8.0
        assert swing_angle(limb, P0, P) == pytest.approx(expected, abs=np.radians(0.5)), step
    for name in ("pelvis", "left_foot"):  # the pole is the lowest target: no pinned effector moves for it
        assert np.linalg.norm(doc.effector_poses()[name][:3, 3] - ends[name]) < 1e-4
    others = POLE_JOINTS - {joint}
    for other in others:
        assert abs(swing_angle(limb_of(doc.skeleton, other), P0, P)) < np.radians(0.5)


def test_reset_puts_the_poles_at_their_rest_places_for_the_standing_pose_in_one_undo_step(doc):
    standing = Document()
    standing.controls.set_poles(True)  # at rest, where Reset puts them
    doc.controls.set_poles(True)
    doc.controls.move_pole("left_knee", doc.controls.poles["left_knee"].position + (-0.3, 0.1, 0.0))
    settle(doc)
    moved, q = doc.controls.pole_snapshot(), doc.q.copy()
    n = len(doc.history.commands)
    doc.reset()
    assert len(doc.history.commands) == n + 1 and doc.history.undo_text == "Reset to standing pose"
    for joint, pole in standing.controls.poles.items():
        np.testing.assert_allclose(doc.controls.poles[joint].position, pole.position, atol=1e-12)
    assert settle(doc)
    knee = doc.skeleton.dof_index("left_knee.x")
    assert abs(doc.q[knee] - doc.skeleton.rest[knee]) < np.radians(3.0)  # not the bent knee it was
    doc.undo()
    assert doc.controls.pole_snapshot() == moved
    np.testing.assert_array_equal(doc.q, q)


def test_reset_with_poles_off_keeps_them_off(doc):
    doc.reset()
    assert doc.controls.poles == {} and doc.controls.pole_snapshot() == ()


def test_limb_of_refuses_a_joint_that_is_no_limb_s_middle():
    sk = gsik.load_skeleton("biped")
    with pytest.raises(gsik.TargetError, match="'hips' is not the middle joint of a limb"):
        limb_of(sk, "hips")
    with pytest.raises(gsik.TargetError, match="no joint 'pelvis' for a pole; joints: hips, waist"):
        limb_of(sk, "pelvis")


def test_on_the_humanoid_the_elbow_s_limb_ends_at_the_wrist():
    sk = gsik.load_skeleton("humanoid")
    limb = limb_of(sk, "left_elbow")
    assert sk.frame_names[limb.start] == "left_shoulder.z" and sk.frame_names[limb.end] == "left_wrist.x"
    doc = Document(sk)
    assert set(doc.controls.pole_joints) == POLE_JOINTS


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from(sorted(POLE_JOINTS)),
       st.tuples(*[st.floats(-1.0, 1.0)] * 3))
def test_the_aim_lies_on_the_joint_s_swing_circle_in_the_plane_of_the_limb_and_the_pole(seed, joint, pole_dir):
    sk = _BIPED
    rng = np.random.default_rng(seed)
    q = sk.lower + rng.uniform(0.0, 1.0, sk.n_dofs) * (sk.upper - sk.lower)
    T = sk.frame_transforms(q)
    P = T[:, :3, 3]
    limb = limb_of(sk, joint)
    pole = P[limb.joint] + 0.4 * np.asarray(pole_dir)
    aim = aim_point(limb, P, pole)
    start, joint_p, end = P[limb.start], P[limb.joint], P[limb.end]
    # On the circle: the limb's bones keep their lengths.
    assert np.linalg.norm(aim - start) == pytest.approx(np.linalg.norm(joint_p - start), abs=1e-9)
    assert np.linalg.norm(aim - end) == pytest.approx(np.linalg.norm(joint_p - end), abs=1e-9)
    # In the plane of the limb's ends and the pole, on the pole's side of the line between the ends.
    n = np.cross(end - start, pole - start)
    if np.linalg.norm(n) > 1e-6 and np.linalg.norm(np.cross(end - start, joint_p - start)) > 1e-6:
        assert abs((aim - start) @ n) / np.linalg.norm(n) < 1e-9
        u = (end - start) / np.linalg.norm(end - start)
        across = (pole - start) - ((pole - start) @ u) * u
        assert (aim - start) @ across >= 0.0
    # No nearer point of the circle: turning the aim a little about the line moves it away from the pole.
    d = np.linalg.norm(aim - pole)
    for angle in (-0.05, 0.05):
        u = (end - start) / np.linalg.norm(end - start)
        r = aim - start
        turned = start + np.cos(angle) * r + np.sin(angle) * np.cross(u, r) + (1 - np.cos(angle)) * (u @ r) * u
        assert np.linalg.norm(turned - pole) >= d - 1e-12


def test_rest_place_is_where_the_limb_bends_even_when_it_is_straight():
    sk = _BIPED
    q = sk.rest.copy()
    for joint in ("left_knee.x", "left_elbow.x"):
        q[sk.dof_index(joint)] = 0.0  # straight
    T = sk.frame_transforms(q)
    P, R = T[:, :3, 3], T[:, :3, :3]
    for joint, way in (("left_knee", 1.0), ("left_elbow", -1.0)):  # a knee bends forwards, an elbow backwards
        limb = limb_of(sk, joint)
        out = rest_place(sk, joint, P, R) - P[limb.joint]
        out /= np.linalg.norm(out)
        line = P[limb.end] - P[limb.start]
        assert abs(out @ line) < 1e-9 * np.linalg.norm(line)  # square to the straight limb
        assert way * out[1] > 0.99


_BIPED = gsik.load_skeleton("biped")


def test_only_the_middle_joints_of_limbs_get_poles():
    sk = gsik.skeleton_from_yaml("""
name: stick
root: foot
effectors: [foot, hand]
joints:
  - {name: hips, offset: [0, 0, 1]}
  - {name: left_knee, parent: hips, offset: [0, 0, -0.5]}
  - {name: left_elbow, parent: hips, offset: [0, 0, 0.3], rotations: [{axis: x, limits: [0, 2]}]}
sites:
  - {name: foot, parent: left_knee, offset: [0, 0, -0.5]}
  - {name: hand, parent: left_elbow, offset: [0, 0, 0.3]}
""")
    assert limbs(sk, POLE_JOINTS) == {"left_elbow": limb_of(sk, "left_elbow")}  # the knee has no DOF
    assert Document(sk).controls.pole_joints == ("left_elbow",)
