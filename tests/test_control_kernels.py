"""The prioritised step's compiled level evaluation, packing and trial (gsik.kernels.control) against NumPy."""

import numpy as np
import pytest

from gsik import Solver, Target
from gsik.control import Controller, frame_tasks
from gsik.kernels import accept as ak
from gsik.kernels import control as ck
from gsik.kernels import priority as priority_kernel
from gsik.kinematics import jacobian, world_frames
from gsik.priority import Level, posture_factor, prioritized_step_svd
from gsik.rotations import rotvec_from_matrix


@pytest.fixture(params=["diagonal", "full"])
def problem(request, biped, rng):
    """``(controller, q, W, R, p, tasks, precision)``: hands at priority 1 (left one with its orientation), pelvis and
    left foot at 0, a posture (per-DOF weights or a full precision matrix), at a random pose within the limits."""
    solver = Solver(biped)
    poses = solver.effector_poses()
    targets = {n: Target.from_transform(poses[n]) for n in ("pelvis", "left_foot")}
    targets["left_hand"] = Target.from_transform(poses["left_hand"] @ _moved(rng), priority=1)
    targets["right_hand"] = Target(poses["right_hand"][:3, 3] + [0.1, 0.2, 0.0], position_only=True, priority=1)
    n = biped.n_dofs
    if request.param == "full":
        A = rng.normal(size=(n, n))
        precision = A @ A.T / n
    else:
        precision = rng.uniform(0.0, 2.0, n)
    from gsik.control import Posture
    posture = Posture(rng.uniform(biped.lower, biped.upper), precision)
    tasks = frame_tasks(biped, targets, solver.settings.orientation_weight)
    c = Controller(biped, tasks, posture, None, solver.settings)
    q = np.ascontiguousarray(biped.rest + 0.3 * (rng.uniform(biped.lower, biped.upper) - biped.rest))
    W = solver.world_from_root
    R, p = world_frames(biped, q, W, biped.root)
    return c, q, W, R, p, tasks, posture


def _moved(rng):
    T = np.eye(4)
    T[:3, 3] = rng.normal(scale=0.05, size=3)
    return T


def _reference_errors(tasks, R, p, biped):
    """(6m,) error rows (target minus current, position then rotation vector) in the controller's task order."""
    ordered = sorted(tasks, key=lambda t: (t.priority, t.name))
    e = []
    for t in ordered:
        f = biped.frame_of(t.name)
        e.append(np.concatenate([t.position - p[f], rotvec_from_matrix(t.rotation @ R[f].T)]))
    return ordered, np.concatenate(e)


def test_level_state_matches_numpy(problem, biped):
    c, q, W, R, p, tasks, posture = problem
    state = c._level_state(q, R, p)
    ordered, e = _reference_errors(tasks, R, p, biped)
    w = np.concatenate([t.row_weight for t in ordered])
    levels = np.repeat([t.priority for t in ordered], 6)
    cost = 0.5 * w * e * e
    g = q - posture.reference
    expected = [cost[levels == 0].sum(), cost[levels == 1].sum(), 0.5 * g @ (np.diag(posture.precision) @ g
                                                                           if posture.precision.ndim == 1
                                                                           else posture.precision @ g)]
    np.testing.assert_allclose(state.costs, expected, rtol=1e-10)
    np.testing.assert_allclose(state.error, e, atol=1e-12)
    assert state.target_cost == pytest.approx(cost.sum(), rel=1e-12)
    tol = c._settings
    pos = np.linalg.norm(e.reshape(-1, 6)[:, :3], axis=1)
    ori = np.where([t.row_weight[3] > 0 for t in ordered], np.linalg.norm(e.reshape(-1, 6)[:, 3:], axis=1), 0.0)
    prio = np.array([t.priority for t in ordered])
    met = [bool(np.all((pos[prio == k] <= 0.5 * tol.position_tolerance)
                       & (ori[prio == k] <= 0.5 * tol.orientation_tolerance))) for k in (0, 1)]
    assert state.met.tolist() == met + [False]
    assert state.converged == bool(np.all(pos <= tol.position_tolerance) and np.all(ori <= tol.orientation_tolerance))


