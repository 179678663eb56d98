"""Solver.move_target: a target moved in place steps and solves exactly as the same target set afresh, keeps its
weight, flags and priority, and refuses bad input with one TargetError, changing nothing."""

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import gsik
from gsik import Target
from gsik.io.urdf_skeleton import skeleton_from_urdf

ARM = Path(__file__).parent / "data" / "seven_dof_arm.urdf"
#: The arm's bent pose (shoulder x, y, z, elbow, wrist z, y, x) [rad]: away from its straight-arm singularity.
BENT = np.array([0.6, 0.2, 0.0, 1.2, 0.0, 0.0, 0.0])


@pytest.fixture(scope="module")
def arm() -> gsik.Skeleton:
    return skeleton_from_urdf(ARM, effectors=["hand"], root="base")


def _circle(start: np.ndarray, frames: int = 30) -> list[np.ndarray]:
    """Poses (4, 4) round a 5 cm circle from ``start``, the orientation turning a little."""
    out = []
    for f in range(frames):
        a = 2.0 * np.pi * f / frames
        T = start.copy()
        T[:3, 3] += 0.05 * np.array([0.0, np.sin(a), 1.0 - np.cos(a)])
        c, s = np.cos(0.2 * a), np.sin(0.2 * a)
        T[:3, :3] = start[:3, :3] @ np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        out.append(T)
    return out


def _same(a: gsik.SolveResult, b: gsik.SolveResult) -> None:
    assert np.array_equal(a.q, b.q)
    assert np.array_equal(a.position_errors, b.position_errors)
    assert np.array_equal(a.orientation_errors, b.orientation_errors)
    assert (a.status, a.iterations, a.sweeps, a.residual) == (b.status, b.iterations, b.sweeps, b.residual)


def _orientation(kind: str, T: np.ndarray):
    """The orientation of ``T`` (4, 4) as a move is given it: a matrix (also slightly off orthonormal, or as
    lists), a quaternion, or None (position only)."""
    if kind == "nearly":  # within Target's tolerance but re-orthonormalised by it
        return T[:3, :3] * (1.0 + 1e-9)
    if kind == "lists":
        return T[:3, :3].tolist()
    return {"matrix": T[:3, :3], "quaternion": Target.from_transform(T).orientation, "position": None}[kind]


@pytest.mark.parametrize("kind", ["matrix", "nearly", "lists", "quaternion", "position"])
def test_moving_steps_exactly_as_setting_the_replaced_target(arm, kind):
    moved, fresh = gsik.Solver(arm, q0=BENT), gsik.Solver(arm, q0=BENT)
    start = moved.effector_poses()["hand"]
    first = Target.from_transform(start, weight=2.0)
    moved.set_target("hand", first)
    for T in _circle(start):
        orientation = _orientation(kind, T)
        moved.move_target("hand", T[:3, 3].tolist() if kind == "lists" else T[:3, 3], orientation)
        new = first.replace(position=T[:3, 3]) if orientation is None else \
            first.replace(position=T[:3, 3], orientation=orientation)
        _same(moved.step(), fresh.step({"hand": new}))
        assert moved.targets == {"hand": new}  # the Target made on reading: weight, flags, priority kept
    assert moved.targets["hand"].weight == 2.0


def test_orientation_none_keeps_the_last_moves(arm):
    solver = gsik.Solver(arm, q0=BENT)
    start = solver.effector_poses()["hand"]
    solver.set_target("hand", Target.from_transform(start))
    turned = _circle(start)[7][:3, :3]
    solver.move_target("hand", start[:3, 3], turned)
    solver.move_target("hand", start[:3, 3] + 0.01)  # the orientation kept: the turned one
    t = solver.targets["hand"]
    assert np.array_equal(t.position, start[:3, 3] + 0.01)
    assert np.array_equal(t.rotation, turned)


def test_a_solve_after_moving_meets_the_moved_target(arm):
    solver = gsik.Solver(arm, q0=BENT)
    start = solver.effector_poses()["hand"]
    solver.set_target("hand", Target.from_transform(start))
    goal = _circle(start)[10]
    solver.move_target("hand", goal[:3, 3], goal[:3, :3])
    result = solver.solve()
    assert result.converged
    assert np.linalg.norm(solver.effector_poses()["hand"][:3, 3] - goal[:3, 3]) <= solver.settings.position_tolerance


