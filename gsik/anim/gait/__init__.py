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

from gsik.anim.gait.measures import (
    Continuity, WalkMeasures, continuity, format_measures, frame_displacements, measure_walk, root_slide,
)
from gsik.anim.gait.params import (
    FEET, GAIT_SITES, HEEL_RISE_TIME, MIN_SWING_FRAMES, REACH_WARNING, WALK_RANGES, WALK_SETTINGS,
    WALK_STEPS_PER_FRAME, Footstep, GaitPlan, WalkParameters,
)
from gsik.anim.gait.plan import plan_walk
from gsik.anim.gait.walk import WalkFrame, WalkResult, walk, walk_frames
from gsik.errors import GaitError

__all__ = [
    "Continuity", "WalkMeasures", "continuity", "format_measures", "frame_displacements", "measure_walk", "root_slide",
    "FEET", "GAIT_SITES", "HEEL_RISE_TIME", "MIN_SWING_FRAMES", "REACH_WARNING", "WALK_RANGES", "WALK_SETTINGS",
    "WALK_STEPS_PER_FRAME", "Footstep", "GaitPlan", "WalkParameters", "plan_walk", "WalkFrame", "WalkResult", "walk",
    "walk_frames", "GaitError",
]
