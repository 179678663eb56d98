"""Planning a walk: footprints, then target trajectories of feet, pelvis, head and hands, then the roots.

Each step of :func:`plan_walk` is one function below, in the order it runs.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from gsik.anim.gait.curves import lift, min_jerk, pchip, toe_off
from gsik.anim.gait.params import (
    FEET, FORWARD, GAIT_SITES, HEEL_RISE_TIME, OTHER_FOOT, SIDE_HAND, UP, Footstep, GaitPlan, WalkParameters,
    check_skeleton,
)
from gsik.kinematics import world_frames
from gsik.rotations import matrix_from_axis_angle
from gsik.skeleton import Skeleton

_COLUMN = {name: k for k, name in enumerate(GAIT_SITES)}


class _Timeline(NamedTuple):
    """The walk's clock: step duration ``T`` [s], phases [s] and output frames."""

    n: int  # steps
    T: float  # step duration [s]
    t0: float  # lead-in: lower the pelvis and shift it over the first stance foot [s]
    swing: float  # [s]
    heel: float  # the trailing heel rises while both feet are down [s]
    heel_rise: float  # [rad]
    total: float  # [s]
    fps: float
    times: np.ndarray  # (n_frames,) [s]

    @property
    def n_frames(self) -> int:
        return self.times.shape[0]

    def first_frame(self, t: float) -> int:
        """The first frame at or after time ``t`` [s] (the last frame at most)."""
        return int(min(self.n_frames - 1, math.ceil(t * self.fps - 1e-9)))


class _Step(NamedTuple):
    """One swing: ``foot`` leaves ``start`` at time ``ts`` [s] and plants on ``end`` (3,) [m]."""

    foot: str
    stance: str
    start: np.ndarray
    end: np.ndarray
    ts: float


def _timeline(params: WalkParameters) -> _Timeline:
    T = params.step_duration
    heel = params.double_support * T
    # A double support shorter than HEEL_RISE_TIME lifts the heel proportionally less, never abruptly.
    heel_rise = params.heel_rise * min(1.0, heel / HEEL_RISE_TIME)
    total = T + (params.n_steps + 1) * T
    n_frames = int(math.floor(total * params.fps + 1e-9)) + 1
    return _Timeline(params.n_steps, T, T, (1.0 - params.double_support) * T, heel, heel_rise, total, params.fps,
                     np.arange(n_frames) / params.fps)


def _footprints(rest: dict, params: WalkParameters, tl: _Timeline) -> list[_Step]:
    """Who swings when, from where to where: half a stride first and last, whole strides between."""
    feet_at = {f: rest[f][1].copy() for f in FEET}
    swinger = params.lead_foot
    steps = []
    for k in range(tl.n):
        half = k == 0 or (k == tl.n - 1 and tl.n >= 2)
        start = feet_at[swinger].copy()
        end = start + (params.step_length if half else 2.0 * params.step_length) * FORWARD
        steps.append(_Step(swinger, OTHER_FOOT[swinger], start, end, tl.t0 + k * tl.T))
        feet_at[swinger] = end
        swinger = OTHER_FOOT[swinger]
    return steps


def _foot_tracks(rest: dict, ball: dict, steps: list[_Step], params: WalkParameters,
                 tl: _Timeline) -> tuple[dict, dict]:
    """``({foot: (n_frames, 3) position [m]}, {foot: (n_frames,) pitch [rad]})``.

    Planted, then heel-off (the foot pitches about its toe), swing (lift, carry, flatten), planted.
    """
    foot_pos = {f: np.tile(rest[f][1], (tl.n_frames, 1)) for f in FEET}
    foot_pitch = {f: np.zeros(tl.n_frames) for f in FEET}
    for step in steps:
        toe = step.start + rest[step.foot][0] @ ball[step.foot]
        lift_from = _heel_off(foot_pos[step.foot], foot_pitch[step.foot], toe, step, tl)
        _swing(foot_pos[step.foot], foot_pitch[step.foot], lift_from, step, params, tl)
    return foot_pos, foot_pitch


def _heel_off(pos: np.ndarray, pitch: np.ndarray, toe: np.ndarray, step: _Step, tl: _Timeline) -> np.ndarray:
    """Pitch the foot about its toe before the swing; returns where the swing starts (3,) [m]."""
    times, heel, ts = tl.times, tl.heel, step.ts
    u = (times - (ts - heel)) / heel if heel > 0 else (times >= ts).astype(float)
    rising = (times >= ts - heel) & (times < ts)
    pitch_rise = tl.heel_rise * min_jerk(u)
    pitch[rising] = -pitch_rise[rising]
    for i in np.flatnonzero(rising):
        pos[i] = toe + _rot_x(-pitch_rise[i]) @ (step.start - toe)
    return toe + _rot_x(-tl.heel_rise) @ (step.start - toe) if heel > 0 else step.start


