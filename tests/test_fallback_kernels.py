"""A refused full step's fallback compiled (gsik.kernels.fallback) against the controller's Python branches it
replaces: the same drags, step for step, bit for bit (angles, statistics, damping, the full step)."""

import collections
import gc
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from solver_helpers import studio_drag_targets

import gsik
import gsik.control
from gsik.control_settle import ControlSettle
from gsik.kernels import fallback
from gsik.prior import bundled_prior, use_prior

# (posture, hands' priority): bench_drag's controlled paths.
PATHS = {"hands at 0": ("start", 0), "pins": ("start", 1), "studio": ("prior", 1)}


def _targets(poses: dict, frame: int, hand_priority: int, offset) -> dict:
    targets = studio_drag_targets(poses, frame)
    for hand in ("left_hand", "right_hand"):
        t = targets[hand]
        targets[hand] = gsik.Target(t.position + offset, position_only=True, priority=hand_priority)
    return targets


def _drag(monkeypatch, compiled: bool, posture: str, hand_priority: int, frames: int, solve: bool = True,
          offset=(0.0, 0.0, 0.0), settle: bool = True, **config) -> tuple[list, collections.Counter]:
    """``(every controlled step's record, how the Python branches ended)`` of a drag of ``solve()`` (or ``step()``)
    calls: a record is the step's statistics, the damping it left, the angles and the full step (bytes), and each
    frame's result; the counter (the Python branches only) counts each fallback's ending. ``settle``: a worse step
    that settles the posture is refused without retries (``Controller.settle_refusals``); ``config``: settings."""
    records, ends = [], collections.Counter()
    step, damped = gsik.control.Controller.step, gsik.control.Controller._damped_trial
    targets_alone, correction = gsik.control.Controller._targets_alone, gsik.control.Controller._correction

    def recorded(self, q, W, R, p, lam):
        stats = step(self, q, W, R, p, lam)
        records.append((stats, lam.tobytes(), q.tobytes(), R.tobytes(), self.first_step().tobytes()))
        return stats

    def counted(self, *args):
        tries, trial = damped(self, *args)
        ends[("halved", tries, trial[0][0])] += 1
        return tries, trial

    def alone(self, *args):
        trial = targets_alone(self, *args)
        ends[("targets alone", trial is not None)] += 1
        return trial

    def corrected(self, *args):
        trial = correction(self, *args)
        ends[("correction", trial is not None)] += 1
        return trial

    monkeypatch.setattr(gsik.control.Controller, "compiled_step", compiled)
    monkeypatch.setattr(gsik.Solver, "compiled_frame", False)  # every step through Controller.step, watched here
    monkeypatch.setattr(ControlSettle, "compiled_settle", False)  # a solve()'s steps too
    monkeypatch.setattr(gsik.control.Controller, "settle_refusals", settle)
    for name, f in (("step", recorded), ("_damped_trial", counted), ("_targets_alone", alone),
                    ("_correction", corrected)):
        monkeypatch.setattr(gsik.control.Controller, name, f)
    solver = gsik.Solver(gsik.load_skeleton("biped"))
    poses = solver.effector_poses()
    solver.solve(_targets(poses, 0, 0, np.zeros(3)))
    if posture == "start":
        solver.set_posture(solver.q)
    else:
        use_prior(solver, bundled_prior("biped"))
        solver.configure(tracking_steps=3)
    solver.configure(**config)
    for frame in range(frames):
        targets = _targets(poses, frame, hand_priority, np.array(offset))
        r = solver.solve(targets) if solve else solver.step(targets)
        records.append((r.status, r.iterations, r.residual, r.step_norm, r.q.tobytes(), r.position_errors.tobytes()))
    monkeypatch.undo()
    return records, ends


def _assert_same(monkeypatch, *args, **kwargs) -> collections.Counter:
    """The drag through the compiled fallback and through the Python branches alike; the Python branches' endings."""
    compiled, _ = _drag(monkeypatch, True, *args, **kwargs)
    reference, ends = _drag(monkeypatch, False, *args, **kwargs)
    assert len(compiled) == len(reference)
    for a, b in zip(compiled, reference):
        assert a == b
    return ends


# (path, frames, hands' offset [m], settle refusals, fallback endings each seen at least once in the Python branches)
CASES = [("hands at 0", 24, (0.0, 0.0, 0.0), True, [("targets alone", True), ("targets alone", False),
                                                   ("halved", 1, "better"), ("halved", 2, "better"),
                                                   ("halved", 3, "worse")]),
         ("pins", 16, (0.0, 0.0, 0.0), True, [("targets alone", True), ("targets alone", False),
                                             ("halved", 1, "better"), ("halved", 0, "worse")]),
         ("hands at 0", 24, (0.0, 0.1, 0.0), False, [("halved", 3, "same")]),
         ("studio", 30, (0.0, -0.1, 0.0), True, [("targets alone", True), ("targets alone", False),
                                                ("halved", 1, "better"), ("halved", 0, "same")]),
         ("pins", 8, (0.0, -0.3, -0.3), True, [("correction", True), ("correction", False)])]


