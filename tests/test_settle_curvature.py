"""The targets' curvature learnt in a solve()'s settle steps (gsik/kernels/curvature.py, gsik/control_settle.py):
the BFGS update's invariants, the multipliers, the swap in and out of the posture's level, and what it does to a
drag's warm solves with the studio's prior."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from solver_helpers import studio_drag_solver, studio_drag_targets

import gsik
from gsik.control_settle import ControlSettle
from gsik.kernels import curvature as cv


def _curvature(P: np.ndarray, y: np.ndarray, s: np.ndarray) -> tuple[cv.Curvature, np.ndarray]:
    """A :class:`Curvature` whose update sees the step ``s`` and the gradient change ``y`` (n,): the rows are the
    unit vectors, ``J0`` zero and ``J1`` the identity, so ``(J1 - J0)^T lam = lam = y - P s``."""
    n = len(s)
    cur = cv.make_curvature(P, n)
    cur.J1[:] = np.eye(n)
    cur.lam[:] = y - P @ s
    cur.s[:] = s
    return cur, np.arange(n, dtype=np.int64)


def _spd(rng: np.random.Generator, n: int) -> np.ndarray:
    A = rng.normal(size=(n, n))
    return A @ A.T + 0.1 * np.eye(n)


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(2, 8), st.floats(-3.0, 3.0))
def test_the_update_keeps_B_symmetric_positive_definite_and_meets_the_secant_or_powells_blend(seed, n, bend):
    rng = np.random.default_rng(seed)
    P, B = _spd(rng, n), _spd(rng, n)
    s = rng.normal(size=n)
    y = bend * (B @ s) + 0.3 * rng.normal(size=n)  # any curvature along s, negative too
    cur, rows = _curvature(P, y, s)
    sBs, sy = s @ B @ s, s @ y
    B1 = B.copy()
    assert cv._bfgs(cur, rows, B1)
    assert np.array_equal(B1, B1.T)
    np.linalg.cholesky(B1)  # positive definite
    if sy >= cv.POWELL_FRACTION * sBs:
        np.testing.assert_allclose(B1 @ s, y, rtol=1e-8, atol=1e-8 * np.abs(y).max())  # the secant equation
    else:  # Powell's blend: the curvature along s is the fraction of the old, exactly as the update's r
        np.testing.assert_allclose(s @ B1 @ s, cv.POWELL_FRACTION * sBs, rtol=1e-8)


def test_a_step_along_which_B_has_no_curvature_leaves_it():
    P = np.eye(3)
    cur, rows = _curvature(P, np.ones(3), np.zeros(3))
    B = P.copy()
    assert not cv._bfgs(cur, rows, B)
    assert np.array_equal(B, P)


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 5), st.booleans())
def test_the_multipliers_project_the_postures_gradient_onto_the_rows(seed, m, repeated):
    rng = np.random.default_rng(seed)
    n = 7
    P, J = _spd(rng, n), rng.normal(size=(m, n))
    if repeated and m > 1:
        J[-1] = J[0]  # rank-deficient: still the least-squares projection
    cur = cv.make_curvature(P, m)
    cur.J1[:] = J
    q, ref = rng.normal(size=n), rng.normal(size=n)
    cv._multipliers(cur, np.arange(m, dtype=np.int64), ref, q)
    g = P @ (q - ref)
    projected = J.T @ np.linalg.lstsq(J.T, -g, rcond=None)[0]
    np.testing.assert_allclose(J.T @ cur.lam, projected, atol=1e-6 * np.abs(g).max())


def _settled_studio(frames: int = 3):
    solver, poses = studio_drag_solver(True)
    for f in range(frames):
        solver.solve(studio_drag_targets(poses, f))
    return solver, poses, solver._last_controller


def test_the_posture_level_holds_the_curvature_only_while_a_settle_runs():
    solver, poses, c = _settled_studio()
    cur, normal = c._curvature, c._posture_rows.normal
    assert cur is not None and cur.state[cv.S_LEARNT] > 0  # it learnt
    assert np.array_equal(normal, cur.P) and not np.array_equal(cur.B, cur.P)  # ... and keeps it out of a step()
    before = cur.B.copy()
    c.curvature_begin(solver.q, solver._ws.R, solver._ws.p, True, True)
    assert np.array_equal(normal, before)  # a warm settle goes on from it
    c.curvature_end()
    c.curvature_end()  # once: the second changes nothing
    assert np.array_equal(normal, cur.P) and np.array_equal(cur.B, before)
    c.curvature_begin(solver.q, solver._ws.R, solver._ws.p, False, True)
    assert np.array_equal(normal, cur.P) and cur.state[cv.S_LEARNT] == 0  # any other starts from the posture's
    c.curvature_end()


def test_a_step_that_raises_in_the_python_loop_leaves_the_postures_own_matrix(monkeypatch):
    monkeypatch.setattr(ControlSettle, "compiled_settle", False)
    solver, poses, c = _settled_studio()
    step = gsik.control.Controller.step

    def failing(self, *args):
        step(self, *args)
        raise np.linalg.LinAlgError("a priority level's Jacobian holds a non-finite number")

    monkeypatch.setattr(gsik.control.Controller, "step", failing)
    with pytest.raises(np.linalg.LinAlgError):
        solver.solve(studio_drag_targets(poses, 10))
    assert np.array_equal(c._posture_rows.normal, c._curvature.P)


def _warm_drag(frames: int, learns: bool, monkeypatch) -> tuple[list, gsik.Solver]:
    monkeypatch.setattr(ControlSettle, "learns_curvature", learns)
    solver, poses = studio_drag_solver(True)
    return [solver.solve(studio_drag_targets(poses, f)) for f in range(frames)], solver


def test_a_studio_drag_settles_in_fewer_linearisations_no_further_from_the_prior(monkeypatch):
    """With the prior (hands round a circle, pelvis and foot pinned) Gauss-Newton posture steps close in by a
    fraction a step; with the curvature learnt a warm solve settles in fewer, where the posture costs no more."""
    on, solver_on = _warm_drag(40, True, monkeypatch)
    off, solver_off = _warm_drag(40, False, monkeypatch)
    for r in on + off:
        assert r.status is gsik.Status.CONVERGED
        assert r.position_errors.max() <= solver_on.settings.position_tolerance
    assert sum(r.iterations for r in on) < 0.75 * sum(r.iterations for r in off)
    rows = solver_on._last_controller._posture_rows

    def cost(r):
        return 0.5 * np.sum((rows.factor @ (r.q - rows.reference)) ** 2)

    assert np.mean([cost(r) for r in on]) <= np.mean([cost(r) for r in off]) * (1 + 1e-4)


def test_a_cold_solve_is_the_same_whatever_the_drag_before_it_learnt(monkeypatch):
    solver, poses = studio_drag_solver(True)
    start = solver.q
    for f in range(12):
        solver.solve(studio_drag_targets(poses, f))
    solver.set_q(start)  # not where the last solve converged: a cold solve
    after_drag = solver.solve(studio_drag_targets(poses, 20))
    fresh, _ = studio_drag_solver(True)
    fresh.set_q(start)
    alone = fresh.solve(studio_drag_targets(poses, 20))
    assert after_drag.q.tobytes() == alone.q.tobytes() and after_drag.iterations == alone.iterations


def test_a_diagonal_posture_learns_nothing(monkeypatch):
    solver, poses = studio_drag_solver(False)  # the start pose as the posture: a diagonal normal matrix
    for f in range(3):
        solver.solve(studio_drag_targets(poses, f))
    assert solver._last_controller._curvature is None


def test_an_unreachable_targets_solve_learns_nothing(monkeypatch):
    """Hands 0.9 m above their reach: no step meets the targets, so no multiplier models a constraint's force and
    the settle stays Gauss-Newton's, bit for bit."""
    out = []
    for learns in (True, False):
        monkeypatch.setattr(ControlSettle, "learns_curvature", learns)
        solver, poses = studio_drag_solver(True)
        targets = studio_drag_targets(poses, 0)
        for hand in ("left_hand", "right_hand"):
            t = targets[hand]
            targets[hand] = gsik.Target(t.position + [0.0, 0.9, 0.0], position_only=True, priority=t.priority)
        r = solver.solve(targets)
        assert r.status is not gsik.Status.CONVERGED
        c = solver._last_controller
        assert c._curvature is None or c._curvature.state[cv.S_LEARNT] == 0
        out.append((r.q.tobytes(), r.iterations, r.status))
    assert out[0] == out[1]
