"""Pose scenarios and robustness runs (Kenwright 2012, sections IX.B and IX.C).

A :class:`Scenario` is a set of effector targets, held still or animated for
a few frames (the wave). The built-in ones for the biped are authored as
joint angles and turned into targets by forward kinematics, so each has an
exact solution; the ``impossible`` one puts every target far out of reach.
:func:`random_scenario` makes seeded random poses the same way.

:func:`gsik.anim.scenario_run.run_scenario` runs one the way the interactive
app does and measures how the solver settles and holds.

Example:
    >>> import gsik
    >>> from gsik.anim.scenarios import builtin_scenario
    >>> from gsik.anim.scenario_run import run_scenario
    >>> sk = gsik.load_skeleton("biped")
    >>> report = run_scenario(builtin_scenario(sk, "kneel"))
    >>> report.settled, report.max_position_error < 1e-3
    (True, True)
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np


from gsik import validate
from gsik.errors import ScenarioError, choices, show_value
from gsik.kinematics import world_frames
from gsik.io.pose import Pose
from gsik.rotations import matrix_from_axis_angle, quaternion_from_matrix, transform
from gsik.skeleton import Skeleton
from gsik.targets import Target


@dataclass(frozen=True, eq=False)
class Scenario:
    """Effector targets for one skeleton, held or animated. Read-only arrays.

    Attributes:
        name: Short name (``"kneel"``).
        description: One line for people.
        skeleton: The skeleton, with ``root`` the IK root of the scenario.
        effectors: (m,) the effectors with a target.
        positions: (n_frames, m, 3) target world positions [m] per frame.
        rotations: (n_frames, m, 3, 3) target world orientations per frame.
        world_from_root: (4, 4) where the root is pinned.
        reachable: False when the targets are out of reach on purpose.
        frame_time: Seconds per animated frame [s].

    Frame ``i`` of a run uses the targets of ``min(i, n_frames - 1)``: a held
    pose has one frame.
    """

    name: str
    description: str
    skeleton: Skeleton
    effectors: tuple[str, ...]
    positions: np.ndarray
    rotations: np.ndarray
    world_from_root: np.ndarray
    reachable: bool = True
    frame_time: float = 1.0 / 60.0

    def __post_init__(self):
        P, R, W = self._checked_arrays()
        self._check_effectors()
        object.__setattr__(self, "positions", P)
        object.__setattr__(self, "rotations", R)
        object.__setattr__(self, "world_from_root", W)
        object.__setattr__(self, "effectors", tuple(self.effectors))

    def _checked_arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions, rotations and root placement as read-only float arrays of the documented shapes."""
        P, R, W = (validate.frozen(a) for a in (self.positions, self.rotations, self.world_from_root))
        m = len(self.effectors)
        if P.ndim != 3 or P.shape[1:] != (m, 3) or P.shape[0] < 1:
            raise ScenarioError(f"scenario {self.name!r}: positions must have shape (n_frames, {m}, 3), got {P.shape}")
        if R.shape != P.shape[:2] + (3, 3):
            raise ScenarioError(f"scenario {self.name!r}: rotations must have shape {P.shape[:2] + (3, 3)}, "
                                f"got {R.shape}")
        if W.shape != (4, 4):
            raise ScenarioError(f"scenario {self.name!r}: world_from_root must have shape (4, 4), got {W.shape}")
        if not all(np.all(np.isfinite(a)) for a in (P, R, W)):
            raise ScenarioError(f"scenario {self.name!r}: targets must be finite")
        return P, R, W

    def _check_effectors(self) -> None:
        effectors = set(self.skeleton.effector_names)
        for e in self.effectors:
            if e not in effectors:
                raise ScenarioError(f"scenario {self.name!r}: {e!r} is not an effector of root "
                                    f"{self.skeleton.root!r}; effectors: {choices(self.skeleton.effector_names)}")

    @property
    def root(self) -> str:
        return self.skeleton.root

    @property
    def n_frames(self) -> int:
        """Animated frames (1 for a held pose)."""
        return self.positions.shape[0]

    def targets_at(self, i: int) -> dict[str, Target]:
        """The targets of frame ``i`` (held after the last animated frame)."""
        k = min(max(int(i), 0), self.n_frames - 1)
        return {e: Target(self.positions[k, j], self.rotations[k, j]) for j, e in enumerate(self.effectors)}


