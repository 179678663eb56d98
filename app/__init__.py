"""gsik-studio: the interactive pose-authoring desktop app (PySide6 + PyVista).

Layers, top to bottom: :mod:`gsik_studio.window` assembles the app from
:mod:`gsik_studio.actions` (action, menu and toolbar tables), :mod:`gsik_studio.files`
(file commands), :mod:`gsik_studio.widgets` (panels and read-outs bound to the
document) and :mod:`gsik_studio.viewport` (the 3D view, built from
:mod:`gsik_studio.scene`). :mod:`gsik_studio.model` is plain Python (no Qt, no
PyVista): the document, its events, undo history, playback and frame loop.
"""
