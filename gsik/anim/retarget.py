"""Retarget a BVH clip onto a gsik skeleton (the biped): its joints track the clip's, by priority.

Per frame:

1. The clip's world positions (its own forward kinematics), turned to gsik's
   z-up world and scaled so the clip's legs (hip to ankle, rest pose) are as
   long as the skeleton's.
2. The pelvis, the IK root, is placed from the clip: its origin where the
   clip's hip joints put it, facing where the hips and the spine face
   (right = right hip minus left hip, up = towards the first mapped spine
   joint), turned by the rig's constant lean (the mean turn from that frame
   to the one towards the neck over the clip).
3. Targets with the skeleton's proportions: each mapped frame hangs off its
   nearest mapped ancestor along the clip's direction between the two joints,
   at the skeleton's own distance (a rig with longer arms does not ask for
   stretched ones). Frames sharing an ancestor (neck and shoulders on the
   waist) turn together: the rotation that best aligns their rest directions
   with the clip's (Kabsch).
4. The mapped frames track those points as position targets in strict
   priority (:data:`PRIORITIES`): ankles, wrists and head first; knees,
   elbows, toes, the head's top and the neck next (a foot's and the head's
   orientation are carried by two points each: rigs disagree on what their
   zero rotation means, points do not); shoulders last. A few prioritised
   steps from the previous frame's pose (warm start), with the rest pose as a
   light posture below everything, so directions no target fixes (a straight
   arm's twist) stay natural. A frame the warm start leaves far from its
   targets (:data:`COLD_START_FRACTION`) is solved again from the rest pose.

5. Planted feet stay planted (:mod:`gsik.anim.contacts`): the clip's foot
   and toe contacts (low and slow) pin those targets to one world position
   for the whole contact, tracked at the top priority.

Biped frames nothing maps to and clip joints that drive nothing are
reported; so is every mapped frame's error per clip frame (against the
clip's targets, before pinning), and the foot slide before and after.
:meth:`Retargeted.check` checks the result (:mod:`gsik.anim.retarget_check`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np

from gsik.anim.contacts import Contacts, detect_contacts, pin_targets, planted_speed
from gsik.anim.motion import Motion
from gsik.anim.pelvis_frame import check_rotations, pelvis_frames, rig_lean, unit, up_reference
from gsik.anim.retarget_check import RetargetCheck, Tolerances, check_retarget
from gsik.anim.retarget_map import HEAD_TOP, resolve_mapping, skeleton_bones
from gsik.errors import RetargetError
from gsik.humanoid import rig_from_clip
from gsik.io.bvh import BvhClip, bvh_forward_kinematics
from gsik.io.bvh_skeleton import Z_UP_TO_Y_UP, detect_up
from gsik.kinematics import world_frames
from gsik.skeleton import Skeleton
from gsik.solver import Solver
from gsik.targets import Target

#: Priority level of each skeleton frame's position target (0 is met first).
PRIORITIES = {
    "left_ankle": 0, "right_ankle": 0, "left_hand": 0, "right_hand": 0, "atlas": 0,
    "left_knee": 1, "right_knee": 1, "left_elbow": 1, "right_elbow": 1,
    "left_toe": 1, "right_toe": 1, "head_top": 1, "neck": 1,
    "left_shoulder": 2, "right_shoulder": 2, "waist": 2, "left_hip": 2, "right_hip": 2,
}
#: Priority level of each canonical bone's position target (the same levels on any skeleton).
BONE_PRIORITIES = {
    **dict.fromkeys(("leftFoot", "rightFoot", "leftHand", "rightHand", "head"), 0),
    **dict.fromkeys(("leftLowerLeg", "rightLowerLeg", "leftLowerArm", "rightLowerArm", "leftToes", "rightToes",
                     HEAD_TOP, "neck"), 1),
    **dict.fromkeys(("leftUpperArm", "rightUpperArm", "leftShoulder", "rightShoulder", "spine", "chest",
                     "upperChest", "leftUpperLeg", "rightUpperLeg"), 2),
}
#: The biped's frames the retargeting cannot do without: the pelvis's placement and the leg length need them.
REQUIRED = ("left_hip", "right_hip", "left_knee", "right_knee", "left_ankle", "right_ankle", "neck")
#: Prioritised steps per frame at most (warm-started: a few suffice at 30 fps; a frame ends as soon as a step moves
#: less than 1e-5 rad or holds, and one still 2% of the height off is solved again from the rest pose).
STEPS_PER_FRAME = 6
#: Steps for the first frame, which starts from the rest pose.
FIRST_FRAME_STEPS = 60
#: A warm-started frame whose worst mapped joint misses its target by more than this, in body heights, is solved
#: again from the rest pose, and the closer of the two kept: arms wound into a twist the next frames cannot undo
#: (001_14's arms overhead) start over.
COLD_START_FRACTION = 0.02
#: Weight of the rest posture below every target [1/rad^2]: a tie-breaker only.
REST_POSTURE_WEIGHT = 0.01
#: The canonical bones whose contacts are detected and pinned (a foot's heel point and its toe).
FOOT_BONES = ("leftFoot", "leftToes", "rightFoot", "rightToes")
#: A pelvis frame is degenerate where the hips are closer than this, or the spine this close to their line,
#: in body heights.
DEGENERATE_FRACTION = 1e-3


@dataclass(frozen=True, eq=False)
class Retargeted:
    """A clip retargeted onto a skeleton.

    Attributes:
        motion: The skeleton's motion (IK root ``pelvis`` in every frame).
        mapping: Skeleton frame -> clip joint used.
        unmapped_frames: Skeleton frames nothing in the clip drives.
        unmapped_clip: Clip joints (End Sites included) that drive nothing.
        errors: (n_frames, n_mapped) distance [m] of each mapped frame from its
            target after the solve, columns in ``mapping``'s order.
        scale: Metres of the skeleton per unit of the clip file.
        up: The clip's up axis (``"y"`` or ``"z"``).
        height: The skeleton's rest height [m].
        contacts: The clip's foot contacts (columns: the mapped frames of :data:`FOOT_BONES`).
        slide: p95 planted-foot speed [m/s] of the targets before pinning and of the result.
        degenerate: (n_frames,) bool, frames whose pelvis the clip's hips and spine cannot define.
    """

    motion: Motion
    mapping: dict[str, str]
    unmapped_frames: tuple[str, ...]
    unmapped_clip: tuple[str, ...]
    errors: np.ndarray
    scale: float
    up: str
    height: float
    contacts: Contacts
    slide: tuple[float, float]
    degenerate: np.ndarray

    def check(self, tolerances: Tolerances = Tolerances()) -> RetargetCheck:
        """The result against its tolerances (:mod:`gsik.anim.retarget_check`)."""
        return check_retarget(self.motion, self.errors, self.mapping, self.height, self.slide, self.degenerate,
                              tolerances)

    def error_table(self) -> list[tuple[str, str, float, float, float]]:
        """Per mapped frame: ``(frame, clip joint, mean, p95, max)`` errors [mm]."""
        e = self.errors * 1000.0
        return [(f, j, float(e[:, k].mean()), float(np.percentile(e[:, k], 95)), float(e[:, k].max()))
                for k, (f, j) in enumerate(self.mapping.items())]


#: Scales [m per file unit] a clip may need: a millimetre rig is 1e-3, a rig in kilometres 1e3.
SCALE_RANGE = (1e-6, 1e6)
#: Farthest a clip's joint may be from its origin [file units]: beyond, float64 cannot resolve a bone's length.
MAX_CLIP_EXTENT = 1e10


def clip_world_positions(clip: BvhClip, up: str) -> np.ndarray:
    """The clip's joint positions (n_frames >= 1, n_joints, 3) in gsik's z-up world, in file units;
    :class:`RetargetError` for a clip of no frames or positions that overflow (a root at 1e308)."""
    if clip.n_frames < 1:
        raise RetargetError("cannot retarget a clip of no frames (Frames: 0)")
    with np.errstate(all="ignore"):
        p = bvh_forward_kinematics(clip)[1]
    within = np.all(np.abs(p) <= MAX_CLIP_EXTENT, axis=(1, 2))  # False for NaN too
    if not np.all(within):
        frame = int(np.argmin(within))
        raise RetargetError(f"cannot retarget: at frame {frame + 1} a joint is farther than {MAX_CLIP_EXTENT:g} file "
                            "units from the origin (root position or OFFSETs too large)")
    return p @ Z_UP_TO_Y_UP if up == "y" else p  # row vectors: the export's turn inverted


def _rest_positions(clip: BvhClip) -> np.ndarray:
    """(n_joints, 3) rest-pose positions in file units (offsets summed down the tree)."""
    pos = np.zeros((clip.n_joints, 3))
    for j, joint in enumerate(clip.joints):
        if joint.parent >= 0:
            pos[j] = pos[joint.parent] + joint.offset
    return pos


def _leg_length(points: Callable[[str], np.ndarray]) -> float:
    """Mean of both legs' hip-knee-ankle lengths, from a canonical bone -> position lookup."""
    return 0.5 * sum(np.linalg.norm(points(f"{s}UpperLeg") - points(f"{s}LowerLeg"))
                     + np.linalg.norm(points(f"{s}LowerLeg") - points(f"{s}Foot")) for s in ("left", "right"))