@pytest.mark.parametrize("path, frames, offset, settle, endings", CASES,
                         ids=[f"{c[0]}, {c[1]} frames, settle {c[3]}" for c in CASES])
def test_warm_solves_through_the_compiled_fallback_are_the_python_branches_bit_for_bit(path, frames, offset, settle,
                                                                                      endings, monkeypatch):
    """bench_drag's controlled paths, a warm solve() a frame: the same steps, and the fallback's branches ran: the
    target levels alone better or not, halvings better or unchanged, refused after every retry (``halved, 3,
    worse``) or at once as the step settles the posture (``halved, 0, worse``), the met levels' correction better
    (hands dragged far below the pins) or not."""
    ends = _assert_same(monkeypatch, *PATHS[path], frames, offset=offset, settle=settle)
    assert all(ends[e] > 0 for e in endings), ends


def test_a_worse_step_is_refused_at_once_only_where_it_settles_a_solves_posture(monkeypatch):
    """Without the posture's settle test (``posture_tolerance`` 0) and in step() every worse step is retried; the
    tolerance is off again after a solve."""
    for solve, config in ((True, {"posture_tolerance": 0.0}), (False, {})):
        _, ends = _drag(monkeypatch, False, "start", 1, 16, solve=solve, **config)
        assert ends[("halved", 0, "worse")] == 0 and sum(ends.values()) > 0
    solver = gsik.Solver(gsik.load_skeleton("biped"))
    solver.set_posture(solver.q)
    solver.solve({"left_hand": gsik.Target(solver.effector_poses()["left_hand"][:3, 3] + 0.05, position_only=True)})
    assert solver._controller._cache.settle.tolist() == [0.0]


def test_steps_through_the_compiled_fallback_are_the_python_branches_bit_for_bit(monkeypatch):
    """The studio's drag a step() a frame (three tracking steps): the same steps."""
    _assert_same(monkeypatch, "prior", 1, 40, solve=False)


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                HealthCheck.function_scoped_fixture])
@given(offset=st.lists(st.floats(-0.1, 0.1), min_size=3, max_size=3), path=st.sampled_from(sorted(PATHS)))
def test_random_drags_through_the_compiled_fallback_are_the_python_branches_bit_for_bit(offset, path, monkeypatch):
    """Hands dragged off the circle by ``offset`` [m] (some out of reach): the same steps."""
    _assert_same(monkeypatch, *PATHS[path], 6, offset=tuple(offset))


def test_a_refusal_raises_the_damping_to_its_largest_and_then_holds():
    """:func:`gsik.kernels.fallback._refuse`: a worse step raises the damping tenfold up to the largest; a step
    refused at the largest holds the pose."""
    cache = gsik.kernels.accept.make_cache(2, 1, 1)
    window = gsik.kernels.accept.make_window(np.ones(2))
    posture = gsik.kernels.control.PostureRows(np.zeros(2), np.zeros((0, 2)), np.ones(1))
    lam, costs, met = np.zeros(1), np.ones(2), np.zeros(2, dtype=bool)
    fallback._refuse(fallback.V_WORSE, lam, 10.0, posture, costs, met, cache, window)
    assert lam[0] == 100.0 and cache.out[gsik.kernels.accept.R_CREEPS] == 0.0
    fallback._refuse(fallback.V_WORSE, lam, 0.5 * fallback.MAX_DAMPING, posture, costs, met, cache, window)
    assert lam[0] == fallback.MAX_DAMPING and cache.out[gsik.kernels.accept.R_CREEPS] == 0.0
    fallback._refuse(fallback.V_WORSE, lam, fallback.MAX_DAMPING, posture, costs, met, cache, window)
    assert lam[0] == fallback.MAX_DAMPING and cache.out[gsik.kernels.accept.R_CREEPS] == 1.0
    lam[0] = 3.0
    fallback._refuse(fallback.V_SAME, lam, 3.0, posture, costs, met, cache, window)
    assert lam[0] == 3.0 and cache.out[gsik.kernels.accept.R_CREEPS] == 1.0  # unchanged: held, damping kept


def test_the_uncounted_kernels_neither_keep_nor_drop_a_reference():
    """The controlled step's kernels compiled without numba's reference counting (``_nrt=False``) hold the
    controller's buffers as before after hundreds of steps (committed, refused, gathered): a count kept would leak
    them, one dropped would free them under the compiled code."""
    solver = gsik.Solver(gsik.load_skeleton("biped"))
    use_prior(solver, bundled_prior("biped"))
    poses = solver.effector_poses()
    solver.step(studio_drag_targets(poses, 0))
    controller = solver._controller
    held = []
    for frames in (1, 100):  # the first round makes the held compiled calls (which hold the buffers) once
        for f in range(frames):
            solver.step(studio_drag_targets(poses, f))
        solver.solve()
        gc.collect()
        held.append([sys.getrefcount(a) for a in (*controller._cache, *controller._work, *controller._work.priority,
                                                  *controller._tasks_in, *controller._posture_rows)])
    assert solver._controller is controller
    assert held[1] == held[0]
    assert np.isfinite(solver.q).all()