def _swing(pos: np.ndarray, pitch: np.ndarray, lift_from: np.ndarray, step: _Step, params: WalkParameters,
           tl: _Timeline) -> None:
    """Lift, carry and flatten the foot from ``lift_from`` onto its footprint."""
    lift_pitch = tl.heel_rise if tl.heel > 0 else 0.0
    s = (tl.times - step.ts) / tl.swing
    during = tl.times >= step.ts
    ramp = min_jerk(s)
    traj = lift_from + np.outer(ramp, step.end - lift_from) + np.outer(params.step_height * lift(s), UP)
    pos[during] = traj[during]
    pitch[during] = -(lift_pitch * (1.0 - ramp[during]) + params.toe_off * toe_off(s[during]))


def _pelvis_track(rest: dict, steps: list[_Step], params: WalkParameters, tl: _Timeline) -> np.ndarray:
    """(n_frames, 3) pelvis position [m], one coordinate at a time through its own knots.

    A monotone cubic each, so no overshoot:
    forward: over the stance foot at mid-swing, midway between the feet at each plant;
    sideways: towards the stance foot at mid-swing, centred in the middle of each double support;
    height: lowered for walking, highest at mid-swing, lowest at each plant, back to rest at the end.
    """
    ankle_offset = rest["pelvis"][1] - 0.5 * (rest["left_foot"][1] + rest["right_foot"][1])
    centre_x = 0.5 * (rest["left_foot"][1][0] + rest["right_foot"][1][0])
    side = {f: math.copysign(1.0, rest[f][1][0] - centre_x) for f in FEET}
    rest_x, rest_y, rest_z = rest["pelvis"][1]
    walk_z = rest_z - params.pelvis_drop
    bob = params.pelvis_bob
    kx, ky, kz = [(0.0, rest_x)], [(0.0, rest_y)], [(0.0, rest_z), (tl.t0 - tl.heel, walk_z - bob)]
    placed = {f: rest[f][1].copy() for f in FEET}
    for step in steps:
        mid_swing = step.ts + 0.5 * tl.swing
        plant = step.ts + tl.swing
        kx.append((mid_swing, centre_x + side[step.stance] * params.pelvis_sway))
        kx.append((plant + 0.5 * tl.heel, centre_x))
        ky.append((mid_swing, placed[step.stance][1] + ankle_offset[1]))
        placed[step.foot] = step.end
        ky.append((plant, 0.5 * (placed["left_foot"][1] + placed["right_foot"][1]) + ankle_offset[1]))
        kz.append((mid_swing, walk_z + bob))
        kz.append((plant, walk_z - bob))
    kx.append((tl.total, centre_x))
    ky.append((tl.total, ky[-1][1]))
    # Back to rest height once the feet are side by side again (a single step leaves them a stride apart).
    kz.append((tl.total, rest_z if tl.n >= 2 else walk_z))
    return np.stack([pchip(*zip(*knots), tl.times) for knots in (kx, ky, kz)], axis=1)


def _arm_angles(steps: list[_Step], params: WalkParameters, tl: _Timeline) -> dict[str, np.ndarray]:
    """``{hand: (n_frames,) swing angle about the shoulder [rad]}``, opposite to the legs.

    At each plant the arm on the side of the planted (leading) foot is back, the other forward, in
    proportion to the stride; a smooth curve between.
    """
    L = params.step_length
    knots = {hand: [(0.0, 0.0)] for hand in SIDE_HAND.values()}
    for k, step in enumerate(steps):
        amount = params.arm_swing * min(1.0, float(step.end[1] - step.start[1]) / (2.0 * L)) if L > 0 else 0.0
        last = k == tl.n - 1 and tl.n >= 2
        for f, sign in ((step.foot, -1.0), (step.stance, 1.0)):
            knots[SIDE_HAND[f]].append((step.ts + tl.swing, 0.0 if last else sign * amount))
    for hand_knots in knots.values():
        hand_knots.append((tl.total, 0.0))
    return {hand: pchip(*zip(*hand_knots), tl.times) for hand, hand_knots in knots.items()}


