"""A walking gait by root swapping (Kenwright 2012, section IX.A, Figure 4).

The standing foot is the IK root; at every step the root swaps to the other
foot. While a foot is the root it is pinned to the world, so it cannot slide.
Each step the swinging foot gets a target trajectory (lift, carry forward,
plant flat on its footprint) and the upper body gets matching trajectories:
the pelvis moves forward over the stance foot, sways towards it and bobs; the
head stays level above the pelvis; each hand swings opposite to the foot of
its side. Every frame is solved warm-started from the previous one.

Timeline, with ``T`` the step duration ``60 / cadence`` [s] and ``d`` the
:attr:`WalkParameters.double_support` fraction::

    lead-in (T)         | step 0 (T)                         | step 1 | ... | settle (T)
    pelvis lowers and   | swing (1-d)T     | both feet down dT |        |     | feet side by side,
    sways; heel rises   | lift, carry,     | (the trailing heel|        |     | pelvis back to
    in the last dT      | plant flat       |  rises)           |        |     | rest height

The root swaps on the frame after each plant (heel strike): the foot just
planted carries the weight from then on. Both feet are on the ground at that
moment, so pinning the new foot where it stands changes nothing in the pose,
and the old root becomes an effector that follows its own trajectory (heel
rise, then swing).

Conventions of the bundled biped: metres, z up, the character faces +y. The
walk goes along the skeleton's +y axis from the rest pose where the
skeleton's definition places it.

Example:
    >>> import gsik
    >>> from gsik.anim.gait import WalkParameters, measure_walk, walk
    >>> result = walk(gsik.load_skeleton("biped"), WalkParameters(n_steps=4))
    >>> measure_walk(result).swap_jump_ratio < 3
    True
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass, fields, replace
from typing import NamedTuple

import numpy as np

from gsik.errors import GaitError, choices
from gsik.kinematics import world_frames
from gsik.anim.motion import Motion
from gsik.rotations import angle_between, matrix_from_axis_angle
from gsik.skeleton import Skeleton
from gsik.solver import SolveResult, Solver, SolverSettings, Status
from gsik.targets import Target

#: The effector sites the gait drives, in the column order of the result arrays.
GAIT_SITES = ("head", "pelvis", "left_hand", "right_hand", "left_foot", "right_foot")
FEET = ("left_foot", "right_foot")
_SIDE_HAND = {"left_foot": "left_hand", "right_foot": "right_hand"}
_OTHER = {"left_foot": "right_foot", "right_foot": "left_foot"}
#: Relative weights of the effectors in the least squares.
_WEIGHTS = {"head": 0.5, "pelvis": 1.0, "left_hand": 0.3, "right_hand": 0.3, "left_foot": 1.0, "right_foot": 1.0}
#: Solver settings of :func:`walk` by default: the library's defaults.
WALK_SETTINGS = SolverSettings()
#: Solver steps per frame of :func:`walk` by default. Measured on the biped (8 steps, 60 fps):
#: default settings, 1 step per frame: footprints within 0.4 mm, every target within 3.4 mm;
#: 2 steps: 0.06 mm and 1.7 mm (about 0.5 ms per frame). The paper's plain PGS (10 sweeps, 1 step):
#: 10 mm and 36 mm; it needs about 10 steps of 20 sweeps per frame to get within 1.5 mm.
WALK_STEPS_PER_FRAME = 2
_FORWARD = np.array([0.0, 1.0, 0.0])
_UP = np.array([0.0, 0.0, 1.0])


#: Shortest time the trailing heel takes to rise fully [s]; a shorter double support raises it less.
HEEL_RISE_TIME = 0.1
#: Fewest frames a swing may last.
MIN_SWING_FRAMES = 5
#: (lowest, highest, unit) of every numeric field of :class:`WalkParameters`.
WALK_RANGES = {
    "n_steps": (1, 10_000, "steps"),
    "step_length": (0.0, 1.5, "m"),
    "step_height": (0.0, 0.5, "m"),
    "cadence": (1.0, 300.0, "steps/min"),
    "fps": (1.0, 1000.0, "frames/s"),
    "double_support": (0.0, 0.8, ""),
    "pelvis_drop": (0.0, 0.5, "m"),
    "pelvis_sway": (0.0, 0.3, "m"),
    "pelvis_bob": (0.0, 0.1, "m"),
    "arm_swing": (0.0, 1.5, "rad"),
    "toe_off": (0.0, 1.2, "rad"),
    "heel_rise": (0.0, 1.0, "rad"),
}


@dataclass(frozen=True)
class WalkParameters:
    """What walk to make; every field is checked when the parameters are made.

    Attributes:
        n_steps: Number of steps (foot swings), >= 1. The first step is half
            a stride; with two or more steps the last one brings the feet
            side by side again.
        step_length: Forward distance between consecutive footprints [m].
        step_height: Highest lift of the swinging foot [m].
        cadence: Steps per minute; a step lasts ``60 / cadence`` seconds.
        fps: Frames per second of the output [1/s]; a swing must span at
            least :data:`MIN_SWING_FRAMES` frames.
        double_support: Fraction of each step with both feet planted (0 to 0.8).
        pelvis_drop: How much lower than at rest the pelvis walks [m]
            (bent knees let the legs reach the footprints with flat feet).
        pelvis_sway: Sideways shift of the pelvis towards the stance foot [m].
        pelvis_bob: Up-down amplitude of the pelvis [m], highest at mid-stance.
        arm_swing: Forward/backward swing of the arms at full stride [rad].
        heel_rise: Pitch of the trailing foot about its toe when it lifts off
            [rad]: its heel rises during double support (proportionally
            less when that lasts under :data:`HEEL_RISE_TIME`).
        toe_off: Extra toes-down pitch of the swinging foot early in the swing
            [rad]; the foot plants flat.
        lead_foot: The foot that swings first (``"left_foot"`` or ``"right_foot"``).

    Raises:
        GaitError: a field out of its range, naming it and the range, or
            too few frames per swing.
    """

    n_steps: int = 4
    step_length: float = 0.4
    step_height: float = 0.08
    cadence: float = 100.0
    fps: float = 60.0
    double_support: float = 0.2
    pelvis_drop: float = 0.04
    pelvis_sway: float = 0.03
    pelvis_bob: float = 0.01
    arm_swing: float = 0.35
    toe_off: float = 0.3
    heel_rise: float = 0.3
    lead_foot: str = "left_foot"

    def __post_init__(self):
        for f in fields(self):
            if f.name == "lead_foot":
                continue
            v = getattr(self, f.name)
            lo, hi, unit = WALK_RANGES[f.name]
            unit = f" {unit}" if unit else ""
            if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
                raise GaitError(f"walk parameter {f.name} must be a number, got {v!r}")
            if not (math.isfinite(v) and lo <= v <= hi):
                raise GaitError(f"walk parameter {f.name} must be between {lo} and {hi}{unit}, got {v!r}")
            if f.name == "n_steps" and int(v) != v:
                raise GaitError(f"walk parameter n_steps must be a whole number, got {v!r}")
            object.__setattr__(self, f.name, int(v) if f.name == "n_steps" else float(v))
        swing_frames = self.fps * self.step_duration * (1.0 - self.double_support)
        if swing_frames < MIN_SWING_FRAMES:
            raise GaitError(f"walk parameters give {swing_frames:.3g} frames per swing (fps x step duration x "
                            f"(1 - double_support)); need at least {MIN_SWING_FRAMES}: raise fps or lower cadence")
        if self.lead_foot not in FEET:
            raise GaitError(f"walk parameter lead_foot must be one of {choices(FEET)}, got {self.lead_foot!r}")

    @property
    def step_duration(self) -> float:
        """Seconds per step [s]."""
        return 60.0 / self.cadence

    @property
    def frame_time(self) -> float:
        """Seconds per frame [s]."""
        return 1.0 / self.fps

    @property
    def duration(self) -> float:
        """Length of the whole walk [s]: lead-in, the steps and the settle."""
        return (self.n_steps + 2) * self.step_duration

    def replace(self, **changes) -> WalkParameters:
        """A copy with some fields changed (validated again)."""
        return replace(self, **changes)


#: A walk whose targets stay farther than this from the solved pose [m] is partly out of reach.
REACH_WARNING = 0.01


class Footstep(NamedTuple):
    """One swing of one foot.

    Attributes:
        index: Step number from 0.
        foot: The swinging foot.
        stance: The foot that is the IK root during this step.
        heel_frame: First frame of the heel rise (the foot pitches about its ball).
        lift_frame: First frame of the swing.
        plant_frame: First frame with the foot on its footprint.
        swap_frame: First frame whose root is ``foot`` (the frame after the plant).
        start: (3,) world position of the foot's site before the heel rise [m].
        end: (3,) the footprint: where the foot's site is planted [m].
        ball: (3,) offset from the foot's site to the point it pivots on, in
            the foot's frame [m].
    """

    index: int
    foot: str
    stance: str
    heel_frame: int
    lift_frame: int
    plant_frame: int
    swap_frame: int
    start: np.ndarray
    end: np.ndarray
    ball: np.ndarray


@dataclass(frozen=True, eq=False)
class GaitPlan:
    """The walk as target trajectories, one row per output frame. Read-only arrays.

    Attributes:
        skeleton: The skeleton that walks.
        params: The :class:`WalkParameters`.
        sites: The driven effector sites (:data:`GAIT_SITES`), column order.
        times: (n_frames,) time of each frame [s].
        roots: (n_frames,) the IK root (a foot) of each frame.
        positions: (n_frames, 6, 3) target world positions [m].
        rotations: (n_frames, 6, 3, 3) target world orientations.
        footsteps: The swings, in order.
    """

    skeleton: Skeleton
    params: WalkParameters
    sites: tuple[str, ...]
    times: np.ndarray
    roots: tuple[str, ...]
    positions: np.ndarray
    rotations: np.ndarray
    footsteps: tuple[Footstep, ...]

    @property
    def n_frames(self) -> int:
        return self.times.shape[0]

    @property
    def swap_frames(self) -> tuple[int, ...]:
        """Frames whose root differs from the previous frame's."""
        return tuple(i for i in range(1, self.n_frames) if self.roots[i] != self.roots[i - 1])

    def targets_at(self, i: int) -> dict[str, Target]:
        """The targets of frame ``i`` for every driven effector but that frame's root."""
        return {
            name: Target(self.positions[i, k], self.rotations[i, k], weight=_WEIGHTS[name])
            for k, name in enumerate(self.sites)
            if name != self.roots[i]
        }


