"""The field table: one row makes one editor, model and editor stay in step both ways, values persist."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import pytest

import gsik

pytestmark = pytest.mark.gui


@dataclass(frozen=True)
class Model:
    length: float = 0.002  # [m]
    angle: float = 0.1  # [rad]
    count: int = 3


class Store:
    """A model with a validating setter, standing in for the document's solver settings."""

    def __init__(self):
        self.model = Model()
        self.writes: list[dict] = []

    def write(self, changes):
        if changes.get("count", 1) < 0:
            raise gsik.SolverError(f"count must be >= 0, got {changes['count']}")
        self.writes.append(dict(changes))
        self.model = replace(self.model, **changes)


def _fields():
    from gsik_studio.widgets.fields import DEGREES, MILLIMETRES, Field

    return (Field("length", "Length", float, 0.0, 50.0, MILLIMETRES, tip="a length"),
            Field("angle", "Angle", float, 0.0, 90.0, DEGREES),
            Field("count", "Count", int, -5, 99))


@pytest.fixture()
def form(qapp, studio_settings):
    from gsik_studio.widgets.fields import FieldForm

    store = Store()
    f = FieldForm("Test", _fields(), lambda: store.model, store.write, studio_settings, "test")
    f.show_model()
    return f, store


def test_one_row_makes_one_editor_with_its_range_unit_and_tip(form):
    from PySide6 import QtWidgets

    f, _ = form
    assert list(f.editors) == ["length", "angle", "count"]
    length, angle, count = f.editors.values()
    assert isinstance(length, QtWidgets.QDoubleSpinBox) and isinstance(count, QtWidgets.QSpinBox)
    assert (length.minimum(), length.maximum(), length.suffix(), length.toolTip()) == (0.0, 50.0, " mm", "a length")
    assert angle.suffix() == " °" and (count.minimum(), count.maximum()) == (-5, 99)


def test_model_to_editor_converts_units_and_writes_nothing_back(form):
    f, store = form
    assert f.editors["length"].value() == 2.0  # 0.002 m shown in mm
    assert f.editors["angle"].value() == pytest.approx(math.degrees(0.1), abs=1e-3)
    assert f.editors["count"].value() == 3
    store.model = Model(length=0.0125, angle=0.5, count=7)
    f.show_model()
    assert f.editors["length"].value() == 12.5 and f.editors["count"].value() == 7
    assert store.writes == []  # shown inside signal blockers


def test_editor_to_model_converts_back_and_remembers_the_value(form, studio_settings):
    f, store = form
    f.editors["length"].setValue(7.5)
    f.editors["angle"].setValue(45.0)
    f.editors["count"].setValue(11)
    assert store.writes == [{"length": 0.0075}, {"angle": math.radians(45.0)}, {"count": 11}]
    assert isinstance(store.model.count, int)
    assert float(studio_settings.value("test/length")) == 0.0075
    assert int(studio_settings.value("test/count")) == 11


def test_a_refused_value_is_reported_and_the_editor_shows_the_model_again(form, studio_settings):
    f, store = form
    messages = []
    f.rejected.connect(messages.append)
    f.editors["count"].setValue(-2)
    assert messages == ["count must be >= 0, got -2"]
    assert f.editors["count"].value() == 3 and store.model.count == 3
    assert studio_settings.value("test/count") is None


def test_restore_applies_remembered_values_in_one_write(qapp, studio_settings):
    from gsik_studio.widgets.fields import FieldForm

    studio_settings.setValue("test/length", 0.004)
    studio_settings.setValue("test/count", "nonsense")  # unreadable: skipped
    store = Store()
    f = FieldForm("Test", _fields(), lambda: store.model, store.write, studio_settings, "test")
    f.restore()
    assert store.writes == [{"length": 0.004}]
    assert f.editors["length"].value() == 4.0 and f.editors["count"].value() == 3


def test_solver_panel_rows_name_real_settings_and_follow_the_document(qapp, studio_settings):
    from gsik_studio.model import Document
    from gsik_studio.widgets.solver_panel import SOLVER_FIELDS, solver_panel

    doc = Document()
    panel = solver_panel(doc, studio_settings)
    panel.show_model()
    for field in SOLVER_FIELDS:
        assert hasattr(doc.settings, field.name)
    doc.configure(position_tolerance=0.0025)  # the document's settings signal updates the panel
    assert panel.editors["position_tolerance"].value() == 2.5
    panel.editors["orientation_tolerance"].setValue(2.0)
    assert doc.settings.orientation_tolerance == math.radians(2.0)
