"""The compiled acceptance (gsik.kernels.accept) against the Python references it replaces on the common step."""

import collections

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import gsik
import gsik.control
from gsik.control_settle import ControlSettle
from gsik.acceptance import BETTER, SAME, WORSE, LevelState, anchored, compare
from gsik.kernels import accept as ak
from gsik.kernels.control import O_SHARE, make_work, posture_rows
from gsik.prior import bundled_prior, use_prior
from gsik.stall import STALL_WINDOW, StallDetector, unmet_levels

from solver_helpers import studio_drag_targets

CODES = {ak.V_BETTER: BETTER, ak.V_SAME: SAME, ak.V_WORSE: WORSE}
# Costs drawn from a few values so that ties, equal anchors and tiny changes all occur.
COST = st.sampled_from([0.0, 1e-9, 1e-6, 1.0001e-6, 0.99e-6, 1e-3, 2e-3, 1.0, float("nan")])


def _state(costs, met, anchors) -> LevelState:
    return LevelState(np.array(costs), np.array(met, dtype=bool), np.array(anchors), False, 0.0, np.zeros(6))


@st.composite
def _pairs(draw):
    k = draw(st.integers(1, 5))
    levels = st.lists(COST, min_size=k, max_size=k)
    flags = st.lists(st.booleans(), min_size=k, max_size=k)
    before = _state(draw(levels), draw(flags), draw(levels))
    after = _state(draw(levels), draw(flags), draw(levels))
    floors = np.array(draw(st.lists(st.sampled_from([0.0, 1e-9, 1e-7]), min_size=k, max_size=k)))
    settle = draw(st.sampled_from([0.0, 1e-3, 0.05]))
    upto = draw(st.one_of(st.none(), st.integers(0, k)))
    return before, after, floors, settle, upto


@settings(max_examples=400, deadline=None)
@given(_pairs())
def test_compare_levels_is_the_python_rule(case):
    before, after, floors, settle, upto = case
    want = compare(before, after, settle, floors, upto)
    code, level = ak.compare_levels(before.costs, before.anchors, before.met, after.costs, after.met, floors, settle,
                                    len(floors) if upto is None else upto)
    assert (CODES[code], level) == want


@settings(max_examples=300, deadline=None)
@given(_pairs(), st.integers(0, 5))
def test_anchor_into_is_anchored_bit_for_bit(case, decided):
    before, after, _, _, _ = case
    out = np.zeros_like(after.costs)
    ak.anchor_into(before.anchors, after.costs, decided, out)
    want = anchored(after, before, decided).anchors
    assert out.tobytes() == want.tobytes()


def test_anchor_into_in_place_as_the_controller_calls_it():
    anchors, costs = np.array([1.0, 2.0, 3.0]), np.array([0.5, 2.5, 1.0])
    want = anchored(_state(costs, [False] * 3, anchors), _state(costs, [False] * 3, anchors), 2).anchors
    ak.anchor_into(anchors, costs, 2, anchors)
    assert anchors.tolist() == want.tolist() == [0.5, 2.0, 1.0]


@settings(max_examples=200, deadline=None)
@given(st.integers(2, 4), st.booleans(), st.data())
def test_creeps_is_the_stall_detector(k, posture_on, data):
    """Random runs of met flags and slowly or quickly falling costs (NaN and negative ones too): the same answers
    step after step, with resets between."""
    tolerance_norms = np.array([1e-3] * (k - 1) + [0.0])
    reference, window = StallDetector(tolerance_norms), ak.make_window(tolerance_norms)
    cost = 1e-2
    for _ in range(data.draw(st.integers(1, 4 * STALL_WINDOW))):
        if data.draw(st.integers(0, 15)) == 0:
            reference.reset()
            window.ring[:] = 0
        met = np.array(data.draw(st.lists(st.sampled_from([False, False, False, True]), min_size=k, max_size=k)))
        cost *= data.draw(st.sampled_from([1.0, 0.9999, 0.99, 0.5]))
        costs = np.array([data.draw(st.sampled_from([cost, cost, -1.0, float("nan")])) for _ in range(k)])
        want = reference.creeps(unmet_levels(met, posture_on), costs)
        assert ak.creeps(window, met, posture_on, costs) == want


def test_creeps_after_a_full_window_of_creeping_steps():
    tolerance_norms = np.array([1e-4, 0.0])
    reference, window = StallDetector(tolerance_norms), ak.make_window(tolerance_norms)
    met = np.array([False, False])
    flags = []
    for k in range(STALL_WINDOW + 3):
        costs = np.array([(3e-4 - 1e-7 * k) ** 2, 0.0])
        flags.append(ak.creeps(window, met, False, costs))
        assert flags[-1] == reference.creeps(unmet_levels(met, False), costs)
    assert not any(flags[:STALL_WINDOW]) and all(flags[STALL_WINDOW:])


