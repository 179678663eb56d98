"""gsik.kernels.plain: the single-level step and solve through one held compiled object give the numbers of the
previous paths bit for bit: the bounded solve whatever its held work arrays hold; ``Solver.step`` as the step kernel
called with the named arrays; ``Solver.solve`` (its first attempt in one compiled call returning the statistics) as
the attempts' general path, the state it leaves included (a next step and solve agree too)."""

import gc
import math
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import gsik
from gsik import Target, kernels
from gsik._jit import njit, python_function
from gsik.io.urdf_skeleton import skeleton_from_urdf
from gsik.kernels import O_RESIDUAL, buffers, pgs, plain
from gsik.kernels import step as step_kernels
from gsik.kinematics import kinematic_model, topology

ARM = Path(__file__).parent / "data" / "seven_dof_arm.urdf"
#: The arm's bent pose (shoulder x, y, z, elbow, wrist z, y, x) [rad].
BENT = np.array([0.6, 0.2, 0.0, 1.2, 0.0, 0.0, 0.0])


@pytest.fixture(scope="module")
def arm() -> gsik.Skeleton:
    return skeleton_from_urdf(ARM, effectors=["hand"], root="base")


def _box_problem(rng, n: int, least_damping: float, b_scales: tuple | None, x_scale: float) -> tuple:
    """``(A (n, n), b (n,), lo (n,), hi (n,), x0 (n,))``: damped normal equations of a random (n + 2, n) Jacobian,
    a box holding 0 and a start inside it; ``b`` of unit scale, or of a scale drawn from ``b_scales``."""
    J = rng.normal(size=(n + 2, n))
    A = J.T @ J + rng.uniform(least_damping, 1e-1) * np.eye(n)
    b = rng.normal(size=n) if b_scales is None else rng.normal(scale=rng.uniform(*b_scales), size=n)
    half = rng.uniform(0.01, 2.0, n)
    lo, hi = -half * rng.uniform(0.0, 1.0, n), half
    return A, b, lo, hi, np.clip(rng.normal(scale=x_scale, size=n), lo, hi)


@settings(max_examples=60, deadline=None)
@given(n=st.integers(1, 12), seed=st.integers(0, 2 ** 32 - 1), sweeps=st.integers(0, 12),
       garbage=st.sampled_from([np.nan, 1e300, -3.0]))
def test_bounded_solve_in_is_bounded_solve_whatever_its_work_arrays_hold(n, seed, sweeps, garbage):
    A, b, lo, hi, x0 = _box_problem(np.random.default_rng(seed), n, 1e-6, None, 0.5)
    x_a, x_b = x0.copy(), x0.copy()
    st_a, st_b = np.zeros(kernels.N_STATS), np.zeros(kernels.N_STATS)
    pgs.bounded_solve(A, b, x_a, lo, hi, sweeps, st_a)
    pgs.bounded_solve_in(A, b, x_b, lo, hi, sweeps, st_b, np.full(n, 10 ** 9, dtype=np.int64),
                         np.ones(n, dtype=np.bool_), np.full((n, n), garbage), np.full(n, garbage))
    assert np.array_equal(x_a, x_b)
    assert np.array_equal(st_a, st_b)


@settings(max_examples=80, deadline=None)
@given(n=st.integers(1, 8), seed=st.integers(0, 2 ** 32 - 1), sweeps=st.integers(1, 12))
def test_bounded_solve_stopped_early_is_the_whole_answer_inside_the_box_or_says_not(n, seed, sweeps):
    """``until_inside``: sweeps stopped early give the whole system's answer when it lies inside the box (a step's
    usual case, the box's minimiser), False when it does not (the step then solves again without it), and the
    full path's numbers when no sweep left every unknown inside."""
    A, b, lo, hi, x0 = _box_problem(np.random.default_rng(seed), n, 1e-3, (0.01, 1.0), 0.1)
    x_full, x_early = x0.copy(), x0.copy()
    st_full, st_early = np.zeros(kernels.N_STATS), np.zeros(kernels.N_STATS)
    pgs.bounded_solve(A, b, x_full, lo, hi, sweeps, st_full)
    done = pgs.bounded_solve_in(A, b, x_early, lo, hi, sweeps, st_early, np.empty(n, dtype=np.int64),
                                np.empty(n, dtype=np.bool_), np.empty((n, n)), np.empty(n), True)
    whole = np.linalg.solve(A, b)
    margin = 1e-9 * (1.0 + np.abs(whole))
    if not done:
        assert not np.all((lo + margin < whole) & (whole < hi - margin))
    elif st_early[kernels.O_SWEEPS] < st_full[kernels.O_SWEEPS]:  # stopped early: the whole answer, inside
        assert np.all((lo <= x_early) & (x_early <= hi))
        assert np.allclose(x_early, whole, rtol=1e-9, atol=1e-12)
        assert st_early[O_RESIDUAL] <= 1e-9 * (1.0 + np.abs(b).max())
    else:
        assert np.array_equal(x_early, x_full)


