"""gsik.Target: one immutable target type, compared by value, cheap to make."""

import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import gsik
from gsik import Target
from gsik.rotations import matrix_from_quaternion, matrix_from_rotvec, quaternion_from_matrix, transform


def test_quaternion_is_kept_exactly_as_given():
    q = (0.7071067811865476, 0.0, 0.7071067811865475, 1e-17)
    t = Target([0.1, 0.2, 0.3], q)
    assert t.orientation == q
    np.testing.assert_allclose(t.rotation, matrix_from_quaternion(np.array(q)), atol=1e-15)


def test_from_transform_keeps_the_given_matrix_as_its_rotation():
    T = transform(matrix_from_rotvec([0.3, -1.2, 2.0]), [1.0, 2.0, 3.0])
    t = Target.from_transform(T, weight=2.0, position_only=True, enabled=False)
    np.testing.assert_array_equal(t.rotation, T[:3, :3])
    np.testing.assert_array_equal(t.position, T[:3, 3])
    np.testing.assert_allclose(t.orientation, quaternion_from_matrix(T[:3, :3]), atol=0)
    assert (t.weight, t.position_only, t.enabled) == (2.0, True, False)


def test_target_is_immutable_with_read_only_arrays():
    t = Target([0.0, 0.0, 1.0], np.eye(3))
    with pytest.raises(AttributeError):
        t.weight = 2.0
    with pytest.raises(ValueError):
        t.position[0] = 1.0
    with pytest.raises(ValueError):
        t.rotation[0, 0] = 0.0


def test_target_without_orientation_is_position_only():
    t = Target([0.0, 0.0, 1.0])
    assert t.position_only and not t.uses_orientation and t.orientation == (1.0, 0.0, 0.0, 0.0)


def test_value_equality_and_hash():
    T = transform(matrix_from_rotvec([0.1, 0.2, 0.3]), [0.5, 0.0, 1.0])
    a = Target.from_transform(T)
    b = Target(T[:3, 3].copy(), a.orientation)
    assert a == b and hash(a) == hash(b)
    assert a != a.replace(weight=2.0) and a != a.replace(enabled=False)
    assert len({a, b, a.replace(position_only=True)}) == 2
    assert pickle.loads(pickle.dumps(a)) == a


def test_replace_keeps_the_orientation_and_validates_the_rest():
    t = Target.from_transform(transform(matrix_from_rotvec([0.0, 0.4, 0.0]), [0.0, 0.0, 1.0]))
    moved = t.replace(position=[1.0, 2.0, 3.0])
    assert moved.rotation is t.rotation and moved.orientation == t.orientation
    with pytest.raises(gsik.TargetError, match="weight must be finite and >= 0"):
        t.replace(weight=-1.0)
    with pytest.raises(gsik.TargetError, match="unknown Target field"):
        t.replace(colour="red")


def test_matrix_slightly_off_is_reorthonormalised():
    R = matrix_from_rotvec([0.2, 0.5, -0.1]) * (1 + 1e-8)
    t = Target([0.0, 0.0, 0.0], R)
    np.testing.assert_allclose(t.rotation.T @ t.rotation, np.eye(3), atol=1e-14)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(-1.0, 1.0), min_size=4, max_size=4).filter(lambda v: np.linalg.norm(v) > 0.1))
def test_rotation_and_orientation_agree_with_the_rotation_module(v):
    q = np.array(v) / np.linalg.norm(v)
    t = Target([0.0, 0.0, 0.0], q)
    np.testing.assert_allclose(t.rotation, matrix_from_quaternion(q), atol=1e-12)
    u = Target([0.0, 0.0, 0.0], matrix_from_quaternion(q))
    np.testing.assert_allclose(np.abs(np.dot(u.orientation, q)), 1.0, atol=1e-12)
