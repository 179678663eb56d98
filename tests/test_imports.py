"""The solver library must not pull in any GUI toolkit."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_import_gsik_does_not_import_qt_pyvista_or_vtk():
    code = ("import sys, gsik, gsik.solver, gsik.bvh, gsik.urdf, gsik.motion, gsik.pgs; "
            "import importlib.util as u; "
            "[importlib := __import__('importlib').import_module(m) for m in "
            "('gsik.' + n for n in ('gait', 'scenarios', 'cli', 'pose', 'tracking', 'bvh_skeleton', 'urdf_skeleton')) "
            " if u.find_spec(m)]; "
            "print(' '.join(m for m in ('PySide6', 'pyvista', 'vtk', 'pyvistaqt', 'vtkmodules') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "", f"gsik imported {out.stdout.strip()}"