# -- building scenarios ------------------------------------------------------------------


def _rest_root(skeleton: Skeleton) -> np.ndarray:
    """Where the rest pose, placed as the skeleton's definition places it, puts the root (4, 4)."""
    R, p = world_frames(skeleton, skeleton.rest)
    f = skeleton.frame_of(skeleton.root)
    return transform(R[f], p[f])


def angles(skeleton: Skeleton, values: Mapping[str, float]) -> np.ndarray:
    """The rest pose with some DOFs set by name (n_dofs,) [rad].

    Raises:
        ScenarioError: an unknown DOF name (listing the valid ones) or an angle outside its limits.
    """
    q = skeleton.rest.copy()
    for name, v in values.items():
        if name not in skeleton.dof_names:
            raise ScenarioError(f"skeleton {skeleton.name!r} has no degree of freedom {name!r}; "
                                f"valid: {choices(skeleton.dof_names)}")
        i = skeleton.dof_names.index(name)
        if not skeleton.lower[i] <= v <= skeleton.upper[i]:
            raise ScenarioError(f"angle {name} = {v!r} rad is outside its limits "
                                f"[{skeleton.lower[i]:.6g}, {skeleton.upper[i]:.6g}]")
        q[i] = v
    return q


def scenario_from_angles(skeleton: Skeleton, name: str, description: str, q_frames, root: str | None = None,
                         frame_time: float = 1.0 / 60.0) -> Scenario:
    """A scenario whose targets are where the effectors are at given angles.

    Args:
        skeleton: The skeleton.
        name, description: As in :class:`Scenario`.
        q_frames: Angles (n_dofs,) for a held pose or (n_frames, n_dofs) for
            an animation [rad].
        root: The IK root (default the skeleton's); it is pinned where the
            rest pose puts it, and every other effector gets a target.
        frame_time: Seconds per animated frame [s].
    """
    sk = skeleton if root is None else skeleton.with_root(root)
    Q = np.atleast_2d(np.asarray(q_frames, dtype=float))
    W = _rest_root(sk)
    effectors = sk.effector_names
    frames = [sk.frame_of(e) for e in effectors]
    P = np.empty((Q.shape[0], len(effectors), 3))
    R = np.empty((Q.shape[0], len(effectors), 3, 3))
    for i, q in enumerate(Q):
        Rw, pw = world_frames(sk, q, W, sk.root)
        P[i], R[i] = pw[frames], Rw[frames]
    return Scenario(name, description, sk, effectors, P, R, W, True, frame_time)


def random_scenario(skeleton: Skeleton, seed: int, spread: float = 0.5, root: str | None = None) -> Scenario:
    """A seeded random pose: angles drawn between the rest pose and a uniform draw within the limits.

    ``q = rest + spread * (uniform(lower, upper) - rest)``, so ``spread`` 0 is
    the rest pose and 1 a uniform pose within the limits. The targets (every
    effector, position and orientation) are where that pose puts the
    effectors, so an exact solution exists. Named ``random-<seed>``.
    """
    if not (isinstance(spread, (int, float)) and 0.0 <= spread <= 1.0):
        raise ScenarioError(f"random pose spread must be between 0 and 1, got {spread!r}")
    rng = np.random.default_rng(seed)
    q = skeleton.rest + spread * (rng.uniform(skeleton.lower, skeleton.upper) - skeleton.rest)
    return scenario_from_angles(skeleton, f"random-{seed}", f"random pose, seed {seed}, spread {spread:g}",
                                q, root)


#: Most random scenarios one call makes (each is a full scenario run when played).
MAX_RANDOM_SCENARIOS = 10_000


def random_scenarios(skeleton: Skeleton, n: int, seed: int = 0, spread: float = 0.5) -> tuple[Scenario, ...]:
    """``n`` (0 to :data:`MAX_RANDOM_SCENARIOS`) random poses with seeds ``seed, seed + 1, ...`` (see
    :func:`random_scenario`)."""
    if isinstance(n, bool) or not isinstance(n, int) or not 0 <= n <= MAX_RANDOM_SCENARIOS:
        raise ScenarioError(f"random scenarios: the count must be a whole number from 0 to "
                            f"{MAX_RANDOM_SCENARIOS:,}, got {show_value(n)}")
    return tuple(random_scenario(skeleton, seed + k, spread) for k in range(n))


