"""The posture level's share of a step bounded on its own (gsik.kernels.posture_level): the unbounded step bit for bit
within the bound, else the targets' step plus the posture's share scaled onto the bound, inside the box; which
postures the controller bounds."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

import gsik
from gsik.kernels import control as control_kernels
from gsik.kernels import priority as priority_kernel
from gsik.kernels.control import posture_rows
from gsik.kernels.posture_level import POSTURE_SHARE, prioritized_step_posture
from gsik.priority import BOX_RELATIVE_TOLERANCE, BOX_TOLERANCE, RANK_TOLERANCE, Level, factor_level, pack_levels, \
    posture_factor
from test_posture_level import _full_factor, posture_problems

TOLS = (RANK_TOLERANCE, BOX_TOLERANCE, BOX_RELATIVE_TOLERANCE)


def _bounded(levels, lo, hi, dampings, normal, bound):
    """``(status, largest share component, step (n,), targets' step (n,))`` of :func:`prioritized_step_posture`."""
    packed = pack_levels(levels, lo.shape[0])
    dq, below = np.full(lo.shape[0], np.nan), np.full(lo.shape[0], np.nan)
    status, largest = prioritized_step_posture(*packed, np.array(dampings, dtype=float), lo, hi, *TOLS, normal, bound,
                                               dq, below)
    return status, largest, dq, below


def _unbounded(levels, lo, hi, dampings, normal):
    packed = pack_levels(levels, lo.shape[0])
    dq, below = np.full(lo.shape[0], np.nan), np.full(lo.shape[0], np.nan)
    assert prioritized_step_posture(*packed, np.array(dampings, dtype=float), lo, hi, *TOLS, normal, 0.0, dq,
                                    below) == (priority_kernel.OK, 0.0)
    assert np.isnan(below).all()  # not bounded: the scratch is not touched
    return dq


@settings(max_examples=200, deadline=None)
@given(posture_problems(), st.sampled_from([1e-3, 0.01, 0.05, 0.3, 10.0]))
def test_the_share_is_the_unbounded_one_scaled_onto_the_bound(problem, bound):
    levels, lo, hi, dampings, normal = problem
    full = _unbounded(levels, lo, hi, dampings, normal)
    status, largest, dq, below = _bounded(levels, lo, hi, dampings, normal, bound)
    assert status == priority_kernel.OK
    assert largest == np.abs(full - below).max()
    assert np.all(dq >= lo) and np.all(dq <= hi)
    if largest <= bound:
        np.testing.assert_array_equal(dq, full)
    else:
        assert np.abs(dq - below).max() <= bound * (1.0 + 1e-12)
        np.testing.assert_allclose(dq - below, (bound / largest) * (full - below), rtol=0.0, atol=1e-14)
    # below is the target levels' own step (the posture's level left out)
    targets = pack_levels(levels[:-1], lo.shape[0])
    alone = np.full(lo.shape[0], np.nan)
    assert priority_kernel.prioritized_step(*targets, np.array(dampings[:-1], dtype=float), lo, hi, *TOLS, alone) == \
        priority_kernel.OK
    np.testing.assert_allclose(below, alone, rtol=0.0, atol=1e-12)


@settings(max_examples=50, deadline=None)
@given(posture_problems())
def test_no_bound_or_no_normal_matrix_is_the_unbounded_step(problem):
    levels, lo, hi, dampings, normal = problem
    full = _unbounded(levels, lo, hi, dampings, normal)
    for bound, matrix in ((0.0, normal), (1e-3, np.zeros((0, lo.shape[0])))):
        status, largest, dq, _ = _bounded(levels, lo, hi, dampings, matrix, bound)
        assert status == priority_kernel.OK and largest == 0.0
        np.testing.assert_array_equal(dq, _unbounded(levels, lo, hi, dampings, matrix))
    np.testing.assert_array_equal(_bounded(levels, lo, hi, dampings, normal, 0.0)[2], full)


def test_a_bounded_share_leaves_the_target_levels_linearised_errors_alone(rng):
    """Full-rank target levels (pins, hands) over 30 DOFs: the bounded posture move lies in what they leave free."""
    n = 30
    pins, hands = np.zeros((12, n)), np.zeros((6, n))
    pins[:, :14] = rng.normal(size=(12, 14))
    hands[:, 10:24] = rng.normal(size=(6, 14))
    factor = _full_factor(rng, n)
    levels = [Level(pins, rng.normal(size=12) * 0.01, np.ones(12)), Level(hands, rng.normal(size=6) * 0.01,
                                                                            np.ones(6)),
              factor_level(rng.normal(size=n), np.zeros(n), factor)]
    lo, hi = np.full(n, -1.0), np.full(n, 1.0)
    posture = posture_rows(np.zeros(n), factor)
    status, largest, dq, below = _bounded(levels, lo, hi, [1e-6, 1e-6, 1e-3], posture.normal, 0.02)
    assert status == priority_kernel.OK and largest > 0.02
    assert np.isclose(np.abs(dq - below).max(), 0.02, rtol=1e-12, atol=0.0)
    for level in levels[:2]:
        np.testing.assert_allclose(level.jacobian @ dq, level.jacobian @ below, rtol=0.0, atol=1e-12)


def test_the_controller_bounds_a_full_posture_factor_only(rng, monkeypatch):
    """The learned prior's full factor gets the bound (on by default); a diagonal posture (pins, the retargeter)
    none, so its steps take their whole share (the bundled priors are built with it); no posture, none."""
    n = 12
    assert posture_rows(np.zeros(n), _full_factor(rng, n)).share[0] == POSTURE_SHARE > 0.0
    monkeypatch.setattr(control_kernels, "POSTURE_SHARE", 0.05)
    assert posture_rows(np.zeros(n), _full_factor(rng, n)).share[0] == 0.05
    assert posture_rows(np.zeros(n), posture_factor(np.full(n, 2.0))).share[0] == 0.0
    assert posture_rows(None, np.zeros((0, n))).share[0] == 0.0


def _reach_settled(biped, most=60):
    """The studio's reach (feet and pelvis pinned, hands position-only at priority 1, the bundled prior, three
    tracking steps): the left hand pulled up and out, then steps until one converges. Returns ``(the prior's
    Mahalanobis distance there, steps made, steps whose targets were met but whose share was bounded)``."""
    from gsik.prior import bundled_prior, use_prior

    solver = gsik.Solver(biped, sweeps=8, damping=1e-3, tracking_steps=3)
    targets = {n: gsik.Target.from_transform(T, position_only=n.endswith("_hand"),
                                            priority=0 if n in ("left_foot", "pelvis") else 1)
               for n, T in solver.effector_poses().items()}
    prior = bundled_prior("biped")
    use_prior(solver, prior)
    hand = targets["left_hand"]
    solver.set_targets({**targets, "left_hand": hand.replace(position=hand.position + [0.15, 0.10, 0.25])})
    bounded_met = 0
    for n in range(1, most + 1):
        r = solver.step()
        if r.status is gsik.Status.CONVERGED:
            assert not solver._controller.share_bounded()
            return prior.mahalanobis(solver.q), n, bounded_met
        bounded_met += solver._controller.share_bounded() and max(e[0] for e in r.errors().values()) <= 1e-4
    raise AssertionError(f"no step converged in {most}")


def test_steps_settle_a_bounded_share_where_the_whole_share_does(biped, monkeypatch):
    """A step whose targets are met while the prior's share is bounded is not converged (the posture has further
    to go): steps go on, more of them, to a body at least as likely as the whole share's (issue 20)."""
    bounded = _reach_settled(biped)
    monkeypatch.setattr(control_kernels, "POSTURE_SHARE", 0.0)
    whole = _reach_settled(biped)
    assert whole[2] == 0 and bounded[2] > 0
    assert bounded[1] > whole[1]
    assert bounded[0] <= whole[0] * 1.01
