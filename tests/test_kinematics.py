"""Analytic Jacobians against finite differences, from every root."""

import numpy as np
import pytest

from gsik.kinematics import jacobian, topology, world_frames
from gsik.rotations import rotvec_from_matrix

from solver_helpers import random_q

ROOTS = ["right_foot", "left_foot", "pelvis", "head", "left_hand", "hips", "left_knee"]


def numeric_jacobian(sk, q, root, W, effectors, h=1e-6):
    frames = [sk.frame_of(n) for n in effectors]
    J = np.zeros((6 * len(frames), sk.n_dofs))
    for d in range(sk.n_dofs):
        dq = np.zeros(sk.n_dofs)
        dq[d] = h
        Rp, pp = world_frames(sk, q + dq, W, root)
        Rm, pm = world_frames(sk, q - dq, W, root)
        for k, f in enumerate(frames):
            J[6 * k: 6 * k + 3, d] = (pp[f] - pm[f]) / (2 * h)
            J[6 * k + 3: 6 * k + 6, d] = rotvec_from_matrix(Rp[f] @ Rm[f].T) / (2 * h)
    return J


@pytest.mark.parametrize("root", ROOTS)
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_jacobian_matches_finite_differences(biped, root, seed):
    q = random_q(biped, np.random.default_rng(seed))
    W = biped.frame_transforms(q)[biped.frame_of(root)]
    effectors = [n for n in biped.effector_sites if n != root]
    J = jacobian(biped, q, effectors, root, W)
    J_num = numeric_jacobian(biped, q, root, W, effectors)
    np.testing.assert_allclose(J, J_num, atol=1e-7)


def test_root_stays_pinned_and_dofs_above_it_turn_the_other_way(biped, rng):
    q = random_q(biped, rng)
    W = np.eye(4)
    W[:3, 3] = [0.3, -0.2, 0.0]
    R, p = world_frames(biped, q, W, "right_foot")
    f = biped.frame_of("right_foot")
    np.testing.assert_allclose(p[f], W[:3, 3], atol=1e-12)
    np.testing.assert_allclose(R[f], np.eye(3), atol=1e-12)
    topo = topology(biped, "right_foot")
    sign = dict(zip(biped.dof_names, topo.sign[topo.effector_names.index("left_hand")]))
    assert sign["right_knee.x"] == -1.0  # between the root and the top of the tree
    assert sign["left_elbow.x"] == 1.0
    assert sign["left_knee.x"] == 0.0  # does not move the left hand, seen from the right foot
    assert sign["right_elbow.x"] == 0.0


def test_effector_topology_lists_exactly_the_dofs_on_the_path(biped):
    topo = topology(biped, "right_foot")
    for k, name in enumerate(topo.effector_names):
        listed = set(topo.effector_dofs[k, : topo.effector_dof_count[k]])
        assert listed == set(np.flatnonzero(topo.sign[k])), name
    # Right foot to left foot: right ankle (3), knee (1), hip (3), left hip (3), knee (1), ankle (3).
    assert topo.effector_dof_count[topo.effector_names.index("left_foot")] == 14


def test_fused_linear_system_equals_the_normal_equations_of_the_jacobian(biped):
    """The kernels build J^T W J and J^T W e without forming J; check them against NumPy on J."""
    from gsik.kernels.kinematics import linear_system
    from gsik.kinematics import kinematic_model

    rng = np.random.default_rng(7)
    q = random_q(biped, rng)
    W = biped.frame_transforms(q)[biped.frame_of("right_foot")]
    topo = topology(biped, "right_foot")
    R, p = world_frames(biped, q, W, "right_foot")
    J = jacobian(biped, q, topo.effector_names, "right_foot", W)
    e = rng.normal(size=J.shape[0])
    row_w = rng.uniform(0.1, 2.0, (len(topo.effector_names), 6))
    A = np.empty((biped.n_dofs, biped.n_dofs))
    b = np.empty(biped.n_dofs)
    linear_system(kinematic_model(biped, topo), R, p, e, row_w, A, b, np.empty((2, biped.n_dofs, 6)))
    w = row_w.ravel()
    np.testing.assert_allclose(A, J.T @ (w[:, None] * J), atol=1e-12)
    np.testing.assert_allclose(b, J.T @ (w * e), atol=1e-12)
