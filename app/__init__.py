"""gsik-studio: the interactive pose-authoring desktop app (PySide6 + PyVista).

:mod:`app.model` is plain Python (no Qt, no PyVista); :mod:`app.viewport`
and :mod:`app.main_window` draw it and forward input to it.
"""