def test_moving_on_the_prioritised_path_is_setting_the_replaced_target(biped):
    """With a posture the step is prioritised: a move retargets its controller as set_target does."""
    moved, fresh = gsik.Solver(biped), gsik.Solver(biped)
    targets = {n: Target.from_transform(T) for n, T in moved.effector_poses().items() if n != "left_hand"}
    hand = moved.effector_poses()["left_hand"]
    targets["left_hand"] = Target(hand[:3, 3], priority=1)
    for solver in (moved, fresh):
        solver.set_posture()
        solver.set_targets(targets)
    for f in range(5):
        p = hand[:3, 3] + [0.0, 0.01 * f, 0.01 * f]
        moved.move_target("left_hand", p)
        _same(moved.step(), fresh.step({**targets, "left_hand": targets["left_hand"].replace(position=p)}))


def test_bad_moves_raise_one_target_error_and_change_nothing(arm):
    solver = gsik.Solver(arm, q0=BENT)
    start = solver.effector_poses()["hand"]
    before = Target.from_transform(start)
    solver.set_target("hand", before)
    with pytest.raises(gsik.TargetError, match=r"no effector 'wrist'.*effectors: .*hand"):
        solver.move_target("wrist", start[:3, 3])
    with pytest.raises(gsik.TargetError, match="'base' is the IK root"):
        solver.move_target("base", start[:3, 3])
    for bad in ([np.nan, 0.0, 0.0], [0.0, np.inf, 0.0]):
        with pytest.raises(gsik.TargetError, match=r"target for 'hand': target position must be finite"):
            solver.move_target("hand", bad)
    with pytest.raises(gsik.TargetError, match=r"target for 'hand': target orientation must be finite"):
        solver.move_target("hand", start[:3, 3], np.full((3, 3), np.nan))
    with pytest.raises(gsik.TargetError, match="not a rotation matrix"):
        solver.move_target("hand", start[:3, 3], 2.0 * np.eye(3))
    with pytest.raises(gsik.TargetError, match=r"shape \(3,\)"):
        solver.move_target("hand", [1.0, 2.0])
    assert solver.targets == {"hand": before}
    free = gsik.Solver(arm, q0=BENT)
    with pytest.raises(gsik.TargetError, match="'hand' has no target to move; set one first .*; targets: none"):
        free.move_target("hand", start[:3, 3])
    assert free.targets == {}


@pytest.mark.parametrize("position, orientation", [
    (np.array([np.nan, 0.0, 0.0]), None), (np.array([0.0, np.inf, 0.0]), None), (np.array([1.0, 2.0]), None),
    (np.zeros(4), None), (np.zeros(0), None), (np.array([2e6, 0.0, 0.0]), None), (np.zeros((3, 1)), None),
    (np.array([1, 2], dtype=np.int64), "matrix"), (np.array([np.nan, 0, 0], dtype=np.float32), None),
    (None, np.full((3, 3), np.nan)),
    (None, 2.0 * np.eye(3)), (None, -np.eye(3)), (None, np.eye(4)), (None, np.eye(3)[:2]), (None, np.zeros((3, 3, 1))),
    (np.zeros((2, 3))[:, 0], None), (np.zeros((6, 2))[::2, 1], 2.0 * np.eye(3))])
def test_bad_float_arrays_raise_as_the_same_values_given_as_lists(arm, position, orientation):
    """A float64 array takes the compiled write, which checks its length, finiteness and bounds itself: what it
    refuses raises the TargetError the same values raise as lists, and nothing changes."""
    solver = gsik.Solver(arm, q0=BENT)
    start = solver.effector_poses()["hand"]
    solver.set_target("hand", Target.from_transform(start))
    before, rows = solver.targets, solver._buffers.floats.copy()
    position = start[:3, 3].copy() if position is None else position
    orientation = start[:3, :3].copy() if isinstance(orientation, str) else orientation
    with pytest.raises(gsik.TargetError) as as_lists:
        solver.move_target("hand", position.tolist(), None if orientation is None else orientation.tolist())
    with pytest.raises(gsik.TargetError) as as_arrays:
        solver.move_target("hand", position, orientation)
    assert str(as_arrays.value) == str(as_lists.value)
    assert type(as_arrays.value) is type(as_lists.value)
    assert solver.targets == before
    assert np.array_equal(solver._buffers.floats, rows, equal_nan=True)


def test_strided_float_arrays_move_as_their_copies(arm):
    """A transform's column and corner (strided views) go through the compiled write as contiguous copies do."""
    strided, copied = gsik.Solver(arm, q0=BENT), gsik.Solver(arm, q0=BENT)
    start = strided.effector_poses()["hand"]
    for solver in (strided, copied):
        solver.set_target("hand", Target.from_transform(start))
    for T in _circle(start, 8):
        strided.move_target("hand", T[:3, 3], T[:3, :3])
        copied.move_target("hand", T[:3, 3].copy(), np.ascontiguousarray(T[:3, :3]))
        _same(strided.step(), copied.step())
        strided.move_target("hand", T[:3, 3])
        copied.move_target("hand", T[:3, 3].copy())
        _same(strided.step(), copied.step())
    assert strided.targets == copied.targets


