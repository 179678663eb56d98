"""Centre of mass, its Jacobian (finite differences), and support polygons."""

import numpy as np
import pytest

from gsik.balance import (body_frame, center_of_mass, com_jacobian, convex_hull, mass_model, nearest_point_inside,
                          shrink, signed_distance, support_polygon)
from gsik.kinematics import jacobian, world_frames


def _model(skeleton, rng):
    R, p = world_frames(skeleton, skeleton.rest)
    n = len(skeleton.segment_names)
    return mass_model(skeleton, rng.uniform(0.5, 10.0, n), rng.uniform(0.0, 1.0, n), R, p)


def _frame_names(skeleton, model):
    return [skeleton.frame_names[f] for f in model.body_frame]


def test_segments_are_carried_by_the_joint_that_moves_them_all(biped):
    def body(segment):
        s = biped.segment_names.index(segment)
        bones = biped.bone_frames[biped.bone_segment == s]
        return biped.frame_names[body_frame(biped, [bones[0, 0], *bones[:, 1]])]

    assert body("torso") == "waist.z"
    assert body("pelvis") == "hips"
    assert body("head") == "atlas.y"
    assert body("left_forearm") == "left_elbow.x"
    assert body("right_foot") == "right_ankle.z"


@pytest.mark.parametrize("root", ["right_foot", "pelvis", "left_hand"])
def test_com_jacobian_matches_finite_differences(biped, rng, root):
    model = _model(biped, rng)
    q = biped.clip(biped.rest + rng.normal(scale=0.3, size=biped.n_dofs))
    W = biped.frame_transforms(q)[biped.frame_of(root)]

    def com(qq):
        R, p = world_frames(biped, qq, W, root)
        return center_of_mass(model, R, p)

    R, _ = world_frames(biped, q, W, root)
    J = com_jacobian(model, R, jacobian(biped, q, _frame_names(biped, model), root, W))
    h = 1e-6
    fd = np.column_stack([(com(q + h * np.eye(biped.n_dofs)[d]) - com(q - h * np.eye(biped.n_dofs)[d])) / (2 * h)
                          for d in range(biped.n_dofs)])
    np.testing.assert_allclose(J, fd, atol=1e-8)


def test_center_of_mass_is_the_mass_weighted_mean_of_the_segment_centres(biped, rng):
    model = _model(biped, rng)
    R, p = world_frames(biped, biped.rest)
    points = p[model.body_frame] + np.einsum("sij,sj->si", R[model.body_frame], model.com_local)
    np.testing.assert_allclose(center_of_mass(model, R, p), np.average(points, axis=0, weights=model.mass))


def test_convex_hull_keeps_the_corners_counter_clockwise(rng):
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
    inside = rng.uniform(0.1, 0.9, size=(20, 2))
    hull = convex_hull(np.vstack([inside, square]))
    assert len(hull) == 4 and {tuple(c) for c in hull} == {tuple(c) for c in square}
    x, y = hull[:, 0], hull[:, 1]
    assert np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)) > 0


def test_nearest_point_inside_a_square():
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
    np.testing.assert_allclose(nearest_point_inside(square, [0.3, 0.4]), [0.3, 0.4])
    np.testing.assert_allclose(nearest_point_inside(square, [2.0, 0.5]), [1.0, 0.5])
    np.testing.assert_allclose(nearest_point_inside(square, [-1.0, 3.0]), [0.0, 1.0])
    assert signed_distance(square, [0.5, 0.5]) == pytest.approx(-0.5)
    assert signed_distance(square, [1.5, 0.5]) == pytest.approx(0.5)


def test_shrink_moves_every_edge_inwards():
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
    np.testing.assert_allclose(shrink(square, 0.1), [[0.1, 0.1], [0.9, 0.1], [0.9, 0.9], [0.1, 0.9]])
    np.testing.assert_allclose(shrink(square, 0.6), [[0.5, 0.5]])


def test_support_polygon_of_two_feet_is_the_hull_of_both_soles():
    sole = np.array([[-0.05, -0.1], [0.05, -0.1], [0.05, 0.1], [-0.05, 0.1]])
    left, right = np.eye(4), np.eye(4)
    left[:3, 3] = [-0.2, 0.0, 0.0]
    right[:3, 3] = [0.2, 0.0, 0.0]
    poly = support_polygon([left, right], [sole, sole])
    assert len(poly) == 4
    np.testing.assert_allclose(sorted(map(tuple, poly)), [(-0.25, -0.1), (-0.25, 0.1), (0.25, -0.1), (0.25, 0.1)])
    assert signed_distance(poly, [0.0, 0.0]) < 0 < signed_distance(support_polygon([left], [sole]), [0.0, 0.0])
