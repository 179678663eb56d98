"""The built distribution carries its skeleton files, the studio package and kernels compiled while it was built."""

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_built_package_finds_the_bundled_biped_and_starts_without_compiling(tmp_path):
    # Install a non-editable copy (no dependencies: the test environment has them) into a folder of its own,
    # then import it from outside the repository, so the import can only come from that copy.
    # pip runs from a fresh venv with nothing installed, as README command 1 does: the build's own environment
    # (pip's build isolation) must provide what compiling the kernels needs.
    target, venv = tmp_path / "site", tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, capture_output=True, text=True)
    subprocess.run([str(venv / "bin" / "python"), "-m", "pip", "install", "-q", "--no-deps", "--target", str(target),
                    str(ROOT)], check=True, capture_output=True, text=True)
    assert list((target / "gsik").glob("**/__pycache__/*.nbi")), "the build compiled no kernels into the package"
    for package, folder in (("gsik", ROOT / "gsik"), ("gsik_studio", ROOT / "app"), ("gsik/skeletons", ROOT / "skeletons")):
        for source in folder.rglob("*.py"):
            installed = target / package / source.relative_to(folder)
            assert installed.is_file(), f"{source.relative_to(ROOT)} is missing from the built package (pyproject packages)"
    code = ("import gsik, gsik_studio, importlib.resources as r; from gsik._warmup import kernel_cache_stats; "
            "sk = gsik.load_skeleton('biped'); s = gsik.Solver(sk); "
            "t = {n: gsik.Target.from_transform(T) for n, T in s.effector_poses().items()}; s.step(t); s.solve(t); "
            "print(gsik.__file__); print(gsik_studio.__file__); "
            "print(r.files('gsik.skeletons').joinpath('biped.yaml').is_file()); print(sk.n_dofs); "
            "print(*kernel_cache_stats())")
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")} | {"HOME": str(tmp_path / "home")}
    out = subprocess.run([sys.executable, "-I", "-c", f"import sys; sys.path.insert(0, {str(target)!r}); {code}"],
                         cwd=tmp_path, capture_output=True, text=True, env=env)
    assert out.returncode == 0, out.stderr
    gsik_path, studio_path, has_file, n_dofs, hits, misses = out.stdout.split()
    assert gsik_path.startswith(str(target)) and studio_path.startswith(str(target))
    assert has_file == "True" and n_dofs == "30"
    # The first start loaded every kernel it ran from the cache the build wrote: nothing compiled.
    assert int(hits) > 0 and int(misses) == 0, f"cache hits {hits}, misses {misses}"


def test_run_from_the_clones_root_the_source_trees_gsik_finds_the_bundled_data(tmp_path):
    # Run from a clone's root after a plain install, Python imports the clone's own gsik/ (the current folder comes
    # first on sys.path), which holds no gsik.skeletons package: the bundled data must then be the clone's
    # skeletons/ folder. -S keeps site's .pth files (this venv's editable install, which maps gsik.skeletons) out;
    # the dependencies come from the venv's site-packages folder, added by hand.
    import sysconfig

    purelib = sysconfig.get_paths()["purelib"]
    code = ("import sys; sys.path.append(%r); import gsik; from gsik.prior import bundled_prior; "
            "from gsik.cli import main; "
            "import importlib.util as u; print(u.find_spec('gsik.skeletons') is None); print(gsik.__file__); "
            "print(gsik.bundled_skeletons()); print(gsik.load_skeleton('biped').n_dofs); "
            "print(bundled_prior('biped').mean.shape); sys.exit(main(['info', 'biped']))" % purelib)
    env = {k: v for k, v in os.environ.items() if not k.startswith(("NUMBA_", "PYTHON"))}
    out = subprocess.run([sys.executable, "-S", "-c", code], cwd=ROOT, capture_output=True, text=True, env=env)
    assert out.returncode == 0, out.stderr
    no_package, gsik_path, bundled, n_dofs, prior_shape, *info = out.stdout.splitlines()
    assert no_package == "True" and gsik_path == str(ROOT / "gsik" / "__init__.py")
    assert "biped" in bundled and n_dofs == "30" and prior_shape == "(30,)"
    assert any("biped" in line for line in info)