def best_rotations(rest: np.ndarray, now: np.ndarray) -> np.ndarray:
    """Rotations (n, 3, 3) best turning directions ``rest`` (m, 3) onto ``now`` (n, m, 3) (Kabsch, no reflection)."""
    if rest.shape[0] == 1:  # one direction: the shortest turn
        a, b = unit(rest[0]), unit(now[:, 0])
        v, c = np.cross(a, b), np.sum(a * b, axis=-1)
        K = np.zeros((len(b), 3, 3))
        K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -v[:, 2], v[:, 1], -v[:, 0]
        K -= np.transpose(K, (0, 2, 1))
        return np.eye(3) + K + K @ K / np.maximum(1.0 + c, 1e-9)[:, None, None]
    H = np.einsum("mi,nmj->nij", unit(rest), unit(now))
    U, _, Vt = np.linalg.svd(H)
    d = np.sign(np.linalg.det(np.transpose(Vt, (0, 2, 1)) @ np.transpose(U, (0, 2, 1))))
    D = np.broadcast_to(np.eye(3), H.shape).copy()
    D[:, 2, 2] = d
    return np.transpose(Vt, (0, 2, 1)) @ D @ np.transpose(U, (0, 2, 1))


class _Layout(NamedTuple):
    """The skeleton's rest layout about its pelvis frame (x left hip to right hip, z towards the neck).

    Attributes:
        local: mapped frame -> its rest position in the pelvis frame, from the root [m].
        root_from_mid: the root's offset from the hips' midpoint, in the pelvis frame [m].
        root_turn: (3, 3) the root frame's rest rotation in the pelvis frame.
        groups: anchor frame -> the mapped frames hanging off it (tree order).
        offset: anchored frame -> its rest offset from its anchor (world) [m].
    """

    local: dict
    root_from_mid: np.ndarray
    root_turn: np.ndarray
    groups: dict
    offset: dict


