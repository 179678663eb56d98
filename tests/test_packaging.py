"""The built distribution carries its skeleton files (package data) and the studio package, not only the source tree."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_built_package_finds_the_bundled_biped(tmp_path):
    # Install a non-editable copy (no dependencies: the test environment has them) into a folder of its own,
    # then import it from outside the repository, so the import can only come from that copy.
    target = tmp_path / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps",
                    "--target", str(target), str(ROOT)], check=True, capture_output=True, text=True)
    code = ("import gsik, gsik_studio, importlib.resources as r; sk = gsik.load_skeleton('biped'); "
            "print(gsik.__file__); print(gsik_studio.__file__); "
            "print(r.files('gsik.skeletons').joinpath('biped.yaml').is_file()); print(sk.n_dofs)")
    out = subprocess.run([sys.executable, "-I", "-c", f"import sys; sys.path.insert(0, {str(target)!r}); {code}"],
                         cwd=tmp_path, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    gsik_path, studio_path, has_file, n_dofs = out.stdout.split()
    assert gsik_path.startswith(str(target)) and studio_path.startswith(str(target))
    assert has_file == "True" and n_dofs == "30"