def test_a_single_chain_solves_without_staging_positions_first(arm, biped, rng):
    """positions_first stages only on a skeleton with several effectors: the arm's solve is the unstaged one,
    the whole body's is still the staged one (and staging changes some whole-body solve)."""
    for _ in range(5):
        T = arm.effector_poses(rng.uniform(arm.lower, arm.upper))["hand"]
        runs = [gsik.Solver(arm, **s).solve({"hand": Target.from_transform(T)})
                for s in ({}, {"positions_first": False})]
        _same(*runs)
    differs = False
    for _ in range(5):
        q = rng.uniform(biped.lower, biped.upper)
        targets = {n: Target.from_transform(T) for n, T in biped.effector_poses(q).items()}
        default, staged, unstaged = (gsik.Solver(biped, **s).solve(targets)
                                     for s in ({}, {"positions_first": True}, {"positions_first": False}))
        _same(default, staged)
        differs |= default.iterations != unstaged.iterations or not np.array_equal(default.q, unstaged.q)
    assert differs


def test_a_solve_with_restarts_keeps_the_moved_target(arm):
    """An out-of-reach move: the solve restarts and stages the targets (continuation) in the packed rows; the
    target it reports, and the next step's, is still the moved one."""
    solver = gsik.Solver(arm, q0=BENT)
    start = solver.effector_poses()["hand"]
    first = Target.from_transform(start, weight=3.0)
    solver.set_target("hand", first)
    far = start[:3, 3] + [2.0, 0.0, 0.0]
    turned = _circle(start)[5][:3, :3]
    solver.move_target("hand", far, turned)
    result = solver.solve()
    assert not result.converged and result.attempts > 1
    assert solver.targets == {"hand": first.replace(position=far, orientation=turned)}
    fresh = gsik.Solver(arm, q0=solver.q)
    _same(solver.step(), fresh.step({"hand": first.replace(position=far, orientation=turned)}))


@settings(max_examples=80, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1),
       tilt=st.sampled_from([0.0, 1e-14, 1e-13, 4e-13, 1e-12, 3e-12, 1e-9, 1e-4, 1.0]),
       far=st.sampled_from([None, 1e6, 1e6 * (1.0 + 2e-16), 1e6 + 1.0, np.inf, np.nan]), turned=st.booleans(),
       flip=st.booleans())
def test_a_float_array_moves_as_the_replaced_target_or_raises_as_it(arm, seed, tilt, far, turned, flip):
    """The compiled write's own checks (coordinates within their bound, a rotation kept as given only when its
    columns are orthonormal within EXACT_ROTATION and its determinant positive) against Target's: near and across
    both boundaries, a move packs what setting the replaced target packs, bit for bit, or raises a TargetError as
    replacing does and changes nothing."""
    rng = np.random.default_rng(seed)
    solver, fresh = gsik.Solver(arm, q0=BENT), gsik.Solver(arm, q0=BENT)
    first = Target.from_transform(solver.effector_poses()["hand"], weight=0.5)
    for s in (solver, fresh):
        s.set_target("hand", first)
    position = rng.normal(0.0, 0.3, 3)
    if far is not None:
        position[rng.integers(3)] = far * rng.choice([-1.0, 1.0])
    w, x, y, z = rng.normal(size=4)
    n = np.sqrt(w * w + x * x + y * y + z * z)
    rotation = Target(np.zeros(3), (w / n, x / n, y / n, z / n)).rotation + tilt * rng.normal(size=(3, 3))
    if flip:
        rotation = -rotation
    orientation = rotation if turned else None
    rows = solver._buffers.floats.copy()
    try:
        replaced = first.replace(position=position) if orientation is None else \
            first.replace(position=position, orientation=orientation)
    except gsik.TargetError:  # (its wording for the same values as lists: test_bad_float_arrays_raise_as_...)
        with pytest.raises(gsik.TargetError):
            solver.move_target("hand", position, orientation)
        assert solver.targets == {"hand": first}
        assert np.array_equal(solver._buffers.floats, rows, equal_nan=True)
        return
    solver.move_target("hand", position, orientation)
    fresh.set_target("hand", replaced)
    assert np.array_equal(solver._packed.position, fresh._packed.position)
    assert np.array_equal(solver._packed.rotation, fresh._packed.rotation)
    assert solver.targets == {"hand": replaced}
