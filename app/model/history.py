"""The undo stack of the studio's document: every edit is a :class:`Command` holding the pose from before it."""

from __future__ import annotations

from dataclasses import dataclass, field

from gsik.io.pose import Pose


@dataclass(eq=False)
class Command:
    """One undoable edit.

    Attributes:
        text: What the edit did, for menus ("Move left_hand").
        before: The document's pose before the edit.
        after: The pose to restore on redo; set when the command is undone.
        kept_before, kept_after: What the document keeps besides the pose (its pose library, timeline and pole
            targets: a :class:`gsik_studio.model.kept.Kept`) before the edit, and on redo.
        merge_key: Consecutive commands with the same non-None key merge
            into one (every mouse move of one drag is one command).
    """

    text: str
    before: Pose
    after: Pose | None = None
    merge_key: object | None = None
    kept_before: object = None  # a Kept: library, timeline, poles before the edit
    kept_after: object = None  # ... and on redo


@dataclass(eq=False)
class History:
    """An undo stack: ``commands[:index]`` are done, the rest undone (redoable)."""

    limit: int = 500
    commands: list[Command] = field(default_factory=list)
    index: int = 0
    clean_index: int | None = 0

    @property
    def can_undo(self) -> bool:
        return self.index > 0

    @property
    def can_redo(self) -> bool:
        return self.index < len(self.commands)

    @property
    def undo_text(self) -> str:
        return self.commands[self.index - 1].text if self.can_undo else ""

    @property
    def redo_text(self) -> str:
        return self.commands[self.index].text if self.can_redo else ""

    @property
    def is_clean(self) -> bool:
        return self.index == self.clean_index

    def push(self, command: Command) -> bool:
        """Add a done command; returns False when it merged into the previous one."""
        del self.commands[self.index:]
        if self.clean_index is not None and self.clean_index > self.index:
            self.clean_index = None  # the saved state can no longer be reached
        top = self.commands[-1] if self.commands else None
        if top is not None and command.merge_key is not None and top.merge_key == command.merge_key:
            if self.clean_index == self.index:
                self.clean_index = None
            return False
        self.commands.append(command)
        if len(self.commands) > self.limit:
            del self.commands[0]
            self.clean_index = None if self.clean_index in (None, 0) else self.clean_index - 1
        self.index = len(self.commands)
        return True

    def would_merge(self, merge_key: object | None) -> bool:
        """True if a command with ``merge_key`` would merge into the current top."""
        return (merge_key is not None and self.index == len(self.commands) and bool(self.commands)
                and self.commands[-1].merge_key == merge_key)

    def end_merge(self) -> None:
        """The next command does not merge into the current top (a drag ended)."""
        if self.commands:
            self.commands[-1].merge_key = None

    def set_clean(self) -> None:
        self.clean_index = self.index

    def clear(self) -> None:
        self.commands.clear()
        self.index = 0
        self.clean_index = 0