def _check_skeleton(skeleton: Skeleton) -> None:
    if not isinstance(skeleton, Skeleton):
        raise GaitError(f"walk needs a Skeleton (see gsik.load_skeleton), got {type(skeleton).__name__}")
    missing = [n for n in GAIT_SITES if n not in skeleton.effector_sites]
    if missing:
        raise GaitError(f"skeleton {skeleton.name!r} cannot walk: it has no effector site {choices(missing)}; "
                        f"the gait drives {choices(GAIT_SITES)}; its effectors: {choices(skeleton.effector_sites)}")


def _pchip_slopes(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Fritsch-Carlson slopes: a monotone, C1 cubic through the knots (zero slope at the ends)."""
    h = np.diff(t)
    delta = np.diff(y, axis=0) / h[:, None]
    d = np.zeros_like(y)
    for k in range(1, len(t) - 1):
        a, b = delta[k - 1], delta[k]
        same = a * b > 0.0
        w1 = 2.0 * h[k] + h[k - 1]
        w2 = h[k] + 2.0 * h[k - 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            harmonic = (w1 + w2) / (w1 / a + w2 / b)
        d[k] = np.where(same, harmonic, 0.0)
    return d


def _pchip(t_knots, y_knots, t_eval: np.ndarray) -> np.ndarray:
    """Evaluate the monotone cubic through ``(t_knots, y_knots (k, dim))`` at ``t_eval``; held outside."""
    t = np.asarray(t_knots, dtype=float)
    y = np.asarray(y_knots, dtype=float)
    if y.ndim == 1:
        return _pchip(t, y[:, None], t_eval)[:, 0]
    d = _pchip_slopes(t, y)
    te = np.clip(t_eval, t[0], t[-1])
    k = np.clip(np.searchsorted(t, te, side="right") - 1, 0, len(t) - 2)
    h = (t[k + 1] - t[k])[:, None]
    s = ((te - t[k]) / (t[k + 1] - t[k]))[:, None]
    h00 = 2 * s**3 - 3 * s**2 + 1
    h10 = s**3 - 2 * s**2 + s
    h01 = -2 * s**3 + 3 * s**2
    h11 = s**3 - s**2
    return h00 * y[k] + h10 * h * d[k] + h01 * y[k + 1] + h11 * h * d[k + 1]


def _min_jerk(s: np.ndarray) -> np.ndarray:
    """0 to 1 with zero velocity and acceleration at both ends."""
    s = np.clip(s, 0.0, 1.0)
    return s**3 * (10.0 - 15.0 * s + 6.0 * s**2)


def _lift(s: np.ndarray) -> np.ndarray:
    """0 at both ends, 1 at the middle, zero slope at both ends: the swing foot's height profile."""
    s = np.clip(s, 0.0, 1.0)
    return 16.0 * s**2 * (1.0 - s) ** 2


def _toe_off(s: np.ndarray) -> np.ndarray:
    """0 at both ends with zero slope, 1 at s = 0.4: the swing foot's toes-down pitch profile."""
    s = np.clip(s, 0.0, 1.0)
    return s**2 * (1.0 - s) ** 3 / (0.4**2 * 0.6**3)


def plan_walk(skeleton: Skeleton, params: WalkParameters | None = None) -> GaitPlan:
    """Target trajectories of a walk from the rest pose.

    The character starts from its rest pose where the skeleton's definition
    places it and walks along +y.

    Raises:
        GaitError: the skeleton lacks one of :data:`GAIT_SITES`.
    """
    params = WalkParameters() if params is None else params
    _check_skeleton(skeleton)
    R0, p0 = world_frames(skeleton, skeleton.rest)
    rest = {n: (R0[skeleton.frame_of(n)], p0[skeleton.frame_of(n)]) for n in GAIT_SITES}

    T = params.step_duration
    n = params.n_steps
    L = params.step_length
    t0 = T  # lead-in: lower the pelvis and shift it over the first stance foot
    swing = (1.0 - params.double_support) * T
    heel = params.double_support * T  # the trailing heel rises while both feet are down
    # A double support shorter than HEEL_RISE_TIME lifts the heel proportionally less, never abruptly.
    heel_rise = params.heel_rise * min(1.0, heel / HEEL_RISE_TIME)
    total = t0 + (n + 1) * T
    n_frames = int(math.floor(total * params.fps + 1e-9)) + 1
    times = np.arange(n_frames) / params.fps

    def first_frame(t: float) -> int:
        return int(min(n_frames - 1, math.ceil(t * params.fps - 1e-9)))

    # Footprints: who swings when, from where to where.
    feet_at = {f: rest[f][1].copy() for f in FEET}
    swinger = params.lead_foot
    steps = []
    for k in range(n):
        distance = L if (k == 0 or (k == n - 1 and n >= 2)) else 2.0 * L
        start = feet_at[swinger].copy()
        end = start + distance * _FORWARD
        steps.append((swinger, _OTHER[swinger], start, end, t0 + k * T))
        feet_at[swinger] = end
        swinger = _OTHER[swinger]

    ball = {f: rest[f][0].T @ _ball_offset(skeleton, f, rest[f][1], p0) for f in FEET}
    # Feet: planted, then heel-off (the foot pitches about its toe), swing (lift, carry, flatten), planted.
    foot_pos = {f: np.tile(rest[f][1], (n_frames, 1)) for f in FEET}
    foot_pitch = {f: np.zeros(n_frames) for f in FEET}
    for foot, _, start, end, ts in steps:
        toe = start + rest[foot][0] @ ball[foot]
        u = (times - (ts - heel)) / heel if heel > 0 else (times >= ts).astype(float)
        rising = (times >= ts - heel) & (times < ts)
        pitch_rise = heel_rise * _min_jerk(u)
        foot_pitch[foot][rising] = -pitch_rise[rising]
        for i in np.flatnonzero(rising):
            foot_pos[foot][i] = toe + _rot_x(-pitch_rise[i]) @ (start - toe)
        lift = toe + _rot_x(-heel_rise) @ (start - toe) if heel > 0 else start
        lift_pitch = heel_rise if heel > 0 else 0.0
        s = (times - ts) / swing
        during = times >= ts
        ramp = _min_jerk(s)
        traj = lift + np.outer(ramp, end - lift) + np.outer(params.step_height * _lift(s), _UP)
        foot_pos[foot][during] = traj[during]
        foot_pitch[foot][during] = -(lift_pitch * (1.0 - ramp[during]) + params.toe_off * _toe_off(s[during]))

    # Pelvis, one coordinate at a time through its own knots (a monotone cubic each, so no overshoot):
    # forward: over the stance foot at mid-swing, midway between the feet at each plant;
    # sideways: towards the stance foot at mid-swing, centred in the middle of each double support;
    # height: lowered for walking, highest at mid-swing, lowest at each plant, back to rest at the end.
    ankle_offset = rest["pelvis"][1] - 0.5 * (rest["left_foot"][1] + rest["right_foot"][1])
    centre_x = 0.5 * (rest["left_foot"][1][0] + rest["right_foot"][1][0])
    side = {f: math.copysign(1.0, rest[f][1][0] - centre_x) for f in FEET}
    rest_x, rest_y, rest_z = rest["pelvis"][1]
    walk_z = rest_z - params.pelvis_drop
    bob = params.pelvis_bob
    kx, ky, kz = [(0.0, rest_x)], [(0.0, rest_y)], [(0.0, rest_z), (t0 - heel, walk_z - bob)]
    placed = {f: rest[f][1].copy() for f in FEET}
    for foot, stance, start, end, ts in steps:
        mid_swing = ts + 0.5 * swing
        plant = ts + swing
        kx.append((mid_swing, centre_x + side[stance] * params.pelvis_sway))
        kx.append((plant + 0.5 * heel, centre_x))
        ky.append((mid_swing, placed[stance][1] + ankle_offset[1]))
        placed[foot] = end
        ky.append((plant, 0.5 * (placed["left_foot"][1] + placed["right_foot"][1]) + ankle_offset[1]))
        kz.append((mid_swing, walk_z + bob))
        kz.append((plant, walk_z - bob))
    kx.append((total, centre_x))
    ky.append((total, ky[-1][1]))
    # Back to rest height once the feet are side by side again (a single step leaves them a stride apart).
    kz.append((total, rest_z if n >= 2 else walk_z))
    pelvis = np.stack([_pchip(*zip(*knots), times) for knots in (kx, ky, kz)], axis=1)
    pelvis_shift = pelvis - rest["pelvis"][1]

    positions = np.empty((n_frames, len(GAIT_SITES), 3))
    rotations = np.empty((n_frames, len(GAIT_SITES), 3, 3))
    col = {name: k for k, name in enumerate(GAIT_SITES)}
    positions[:, col["pelvis"]] = pelvis
    rotations[:, col["pelvis"]] = rest["pelvis"][0]
    # The head stays level, above the pelvis: the trunk stays upright.
    positions[:, col["head"]] = rest["head"][1] + pelvis_shift
    rotations[:, col["head"]] = rest["head"][0]
    for foot in FEET:
        positions[:, col[foot]] = foot_pos[foot]
        for i in range(n_frames):
            rotations[i, col[foot]] = _rot_x(foot_pitch[foot][i]) @ rest[foot][0]
    # The arms swing about their shoulders opposite to the legs: at each plant the arm on the side of the
    # planted (leading) foot is back, the other forward, in proportion to the stride; a smooth curve between.
    swing_knots = {hand: [(0.0, 0.0)] for hand in _SIDE_HAND.values()}
    for k, (foot, stance, start, end, ts) in enumerate(steps):
        amount = params.arm_swing * min(1.0, float(end[1] - start[1]) / (2.0 * L)) if L > 0 else 0.0
        last = k == n - 1 and n >= 2
        for f, sign in ((foot, -1.0), (stance, 1.0)):
            swing_knots[_SIDE_HAND[f]].append((ts + swing, 0.0 if last else sign * amount))
    for hand, knots in swing_knots.items():
        knots.append((total, 0.0))
        theta = _pchip(*zip(*knots), times)
        shoulder = _shoulder_position(skeleton, skeleton.frame_of(hand), p0)
        arm = rest[hand][1] - shoulder
        for i in range(n_frames):
            Rx = _rot_x(theta[i])
            positions[i, col[hand]] = shoulder + pelvis_shift[i] + Rx @ arm
            rotations[i, col[hand]] = Rx @ rest[hand][0]

    # The root: the first stance foot until the first plant, then each foot from the frame after it plants.
    footsteps = []
    roots = [steps[0][1]] * n_frames
    for k, (foot, stance, start, end, ts) in enumerate(steps):
        plant_frame = first_frame(ts + swing)
        swap_frame = min(plant_frame + 1, n_frames - 1)
        roots[swap_frame:] = [foot] * (n_frames - swap_frame)
        b = ball[foot].copy()
        for a in (start, end, b):
            a.flags.writeable = False
        footsteps.append(Footstep(k, foot, stance, first_frame(ts - heel), first_frame(ts), plant_frame, swap_frame,
                                  start, end, b))
    for a in (times, positions, rotations):
        a.flags.writeable = False
    return GaitPlan(skeleton, params, GAIT_SITES, times, tuple(roots), positions, rotations, tuple(footsteps))


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
    return 0.1 * _FORWARD


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


class WalkFrame(NamedTuple):
    """One solved frame of a walk.

    Attributes:
        index: Frame number.
        root: The IK root (the stance foot).
        world_from_root: (4, 4) world transform of the root.
        result: The last :class:`SolveResult` of the frame (its ``q`` is the pose).
        sweeps: Gauss-Seidel sweeps spent on the frame.
    """

    index: int
    root: str
    world_from_root: np.ndarray
    result: SolveResult
    sweeps: int


def walk_frames(solver: Solver, plan: GaitPlan, steps_per_frame: int = WALK_STEPS_PER_FRAME) -> Iterator[WalkFrame]:
    """Solve a plan frame by frame, warm-started; a generator, so a caller can stop at any frame.

    The solver is reset to the rest pose, placed as the skeleton's definition
    places it, with the plan's first root. After each yielded frame the solver
    holds that frame's pose, so stopping leaves it in a valid, editable state.

    Args:
        solver: A solver of the plan's skeleton (its settings are used as they are).
        plan: From :func:`plan_walk`.
        steps_per_frame: Solver steps (linearisations) per frame, >= 1.
    """
    if isinstance(steps_per_frame, bool) or not isinstance(steps_per_frame, (int, np.integer)) \
            or steps_per_frame < 1:
        raise GaitError(f"steps_per_frame must be a whole number >= 1, got {steps_per_frame!r}")
    skeleton = solver.skeleton
    if skeleton.frame_names != plan.skeleton.frame_names:
        raise GaitError(f"the solver's skeleton {skeleton.name!r} is not the plan's {plan.skeleton.name!r}")
    R0, p0 = world_frames(skeleton, skeleton.rest)
    start_root = plan.roots[0]
    f = skeleton.frame_of(start_root)
    W0 = np.eye(4)
    W0[:3, :3], W0[:3, 3] = R0[f], p0[f]
    if solver.root != start_root:
        solver.set_root(start_root)
    solver.set_world_from_root(W0)
    solver.set_q(skeleton.rest)
    for i in range(plan.n_frames):
        if plan.roots[i] != solver.root:
            solver.set_root(plan.roots[i])
        solver.set_targets(plan.targets_at(i))
        sweeps = 0
        for _ in range(steps_per_frame):
            result = solver.step()
            sweeps += result.sweeps
            if result.status is Status.CONVERGED:
                break  # within tolerance: more steps this frame would change nothing
        yield WalkFrame(i, solver.root, solver.world_from_root, result, sweeps)


@dataclass(frozen=True, eq=False)
class WalkResult:
    """A solved walk.

    Attributes:
        plan: The target trajectories (:class:`GaitPlan`).
        motion: The walk as a :class:`gsik.anim.motion.Motion`.
        position_errors: (n_frames, 6) distance to each target of :data:`GAIT_SITES` [m]
            after the frame's solve (0 for the root foot, which is pinned).
        orientation_errors: (n_frames, 6) the same for orientations [rad].
        sweeps: (n_frames,) Gauss-Seidel sweeps per frame.
        statuses: (n_frames,) :class:`Status` of each frame's last step.
        steps_per_frame: Solver steps per frame.
    """

    plan: GaitPlan
    motion: Motion
    position_errors: np.ndarray
    orientation_errors: np.ndarray
    sweeps: np.ndarray
    statuses: tuple[Status, ...]
    steps_per_frame: int


def walk(
    skeleton: Skeleton,
    params: WalkParameters | None = None,
    *,
    settings: SolverSettings | None = None,
    steps_per_frame: int = WALK_STEPS_PER_FRAME,
    progress: Callable[[int, int], None] | None = None,
    **overrides,
) -> WalkResult:
    """Generate a walk and solve it frame by frame.

    Args:
        skeleton: A skeleton with the sites of :data:`GAIT_SITES` (the biped).
        params: The walk; default :class:`WalkParameters()`.
        settings: Solver settings, default :data:`WALK_SETTINGS`; keyword
            ``overrides`` change fields of it (``sweeps=30``).
        steps_per_frame: Solver steps (linearisations) per frame.
        progress: Called as ``progress(frames_done, n_frames)`` after each frame.

    Raises:
        GaitError: bad parameters or a skeleton that cannot walk.
        SolverError: unknown or invalid solver settings.
    """
    plan = plan_walk(skeleton, params)
    solver = Solver(skeleton, settings=WALK_SETTINGS if settings is None else settings, **overrides)
    n = plan.n_frames
    q = np.empty((n, skeleton.n_dofs))
    W = np.empty((n, 4, 4))
    roots = []
    pos_err = np.zeros((n, len(GAIT_SITES)))
    ori_err = np.zeros((n, len(GAIT_SITES)))
    sweeps = np.zeros(n, dtype=np.int64)
    statuses = []
    col = {name: k for k, name in enumerate(GAIT_SITES)}
    for frame in walk_frames(solver, plan, steps_per_frame):
        i = frame.index
        q[i] = frame.result.q
        W[i] = frame.world_from_root
        roots.append(frame.root)
        for name, pe, oe in zip(frame.result.effector_names, frame.result.position_errors,
                                frame.result.orientation_errors):
            if name in col:
                pos_err[i, col[name]] = pe
                ori_err[i, col[name]] = oe
        sweeps[i] = frame.sweeps
        statuses.append(frame.result.status)
        if progress is not None:
            progress(i + 1, n)
    motion = Motion(skeleton, q, tuple(roots), W, plan.params.frame_time)
    for a in (pos_err, ori_err, sweeps):
        a.flags.writeable = False
    return WalkResult(plan, motion, pos_err, ori_err, sweeps, tuple(statuses), int(steps_per_frame))


# -- measures -------------------------------------------------------------------


def frame_displacements(motion: Motion) -> np.ndarray:
    """(n_frames - 1,) largest world displacement of any joint or site from each frame to the next [m]."""
    sk = motion.skeleton
    points = np.concatenate([sk.joint_frame, sk.site_frame])
    P = motion.positions()[:, points]
    return np.linalg.norm(np.diff(P, axis=0), axis=2).max(axis=1, initial=0.0)


class Continuity(NamedTuple):
    """Frame-to-frame joint motion at root swaps against elsewhere.

    Attributes:
        swap_frames: Frames whose root differs from the previous frame's.
        max_swap_jump: Largest joint displacement into a swap frame [m].
        median_jump: Median of the largest joint displacement between other
            consecutive frames [m].
        max_jump: Largest joint displacement between any two consecutive frames [m].
    """

    swap_frames: tuple[int, ...]
    max_swap_jump: float
    median_jump: float
    max_jump: float

    @property
    def ratio(self) -> float:
        """``max_swap_jump / median_jump`` (0 without swaps; inf if nothing else moves)."""
        if not self.swap_frames:
            return 0.0
        return self.max_swap_jump / self.median_jump if self.median_jump > 0 else math.inf


def continuity(motion: Motion) -> Continuity:
    """Compare the joints' displacement into each root-swap frame with the median displacement."""
    d = frame_displacements(motion)
    swaps = tuple(i for i in range(1, motion.n_frames) if motion.roots[i] != motion.roots[i - 1])
    is_swap = np.zeros(d.shape[0], dtype=bool)
    is_swap[[i - 1 for i in swaps]] = True
    other = d[~is_swap]
    return Continuity(
        swaps,
        float(d[is_swap].max(initial=0.0)),
        float(np.median(other)) if other.size else 0.0,
        float(d.max(initial=0.0)),
    )


def root_slide(motion: Motion) -> float:
    """Largest drift [m] of the root's world position while it stays the root.

    Each run of consecutive frames with the same root is compared with its
    first frame. A pinned root gives 0 up to rounding.
    """
    sk = motion.skeleton
    worst = 0.0
    start = 0
    for i in range(1, motion.n_frames + 1):
        if i == motion.n_frames or motion.roots[i] != motion.roots[start]:
            f = sk.frame_of(motion.roots[start])
            first = motion.frames(start)[1][f]
            for j in range(start + 1, i):
                worst = max(worst, float(np.linalg.norm(motion.frames(j)[1][f] - first)))
            start = i
    return worst


class WalkMeasures(NamedTuple):
    """The figures of a walk (:func:`measure_walk`). Lengths [m], angles [rad].

    Attributes:
        n_frames: Frames.
        n_swaps: Root swaps.
        continuity: :class:`Continuity` of the joints' motion.
        root_slide: Drift of the stance foot while it is the root (:func:`root_slide`).
        ball_slide: Drift of the ball of the trailing foot (an effector, not
            the root) while its heel rises, against where the rise began.
        max_plant_error: Largest distance from a swinging foot to its
            footprint at the frame before the root swaps to it.
        max_plant_angle: Largest angle between that foot and flat.
        max_tracking_error: Largest position error of any effector, any frame.
        mean_sweeps: Mean Gauss-Seidel sweeps per frame.
        finite: No NaN or infinity anywhere in the angles.
    """

    n_frames: int
    n_swaps: int
    continuity: Continuity
    root_slide: float
    ball_slide: float
    max_plant_error: float
    max_plant_angle: float
    max_tracking_error: float
    mean_sweeps: float
    finite: bool

    @property
    def swap_jump_ratio(self) -> float:
        return self.continuity.ratio


def measure_walk(result: WalkResult) -> WalkMeasures:
    """Continuity at the swaps, foot slide and footprint accuracy of a solved walk."""
    motion = result.motion
    plan = result.plan
    sk = motion.skeleton
    ball_slide = 0.0
    plant_error = 0.0
    plant_angle = 0.0
    for step in plan.footsteps:
        f = sk.frame_of(step.foot)
        k = plan.sites.index(step.foot)
        # The frame before the swap: the foot's last frame as an effector, on its footprint.
        last = step.swap_frame - 1
        R_last, p_last = motion.frames(last)
        plant_error = max(plant_error, float(np.linalg.norm(p_last[f] - step.end)))
        plant_angle = max(plant_angle, angle_between(R_last[f], plan.rotations[last, k]))
        R_h, p_h = motion.frames(step.heel_frame)
        ball0 = p_h[f] + R_h[f] @ step.ball
        for j in range(step.heel_frame + 1, step.lift_frame + 1):
            R_j, p_j = motion.frames(j)
            ball_slide = max(ball_slide, float(np.linalg.norm(p_j[f] + R_j[f] @ step.ball - ball0)))
    return WalkMeasures(
        motion.n_frames,
        len(plan.swap_frames),
        continuity(motion),
        root_slide(motion),
        ball_slide,
        plant_error,
        plant_angle,
        float(result.position_errors.max(initial=0.0)),
        float(result.sweeps.mean()) if result.sweeps.size else 0.0,
        bool(np.all(np.isfinite(motion.q)) and np.all(np.isfinite(motion.world_from_root))),
    )


def format_measures(m: WalkMeasures) -> str:
    """The figures of :func:`measure_walk` as readable lines."""
    c = m.continuity
    return "\n".join([
        f"frames:                 {m.n_frames} ({m.n_swaps} root swaps)",
        f"largest joint jump at a root swap: {c.max_swap_jump * 1e3:.3f} mm "
        f"(median elsewhere {c.median_jump * 1e3:.3f} mm, ratio {c.ratio:.2f}; largest anywhere "
        f"{c.max_jump * 1e3:.3f} mm)",
        f"stance foot slide while root:      {m.root_slide:.3g} m",
        f"trailing foot's ball slide (heel rise): {m.ball_slide * 1e3:.3f} mm",
        f"footprint error at plant:          {m.max_plant_error * 1e3:.3f} mm, "
        f"{math.degrees(m.max_plant_angle):.3f} deg",
        f"largest tracking error:            {m.max_tracking_error * 1e3:.3f} mm",
        f"sweeps per frame:                  {m.mean_sweeps:.1f}",
        f"finite:                            {'yes' if m.finite else 'NO'}",
    ])
