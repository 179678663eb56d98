"""The studio's layers import one way down: nothing imports the window back, the model imports no widget."""

from __future__ import annotations

import ast
from pathlib import Path

APP = Path(__file__).resolve().parents[2] / "app"


def _imports() -> dict[str, set[str]]:
    """``{module: gsik_studio modules it imports}`` for every module of the studio."""
    out = {}
    for path in APP.rglob("*.py"):
        parts = path.relative_to(APP).with_suffix("").parts
        name = ".".join(("gsik_studio",) + (parts[:-1] if parts[-1] == "__init__" else parts))
        deps = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module:
                deps.add(node.module)
                deps.update(f"{node.module}.{a.name}" for a in node.names)
            elif isinstance(node, ast.Import):
                deps.update(a.name for a in node.names)
        out[name] = {d for d in deps if d.startswith("gsik_studio")}
    return out


def test_the_layer_check_sees_the_studio():
    graph = _imports()
    assert "gsik_studio.window" in graph and "gsik_studio.model.document" in graph
    assert "gsik_studio.model" in graph["gsik_studio.window"]


def test_only_the_entry_point_imports_the_window():
    users = sorted(m for m, deps in _imports().items() if "gsik_studio.window" in deps)
    assert users == ["gsik_studio.main"]


def test_the_model_imports_only_the_model():
    bad = {m: sorted(d for d in deps if not d.startswith("gsik_studio.model"))
           for m, deps in _imports().items() if m.startswith("gsik_studio.model")}
    assert not {m: d for m, d in bad.items() if d}


def test_widgets_do_not_import_the_viewport_or_the_window():
    bad = {m: sorted(d for d in deps if d.startswith(("gsik_studio.viewport", "gsik_studio.window")))
           for m, deps in _imports().items() if m.startswith("gsik_studio.widgets")}
    assert not {m: d for m, d in bad.items() if d}
