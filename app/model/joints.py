"""Direct joint rotation (FK): the selected joint, its one-DOF rotations, and turning one of them.

Plain Python. The viewport's axis rings and the joint panel both go through a
:class:`JointEditor`, which edits the pose through the document's commands
only (:meth:`Document.set_angles`): a ring drag is one undo step.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from gsik.errors import choices
from gsik_studio.model.document import Document
from gsik_studio.model.events import Signal
from gsik_studio.model.words import dof_words

AXIS_NAMES = "xyz"


class DofInfo(NamedTuple):
    """One one-DOF rotation of a joint.

    Attributes:
        index: The DOF's index in the skeleton's angle vector.
        name: The DOF's name (``"left_elbow.x"``).
        axis: "x", "y" or "z": the axis of its frame it turns about (the ring's colour).
        lower, upper: Its limits [rad].
    """

    index: int
    name: str
    axis: str
    lower: float
    upper: float


def joint_dofs(doc: Document, joint: str) -> tuple[DofInfo, ...]:
    """The one-DOF rotations of ``joint`` in the skeleton's order."""
    sk = doc.skeleton
    try:
        j = sk.joint_names.index(joint)
    except ValueError:
        raise ValueError(f"no joint {joint!r}; joints: {choices(sk.joint_names)}") from None
    out = []
    for d in sk.joint_dofs[j]:
        axis = np.asarray(sk.frame_axis[sk.dof_frame[d]])
        out.append(DofInfo(int(d), sk.dof_names[d], AXIS_NAMES[int(np.argmax(np.abs(axis)))],
                           float(sk.lower[d]), float(sk.upper[d])))
    return tuple(out)


class JointEditor:
    """The selected joint and the artist's choice of what the targets do when a joint turns.

    Args:
        doc: The document.

    Attributes:
        selected: The selected joint's name, or None.
        targets_follow: True: the targets move with the turned limb (the pose holds as turned);
            False: the targets stay and the solver brings the effectors back to them.
        selection_changed: Signal(name or None).
    """

    def __init__(self, doc: Document):
        self.doc = doc
        self.selected: str | None = None
        self.targets_follow = True
        self.selection_changed = Signal()

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Joints that can be turned (those with at least one DOF)."""
        sk = self.doc.skeleton
        return tuple(n for n, dofs in zip(sk.joint_names, sk.joint_dofs) if dofs)

    def select(self, joint: str | None) -> None:
        """Select a joint (``None`` clears); ValueError for a joint that cannot turn."""
        if joint is not None and joint not in self.joint_names:
            raise ValueError(f"no joint {joint!r} to turn; joints: {choices(self.joint_names)}")
        if joint != self.selected:
            self.selected = joint
            self.selection_changed.emit(joint)

    def dofs(self) -> tuple[DofInfo, ...]:
        """The selected joint's rotations (empty when none is selected)."""
        return joint_dofs(self.doc, self.selected) if self.selected else ()

    def angle(self, dof: int) -> float:
        """The DOF's angle now [rad]."""
        return float(self.doc.q[dof])

    def set_angle(self, dof: int, angle: float, drag: object | None = None) -> float:
        """Turn one DOF to ``angle`` [rad], clamped into its limits; returns the angle set.

        Calls with one ``drag`` token (one mouse drag on a ring) are one undo step.
        """
        sk = self.doc.skeleton
        if not 0 <= dof < sk.n_dofs:
            raise ValueError(f"DOF index must be in 0..{sk.n_dofs - 1}, got {dof}")
        q = self.doc.q
        q[dof] = float(np.clip(angle, sk.lower[dof], sk.upper[dof]))
        self.doc.set_angles(q, f"Turn {dof_words(sk.dof_names[dof])}", snap_targets=self.targets_follow, drag=drag)
        return float(q[dof])