@njit(cache=False)
def _norm_as_summed(x):
    return math.sqrt(np.sum(x * x))


@settings(max_examples=60, deadline=None)
@given(x=hnp.arrays(np.float64, st.integers(0, 40), elements=st.floats(-1e6, 1e6)))
def test_norm_of_is_the_summed_norm_it_replaced(x):
    assert step_kernels.norm_of(x) == _norm_as_summed(x)


@pytest.mark.parametrize("paper", [False, True])
def test_step_plain_is_the_named_step_bit_for_bit(biped, rng, paper):
    """The held inputs over the buffers against the step kernel given fresh named arrays (its own scratch)."""
    sk = biped
    topo = topology(sk, sk.root)
    model = kinematic_model(sk, topo)
    ks = (gsik.SolverSettings.paper() if paper else gsik.SolverSettings()).kernel_settings()
    m = topo.effector_frame.shape[0]
    b = buffers.make_buffers(model, topo.root_frame)
    targets, W, q, ws = buffers.python_views(b)
    held = plain.make_plain_inputs(ks, ks, *b)
    named = (kernels.TargetArrays(np.zeros((m, 3)), np.zeros((m, 3, 3)), np.zeros((m, 6))), np.eye(4),
             np.zeros(sk.n_dofs), kernels.make_workspace(sk.n_frames, sk.n_dofs, m))
    start = gsik.Solver(sk)
    poses = start.effector_poses()
    q[:] = named[2][:] = sk.rest
    ws.R[:], ws.p[:] = start.world_rotations(), start.world_positions()
    named[3].R[:], named[3].p[:] = ws.R, ws.p
    W[:] = named[1][:] = start.world_from_root
    ws.lam[0] = named[3].lam[0] = ks.damping
    for _frame in range(12):
        for k, name in enumerate(topo.effector_names):
            T = poses[name]
            targets.position[k] = named[0].position[k] = T[:3, 3] + rng.normal(0.0, 0.05, 3)
            targets.rotation[k] = named[0].rotation[k] = T[:3, :3]
            targets.row_weight[k] = named[0].row_weight[k] = (1.0, 1.0, 1.0, 0.5, 0.5, 0.5) if k % 2 else \
                (1.0, 1.0, 1.0, 0.0, 0.0, 0.0)
        out = plain.step_plain(held)
        finite = step_kernels.step(model, ks, named[0], topo.root_frame, named[1], named[2], named[3])
        stats = named[3].stats
        assert out == (finite, int(stats[kernels.O_STATUS]), int(stats[kernels.O_ITERATIONS]),
                       int(stats[kernels.O_SWEEPS]), stats[kernels.O_RESIDUAL], stats[kernels.O_STEP_NORM])
        assert np.array_equal(q, named[2])
        for field, x, y in zip(ws._fields, ws, named[3]):
            assert np.array_equal(x, y), field


def _previous_step(solver: gsik.Solver) -> gsik.SolveResult:
    """``Solver.step()`` as it was: the step kernel with the named arrays, the result from its statistics."""
    step, inputs = solver._kernel_inputs()
    if not step(*inputs):
        solver._refuse_non_finite(None, solver._ws.stats)
    return solver._result(solver._ws.stats, O_RESIDUAL, 1)


def _same(a: gsik.SolveResult, b: gsik.SolveResult) -> None:
    for field, x, y in zip(gsik.SolveResult._fields, a, b):
        if isinstance(x, np.ndarray):
            assert x.dtype == y.dtype and np.array_equal(x, y), field
        else:
            assert type(x) is type(y) and x == y, field


def _same_state(a: gsik.Solver, b: gsik.Solver) -> None:
    """Angles, frames, errors, statistics, warm step, damping and packed targets the same (not the scratch)."""
    for x, y in zip((a._q, *a._ws, *a._packed), (b._q, *b._ws, *b._packed)):
        assert np.array_equal(x, y)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), position_only=st.booleans(), speed=st.sampled_from([0.002, 0.02, 0.2]))
def test_solver_step_is_the_previous_step_bit_for_bit(arm, seed, position_only, speed):
    """A tracked arm: moved targets, slow to far too fast (the safeguard halving and refusing steps)."""
    rng = np.random.default_rng(seed)
    new, old = gsik.Solver(arm, q0=BENT), gsik.Solver(arm, q0=BENT)
    T = new.effector_poses()["hand"]
    for s in (new, old):
        s.set_targets({"hand": Target(T[:3, 3]) if position_only else Target.from_transform(T)})
    p = T[:3, 3].copy()
    for _frame in range(15):
        p += rng.normal(0.0, speed, 3)
        for s in (new, old):
            s.move_target("hand", p)
        _same(new.step(), _previous_step(old))
        _same_state(new, old)


