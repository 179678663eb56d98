"""The document's pose library: several named poses kept with the pose, every change one undo step.

Plain Python. The library's state is an immutable snapshot (a tuple of
``(name, Pose)``) that the document's undo history keeps next to the pose,
so undo and redo restore both exactly.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from gsik.errors import PoseError, choices
from gsik.io.pose import Pose
from gsik_studio.model.events import Signal
from gsik_studio.model.poses import check_pose

if TYPE_CHECKING:
    from gsik_studio.model.document import Document

LibraryState = tuple[tuple[str, Pose], ...]


class PoseLibrary:
    """Named poses of one document, in the order they were added.

    Attributes:
        changed: Signal (no arguments): a pose was added, renamed, duplicated or deleted (or undone).
    """

    def __init__(self, doc: Document):
        self.doc = doc
        self.changed = Signal()
        self._poses: dict[str, Pose] = {}

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(self._poses)

    def pose(self, name: str) -> Pose:
        try:
            return self._poses[name]
        except KeyError:
            raise PoseError(f"no pose named {name!r} in the library; poses: {choices(self._poses)}") from None

    def snapshot(self) -> LibraryState:
        return tuple(self._poses.items())

    def restore(self, state: LibraryState) -> None:
        """Show ``state`` (undo, redo, a file opened); no undo step."""
        for name, pose in state:
            check_pose(self.doc.skeleton, pose)
        if state != self.snapshot():
            self._poses = dict(state)
            self.changed.emit()

    def _change(self, text: str, poses: dict[str, Pose]) -> None:
        def apply():
            self._poses = poses

        self.doc._edit(text, apply, signal=self.changed)  # one undo step holding the library before it

    def _free_name(self, base: str) -> str:
        if base not in self._poses:
            return base
        k = 2
        while f"{base} {k}" in self._poses:
            k += 1
        return f"{base} {k}"

    def _check_new_name(self, name: str) -> str:
        name = str(name).strip()
        if not name:
            raise PoseError("a pose name must not be empty")
        if name in self._poses:
            raise PoseError(f"the library already has a pose named {name!r}; poses: {choices(self._poses)}")
        return name

    def add(self, name: str | None = None) -> str:
        """Add the document's current pose under ``name`` (default "pose N"); returns the name."""
        name = self._free_name(f"pose {len(self._poses) + 1}") if name is None else self._check_new_name(name)
        self._change(f"Add pose {name}", {**self._poses, name: self.doc.pose()})
        return name

    def rename(self, old: str, new: str) -> None:
        self.pose(old)
        if new == old:
            return
        new = self._check_new_name(new)
        self._change(f"Rename pose {old} to {new}", {(new if n == old else n): p for n, p in self._poses.items()})

    def duplicate(self, name: str) -> str:
        """A copy of pose ``name`` right after it ("name copy"); returns the copy's name."""
        pose = self.pose(name)
        copy = self._free_name(f"{name} copy")
        poses: dict[str, Pose] = {}
        for n, p in self._poses.items():
            poses[n] = p
            if n == name:
                poses[copy] = pose
        self._change(f"Duplicate pose {name}", poses)
        return copy

    def delete(self, name: str) -> None:
        self.pose(name)
        self._change(f"Delete pose {name}", {n: p for n, p in self._poses.items() if n != name})

    def apply(self, name: str) -> None:
        """Show pose ``name`` (angles, root, targets) as one undo step."""
        self.doc.set_pose(self.pose(name), f"Apply pose {name}")
