"""gsik.kernels.buffers: the plain step's arrays in two buffers. The compiled views are the model's arrays and the
solver's views (the step over them is the step over the named arrays bit for bit: tests/test_kernel_plain.py); moves
land in the rows the step reads after the buffers are made again (a new root) and after the prioritised path; results
own their arrays."""

import numpy as np

import gsik
from gsik import Target
from gsik.kernels import buffers
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
    # Every field its own memory: writing one changes no other (the scratch's int and bool work arrays are their own).
    fields = (*p_targets, p_W, p_q, *p_ws, *(a for a in sc if a.dtype == np.float64))
    for k, a in enumerate(fields):
        a[...] = k + 1.0
    for k, a in enumerate(fields):
        assert np.all(a == k + 1.0)
    assert np.array_equal(buffers.views.py_func(b.floats, b.ints, b.sizes)[0].lower, model.lower)


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
