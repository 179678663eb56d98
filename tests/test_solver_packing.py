"""Packing targets each frame: a drag's repeated layout packs only positions and orientations, with the same results
as packing every row afresh; any change of layout or orientation weight is packed in full."""

import numpy as np
import pytest

import gsik
from gsik import Target

#: Settings under which a step depends on the angles and the packed targets alone (no warm start, fixed damping).
MEMORYLESS = dict(warm_start=False, adaptive_damping=False)


def _drag(solver, frames=40):
    """A left-hand target moving 2 mm a frame, its orientation turning, from where the hand stands."""
    start = solver.effector_poses()["left_hand"]
    out = []
    for f in range(frames):
        T = start.copy()
        T[:3, 3] += [-0.002 * f, 0.002 * f, 0.001 * f]
        angle = 0.01 * f
        T[:3, :3] = start[:3, :3] @ np.array([[1.0, 0.0, 0.0], [0.0, np.cos(angle), -np.sin(angle)],
                                              [0.0, np.sin(angle), np.cos(angle)]])
        out.append(T)
    return out


def test_a_repeated_layout_steps_exactly_as_a_fresh_packing(biped):
    """One solver sees the same layout every frame (only values move); the other sees a weight-0 head target come
    and go, so every frame is packed in full; a weight-0 row adds nothing, so both must agree bit for bit."""
    repeated, fresh = gsik.Solver(biped), gsik.Solver(biped)
    head = Target.from_transform(fresh.effector_poses()["head"], weight=0.0)
    for f, T in enumerate(_drag(repeated)):
        a = repeated.step({"left_hand": Target.from_transform(T)})
        b = fresh.step({"left_hand": Target.from_transform(T), **({"head": head} if f % 2 else {})})
        assert np.array_equal(a.q, b.q)
        assert np.array_equal(a.position_errors, b.position_errors)
        assert np.array_equal(a.orientation_errors, b.orientation_errors)
    assert a.position_errors.max() > 0.0  # the drag moved the hand: the frames did work


@pytest.mark.parametrize("change", ["position_only", "weight", "priority-free effector"])
def test_a_changed_layout_is_packed_in_full(biped, change):
    """Between two frames with the same target values, a change of flag, weight or targeted effector takes effect:
    the step equals a fresh solver's from the same angles with the new targets (no warm start, fixed damping: a step
    then depends on the angles and the packed rows alone)."""
    solver = gsik.Solver(biped, **MEMORYLESS)
    T = _drag(solver)[20]
    targets = {"left_hand": Target.from_transform(T)}
    for _ in range(3):
        solver.step(targets)
    if change == "position_only":
        targets = {"left_hand": Target.from_transform(T, position_only=True)}
    elif change == "weight":
        targets = {"left_hand": Target.from_transform(T, weight=0.5)}
    else:
        targets = {"right_hand": Target.from_transform(T)}
    reference = gsik.Solver(biped, q0=solver.q, world_from_root=solver.world_from_root, **MEMORYLESS)
    a, b = solver.step(targets), reference.step(targets)
    assert np.array_equal(a.q, b.q)
    assert np.array_equal(a.orientation_errors, b.orientation_errors)


def test_configure_repacks_the_orientation_weight(biped):
    """configure(orientation_weight=...) between frames with one layout weighs the orientation rows anew."""
    solver = gsik.Solver(biped, **MEMORYLESS)
    targets = {"left_hand": Target.from_transform(_drag(solver)[30])}
    solver.step(targets)
    solver.configure(orientation_weight=2.0)
    reference = gsik.Solver(biped, q0=solver.q, world_from_root=solver.world_from_root, orientation_weight=2.0,
                            **MEMORYLESS)
    a, b = solver.step(targets), reference.step(targets)
    assert np.array_equal(a.q, b.q)


def test_repeated_layouts_write_each_target_into_its_own_row(biped):
    """Frames of one layout write only the values, at the rows found for that layout: with a target off the
    effectors (no row) between two that have one, and after the same targets come in another order (another
    layout), the packed rows are a fresh solver's, bit for bit."""
    solver = gsik.Solver(biped)
    poses = solver.effector_poses()
    elbow = solver.world_positions()[biped.frame_of("left_elbow")]
    for f, T in enumerate(_drag(solver, 6)):
        targets = {"left_hand": Target.from_transform(T), "left_elbow": Target(elbow + 0.001 * f, priority=1),
                   "right_hand": Target(poses["right_hand"][:3, 3] - 0.001 * f)}
        if f >= 3:
            targets = dict(reversed(targets.items()))
        solver.set_targets(targets)
        fresh = gsik.Solver(biped)
        fresh.set_targets(targets)
        assert all(a.tobytes() == b.tobytes() for a, b in zip(solver._packed, fresh._packed))
        assert solver._packed.position[fresh._row_of["left_hand"]].tolist() == T[:3, 3].tolist()
