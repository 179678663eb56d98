"""What a walk is asked to be: its parameters, the sites it drives, and the plan it becomes."""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from typing import NamedTuple

import numpy as np

from gsik import validate
from gsik.errors import GaitError, choices
from gsik.skeleton import Skeleton
from gsik.solver import SolverSettings
from gsik.targets import Target

#: The effector sites the gait drives, in the column order of the result arrays.
GAIT_SITES = ("head", "pelvis", "left_hand", "right_hand", "left_foot", "right_foot")
FEET = ("left_foot", "right_foot")
SIDE_HAND = {"left_foot": "left_hand", "right_foot": "right_hand"}
OTHER_FOOT = {"left_foot": "right_foot", "right_foot": "left_foot"}
#: Relative weights of the effectors in the least squares.
_WEIGHTS = {"head": 0.5, "pelvis": 1.0, "left_hand": 0.3, "right_hand": 0.3, "left_foot": 1.0, "right_foot": 1.0}
#: Solver settings of :func:`walk` by default: the library's defaults.
WALK_SETTINGS = SolverSettings()
#: Solver steps per frame of :func:`walk` by default. Measured on the biped (8 steps, 60 fps):
#: default settings, 1 step per frame: footprints within 0.4 mm, every target within 3.4 mm;
#: 2 steps: 0.06 mm and 1.7 mm (about 0.5 ms per frame). The paper's plain PGS (10 sweeps, 1 step):
#: 10 mm and 36 mm; it needs about 10 steps of 20 sweeps per frame to get within 1.5 mm.
WALK_STEPS_PER_FRAME = 2
FORWARD = np.array([0.0, 1.0, 0.0])
UP = np.array([0.0, 0.0, 1.0])


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
            lo, hi, unit = WALK_RANGES[f.name]
            what = f"walk parameter {f.name}"
            v = validate.in_range(getattr(self, f.name), lo, hi, what, GaitError, unit)
            object.__setattr__(self, f.name, validate.whole(v, what, GaitError, 1, floats=True) if f.name == "n_steps" else v)
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



def check_skeleton(skeleton: Skeleton) -> None:
    if not isinstance(skeleton, Skeleton):
        raise GaitError(f"walk needs a Skeleton (see gsik.load_skeleton), got {type(skeleton).__name__}")
    missing = [n for n in GAIT_SITES if n not in skeleton.effector_sites]
    if missing:
        raise GaitError(f"skeleton {skeleton.name!r} cannot walk: it has no effector site {choices(missing)}; "
                        f"the gait drives {choices(GAIT_SITES)}; its effectors: {choices(skeleton.effector_sites)}")
