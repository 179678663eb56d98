"""Linear blend skinning (gsik.skinning): rigid parts move with their frame, blends are weighted, in place."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from gsik.rotations import matrix_from_axis_angle, transform
from gsik.skinning import SkinBinding, skin_into, skinned


def _binding(positions, slots, weights, slot_frames, bind) -> SkinBinding:
    n = len(positions)
    normals = np.tile([0.0, 0.0, 1.0], (n, 1))
    return SkinBinding(np.array(positions, float), normals, np.array(slots), np.array(weights, float),
                       np.array(slot_frames), np.array(bind, float), np.zeros((0, 3), np.int64), np.ones((n, 3)))


def _turn(axis, angle, p) -> np.ndarray:
    return transform(matrix_from_axis_angle(np.array(axis, float), angle), np.array(p, float))


@settings(max_examples=40, deadline=None)
@given(st.floats(-3, 3), st.floats(-3, 3), st.floats(-1, 1))
def test_a_vertex_bound_to_one_frame_moves_rigidly_with_it(a, b, x):
    frames = np.stack([_turn([0, 0, 1], a, [x, 0, 0]), _turn([1, 0, 0], b, [0, x, 1])])
    bind = np.stack([np.eye(4), np.linalg.inv(_turn([0, 1, 0], 0.3, [0, 0, 1]))])
    p = np.array([[0.1, 0.2, 0.3], [0.4, -0.5, 0.6]])
    binding = _binding(p, [[0], [1]], [[1.0], [1.0]], [0, 1], bind)
    points, normals = skinned(binding, frames)
    np.testing.assert_allclose(points[0], frames[0][:3, :3] @ p[0] + frames[0][:3, 3], atol=1e-12)
    M = frames[1] @ bind[1]
    np.testing.assert_allclose(points[1], M[:3, :3] @ p[1] + M[:3, 3], atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0)


def test_weights_blend_the_frames_transforms_and_write_in_place():
    frames = np.stack([np.eye(4), transform(np.eye(3), np.array([0.0, 0.0, 1.0]))])
    binding = _binding([[1.0, 0.0, 0.0]], [[0, 1]], [[0.25, 0.75]], [0, 1], np.stack([np.eye(4)] * 2))
    points = np.zeros((1, 3))
    buffer = points
    skin_into(binding, frames, points)
    assert buffer is points
    np.testing.assert_allclose(points, [[1.0, 0.0, 0.75]])


def test_a_binding_is_frozen():
    binding = _binding([[1.0, 0.0, 0.0]], [[0]], [[1.0]], [0], np.eye(4)[None])
    assert not binding.positions.flags.writeable and not binding.bind.flags.writeable


def test_float32_buffers_get_the_same_skin_as_float64():
    """A viewer's float32 vertex buffer is written in place with the float64 result, rounded."""
    rng = np.random.default_rng(5)
    n = 50
    frames = np.stack([_turn([0, 0, 1], 0.4, [0.1, 0, 0]), _turn([1, 1, 0], -0.9, [0, 0.2, 1])])
    weights = rng.uniform(0.0, 1.0, (n, 2))
    binding = _binding(rng.normal(size=(n, 3)), np.tile([0, 1], (n, 1)), weights / weights.sum(1, keepdims=True),
                       [0, 1], np.stack([np.eye(4), np.linalg.inv(frames[1])]))
    points, normals = np.zeros((n, 3), np.float32), np.zeros((n, 3), np.float32)
    buffers = (points, normals)
    skin_into(binding, frames, points, normals)
    assert buffers[0] is points and points.dtype == np.float32
    expected_points, expected_normals = skinned(binding, frames)
    np.testing.assert_allclose(points, expected_points, atol=1e-6)
    np.testing.assert_allclose(normals, expected_normals, atol=1e-6)