#: The biped's scenario poses as joint angles [rad] (the rest pose elsewhere). Root: the right foot.
#: Signs (skeletons/biped.yaml): hip x > 0 and shoulder x > 0 swing forward, knee x < 0 bends,
#: ankle x > 0 lifts the toes, waist x < 0 bends forward, right shoulder y < 0 lifts the arm sideways.
_BIPED_POSES: dict[str, tuple[str, dict[str, float]]] = {
    "kneel": ("kneel on the left knee, right foot planted, hands forward", {
        "right_hip.x": 1.5, "right_knee.x": -1.95, "right_ankle.x": 0.45,
        "left_hip.x": -0.05, "left_knee.x": -1.82, "left_ankle.x": 0.5,
        "left_shoulder.x": 0.3, "right_shoulder.x": 0.3, "left_elbow.x": 0.6, "right_elbow.x": 0.6,
    }),
    "one_leg": ("stand on the right leg, left knee raised, arms out sideways", {
        "left_hip.x": 1.2, "left_knee.x": -1.6, "left_ankle.x": -0.3,
        "right_hip.y": 0.08, "right_ankle.y": -0.08,
        "left_shoulder.y": 1.4, "right_shoulder.y": -1.4,
    }),
    "reach_up": ("both arms straight up, looking up", {
        "left_shoulder.x": 2.9, "right_shoulder.x": 2.9, "left_elbow.x": 0.05, "right_elbow.x": 0.05,
        "waist.x": 0.25, "neck.x": 0.3, "atlas.x": 0.2,
    }),
    "crouch": ("deep crouch, heels down, leaning forward, arms forward", {
        "left_hip.x": 1.7, "right_hip.x": 1.7, "left_knee.x": -2.2, "right_knee.x": -2.2,
        "left_ankle.x": 0.5, "right_ankle.x": 0.5, "waist.x": -0.5, "neck.x": 0.3,
        "left_shoulder.x": 1.3, "right_shoulder.x": 1.3, "left_elbow.x": 0.3, "right_elbow.x": 0.3,
    }),
    "twist": ("upper body twisted to the left, one arm forward, one back", {
        "waist.z": 0.7, "neck.z": 0.9, "left_shoulder.x": -0.6, "right_shoulder.x": 1.2,
        "left_elbow.x": 0.4, "right_elbow.x": 1.0,
    }),
}

#: The wave: the right arm rises sideways, the forearm waves twice, then holds.
_WAVE_ARM = {"right_shoulder.y": -2.4, "right_elbow.x": 1.2, "neck.z": -0.3}
_WAVE_SWING = ("right_shoulder.z", 0.5)  # the DOF that waves and its amplitude [rad]

#: Names of the built-in scenarios, in table order.
SCENARIO_NAMES = ("kneel", "one_leg", "reach_up", "wave", "crouch", "twist", "impossible")


def _wave(skeleton: Skeleton, fps: float = 60.0, raise_time: float = 0.5, cycles: int = 2,
          period: float = 1.0) -> Scenario:
    up = angles(skeleton, _WAVE_ARM)
    rest = skeleton.rest
    n_raise = int(round(raise_time * fps))
    n_wave = int(round(cycles * period * fps))
    s = np.linspace(0.0, 1.0, n_raise + 1)[1:]
    ease = s * s * (3.0 - 2.0 * s)
    Q = [rest + e * (up - rest) for e in ease]
    dof, amplitude = _WAVE_SWING
    d = skeleton.dof_names.index(dof)
    for k in range(1, n_wave + 1):
        q = up.copy()
        q[d] += amplitude * math.sin(2.0 * math.pi * k / (period * fps))
        Q.append(q)
    return scenario_from_angles(skeleton, "wave", f"raise the right arm and wave {cycles} times",
                                np.array(Q), "right_foot", 1.0 / fps)


