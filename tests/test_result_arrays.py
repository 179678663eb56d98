"""A single-level result's arrays: reused from a dropped result only, so a result (or any array of it the caller
keeps) never changes when the solver moves on, and every result holds the state it was made from."""

import gc
from pathlib import Path

import numpy as np
import pytest

import gsik
from gsik import Target
from gsik.io.urdf_skeleton import skeleton_from_urdf
from gsik.result_arrays import ResultArrays

ARM = Path(__file__).parent / "data" / "seven_dof_arm.urdf"
BENT = np.array([0.6, 0.2, 0.0, 1.2, 0.0, 0.0, 0.0])


@pytest.fixture(scope="module")
def arm() -> gsik.Skeleton:
    return skeleton_from_urdf(ARM, effectors=["hand"], root="base")


def _tracking(arm) -> tuple[gsik.Solver, np.ndarray]:
    solver = gsik.Solver(arm, q0=BENT)
    start = solver.effector_poses()["hand"]
    solver.set_targets({"hand": Target.from_transform(start)})
    return solver, start


def _fields(r: gsik.SolveResult) -> tuple:
    return r.q.copy(), r.position_errors.copy(), r.orientation_errors.copy()


def _same(r: gsik.SolveResult, fields: tuple) -> None:
    assert np.array_equal(r.q, fields[0])
    assert np.array_equal(r.position_errors, fields[1])
    assert np.array_equal(r.orientation_errors, fields[2])


def _move(solver: gsik.Solver, start: np.ndarray, f: int) -> gsik.SolveResult:
    solver.move_target("hand", start[:3, 3] + [0.0, 0.01 * f, 0.005 * f])
    return solver.step()


@pytest.mark.parametrize("steps", [1, 2, 3, 7])
def test_a_kept_result_never_changes_when_the_solver_moves_on(arm, steps):
    solver, start = _tracking(arm)
    kept = [_move(solver, start, 1)]
    seen = [_fields(kept[0])]
    for f in range(2, 2 + steps):
        r = _move(solver, start, f)
        if f % 2:
            kept.append(r)
            seen.append(_fields(r))
        del r
    kept.append(solver.solve())
    seen.append(_fields(kept[-1]))
    for r, fields in zip(kept, seen):
        _same(r, fields)
    assert len({r.q.tobytes() for r in kept}) == len(kept)  # each made from its own state


#: What a caller may keep of a result it drops.
_PARTS = {"q": lambda r: r.q, "position_errors": lambda r: r.position_errors,
          "orientation_errors": lambda r: r.orientation_errors, "slice": lambda r: r.q[2:5], "base": lambda r: r.q.base,
          "memoryview": lambda r: memoryview(r.position_errors), "tuple": tuple}


@pytest.mark.parametrize("keep", list(_PARTS))
def test_any_kept_part_of_a_dropped_result_never_changes(arm, keep):
    solver, start = _tracking(arm)
    r = _move(solver, start, 1)
    part = _PARTS[keep](r)
    before = bytes(part) if keep != "tuple" else tuple(a.copy() for a in (part[0], part[6], part[7]))
    del r
    gc.collect()
    for f in range(2, 8):
        _move(solver, start, f)
    if keep == "tuple":
        for a, b in zip((part[0], part[6], part[7]), before):
            assert np.array_equal(a, b)
    else:
        assert bytes(part) == before


def test_results_hold_the_state_they_were_made_from(arm):
    """Reused or not, a step's result is the solver's angles and the hand's distance to its target after that
    step."""
    solver, start = _tracking(arm)
    for f in range(1, 12):
        r = _move(solver, start, f)
        assert np.array_equal(r.q, solver.q)
        hand = solver.effector_poses()["hand"][:3, 3]
        target = solver.targets["hand"].position
        assert r.position_errors[0] == pytest.approx(np.linalg.norm(hand - target), rel=1e-9, abs=1e-15)


def test_dropped_sets_are_reused_and_kept_ones_are_not():
    state = np.arange(7.0)
    arrays = ResultArrays(state, (slice(0, 3), slice(3, 5), slice(5, 7)))
    first = arrays.take()[2:]
    assert [a.tolist() for a in first] == [[0.0, 1.0, 2.0], [3.0, 4.0], [5.0, 6.0]]
    state[:] = -state
    second = arrays.take()[2:]
    assert [a.tolist() for a in first] == [[0.0, 1.0, 2.0], [3.0, 4.0], [5.0, 6.0]]  # kept: untouched
    ids = [id(a) for a in second]
    del second
    state[:] = 10.0
    third = arrays.take()[2:]  # the first set is still kept: a new one
    assert not any(a is b for a in third for b in first)
    assert all(a.tolist() == [10.0] * a.size for a in third)
    del first
    state[:] = 20.0
    fourth = arrays.take()[2:]  # the second set, dropped: written again in place
    assert [id(a) for a in fourth] == ids
    assert all(a.tolist() == [20.0] * a.size for a in fourth)
    assert all(a.tolist() == [10.0] * a.size for a in third)
