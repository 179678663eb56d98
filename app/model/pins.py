"""The artist's control over the solve: pins (strict priority levels), posture strength, balance, centre of mass.

Plain Python. A pin is a target's priority (:attr:`gsik.Target.priority`):
a pinned target is on level :data:`PINNED` (0), an unpinned one on
:data:`FREE` (1), so pulling an unpinned hand never moves a pinned foot or
pelvis (the solver meets level 1 only in what level 0 leaves free). The pin
travels with the target: undo, redo and pose files keep it.

Posture strength and balance are solver state, not pose: the document owns one
:class:`SolveControls` (``doc.controls``), the only other place that tells
the solver anything.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np

import gsik
from gsik import balance, control
from gsik.rotations import transform
from gsik.targets import Target
from gsik_studio.model.events import Signal
from gsik_studio.model.pole_places import aim_point, limbs, pole_joints, rest_place
from gsik_studio.model.posture import Posture

PINNED = 0  #: priority level of a pinned target
FREE = 1  #: priority level of an unpinned target
POLE = 2  #: priority level of a pole target: it only bends a limb in what the targets leave free
#: Joints that get a pole target (where the skeleton has them): the knees and elbows; a skeleton without them
#: gets its recognised knees and elbows (:func:`gsik_studio.model.pole_places.pole_joints`).
POLE_JOINTS = ("left_knee", "right_knee", "left_elbow", "right_elbow")
#: Effectors pinned in a new document: pulling a hand never moves them unless unpinned.
PINNED_BY_DEFAULT = ("left_foot", "right_foot", "pelvis")
#: A pole's aim is handed to the solver again once the limb has moved it this far [m] (far below the tolerance).
AIM_TOLERANCE = 1e-5


def is_pinned(t: Target) -> bool:
    return t.priority == PINNED


def pin_level(pinned: bool) -> int:
    """The priority level of a pinned (True) or unpinned target."""
    return PINNED if pinned else FREE


def default_levels(skeleton: gsik.Skeleton) -> dict[str, int]:
    """``{effector site: level}`` of a new document: :data:`PINNED_BY_DEFAULT` pinned, the others free."""
    return {n: pin_level(n in PINNED_BY_DEFAULT) for n in skeleton.effector_sites}


class Support(NamedTuple):
    """Where the body stands, for drawing.

    Attributes:
        com: Centre of mass (3,) in the world [m].
        polygon: Support polygon on the ground (k, 2) [m], counter-clockwise: the convex hull of the soles on it.
        ground: Height of the ground [m] (the root foot's sole).
        inside: True when the centre of mass's ground projection lies inside the polygon.
    """

    com: np.ndarray
    polygon: np.ndarray
    ground: float
    inside: bool


class SolveControls:
    """Posture (strength, natural or rest) and balance of a document's solver, its pole targets, the centre of mass
    and support read-outs.

    Pole targets are position-only targets on knees and elbows at level
    :data:`POLE`, resting out in front of the knees and behind the elbows; the
    solver aims each joint at the point of its swing nearest the pole
    (:mod:`gsik_studio.model.pole_places`), so dragging one swings the limb's
    bend towards it without moving any hand or foot. Unlike the posture and
    balance they are document state: every change is one undo step, and pose files keep them.

    Args:
        solver: The document's solver.
        push: Hands the document's targets and the enabled poles to the solver (the document's own method).
        edit: Runs a change as one undo step (the document's ``_edit(text, apply, merge_key, signal)``).

    Attributes:
        posture: The :class:`gsik_studio.model.posture.Posture` (natural or rest, and its strength).
        changed: Signal() after the posture (strength, natural), balance or a pole changed.
    """

    def __init__(self, solver: gsik.Solver, push: Callable[[], None], edit: Callable[..., None]):
        self._solver = solver
        self._push = push
        self._edit = edit
        self.posture = Posture(solver)  # natural (the bundled prior) when there is one
        self._poles: dict[str, Target] = {}  # every pole placed so far, enabled or not
        self._aimed: dict[str, np.ndarray] = {}  # the aims last handed to the solver
        self._limbs = limbs(solver.skeleton, pole_joints(solver.skeleton, POLE_JOINTS))  # the ones this skeleton has
        self.changed = Signal()

    @property
    def pole_joints(self) -> tuple[str, ...]:
        """The knee and elbow joints this skeleton has (:data:`POLE_JOINTS` or recognised; each a limb's middle)."""
        return tuple(self._limbs)

    @property
    def poles(self) -> dict[str, Target]:
        """``{joint: Target}`` of the enabled pole targets (a new dict)."""
        return {n: t for n, t in self._poles.items() if t.enabled}

    def pole_aims(self) -> dict[str, Target]:
        """``{joint: Target}`` the solver gets for the enabled poles: each aims its joint at the point of the limb's
        swing nearest the pole (:func:`gsik_studio.model.pole_places.aim_point`)."""
        P = self._solver.world_positions()
        aims = {n: t.replace(position=aim_point(self._limbs[n], P, t.position)) for n, t in self.poles.items()}
        self._aimed = {n: np.array(t.position) for n, t in aims.items()}
        return aims

    def aim_poles(self) -> None:
        """Before a solver step: hand the poles' aims to the solver again if the limbs moved them (the ends moved)."""
        if not self._aimed:
            return
        P = self._solver.world_positions()
        for n, t in self.poles.items():
            if np.linalg.norm(aim_point(self._limbs[n], P, t.position) - self._aimed[n]) > AIM_TOLERANCE:
                self._push()
                return

    def joint_position(self, joint: str) -> np.ndarray:
        """World position (3,) [m] of a joint now."""
        sk = self._solver.skeleton
        return self._solver.world_positions()[sk.joint_frame[sk.joint_names.index(joint)]]

    def _pole_at_rest(self, joint: str) -> Target:
        """A pole target for ``joint`` at its rest place for the pose now (the joint already points at it)."""
        s = self._solver
        return Target(rest_place(s.skeleton, joint, s.world_positions(), s.world_rotations()),
                      position_only=True, priority=POLE)

    def set_poles(self, on: bool) -> None:
        """Turn every pole target on (each at its rest place, so nothing moves yet) or off: one undo step."""
        new = ({n: self._pole_at_rest(n) for n in self.pole_joints} if on
               else {n: t.replace(enabled=False) for n, t in self._poles.items()})
        if new != self._poles:
            self._change("Pole targets on" if on else "Pole targets off", new)

    def poles_to_rest(self) -> None:
        """Put every enabled pole back at its rest place for the pose now (inside the caller's undo step: Reset)."""
        if self.poles:
            self._set_poles({n: self._pole_at_rest(n) if t.enabled else t for n, t in self._poles.items()})
            self.changed.emit()

    def set_pole_enabled(self, joint: str, on: bool) -> None:
        """Turn one pole target on (at its rest place when it had none yet) or off: one undo step."""
        if joint not in self.pole_joints:
            raise gsik.TargetError(f"no pole target on {joint!r}; pole joints: {', '.join(self.pole_joints) or 'none'}")
        old = self._poles.get(joint) or self._pole_at_rest(joint).replace(enabled=False)
        if old.enabled != bool(on):
            self._change(f"Pole {joint} {'on' if on else 'off'}", {**self._poles, joint: old.replace(enabled=bool(on))})

    def move_pole(self, joint: str, position, drag: object | None = None) -> None:
        """Move one enabled pole target to a world position (3,) [m]: one undo step (one per ``drag`` token)."""
        if joint not in self.poles:
            raise gsik.TargetError(f"no pole target on {joint!r}; poles: {', '.join(self.poles) or 'none (off)'}")
        moved = self._poles[joint].replace(position=position)
        key = None if drag is None else ("pole", joint, drag)
        self._change(f"Move pole {joint}", {**self._poles, joint: moved}, key)

    def pole_snapshot(self) -> tuple[tuple[str, Target], ...]:
        """Every pole target placed, enabled or not (the undo history and pose files keep it)."""
        return tuple(self._poles.items())

    def restore_poles(self, poles: tuple[tuple[str, Target], ...]) -> None:
        """Show ``poles`` (undo, redo, a file opened); no undo step."""
        if poles != self.pole_snapshot():
            self._set_poles(dict(poles))
            self.changed.emit()

    def _set_poles(self, poles: dict[str, Target]) -> None:
        self._poles = poles
        self._push()

    def _change(self, text: str, poles: dict[str, Target], merge_key: object | None = None) -> None:
        self._edit(text, lambda: self._set_poles(poles), merge_key, self.changed)

    @property
    def has_masses(self) -> bool:
        """True when the skeleton gives segment masses (balance and the centre of mass need them)."""
        return self._solver.skeleton.total_mass > 0.0

    @property
    def balance(self) -> bool:
        return self._solver.balance

    @property
    def posture_strength(self) -> float:
        return self.posture.strength

    @property
    def natural(self) -> bool:
        """True while the learned pose prior is the posture (see :mod:`gsik_studio.model.posture`)."""
        return self.posture.natural

    def set_posture_strength(self, strength: float) -> None:
        """Prefer the posture with weight ``strength`` (>= 0, per DOF; 0 turns it off), below every target."""
        self.posture.set_strength(strength)
        self.changed.emit()

    def set_natural(self, on: bool) -> None:
        """The learned pose prior (True) or the plain rest pose as the posture (SolverError without a prior)."""
        self.posture.set_natural(on)
        self.changed.emit()

    def set_balance(self, on: bool) -> None:
        """Hold the centre of mass over the support polygon (SolverError without segment masses)."""
        self._solver.set_balance(bool(on))
        self.changed.emit()

    def center_of_mass(self) -> np.ndarray:
        """The centre of mass (3,) in the world [m]."""
        return self._solver.center_of_mass()

    def support(self) -> Support:
        """The centre of mass and the support polygon of the feet on the ground now."""
        s = self._solver
        sk = s.skeleton
        P, R = s.world_positions(), s.world_rotations()
        feet = control.support(sk, s.targets, P)
        transforms = [transform(R[f], P[f]) for f in feet.feet]
        polygon = balance.support_polygon(transforms, feet.soles)
        ground = float(P[sk.frame_of(sk.root)][2]) if sk.root in sk.soles else 0.0
        com = s.center_of_mass()
        inside = len(polygon) >= 3 and balance.signed_distance(polygon, com[:2]) <= 0.0
        return Support(com, polygon, ground, bool(inside))
