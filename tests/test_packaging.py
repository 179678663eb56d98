"""The installed distribution carries its skeleton files (package data), not only the source tree."""

import subprocess
import sys

import pytest


def test_installed_package_finds_the_bundled_biped(tmp_path):
    # Run outside the repository so the import can only come from an installed copy.
    code = ("import gsik, importlib.resources as r; sk = gsik.load_skeleton('biped'); "
            "print(gsik.__file__); print(r.files('gsik.skeletons').joinpath('biped.yaml').is_file()); "
            "print(sk.n_dofs)")
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True)
    if "No module named 'gsik'" in out.stderr:
        pytest.skip("gsik is not installed in this environment (running from the source tree)")
    assert out.returncode == 0, out.stderr
    path, has_file, n_dofs = out.stdout.split()
    assert "site-packages" in path
    assert has_file == "True" and n_dofs == "30"
