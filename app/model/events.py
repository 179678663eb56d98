"""Typed change signals of the document: one small plain-Python signal class, napari's way.

A widget connects to the one change it shows (``doc.events.options.connect(cb)``)
instead of filtering a string "kind" out of one catch-all signal.
"""

from __future__ import annotations

from collections.abc import Callable


class Signal:
    """A list of callbacks: :meth:`connect` one, :meth:`emit` calls them all in order."""

    def __init__(self):
        self._slots: list[Callable] = []

    def connect(self, slot: Callable) -> None:
        self._slots.append(slot)

    def emit(self, *args) -> None:
        for slot in list(self._slots):
            slot(*args)


class DocumentEvents:
    """What changed in a :class:`gsik_studio.model.document.Document` (each signal takes no arguments).

    Attributes:
        pose: Angles, root or all targets were replaced (an edit of the pose, undo, redo, load, a playback frame).
        targets: A target moved or turned (flags unchanged).
        options: A target's enabled / weight / position-only flag or priority level (its pin) changed.
        settings: The solver settings changed.
        file: The file path or the unsaved-changes flag changed.
        history: The undo stack changed (a new step, undo, redo, cleared).
    """

    __slots__ = ("pose", "targets", "options", "settings", "file", "history")

    def __init__(self):
        for name in self.__slots__:
            setattr(self, name, Signal())