def test_solver_step_is_the_previous_step_on_the_biped(biped, rng):
    new, old = gsik.Solver(biped), gsik.Solver(biped)
    poses = new.effector_poses()
    for frame in range(10):
        targets = {n: Target(T[:3, 3] + rng.normal(0.0, 0.03, 3), T[:3, :3]) for n, T in poses.items()
                   if n != "right_foot" or frame % 2}
        _same(new.step(targets), (old.set_targets(targets), _previous_step(old))[1])
        _same_state(new, old)


def _general(solver: gsik.Solver) -> gsik.Solver:
    """``solver`` with its first single-level attempt made as the other attempts are (the path before the one
    compiled call): :meth:`~gsik.attempts.AttemptPolicy._attempts` makes it."""
    solver._plain_first_attempt = lambda: None
    return solver


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), position_only=st.booleans(), far=st.booleans())
def test_solver_solve_is_the_general_path_bit_for_bit(arm, seed, position_only, far):
    """Reachable targets (the arm's pose at random angles) and, ``far``, ones beyond its reach (restarts, a
    settled best reach); then a step and the same solve again from where each left."""
    rng = np.random.default_rng(seed)
    new, old = gsik.Solver(arm), _general(gsik.Solver(arm))
    T = arm.effector_poses(rng.uniform(arm.lower, arm.upper))["hand"]
    if far:
        T[:3, 3] *= 3.0
    target = Target(T[:3, 3]) if position_only else Target.from_transform(T)
    _same(new.solve({"hand": target}), old.solve({"hand": target}))
    _same_state(new, old)
    assert (new._warm, new._settled is None) == (old._warm, old._settled is None)
    _same(new.step(), old.step())
    _same(new.solve(), old.solve())
    _same_state(new, old)


def test_solver_solve_is_the_general_path_on_the_biped(biped, rng):
    new, old = gsik.Solver(biped), _general(gsik.Solver(biped))
    for _ in range(6):
        q = rng.uniform(biped.lower, biped.upper)
        targets = {n: Target.from_transform(T) for n, T in biped.effector_poses(q, new.world_from_root).items()}
        _same(new.solve(targets, q0=biped.rest), old.solve(targets, q0=biped.rest))
        _same_state(new, old)


@pytest.mark.parametrize("which", ["arm", "biped"])
def test_the_uncounted_kernels_neither_keep_nor_drop_a_reference(arm, biped, which):
    """The step, solve and move kernels compiled without numba's reference counting (``_nrt=False``) hold the
    solver's buffers as before after hundreds of calls: a count kept would leak them, one dropped would free them
    under the compiled code."""
    sk, q0 = (arm, BENT) if which == "arm" else (biped, None)
    solver = gsik.Solver(sk, q0=q0)
    name = solver.effector_names[0]
    T = solver.effector_poses()[name]
    solver.set_target(name, Target.from_transform(T))
    floats, ints = solver._buffers.floats, solver._buffers.ints
    held = []
    for frames in (1, 100):  # the first round makes the held compiled calls (which hold the buffers) once
        for f in range(frames):
            p = T[:3, 3] + 0.002 * f * np.array([0.0, 1.0, 1.0])
            solver.move_target(name, p, T[:3, :3])
            solver.step()
            solver.move_target(name, p)
            solver.step()
        solver.solve()
        gc.collect()
        held.append((sys.getrefcount(floats), sys.getrefcount(ints)))
    assert held[1] == held[0]
    assert np.isfinite(solver.q).all()


@pytest.mark.parametrize("x, inside", [
    (np.zeros(3), False),  # no last step to go by: an idle frame, a new pose
    (np.array([0.1, 0.0, -0.1]), True),
    (np.array([0.2, 0.0, -0.1]), False),  # at a bound: the last step touched it
])
def test_the_whole_body_guesses_an_early_stop_from_a_moving_warm_start_inside_the_box(x, inside):
    lo, hi = np.full(3, -0.2), np.full(3, 0.2)
    assert bool(python_function(step_kernels._guess)(x, lo, hi)) is inside


def test_a_drag_step_stopped_early_on_the_biped_is_the_step_from_rest_with_every_sweep(biped):
    """Along a smooth drag the biped's steps stop their sweeps early (the warm start lies inside the box) and take
    the whole system's answer: the box's minimiser a step without a warm start reaches with all its sweeps."""
    from gsik.benchmark import _targets, smooth_trajectory

    settings = dict(adaptive_damping=False, sweeps=5)
    Q = smooth_trajectory(biped, 40, seed=3)
    solver = gsik.Solver(biped, q0=Q[0], **settings)
    W = solver.world_from_root
    early = 0
    for q in Q[1:]:
        targets = _targets(biped, q, W)
        cold = gsik.Solver(biped, q0=solver.q, world_from_root=W, **settings)  # x = 0: no guess, every sweep
        a, b = solver.step(targets), cold.step(targets)
        early += a.sweeps < b.sweeps
        np.testing.assert_allclose(a.q, b.q, rtol=0.0, atol=1e-12)
    assert early >= 30