def test_packed_levels_are_the_jacobian_rows_and_the_posture_factor(problem, biped):
    c, q, W, R, p, tasks, posture = problem
    ordered, e = _reference_errors(tasks, R, p, biped)
    c._linearise(q, R, p, e)
    wk, starts = c._work, c._tasks_in.starts
    J = jacobian(biped, q, [t.name for t in ordered], world_from_root=W)
    w = np.concatenate([t.row_weight for t in ordered])
    prio = np.repeat([t.priority for t in ordered], 6)
    for k in (0, 1):
        rows = np.flatnonzero((prio == k) & (w > 0))
        a, b = starts[k], starts[k + 1]
        np.testing.assert_allclose(wk.rows[a:b], J[rows], atol=1e-12)
        np.testing.assert_array_equal(wk.errors[a:b], e[rows])
        np.testing.assert_array_equal(wk.weights[a:b], w[rows])
    L = posture_factor(posture.precision)
    a = starts[2]
    np.testing.assert_allclose(wk.rows[a:], L, atol=1e-12)
    np.testing.assert_allclose(wk.errors[a:], L @ (posture.reference - q), atol=1e-10)
    np.testing.assert_array_equal(wk.weights[a:], 1.0)


def test_step_and_trial_match_the_svd_step_and_forward_kinematics(problem, biped):
    c, q, W, R, p, tasks, posture = problem
    state0 = c._level_state(q, R, p)
    damping = 3e-3
    dq = c._first_trial(q, W, R, p, state0, damping)
    wk, starts = c._work, c._tasks_in.starts
    base = c._settings.damping
    near = c._near
    dampings = [min(base, damping) if state0.costs[k] <= near[k] else damping for k in range(2)]
    dampings.append(base * max(1.0, damping / base))
    np.testing.assert_array_equal(wk.dampings, dampings)
    levels = [Level(wk.rows[a:b], wk.errors[a:b], wk.weights[a:b]) for a, b in zip(starts[:-1], starts[1:])]
    lo = np.minimum(np.maximum(biped.lower - q, -c._settings.max_step), 0.0)
    hi = np.maximum(np.minimum(biped.upper - q, c._settings.max_step), 0.0)
    full, below = prioritized_step_svd(levels, lo, hi, dampings), prioritized_step_svd(levels[:-1], lo, hi,
                                                                                       dampings[:-1])
    # a full posture factor's share of the step (the step minus the targets' own) is scaled onto its bound
    bound, largest = c._posture_rows.share[0], np.abs(full - below).max()
    scale = bound / largest if 0.0 < bound < largest else 1.0
    np.testing.assert_allclose(dq, below + scale * (full - below), atol=1e-7)
    assert (bound > 0.0) == (posture.precision.ndim == 2 and ck.POSTURE_SHARE > 0.0)
    q2 = np.clip(q + dq, biped.lower, biped.upper)
    np.testing.assert_array_equal(wk.q, q2)
    R2, p2 = world_frames(biped, q2, W, biped.root)
    np.testing.assert_allclose(wk.R, R2, atol=1e-13)
    np.testing.assert_allclose(wk.p, p2, atol=1e-13)
    trial = c._trial_state()[3]
    np.testing.assert_allclose(trial.costs, c._level_state(q2, R2, p2).costs, rtol=1e-12)


def test_a_non_finite_jacobian_is_reported_not_stepped(problem):
    c, q, W, R, p, tasks, posture = problem
    state0 = c._level_state(q, R, p)
    broken = R.copy()
    broken[:] = np.nan
    with pytest.raises(np.linalg.LinAlgError, match="non-finite"):
        c._first_trial(q, W, broken, p, state0, 1e-3)
    assert c._work.out[ck.O_STATUS] == priority_kernel.NOT_FINITE


