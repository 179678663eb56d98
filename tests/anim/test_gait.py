"""The walking gait: plan, root swaps, continuity and foot slide (paper IX.A)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import gsik
from gsik.anim.gait import (
    FEET,
    GAIT_SITES,
    HEEL_RISE_TIME,
    GaitError,
    WalkParameters,
    continuity,
    format_measures,
    frame_displacements,
    measure_walk,
    plan_walk,
    root_slide,
    walk,
    walk_frames,
)
from gsik.anim.motion import Motion
from gsik.skeleton import JointSpec, RotationSpec, SiteSpec, build_skeleton

N_STEPS = 4


@pytest.fixture(scope="module")
def biped():
    return gsik.load_skeleton("biped")


@pytest.fixture(scope="module")
def walked(biped):
    return walk(biped, WalkParameters(n_steps=N_STEPS))


@pytest.fixture(scope="module")
def measures(walked):
    return measure_walk(walked)


# -- parameters -------------------------------------------------------------------


@pytest.mark.parametrize(
    "field, value",
    [("n_steps", 0), ("n_steps", 2.5), ("n_steps", float("nan")), ("step_length", -0.1),
     ("step_height", float("nan")), ("cadence", 0.0), ("fps", float("inf")), ("double_support", 0.9),
     ("arm_swing", "a lot"), ("pelvis_drop", True)],
)
def test_walk_parameters_reject_bad_values_naming_the_field(field, value):
    with pytest.raises(GaitError, match=field):
        WalkParameters(**{field: value})


def test_walk_parameters_reject_an_unknown_lead_foot():
    with pytest.raises(GaitError, match="'left_foot', 'right_foot'"):
        WalkParameters(lead_foot="left_hand")


def test_walk_parameters_are_gsik_errors_and_value_errors():
    with pytest.raises(gsik.GsikError):
        WalkParameters(cadence=-1)
    with pytest.raises(ValueError):
        WalkParameters(cadence=-1)


def test_walk_parameters_need_enough_frames_per_swing():
    with pytest.raises(GaitError, match="frames per swing"):
        WalkParameters(fps=5, cadence=120)
    assert WalkParameters(fps=10, cadence=100, double_support=0.0).fps == 10


def test_step_duration_follows_cadence():
    p = WalkParameters(cadence=120, fps=50)
    assert p.step_duration == pytest.approx(0.5)
    assert p.frame_time == pytest.approx(0.02)
    assert p.replace(cadence=60).step_duration == pytest.approx(1.0)


# -- the plan ---------------------------------------------------------------------


def _runs(roots):
    """The distinct consecutive roots: ('right_foot', 'left_foot', ...)."""
    out = [roots[0]]
    for r in roots[1:]:
        if r != out[-1]:
            out.append(r)
    return out


def test_plan_root_starts_on_the_stance_foot_and_alternates_every_step(biped):
    plan = plan_walk(biped, WalkParameters(n_steps=5))
    runs = _runs(plan.roots)
    assert runs[0] == "right_foot"  # the left foot leads
    assert len(runs) == 5 + 1
    assert all(a != b for a, b in zip(runs, runs[1:]))
    assert len(plan.swap_frames) == 5
    for step, swap in zip(plan.footsteps, plan.swap_frames):
        assert step.swap_frame == swap
        assert plan.roots[swap] == step.foot
        assert plan.roots[swap - 1] == step.stance


def test_plan_lead_foot_decides_the_first_stance(biped):
    plan = plan_walk(biped, WalkParameters(n_steps=2, lead_foot="right_foot"))
    assert plan.roots[0] == "left_foot"
    assert plan.footsteps[0].foot == "right_foot"


def test_plan_footprints_are_half_then_full_strides_then_a_closing_step(biped):
    L = 0.35
    plan = plan_walk(biped, WalkParameters(n_steps=4, step_length=L))
    travelled = [float(s.end[1] - s.start[1]) for s in plan.footsteps]
    assert travelled == pytest.approx([L, 2 * L, 2 * L, L])
    for s in plan.footsteps:
        np.testing.assert_allclose(s.end[[0, 2]], s.start[[0, 2]], atol=1e-12)  # straight ahead, on the floor
    last = {s.foot: s.end for s in plan.footsteps}
    assert last["left_foot"][1] == pytest.approx(last["right_foot"][1])  # side by side at the end


def test_plan_plants_the_swinging_foot_flat_on_its_footprint(biped):
    plan = plan_walk(biped, WalkParameters(n_steps=3))
    for s in plan.footsteps:
        k = plan.sites.index(s.foot)
        for i in range(s.plant_frame, s.swap_frame + 1):
            np.testing.assert_allclose(plan.positions[i, k], s.end, atol=1e-12)
            np.testing.assert_allclose(plan.rotations[i, k], np.eye(3), atol=1e-12)


def test_plan_lifts_the_swinging_foot_to_the_step_height(biped):
    p = WalkParameters(n_steps=3, step_height=0.1, heel_rise=0.0, toe_off=0.0)
    plan = plan_walk(biped, p)
    for s in plan.footsteps:
        k = plan.sites.index(s.foot)
        z = plan.positions[s.lift_frame:s.plant_frame + 1, k, 2] - s.start[2]
        assert z.min() >= -1e-12
        assert z.max() == pytest.approx(0.1, abs=2e-3)


def test_plan_targets_move_smoothly(biped):
    """No target jumps between frames: the plan is continuous everywhere, root swaps included."""
    p = WalkParameters(n_steps=4)
    plan = plan_walk(biped, p)
    step = np.linalg.norm(np.diff(plan.positions, axis=0), axis=2)
    # The fastest target is the swinging foot: 2 step lengths in one swing, min-jerk peak 1.875x the mean speed.
    fastest = 1.875 * 2 * p.step_length / ((1 - p.double_support) * p.step_duration) / p.fps
    assert step.max() <= fastest * 1.05
    accel = np.linalg.norm(np.diff(plan.positions, n=2, axis=0), axis=2)
    assert accel.max() < 0.01  # [m / frame^2]: velocities have no jumps either


@settings(max_examples=25, deadline=None)
@given(n_steps=st.integers(1, 5), step_length=st.floats(0.0, 0.5), cadence=st.floats(60, 140),
       fps=st.sampled_from([24.0, 30.0, 60.0, 120.0]), double_support=st.floats(0.0, 0.5),
       lead=st.sampled_from(FEET))
def test_plan_properties_hold_for_any_parameters(biped, n_steps, step_length, cadence, fps, double_support, lead):
    p = WalkParameters(n_steps=n_steps, step_length=step_length, cadence=cadence, fps=fps,
                       double_support=double_support, lead_foot=lead)
    # The heel rises within the double support: sampled in fewer than 5 frames it is a short bump.
    assume(double_support == 0 or double_support * p.step_duration * fps >= 5)
    plan = plan_walk(biped, p)
    assert np.all(np.isfinite(plan.positions)) and np.all(np.isfinite(plan.rotations))
    assert plan.n_frames == int(math.floor(p.duration * fps + 1e-9)) + 1
    runs = _runs(plan.roots)
    assert len(runs) == n_steps + 1 and all(a != b for a, b in zip(runs, runs[1:]))
    assert plan.footsteps[0].foot == lead
    # Continuous: no target moves farther in one frame than the swinging foot's peak speed allows
    # (min-jerk carry over the stride plus the heel lift, the lift's steepest slope, the heel rise about
    # the ball of the foot, and the upper body)...
    swing = (1 - double_support) * p.step_duration
    heel_rise = 1.875 * p.heel_rise / HEEL_RISE_TIME * 0.12
    fastest = ((1.875 * (2 * step_length + 0.05) + 3.1 * p.step_height) / swing + heel_rise + 1.2) / fps
    step = np.linalg.norm(np.diff(plan.positions, axis=0), axis=2)
    assert step.max() <= fastest
    # ... and no frame's move is a spike against both of its neighbours (a jump would be).
    inner = step[1:-1]
    assert np.all(inner <= 2.5 * np.maximum(step[:-2], step[2:]) + 1e-4)
    # Every footprint lies on the floor, straight ahead of where the foot started.
    for s in plan.footsteps:
        assert s.end[2] == pytest.approx(s.start[2]) and s.end[0] == pytest.approx(s.start[0])
        assert s.heel_frame <= s.lift_frame < s.plant_frame < s.swap_frame


def test_plan_targets_use_no_root_and_cover_every_other_site(biped):
    plan = plan_walk(biped, WalkParameters(n_steps=2))
    for i in (0, plan.swap_frames[0], plan.n_frames - 1):
        targets = plan.targets_at(i)
        assert set(targets) == set(GAIT_SITES) - {plan.roots[i]}


def test_plan_needs_the_gait_sites():
    sk = build_skeleton(
        "stick",
        [JointSpec("base", None, (0, 0, 0)), JointSpec("arm", "base", (0, 0, 1), (RotationSpec((1, 0, 0), -1, 1),))],
        sites=[SiteSpec("tip", "arm", (0, 0, 1))],
        effectors=["tip"],
    )
    with pytest.raises(GaitError, match="cannot walk.*'head'"):
        plan_walk(sk)


# -- the solved walk ------------------------------------------------------------------


def test_walk_output_is_a_motion_with_one_root_per_frame(walked, biped):
    m = walked.motion
    assert isinstance(m, Motion)
    assert m.n_frames == walked.plan.n_frames
    assert m.q.shape == (m.n_frames, biped.n_dofs)
    assert set(m.roots) == set(FEET)
    assert m.frame_time == pytest.approx(1 / 60)
    assert np.all(np.isfinite(m.q)) and np.all(np.isfinite(m.world_from_root))
    assert np.all(m.q >= biped.lower - 1e-9) and np.all(m.q <= biped.upper + 1e-9)


def test_walk_root_is_the_stance_foot_and_alternates_each_step(walked):
    runs = _runs(walked.motion.roots)
    assert len(runs) == N_STEPS + 1
    assert all(a != b for a, b in zip(runs, runs[1:]))
    assert walked.motion.roots == walked.plan.roots


def test_walk_stance_foot_does_not_slide_while_it_is_the_root(measures):
    assert measures.root_slide < 1e-9


def test_walk_is_continuous_across_root_swaps(measures):
    c = measures.continuity
    assert len(c.swap_frames) == N_STEPS
    assert c.median_jump > 1e-3  # the character does move
    assert c.max_swap_jump <= 3 * c.median_jump


def test_walk_plants_the_swinging_foot_on_its_footprint(measures):
    assert measures.max_plant_error < 3e-3  # [m]
    assert measures.max_plant_angle < math.radians(1)


def test_walk_trailing_foot_pivots_on_its_ball(measures):
    assert measures.ball_slide < 5e-3


def test_walk_tracks_every_target_closely(walked, measures):
    assert measures.max_tracking_error < 0.015
    assert np.percentile(walked.position_errors.max(axis=1), 95) < 5e-3
    assert measures.finite


def test_walk_travels_forward_and_ends_standing(walked, biped):
    p = walked.plan.params
    P = walked.motion.positions()
    for foot in FEET:
        f = biped.frame_of(foot)
        assert P[-1, f, 1] - P[0, f, 1] == pytest.approx((N_STEPS - 1) * p.step_length, abs=3e-3)
        assert P[-1, f, 2] == pytest.approx(0.0, abs=3e-3)
    pelvis = biped.frame_of("pelvis")
    assert P[-1, pelvis, 2] == pytest.approx(P[0, pelvis, 2], abs=5e-3)


def test_walk_swings_each_arm_opposite_to_its_leg(walked, biped):
    """While the left foot swings forward, the left hand moves backward (and the right hand forward)."""
    P = walked.motion.positions()
    for s in walked.plan.footsteps[1:-1]:  # full strides
        hand = "left_hand" if s.foot == "left_foot" else "right_hand"
        other = "right_hand" if hand == "left_hand" else "left_hand"
        pelvis = P[:, biped.frame_of("pelvis"), 1]
        rel = {h: P[:, biped.frame_of(h), 1] - pelvis for h in (hand, other)}
        assert rel[hand][s.plant_frame] < rel[hand][s.lift_frame] - 0.05
        assert rel[other][s.plant_frame] > rel[other][s.lift_frame] + 0.05


def test_walk_keeps_the_head_level(walked):
    k = GAIT_SITES.index("head")
    assert walked.orientation_errors[:, k].max() < math.radians(2)


def test_format_measures_names_the_figures(measures):
    text = format_measures(measures)
    for words in ("root swap", "median", "stance foot slide", "footprint error", "finite"):
        assert words in text


def test_a_single_step_walk_ends_in_a_stride_and_stays_in_reach(biped):
    r = walk(biped, WalkParameters(n_steps=1))
    m = measure_walk(r)
    assert m.n_swaps == 1 and m.root_slide < 1e-9 and m.max_tracking_error < 5e-3
    P = r.motion.positions()
    gap = P[-1, biped.frame_of("left_foot"), 1] - P[-1, biped.frame_of("right_foot"), 1]
    assert gap == pytest.approx(0.4, abs=3e-3)


def test_walk_frames_can_stop_at_any_frame_leaving_that_pose(biped):
    plan = plan_walk(biped, WalkParameters(n_steps=2))
    solver = gsik.Solver(biped)
    frames = walk_frames(solver, plan)
    for _ in range(plan.swap_frames[0] + 3):
        last = next(frames)
    frames.close()
    np.testing.assert_array_equal(solver.q, last.result.q)
    assert solver.root == last.root == plan.roots[last.index]
    # The solver is still usable: a fresh solve from there works.
    assert solver.step().status in tuple(gsik.Status)


def test_walk_rejects_bad_solver_settings_and_steps_per_frame(biped):
    with pytest.raises(gsik.SolverError, match="sweeps"):
        walk(biped, WalkParameters(n_steps=1), sweeps=0)
    with pytest.raises(GaitError, match="steps_per_frame"):
        walk(biped, WalkParameters(n_steps=1), steps_per_frame=0)


def test_walk_reports_progress(biped):
    seen = []
    r = walk(biped, WalkParameters(n_steps=1, fps=20), progress=lambda done, total: seen.append((done, total)))
    n = r.motion.n_frames
    assert seen[0] == (1, n) and seen[-1] == (n, n) and len(seen) == n


# -- the measures themselves fire ---------------------------------------------------


def _still_motion(biped, n=6, roots=None, W=None):
    q = np.tile(biped.rest, (n, 1))
    T = biped.frame_transforms(biped.rest)
    roots = roots or ["right_foot"] * n
    if W is None:
        W = np.stack([T[biped.frame_of(r)] for r in roots])
    return Motion(biped, q, tuple(roots), W, 1 / 60)


def test_continuity_flags_a_jump_at_a_root_swap(biped):
    n = 8
    q = np.tile(biped.rest, (n, 1))
    q[:, biped.dof_index("waist.x")] = np.linspace(0, -0.07, n)  # steady motion
    roots = ["right_foot"] * 4 + ["left_foot"] * 4
    T0 = biped.frame_transforms(biped.rest)
    W = np.stack([T0[biped.frame_of(r)] for r in roots])
    W[4:, 0, 3] += 0.05  # the new root lands 5 cm off: every joint jumps
    motion = Motion(biped, q, tuple(roots), W, 1 / 60)
    c = continuity(motion)
    assert c.swap_frames == (4,)
    assert c.max_swap_jump > 0.04
    assert c.ratio > 3


def test_continuity_of_a_still_motion_has_no_swaps(biped):
    c = continuity(_still_motion(biped))
    assert c.swap_frames == () and c.max_jump == 0.0 and c.ratio == 0.0
    assert frame_displacements(_still_motion(biped)).shape == (5,)


def test_root_slide_measures_a_sliding_root(biped):
    m = _still_motion(biped)
    W = m.world_from_root.copy()
    W[:, 1, 3] += np.linspace(0.0, 0.02, m.n_frames)
    assert root_slide(_still_motion(biped, W=W)) == pytest.approx(0.02)
    assert root_slide(m) == 0.0
