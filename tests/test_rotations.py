import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gsik import rotations as rot

unit_vectors = st.tuples(*[st.floats(-1, 1)] * 3).map(np.array).filter(lambda v: np.linalg.norm(v) > 0.1)


@given(axis=unit_vectors, angle=st.floats(0.0, np.pi))
@settings(max_examples=300, deadline=None)
def test_log_map_inverts_exp_map_over_the_whole_range(axis, angle):
    axis = axis / np.linalg.norm(axis)
    R = rot.matrix_from_axis_angle(axis, angle)
    v = rot.rotvec_from_matrix(R)
    np.testing.assert_allclose(rot.matrix_from_rotvec(v), R, atol=1e-12)
    assert abs(np.linalg.norm(v) - angle) < 1e-12


def test_log_map_near_pi_keeps_the_axis():
    axis = np.array([1.0, 2.0, -0.5]) / np.linalg.norm([1.0, 2.0, -0.5])
    for angle in (np.pi - 1e-3, np.pi - 1e-7, np.pi):
        v = rot.rotvec_from_matrix(rot.matrix_from_axis_angle(axis, angle))
        assert abs(np.linalg.norm(v) - angle) < 1e-6
        assert abs(abs(v @ axis) / np.linalg.norm(v) - 1.0) < 1e-6


@given(q=st.tuples(*[st.floats(-1, 1)] * 4).map(np.array).filter(lambda v: np.linalg.norm(v) > 0.1))
@settings(max_examples=200, deadline=None)
def test_quaternion_round_trip(q):
    q = q / np.linalg.norm(q)
    R = rot.matrix_from_quaternion(q)
    assert rot.is_rotation_matrix(R)
    q2 = rot.quaternion_from_matrix(R)
    assert q2[0] >= 0
    # q and -q are the same rotation; at w = 0 either sign is valid.
    assert min(np.abs(q2 - q).max(), np.abs(q2 + q).max()) < 1e-9


def test_quaternion_convention_is_w_first():
    # 90 degrees about z: x goes to y.
    q = np.array([np.cos(np.pi / 4), 0.0, 0.0, np.sin(np.pi / 4)])
    np.testing.assert_allclose(rot.matrix_from_quaternion(q) @ [1, 0, 0], [0, 1, 0], atol=1e-12)


@pytest.mark.parametrize("R", [np.diag([1.0, 1.0, -1.0]), np.eye(3) * 2, np.full((3, 3), np.nan), np.eye(2)])
def test_is_rotation_matrix_rejects_non_rotations(R):
    assert not rot.is_rotation_matrix(R)
