"""The solver settings panel: one table row per setting of :class:`gsik.SolverSettings`."""

from __future__ import annotations

from PySide6 import QtCore

from gsik_studio.model import Document
from gsik_studio.widgets.fields import DEGREES, MILLIMETRES, RADIANS, Field, FieldForm

#: The solver settings the studio edits. Adding a setting is adding a row.
SOLVER_FIELDS = (
    Field("sweeps", "Sweeps / frame", int, 1, 500, tip="Gauss-Seidel sweeps per frame"),
    Field("damping", "Damping δ", float, 1e-6, 10.0, decimals=6, step=0.001,
          tip="Damping δ added to the diagonal of JᵀWJ"),
    Field("position_tolerance", "Position tolerance", float, 0.001, 100.0, MILLIMETRES,
          tip="Converged when every position error is below this"),
    Field("orientation_tolerance", "Orientation tolerance", float, 0.001, 90.0, DEGREES,
          tip="Converged when every orientation error is below this"),
    Field("max_step", "Max step", float, 0.0, 3.2, RADIANS, tip="Largest change of one angle per frame (0: none)"),
)


def solver_panel(doc: Document, settings: QtCore.QSettings) -> FieldForm:
    """The "Solver" group bound to ``doc``'s settings, remembered under ``solver/`` in ``settings``."""
    form = FieldForm("Solver", SOLVER_FIELDS, lambda: doc.settings, lambda changes: doc.configure(**changes),
                     settings, "solver")
    doc.events.settings.connect(form.show_model)
    return form