def test_is_fresh_only_for_the_very_bits_cached():
    cache = ak.make_cache(3, 1, 1)
    q, W = np.array([0.1, -0.0, 2.0]), np.eye(4)
    assert not ak.is_fresh(cache, q, W)  # nothing cached
    cache.q[:], cache.W[:], cache.flags[ak.F_VALID] = q, W, 1.0
    assert ak.is_fresh(cache, q.copy(), W.copy())
    assert not ak.is_fresh(cache, np.array([0.1, 0.0, 2.0]), W)  # -0.0 is not 0.0 bit for bit
    moved = W.copy()
    moved[2, 3] = 1e-300
    assert not ak.is_fresh(cache, q, moved)
    cache.flags[ak.F_VALID] = 0.0
    assert not ak.is_fresh(cache, q, W)


def _studio_drag(compiled: bool, frames: int, solve: bool, monkeypatch) -> tuple[list, collections.Counter]:
    """The studio's drag (pelvis and left foot pinned, hands at 1 dragged round a circle, the bundled prior, three
    tracking steps), a ``step()`` or a warm ``solve()`` a frame: every frame's result, and how each compiled step
    ended: ``(committed, restoring steps made)``."""
    ends, step = collections.Counter(), gsik.control.Controller.step

    def counted(self, *args):
        stats = step(self, *args)
        ends[(bool(self._cache.out[ak.R_COMMITTED]), bool(self._cache.out[ak.R_RESTORED]))] += compiled
        return stats

    monkeypatch.setattr(gsik.control.Controller, "compiled_step", compiled)
    monkeypatch.setattr(gsik.Solver, "compiled_frame", False)  # every step through Controller.step, counted here
    monkeypatch.setattr(ControlSettle, "compiled_settle", False)  # a solve()'s steps too
    monkeypatch.setattr(gsik.control.Controller, "step", counted)
    solver = gsik.Solver(gsik.load_skeleton("biped"), tracking_steps=3)
    poses = solver.effector_poses()
    use_prior(solver, bundled_prior("biped"))
    results = []
    for frame in range(frames):
        targets = studio_drag_targets(poses, frame)
        results.append(solver.solve(targets) if solve else solver.step(targets))
    return results, ends


@pytest.mark.parametrize("solve", [False, True], ids=["step", "solve"])
def test_the_compiled_step_is_the_python_branches_bit_for_bit(solve, monkeypatch):
    """Same angles, errors, status and step norms every frame; the compiled path commits on the first trial, and
    after restoring steps or its fallback (gsik.kernels.fallback: ``tests/test_fallback_kernels.py``)."""
    compiled, ends = _studio_drag(True, 12 if solve else 60, solve, monkeypatch)
    reference, _ = _studio_drag(False, 12 if solve else 60, solve, monkeypatch)
    for a, b in zip(compiled, reference):
        assert a.q.tobytes() == b.q.tobytes()
        assert a.position_errors.tobytes() == b.position_errors.tobytes()
        assert (a.status, a.iterations, a.residual, a.step_norm) == (b.status, b.iterations, b.residual, b.step_norm)
    assert ends[(True, False)] > 0
    assert ends[(True, True)] > 0


def test_a_full_step_whose_posture_share_was_bounded_never_creeps_and_starts_the_window_again():
    """A creeping run, then one more step: a full step with its posture share scaled onto the bound (the posture
    closing in at the bound's pace) is no creep and empties the window; a halved or targets-alone step (not whole),
    or one whose share was within the bound, is the plain window's."""
    n, tolerance_norms, met = 4, np.array([1e-4, 0.0]), np.array([False, False])
    posture = posture_rows(np.zeros(n), np.eye(n) + 0.1 * np.ones((n, n)))  # a full factor: bounded
    wk = make_work(1, n, 1, np.array([0, 0, n]), 1)
    assert posture.share[0] > 0.0

    def creeping_window():
        window = ak.make_window(tolerance_norms)
        for k in range(STALL_WINDOW):
            assert not ak.creeps(window, met, True, np.array([(3e-4 - 1e-7 * k) ** 2, 1.0]))
        return window

    costs = np.array([(3e-4 - 1e-7 * STALL_WINDOW) ** 2, 1.0])
    for whole, share, creeps in ((True, 2.0, False), (False, 2.0, True), (True, 0.5, True)):
        wk.out[O_SHARE] = share * posture.share[0]
        window = creeping_window()
        assert ak.creeps_after(whole, posture, wk, window, met, costs) == creeps
        assert (window.ring[0] == 0) == (not creeps)
