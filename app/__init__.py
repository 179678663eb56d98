"""gsik-studio: the interactive pose-authoring desktop app (PySide6 + PyVista).

:mod:`gsik_studio.model` is plain Python (no Qt, no PyVista); :mod:`gsik_studio.viewport`
and :mod:`gsik_studio.main_window` draw it and forward input to it.
"""