def _layout(skeleton: Skeleton, frames: Mapping[str, str], mapping: Mapping[str, str],
            anchor: Mapping[str, str | None], rest) -> _Layout:
    """The :class:`_Layout` of ``skeleton`` from its rest frames ``rest`` (R, p); ``frames``: bone -> frame."""
    R, p = rest
    at = {b: p[skeleton.frame_of(f)] for b, f in frames.items()}
    pelvis = pelvis_frames(at["leftUpperLeg"][None], at["rightUpperLeg"][None], at["neck"][None])[0]
    root = skeleton.frame_of(frames["hips"])
    mid = 0.5 * (at["leftUpperLeg"] + at["rightUpperLeg"])
    local = {f: pelvis.T @ (p[skeleton.frame_of(f)] - p[root]) for f in mapping}
    groups: dict[str, list[str]] = {}
    for f in mapping:
        if anchor[f] is not None:
            groups.setdefault(anchor[f], []).append(f)
    offset = {f: p[skeleton.frame_of(f)] - p[skeleton.frame_of(a)] for a, fs in groups.items() for f in fs}
    return _Layout(local, pelvis.T @ (p[root] - mid), pelvis.T @ R[root], groups, offset)


def _targetable(skeleton: Skeleton, frames: Mapping[str, str]) -> list[str]:
    """The frames retargeting can aim (the recognised bones'), in tree order (an anchor before what hangs off it)."""
    return sorted(set(frames.values()) & set(skeleton.target_names), key=skeleton.frame_of)