def _drag_frame1(biped, tracking_steps):
    """The second frame of bench_drag's studio default: pins on the pelvis and left foot, hands pulled 0.15 m at
    priority 1, the bundled prior as the posture, the hands then moved on their circle by one frame (6 mm);
    returns ``(that frame's step's result, the solver)``."""
    from gsik.prior import bundled_prior, use_prior

    solver = Solver(biped, tracking_steps=tracking_steps)
    poses = solver.effector_poses()
    targets = {n: Target.from_transform(poses[n]) for n in ("pelvis", "left_foot")}
    for hand in ("left_hand", "right_hand"):
        targets[hand] = Target(poses[hand][:3, 3] + [0.0, 0.15, 0.0], position_only=True, priority=0)
    solver.solve(targets)
    use_prior(solver, bundled_prior("biped"))
    for hand in ("left_hand", "right_hand"):
        targets[hand] = targets[hand].replace(priority=1)
    solver.step(targets)
    angle = 2.0 * np.pi / 100
    for hand in ("left_hand", "right_hand"):
        targets[hand] = targets[hand].replace(
            position=targets[hand].position + 0.1 * np.array([np.cos(angle) - 1.0, 0.0, np.sin(angle)]))
    return solver.step(targets), solver


def test_tracking_steps_keep_a_dragged_hand_within_1_mm_where_one_linearisation_lags(biped, monkeypatch):
    monkeypatch.setattr(ck, "POSTURE_SHARE", 0.0)  # the prior's whole move: its second order breaks the hands
    (one, _), (three, solver) = _drag_frame1(biped, 1), _drag_frame1(biped, 3)
    hands = ("left_hand", "right_hand")
    assert one.iterations == 1
    assert max(one.errors()[h][0] for h in hands) > 1e-3  # the posture's move leaves a hand off by millimetres
    assert three.iterations <= 3
    assert max(three.errors()[h][0] for h in hands) <= 1e-3
    assert max(three.errors()[n][0] for n in ("pelvis", "left_foot")) <= 1e-4
    assert solver.step().iterations == 1  # nothing lags: one linearisation


def test_the_prior_s_bounded_share_keeps_the_hands_in_one_linearisation_without_restoring(biped, monkeypatch):
    """The same frame with the prior's share of the step bounded (0.07 rad, the default): one linearisation keeps
    both hands within 1 mm and the pins within 0.1 mm, and its full step is accepted without a restoring step."""
    monkeypatch.setattr(ck, "POSTURE_SHARE", 0.07)
    one, solver = _drag_frame1(biped, 1)
    assert solver._controller._posture_rows.share[0] == ck.POSTURE_SHARE > 0.0
    assert one.iterations == 1
    assert max(one.errors()[h][0] for h in ("left_hand", "right_hand")) <= 1e-3
    assert max(one.errors()[n][0] for n in ("pelvis", "left_foot")) <= 1e-4
    assert solver._controller._cache.out[ak.R_RESTORED] == 0.0 and solver._controller._cache.out[ak.R_COMMITTED]


def test_a_solve_s_settling_steps_leave_the_prior_s_share_unbounded(problem, monkeypatch):
    """With a bound set: while a solve()'s posture settles (its own gain scales the posture's step) the share is not
    bounded; after, a full factor's is again (a diagonal one's never)."""
    c, _, _, _, _, _, posture = problem
    monkeypatch.setattr(ck, "POSTURE_SHARE", 0.07)
    c.settle_steps(0.0)
    bounded = 0.07 if posture.precision.ndim == 2 else 0.0
    assert c._posture_rows.share[0] == bounded
    c.settle_steps(1e-3)
    assert c._posture_rows.share[0] == 0.0
    c.settle_steps(0.0)
    assert c._posture_rows.share[0] == bounded