def _impossible(skeleton: Skeleton) -> Scenario:
    """Every target far out of reach: above, beside and ahead of the character, turned."""
    sk = skeleton.with_root("right_foot")
    W = _rest_root(sk)
    goals = {
        "head": ((0.0, 0.3, 3.2), ((0, 0, 1), 0.8)),
        "pelvis": ((0.5, 0.6, 1.8), ((1, 0, 0), -0.6)),
        "left_hand": ((-2.5, 0.5, 2.5), ((0, 1, 0), 1.5)),
        "right_hand": ((2.5, -0.5, 0.3), ((0, 1, 0), -1.5)),
        "left_foot": ((-1.5, 2.0, 1.2), ((1, 0, 0), 1.0)),
    }
    effectors = tuple(e for e in sk.effector_names if e in goals)
    P = np.array([[goals[e][0] for e in effectors]])
    R = np.array([[matrix_from_axis_angle(np.array(goals[e][1][0], float), goals[e][1][1]) for e in effectors]])
    return Scenario("impossible", "every target metres out of reach: the best reach must hold still",
                    sk, effectors, P, R, W, reachable=False)


def _split_spine(skeleton: Skeleton, pose: Mapping[str, float]) -> dict[str, float]:
    """The biped's pose angles for ``skeleton``: on a two-joint spine (the humanoid's ``waist`` and ``chest``) each
    waist angle is shared between the two joints, in proportion to their ranges on its side."""
    if not all(f"chest.{a}" in skeleton.dof_names for a in "xyz"):
        return dict(pose)
    out = dict(pose)
    for a in "xyz":
        if f"waist.{a}" not in out:
            continue
        v = out[f"waist.{a}"]
        w, c = skeleton.dof_index(f"waist.{a}"), skeleton.dof_index(f"chest.{a}")
        room_w, room_c = (skeleton.upper[w], skeleton.upper[c]) if v > 0 else (skeleton.lower[w], skeleton.lower[c])
        share = room_w / (room_w + room_c) if room_w + room_c else 0.5
        out[f"waist.{a}"], out[f"chest.{a}"] = v * share, v * (1.0 - share)
    return out


def builtin_scenario(skeleton: Skeleton, name: str) -> Scenario:
    """One of :data:`SCENARIO_NAMES` for the biped (or a skeleton with its joints: the humanoid).

    Raises:
        ScenarioError: an unknown name (listing the valid ones), or a skeleton
            without the biped's joints and effectors.
    """
    if name not in SCENARIO_NAMES:
        raise ScenarioError(f"no scenario {name!r}; scenarios: {choices(SCENARIO_NAMES)}")
    needed = {d for _, pose in _BIPED_POSES.values() for d in pose} | set(_WAVE_ARM) | {_WAVE_SWING[0]}
    missing = sorted(needed - set(skeleton.dof_names))
    sites = ("head", "pelvis", "left_hand", "right_hand", "left_foot", "right_foot")
    missing_sites = [s for s in sites if s not in skeleton.effector_sites]
    if missing or missing_sites:
        raise ScenarioError(f"the built-in scenarios are written for the biped; skeleton {skeleton.name!r} lacks "
                            f"{choices(missing + missing_sites)} (use random scenarios instead)")
    if name == "wave":
        return _wave(skeleton)
    if name == "impossible":
        return _impossible(skeleton)
    description, pose = _BIPED_POSES[name]
    return scenario_from_angles(skeleton, name, description, angles(skeleton, _split_spine(skeleton, pose)),
                                "right_foot")


def builtin_scenarios(skeleton: Skeleton) -> tuple[Scenario, ...]:
    """Every built-in scenario, in :data:`SCENARIO_NAMES` order."""
    return tuple(builtin_scenario(skeleton, n) for n in SCENARIO_NAMES)


def scenario_pose(scenario: Scenario, q: np.ndarray | None = None) -> Pose:
    """A :class:`gsik.io.pose.Pose` of a scenario: its last targets, with the angles ``q`` (default the rest pose).

    Every effector of the scenario's root is in the pose; one the scenario
    does not drive is written disabled, at where ``q`` puts it.
    """
    sk = scenario.skeleton
    q = sk.rest if q is None else sk.validate_q(q)
    W = scenario.world_from_root
    achieved = sk.effector_poses(q, W)
    k = scenario.n_frames - 1
    targets = {}
    for e in sk.effector_names:
        if e in scenario.effectors:
            j = scenario.effectors.index(e)
            quaternion = quaternion_from_matrix(scenario.rotations[k, j])
            targets[e] = Target(scenario.positions[k, j], tuple(quaternion))
        else:
            targets[e] = Target.from_transform(achieved[e], enabled=False)
    return Pose(sk.name, sk.root, tuple(W[:3, 3]), tuple(quaternion_from_matrix(W[:3, :3])),
                dict(zip(sk.dof_names, (float(v) for v in q))), targets)