def _targets(skeleton: Skeleton, rest: dict, p0: np.ndarray, feet: tuple[dict, dict], pelvis: np.ndarray,
             arm_angles: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """(n_frames, 6, 3) positions [m] and (n_frames, 6, 3, 3) orientations, columns as :data:`GAIT_SITES`."""
    n_frames = pelvis.shape[0]
    positions = np.empty((n_frames, len(GAIT_SITES), 3))
    rotations = np.empty((n_frames, len(GAIT_SITES), 3, 3))
    pelvis_shift = pelvis - rest["pelvis"][1]
    positions[:, _COLUMN["pelvis"]] = pelvis
    rotations[:, _COLUMN["pelvis"]] = rest["pelvis"][0]
    # The head stays level, above the pelvis: the trunk stays upright.
    positions[:, _COLUMN["head"]] = rest["head"][1] + pelvis_shift
    rotations[:, _COLUMN["head"]] = rest["head"][0]
    foot_pos, foot_pitch = feet
    for foot in FEET:
        positions[:, _COLUMN[foot]] = foot_pos[foot]
        for i in range(n_frames):
            rotations[i, _COLUMN[foot]] = _rot_x(foot_pitch[foot][i]) @ rest[foot][0]
    for hand, theta in arm_angles.items():
        shoulder = _shoulder_position(skeleton, skeleton.frame_of(hand), p0)
        arm = rest[hand][1] - shoulder
        for i in range(n_frames):
            Rx = _rot_x(theta[i])
            positions[i, _COLUMN[hand]] = shoulder + pelvis_shift[i] + Rx @ arm
            rotations[i, _COLUMN[hand]] = Rx @ rest[hand][0]
    return positions, rotations


def _roots_and_footsteps(steps: list[_Step], ball: dict, tl: _Timeline) -> tuple[list[str], list[Footstep]]:
    """The root of each frame: the first stance foot until the first plant, then each foot from the frame after
    it plants; and the swings as :class:`Footstep`."""
    footsteps = []
    roots = [steps[0].stance] * tl.n_frames
    for k, step in enumerate(steps):
        plant_frame = tl.first_frame(step.ts + tl.swing)
        swap_frame = min(plant_frame + 1, tl.n_frames - 1)
        roots[swap_frame:] = [step.foot] * (tl.n_frames - swap_frame)
        b = ball[step.foot].copy()
        for a in (step.start, step.end, b):
            a.flags.writeable = False
        footsteps.append(Footstep(k, step.foot, step.stance, tl.first_frame(step.ts - tl.heel),
                                  tl.first_frame(step.ts), plant_frame, swap_frame, step.start, step.end, b))
    return roots, footsteps


def plan_walk(skeleton: Skeleton, params: WalkParameters | None = None) -> GaitPlan:
    """Target trajectories of a walk from the rest pose.

    The character starts from its rest pose where the skeleton's definition
    places it and walks along +y.

    Raises:
        GaitError: the skeleton lacks one of :data:`GAIT_SITES`.
    """
    params = WalkParameters() if params is None else params
    check_skeleton(skeleton)
    R0, p0 = world_frames(skeleton, skeleton.rest)
    rest = {n: (R0[skeleton.frame_of(n)], p0[skeleton.frame_of(n)]) for n in GAIT_SITES}
    tl = _timeline(params)
    steps = _footprints(rest, params, tl)
    ball = {f: rest[f][0].T @ _ball_offset(skeleton, f, rest[f][1], p0) for f in FEET}
    feet = _foot_tracks(rest, ball, steps, params, tl)
    pelvis = _pelvis_track(rest, steps, params, tl)
    positions, rotations = _targets(skeleton, rest, p0, feet, pelvis, _arm_angles(steps, params, tl))
    roots, footsteps = _roots_and_footsteps(steps, ball, tl)
    for a in (tl.times, positions, rotations):
        a.flags.writeable = False
    return GaitPlan(skeleton, params, GAIT_SITES, tl.times, tuple(roots), positions, rotations, tuple(footsteps))


def _rot_x(angle: float) -> np.ndarray:
    return matrix_from_axis_angle((1.0, 0.0, 0.0), angle)


def _ball_offset(skeleton: Skeleton, foot: str, foot_position: np.ndarray, p: np.ndarray) -> np.ndarray:
    """From a foot's sole site to the ball of the foot on the ground (3,) [m], at rest.

    Uses the site ``<side>_toe`` when the skeleton has one, else 0.1 m forward.
    """
    toe = foot.replace("_foot", "_toe")
    if toe in skeleton.site_names:
        d = p[skeleton.frame_of(toe)] - foot_position
        d[2] = 0.0
        if np.linalg.norm(d) > 1e-3:
            return d
    return 0.1 * FORWARD


def _shoulder_position(skeleton: Skeleton, hand_frame: int, p: np.ndarray) -> np.ndarray:
    """World position of the shoulder above a hand: the second joint with DOFs up the chain."""
    joint_of_frame = {int(f): j for j, f in enumerate(skeleton.joint_frame)}
    f = hand_frame
    found = []
    while f >= 0:
        j = joint_of_frame.get(f)
        if j is not None and skeleton.joint_dofs[j]:
            found.append(j)
            if len(found) == 2:
                return p[f].copy()
        f = int(skeleton.frame_parent[f])
    return p[hand_frame].copy()