def _unmapped(targetable: list[str], names: list[str], mapping: dict[str, str]) -> tuple[tuple[str, ...], ...]:
    """The skeleton frames left without a clip joint, and the clip joints nothing follows."""
    used = set(mapping.values())
    return tuple(f for f in targetable if f not in mapping), tuple(n for n in names if n not in used)


def _scale(skeleton: Skeleton, frames: Mapping[str, str], rest_positions: np.ndarray,
           clip_rest: dict[str, np.ndarray]) -> float:
    """Skeleton leg length over the clip's (``rest_positions`` (n_frames, 3) [m]; ``clip_rest``: frame -> position;
    ``frames``: canonical bone -> skeleton frame)."""
    with np.errstate(all="ignore"):
        clip_leg = _leg_length(lambda b: clip_rest[frames[b]])
        scale = _leg_length(lambda b: rest_positions[skeleton.frame_of(frames[b])]) / clip_leg
    if not SCALE_RANGE[0] <= scale <= SCALE_RANGE[1]:
        raise RetargetError(f"cannot retarget: the clip's legs (hip to knee to ankle) are {clip_leg:.6g} file units "
                            f"long, a scale of {scale:.6g} m per unit; the range is {SCALE_RANGE[0]:g} to "
                            f"{SCALE_RANGE[1]:g} (zero or huge OFFSETs?)")
    return float(scale)


def _with_direction(found: dict[str, str], anchor: dict, rest_points: np.ndarray, scale: float) -> dict[str, str]:
    """``found`` less the joints that sit at their anchor's place in the clip's rest pose (a zero End Site gives
    no direction). ``rest_points`` (len(found), 3): the clip's rest positions of ``found``'s joints, in order."""
    at = dict(zip(found, rest_points))
    kept = {f: j for f, j in found.items()
            if anchor[f] is None or np.linalg.norm(at[f] - at[anchor[f]]) > 1e-6 / scale}
    lost = [f"{f} ({found[f]!r})" for f in REQUIRED if f in found and f not in kept]
    if lost:
        raise RetargetError(f"cannot retarget: {', '.join(lost)} sit where the joint they hang from sits in the "
                            "clip's rest pose (a zero OFFSET gives no direction)")
    return kept


def widened(skeleton: Skeleton, margin: float) -> Skeleton:
    """``skeleton`` with the ranges of its ball joints (two or more DOFs) widened by ``margin`` each side [rad], but
    never past +-pi: an angle beyond is a second copy of a pose the range already holds (a shoulder raised 210 deg is
    one lowered 150 deg the other way), a branch a warm-started solve slides into and cannot leave (CMU 001_14's
    arms overhead). Hinges (knees, elbows) keep theirs, so a straight limb never bends the wrong way."""
    ball = np.zeros(skeleton.n_dofs, dtype=bool)
    for dofs in skeleton.joint_dofs:
        if len(dofs) >= 2:
            ball[list(dofs)] = True
    lower = np.minimum(skeleton.lower, np.maximum(skeleton.lower - margin * ball, -np.pi))
    upper = np.maximum(skeleton.upper, np.minimum(skeleton.upper + margin * ball, np.pi))
    return replace(skeleton, lower=lower, upper=upper)


