"""The studio's model: plain Python, no Qt, no PyVista.

:class:`Document` is the app's only door to the solver and says what changed
through :class:`DocumentEvents`; :class:`History` holds the undo steps;
:class:`Playback` sequences frames through the document's public methods;
:class:`FrameLoop` is the per-frame work that the studio's timer and the app
benchmark both drive.
"""

from gsik_studio.model.document import DEFAULT_SETTINGS, WORLD_AXES, Document, mirror_map
from gsik_studio.model.events import DocumentEvents, Signal
from gsik_studio.model.frame_loop import FrameLoop, LoopEvents
from gsik_studio.model.history import Command, History
from gsik_studio.model.playback import Playback

__all__ = ["DEFAULT_SETTINGS", "WORLD_AXES", "Command", "Document", "DocumentEvents", "FrameLoop", "History",
           "LoopEvents", "Playback", "Signal", "mirror_map"]
