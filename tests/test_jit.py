"""gsik imports and solves wherever it is installed, even where numba's usual cache folders cannot be written."""

import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from gsik import _jit

# Run in a fresh process: numba picks a cache folder per kernel when the kernel module is imported.
_SOLVE = """
import warnings
warnings.simplefilter("always")
with warnings.catch_warnings(record=True) as caught:
    import gsik
    biped = gsik.load_skeleton("biped")  # forward kinematics compiles one small kernel: quick without a cache
    T = biped.frame_transforms(biped.rest)
print(bool(abs(T[biped.frame_of("head"), 2, 3] - 1.6) < 0.2), sum(w.category.__name__ == "KernelCacheWarning" for w in caught))
print(*[str(w.message) for w in caught if w.category.__name__ == "KernelCacheWarning"], sep="\\n")
"""


def _run(prelude: str, tmp_path, **env) -> list[str]:
    code = textwrap.dedent(prelude) + _SOLVE
    environ = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")} | env
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=environ, cwd=tmp_path)
    assert out.returncode == 0, out.stderr[-2000:]
    return out.stdout.splitlines()


# Pretend that neither the package folder nor the home folder can be written (as for a read-only install run by a
# service account without a home): numba's own locators then find no place.
_NO_USUAL_PLACE = """
from numba.core import caching
caching.InTreeCacheLocator.from_function = classmethod(lambda cls, f, p: None)
caching.UserWideCacheLocator.from_function = classmethod(lambda cls, f, p: None)
"""


def test_unwritable_package_and_home_fall_back_to_the_temporary_folder_and_say_so_once(tmp_path):
    lines = _run(_NO_USUAL_PLACE, tmp_path, TMPDIR=str(tmp_path))
    assert lines[0] == "True 1"
    assert str(tmp_path) in lines[1] and "caching compiled kernels" in lines[1]
    assert list(tmp_path.glob("gsik-numba-cache-*/*/*.nbi")), "nothing was cached in the temporary folder"


def test_no_writable_folder_at_all_compiles_without_a_cache_and_says_so_once(tmp_path):
    # A file where the temporary cache folder would go: even root cannot make that folder.
    (tmp_path / f"gsik-numba-cache-{os.getuid()}").write_text("")
    lines = _run(_NO_USUAL_PLACE, tmp_path, TMPDIR=str(tmp_path))
    assert lines[0] == "True 1"
    assert "compile at every start" in lines[1]


@pytest.mark.skipif(not hasattr(os, "getuid") or os.getuid() == 0, reason="root can write to read-only folders")
def test_read_only_install_without_home_imports_and_solves(tmp_path):
    import shutil

    import gsik
    site = tmp_path / "site"
    shutil.copytree(os.path.dirname(gsik.__file__), site / "gsik", ignore=shutil.ignore_patterns("__pycache__"))
    for root, dirs, files in os.walk(site):
        for name in dirs + files:
            os.chmod(os.path.join(root, name), 0o555)
    lines = _run(f"import sys; sys.path.insert(0, {str(site)!r})", tmp_path, HOME="/nonexistent", TMPDIR=str(tmp_path))
    assert lines[0].startswith("True")


# The documented fallback: without numba's compiler (here ``NUMBA_DISABLE_JIT``) every kernel runs as plain Python. A
# crouch as in the README, solved, then one controlled step.
_SOLVE_BOTH_PATHS = """
import json
import gsik, numpy as np
s = gsik.Solver(gsik.load_skeleton("biped"))
t = {n: gsik.Target.from_transform(T) for n, T in s.effector_poses().items()}
t.update({n: t[n].replace(position=t[n].position - [0.0, 0.0, 0.07]) for n in ("pelvis", "head", "right_hand")})
t.update({n: t[n].replace(position_only=True) for n in ("left_hand", "right_hand")})
plain = s.solve(t)
s.set_posture(s.q.copy())
t["left_hand"] = t["left_hand"].replace(position=t["left_hand"].position + [0.0, 0.03, 0.0])
controlled = s.step(t)
print(plain.converged, json.dumps(np.concatenate([plain.q, controlled.q]).tolist()))
"""


def _both_paths(tmp_path, **env) -> tuple[str, np.ndarray]:
    environ = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")} | env
    out = subprocess.run([sys.executable, "-c", _SOLVE_BOTH_PATHS], capture_output=True, text=True, env=environ,
                         cwd=tmp_path)
    assert out.returncode == 0, out.stderr[-2000:]
    converged, q = out.stdout.split(" ", 1)
    return converged, np.array(json.loads(q))


def test_without_the_compiler_the_kernels_run_as_python_with_the_compiled_results(tmp_path):
    converged, q_python = _both_paths(tmp_path, NUMBA_DISABLE_JIT="1")
    assert converged == "True"
    _, q_compiled = _both_paths(tmp_path)
    np.testing.assert_allclose(q_python, q_compiled, atol=1e-9)


def _recorded_options(monkeypatch, nrt_option: bool) -> dict:
    seen = {}

    def fake_njit(**options):
        seen.update(options)
        return lambda f: f

    monkeypatch.setattr(_jit, "_numba_njit", fake_njit)
    monkeypatch.setattr(_jit, "_NRT_OPTION", nrt_option)
    kernel = _jit.njit(_nrt=False, fastmath=False)(lambda x: x + 1)
    assert kernel(1) == 2
    return seen


def test_the_private_nrt_option_reaches_numba_only_where_numba_has_it(monkeypatch):
    assert _recorded_options(monkeypatch, True) == {"_nrt": False, "fastmath": False}
    assert _recorded_options(monkeypatch, False) == {"fastmath": False}