class Retargeter:
    """Retargets clips of one rig onto one skeleton (reuse it for every clip of that rig).

    Args:
        skeleton: The target skeleton: the biped, or any humanoid gsik skeleton (recognised by
            :mod:`gsik.humanoid`: hips, legs and neck at least); its rest pose (A, T or other) does not matter.
        clip: A clip of the source rig; its hierarchy and rest pose fix the mapping and the scale.
        mapping: Canonical bone (or skeleton frame) -> clip joint entries overriding the recognition
            (:mod:`gsik.anim.retarget_map`).
        up: The clip's up axis, ``"y"`` or ``"z"``; default detected over the clip.
        name: The clip's name in messages.
        limit_margin: How far beyond the skeleton's ball joints' limits the retargeted pose may go, each side
            [rad] (:func:`widened`): real motion (a kneel, a climb) exceeds the biped's authoring ranges.
            0 keeps them.

    Raises:
        RetargetError: a bad mapping entry, a required bone missing in the clip or the skeleton, or a pelvis
            frame the clip leaves undefined.
    """

    def __init__(self, skeleton: Skeleton, clip: BvhClip, mapping: Mapping[str, str] | None = None,
                 up: str | None = None, *, name: str = "clip", limit_margin: float = 0.0):
        names = [j.name for j in clip.joints]
        if limit_margin:
            skeleton = widened(skeleton, limit_margin)
        frames = skeleton_bones(skeleton)
        targetable = _targetable(skeleton, frames)
        found = resolve_mapping(rig_from_clip(clip), frames, mapping, clip=name)
        found = {f: found[f] for f in targetable if f in found}
        self.skeleton, self.name, self._frames = skeleton, name, frames
        self._bone = {f: b for b, f in frames.items()}
        self._root = frames["hips"]
        self.up = detect_up(clip) if up is None else up
        index = {n: k for k, n in enumerate(names)}
        rest_clip = _rest_positions(clip)
        rest = world_frames(skeleton, skeleton.rest, np.eye(4), skeleton.root)
        self.scale = _scale(skeleton, frames, rest[1], {f: rest_clip[index[j]] for f, j in found.items()})
        self._anchor = _anchors(skeleton, [f for f in targetable if f in found], self._root)
        self.mapping = _with_direction(found, self._anchor, rest_clip[[index[j] for j in found.values()]], self.scale)
        self._columns = np.array([index[j] for j in self.mapping.values()])
        self._spine = self._up_point(clip, index)
        self._upright = self._lean(clip, index)
        self._layout = _layout(skeleton, frames, self.mapping, self._anchor, rest)
        self.unmapped_frames, self.unmapped_clip = _unmapped(targetable, names, self.mapping)

    def _up_point(self, clip: BvhClip, index: dict[str, int]) -> str:
        """The mapped frame the pelvis's up axis points to: the waist, or the neck where the clip's waist sits on
        the line through its hips (a degenerate frame); :class:`RetargetError` if neither is off that line."""
        at = clip_world_positions(clip, self.up)
        roles = {"left_hip": "leftUpperLeg", "right_hip": "rightUpperLeg", "waist": "spine", "neck": "neck"}
        joints = {r: self.mapping[self._frames[b]] for r, b in roles.items() if self._frames.get(b) in self.mapping}
        points = {r: at[:, index[j]] for r, j in joints.items()}
        return self._frames[roles[up_reference(points, joints, self.name)]]

    def _lean(self, clip: BvhClip, index: dict[str, int]) -> np.ndarray:
        """The rotation (3, 3) that takes out the rig's constant lean, averaged over ``clip``."""
        at = clip_world_positions(clip, self.up)
        frames = (self._frames["leftUpperLeg"], self._frames["rightUpperLeg"], self._spine, self._frames["neck"])
        return rig_lean(*(at[:, index[self.mapping[f]]] for f in frames))

    def world_targets(self, clip: BvhClip) -> tuple[np.ndarray, np.ndarray]:
        """Per frame: the pelvis's world transform (n, 4, 4) and the mapped frames' targets (n, n_mapped, 3) [m]."""
        p = clip_world_positions(clip, self.up)[:, self._columns] * self.scale
        col = {f: k for k, f in enumerate(self.mapping)}
        left, right = (self._frames[b] for b in ("leftUpperLeg", "rightUpperLeg"))
        R = pelvis_frames(p[:, col[left]], p[:, col[right]], p[:, col[self._spine]]) @ self._upright
        check_rotations(R, f"{self.name}: the pelvis frame from {self.mapping[left]!r}, "
                           f"{self.mapping[right]!r} and {self.mapping[self._spine]!r}")
        lay = self._layout
        W = np.broadcast_to(np.eye(4), (len(p), 4, 4)).copy()
        W[:, :3, :3] = R @ lay.root_turn
        W[:, :3, 3] = 0.5 * (p[:, col[left]] + p[:, col[right]]) + R @ lay.root_from_mid
        out = np.empty_like(p)
        for f, k in col.items():
            if self._anchor[f] is None:  # rigid with the pelvis: where the pelvis puts it
                out[:, k] = W[:, :3, 3] + R @ lay.local[f]
        for anchor, group in lay.groups.items():  # anchors in tree order: each one's target is known
            ks = [col[f] for f in group]
            offsets = np.array([lay.offset[f] for f in group])
            turn = best_rotations(offsets, p[:, ks] - p[:, [col[anchor]]])
            out[:, ks] = out[:, [col[anchor]]] + np.einsum("nij,mj->nmi", turn, offsets)
        return W, out

    def solver(self) -> Solver:
        """A solver rooted at the pelvis, with the rest pose as a light posture below every target."""
        s = Solver(self.skeleton, restarts=0)
        s.set_root(self._root)
        s.set_posture(None, REST_POSTURE_WEIGHT)
        return s

    def retarget(self, clip: BvhClip, progress: Callable[[int], None] | None = None) -> Retargeted:
        """Solve every frame of ``clip``, each warm-started from the previous one's pose, planted feet pinned."""
        W, asked = self.world_targets(clip)
        clip_points = clip_world_positions(clip, self.up)[:, self._columns] * self.scale
        feet = [k for k, f in enumerate(self.mapping) if self._bone[f] in FOOT_BONES]
        height = skeleton_height(self.skeleton)
        contacts = detect_contacts(clip_points[:, feet], tuple(list(self.mapping)[k] for k in feet),
                                   1.0 / clip.frame_time, height)
        points = asked.copy()
        points[:, feet] = pin_targets(asked[:, feet], contacts)
        Q, got = self._solve(W, points, contacts, progress)
        frames = [self.skeleton.frame_of(f) for f in self.mapping]
        err = np.linalg.norm(got[:, frames] - asked, axis=-1)
        slide = (planted_speed(asked[:, feet], contacts.planted, contacts.fps),
                 planted_speed(got[:, [frames[k] for k in feet]], contacts.planted, contacts.fps))
        motion = Motion(self.skeleton, Q, (self._root,) * clip.n_frames, W, clip.frame_time)
        return Retargeted(motion, dict(self.mapping), self.unmapped_frames, self.unmapped_clip, err,
                          self.scale, self.up, height, contacts, slide, self._degenerate(clip_points, height))

    def _solve(self, W: np.ndarray, points: np.ndarray, contacts: Contacts,
               progress: Callable[[int], None] | None) -> tuple[np.ndarray, np.ndarray]:
        """Angles (n, n_dofs) and world positions (n, n_skeleton_frames, 3) [m] tracking ``points``; a foot point
        in contact is at priority 0, the other point of that foot (the heel lifting off a planted toe) at 1."""
        levels = {f: BONE_PRIORITIES.get(self._bone[f], 2) for f in self.mapping if f != self._root}
        side = {f: "left" if self._bone[f].startswith("left") else "right" for f in contacts.names}
        s = self.solver()
        frames = [self.skeleton.frame_of(f) for f in self.mapping]
        cold = COLD_START_FRACTION * skeleton_height(self.skeleton)
        n = len(points)
        Q = np.empty((n, self.skeleton.n_dofs))
        got = np.empty((n, self.skeleton.n_frames, 3))
        for i in range(n):
            s.set_world_from_root(W[i])
            level = {**levels, **_foot_levels(contacts, i, side, levels)}
            s.set_targets({f: Target(points[i, k], position_only=True, priority=level[f])
                           for k, f in enumerate(self.mapping) if f in level})
            _steps(s, STEPS_PER_FRAME if i else FIRST_FRAME_STEPS)
            miss = _worst_miss(s, frames, points[i])
            if i and miss > cold:  # trapped by the warm start? try from the rest pose
                warm = s.q.copy()
                s.set_q(self.skeleton.rest)
                _steps(s, FIRST_FRAME_STEPS)
                if _worst_miss(s, frames, points[i]) >= miss:
                    s.set_q(warm)
            Q[i] = s.q
            got[i] = s.world_positions()
            if progress is not None:
                progress(i)
        return Q, got

    def _degenerate(self, clip_points: np.ndarray, height: float) -> np.ndarray:
        """(n,) bool: frames where the clip's hips coincide or its spine joint lies on their line."""
        col = {f: k for k, f in enumerate(self.mapping)}
        left, right = (clip_points[:, col[self._frames[b]]] for b in ("leftUpperLeg", "rightUpperLeg"))
        across = right - left
        width = np.linalg.norm(across, axis=-1)
        rise = clip_points[:, col[self._spine]] - 0.5 * (left + right)
        off_line = np.linalg.norm(np.cross(rise, unit(across)), axis=-1)
        eps = DEGENERATE_FRACTION * height
        return (width < eps) | (off_line < eps)


