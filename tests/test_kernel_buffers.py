"""gsik.kernels.buffers: the plain step's arrays in two buffers. The compiled views are the model's arrays and the
solver's views; the step over the buffers is the step over the named arrays bit for bit; moves land in the rows the
step reads after the buffers are made again (a new root) and after the prioritised path; results own their arrays."""

import numpy as np
import pytest

import gsik
from gsik import Target, kernels
from gsik.kernels import buffers, step as step_kernels
from gsik.kinematics import kinematic_model, topology


def _model(biped, root):
    sk = biped.with_root(root)
    topo = topology(sk, root)
    return kinematic_model(sk, topo), topo


def test_the_compiled_views_are_the_model_and_the_python_views(biped):
    model, topo = _model(biped, "left_foot")
    b = buffers.make_buffers(model, topo.root_frame)
    m2, targets, W, q, ws, sc = buffers.views.py_func(b.floats, b.ints, b.sizes)  # the compiled call's cutting
    for name, a, c in zip(model._fields, model, m2):
        assert a.shape == c.shape and a.dtype == c.dtype and np.array_equal(a, c), name
    p_targets, p_W, p_q, p_ws = buffers.python_views(b)
    for a, c in zip((*targets, W, q, *ws), (*p_targets, p_W, p_q, *p_ws)):
        assert a.shape == c.shape
        assert a.__array_interface__["data"][0] == c.__array_interface__["data"][0]  # the same memory
    # Every field its own memory: writing one changes no other.
    fields = (*p_targets, p_W, p_q, *p_ws, *sc)
    for k, a in enumerate(fields):
        a[...] = k + 1.0
    for k, a in enumerate(fields):
        assert np.all(a == k + 1.0)
    assert np.array_equal(buffers.views.py_func(b.floats, b.ints, b.sizes)[0].lower, model.lower)


@pytest.mark.parametrize("paper", [False, True])
def test_the_step_over_the_buffers_is_the_step_bit_for_bit(biped, rng, paper):
    model, topo = _model(biped, biped.root)
    settings = (gsik.SolverSettings.paper() if paper else gsik.SolverSettings()).kernel_settings()
    m = topo.effector_frame.shape[0]
    b = buffers.make_buffers(model, topo.root_frame)
    targets, W, q, ws = buffers.python_views(b)
    plain = (kernels.TargetArrays(np.zeros((m, 3)), np.zeros((m, 3, 3)), np.zeros((m, 6))), np.eye(4),
             np.zeros(biped.n_dofs), kernels.make_workspace(biped.n_frames, biped.n_dofs, m))
    solver = gsik.Solver(biped)  # the rest pose's frames and effector poses to aim near
    start = solver.effector_poses()
    for frame in range(12):
        for k, name in enumerate(topo.effector_names):
            T = start[name]
            for tp, tR, tw in (targets, plain[0]):
                tp[k] = T[:3, 3] + rng.normal(0.0, 0.05, 3)
                tR[k] = T[:3, :3]
                tw[k] = (1.0, 1.0, 1.0, 0.5, 0.5, 0.5) if k % 2 else (1.0, 1.0, 1.0, 0.0, 0.0, 0.0)
            plain[0].position[k] = targets.position[k]
        if frame == 0:
            for a, c in zip((W, q, *ws), (plain[1], plain[2], *plain[3])):
                a[...] = c
            q[:] = plain[2][:] = biped.rest
            ws.R[:], ws.p[:] = solver.world_rotations(), solver.world_positions()
            plain[3].R[:], plain[3].p[:] = ws.R, ws.p
            W[:] = plain[1][:] = solver.world_from_root
            ws.lam[0] = plain[3].lam[0] = settings.damping
        a = step_kernels.step_buffers(settings, *b)
        c = step_kernels.step(model, settings, plain[0], topo.root_frame, plain[1], plain[2], plain[3])
        assert a == c
        assert np.array_equal(q, plain[2])
        for name, x, y in zip(ws._fields, ws, plain[3]):
            assert np.array_equal(x, y), name


def _same(a, b):
    assert np.array_equal(a.q, b.q)
    assert np.array_equal(a.position_errors, b.position_errors)
    assert np.array_equal(a.orientation_errors, b.orientation_errors)
    assert (a.status, a.iterations, a.sweeps, a.residual) == (b.status, b.iterations, b.sweeps, b.residual)


def test_moves_land_in_the_rows_after_a_new_root_and_the_prioritised_path(biped):
    """One solver moves the left hand's target, the other sets the replaced target, through the same changes."""
    moving, setting = gsik.Solver(biped), gsik.Solver(biped)
    poses = moving.effector_poses()
    hand = poses["left_hand"]
    for s in (moving, setting):
        s.set_targets({n: Target.from_transform(T) for n, T in poses.items()})
    for frame, (root, posture) in enumerate([("right_foot", False), ("left_foot", False), ("left_foot", True),
                                             ("left_foot", False), ("left_foot", False)]):
        for s in (moving, setting):
            s.set_root(root)  # a new root makes new buffers: the moves must write into them
            if posture:
                s.set_posture()
            elif s.posture is not None:
                s.set_posture(weights=0.0)  # off: back on the single-level path's rows
        p = hand[:3, 3] + [0.02 * (frame + 1), 0.0, -0.01]
        moving.move_target("left_hand", p, hand[:3, :3])
        setting.set_target("left_hand", Target(p, hand[:3, :3]))
        _same(moving.step(), setting.step())
        assert moving.targets == setting.targets


def test_results_own_their_arrays(biped):
    solver = gsik.Solver(biped)
    name, T = next(iter(solver.effector_poses().items()))
    T = T.copy()
    T[:3, 3] += [0.05, 0.0, 0.05]
    first = solver.step({name: Target(T[:3, 3])})
    kept = (first.q.copy(), first.position_errors.copy(), first.orientation_errors.copy())
    solver.step()
    assert all(np.array_equal(a, b) for a, b in zip(kept, first[:1] + first[6:8]))
    first.q[:] = 0.0
    first.position_errors[:] = -1.0
    assert not np.array_equal(solver.q, first.q)
    assert np.all(solver.step().position_errors >= 0.0)