def _steps(s: Solver, most: int) -> None:
    """Up to ``most`` prioritised steps of ``s``, fewer once a step moves the pose by under 1e-5 rad."""
    for _ in range(most):
        if s.step().step_norm < 1e-5:
            break


def _worst_miss(s: Solver, frames: list[int], points: np.ndarray) -> float:
    """Largest distance [m] of the skeleton frames ``frames`` from their targets ``points`` (len(frames), 3)."""
    return float(np.linalg.norm(s.world_positions()[frames] - points, axis=-1).max())


def _foot_levels(contacts: Contacts, i: int, side: Mapping[str, str], levels: Mapping[str, int]) -> dict[str, int]:
    """Priority levels of the foot points in clip frame ``i``: 0 when planted, at least 1 for the other point of
    a foot that has one planted (it follows, it does not drag the pin); ``side``: each point's side."""
    planted = {f for f, on in zip(contacts.names, contacts.planted[i]) if on}
    sides = {side[f] for f in planted}
    return {f: 0 if f in planted else max(levels[f], 1)
            for f in contacts.names if f in planted or side[f] in sides}


def skeleton_height(skeleton: Skeleton) -> float:
    """The skeleton's rest height [m]: the vertical (z) extent of its frames in the rest pose."""
    z = world_frames(skeleton, skeleton.rest, np.eye(4), skeleton.root)[1][:, 2]
    return float(z.max() - z.min())


def _anchors(skeleton: Skeleton, frames: list[str], root: str) -> dict[str, str | None]:
    """Each frame's nearest ancestor among ``frames``, or ``None`` when no angle moves it relative to ``root``."""
    mapped = {skeleton.frame_of(f): f for f in frames}
    # Rigid with the pelvis: at the same place, pelvis at the origin, in the rest pose and in another pose.
    a = world_frames(skeleton, skeleton.rest, np.eye(4), root)[1]
    b = world_frames(skeleton, 0.5 * (skeleton.lower + skeleton.upper) + 0.1, np.eye(4), root)[1]
    out = {}
    for f in frames:
        i = skeleton.frame_of(f)
        up = int(skeleton.frame_parent[i])
        while up >= 0 and up not in mapped:
            up = int(skeleton.frame_parent[up])
        out[f] = None if up < 0 or np.linalg.norm(a[i] - b[i]) < 1e-9 else mapped[up]
    return out


def retarget(skeleton: Skeleton, clip: BvhClip, mapping: Mapping[str, str] | None = None,
             up: str | None = None) -> Retargeted:
    """Retarget ``clip`` onto ``skeleton``; see :class:`Retargeter`."""
    return Retargeter(skeleton, clip, mapping, up).retarget(clip)
