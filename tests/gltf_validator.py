"""Khronos' glTF validator (npm ``gltf-validator``, installed by ``.ci/run`` into ``.ci/node``), run by node.

Callers are skipped, with the reason, where node or the validator is not installed.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path

import pytest

NODE_DIR = Path(__file__).resolve().parents[1] / ".ci" / "node"
SCRIPT = NODE_DIR / "validate.js"


def _node() -> str:
    node = shutil.which("node")
    if node is None:
        pytest.skip("node is not installed (.ci/run installs it): the glTF validator cannot run")
    if not (NODE_DIR / "node_modules" / "gltf-validator").is_dir():
        pytest.skip(f"the glTF validator is not installed: run 'npm ci' in {NODE_DIR} (.ci/run does)")
    return node


def validate(path: str | os.PathLike) -> dict:
    """The validator's report of ``path`` (its ``issues``: numErrors, numWarnings, messages ...)."""
    done = subprocess.run([_node(), str(SCRIPT), os.fspath(path)], capture_output=True, text=True, timeout=300)
    if done.returncode != 0 or not done.stdout.strip():
        raise RuntimeError(f"the glTF validator failed on {path}, exit {done.returncode}:\n{done.stderr[-2000:]}")
    report = json.loads(done.stdout.splitlines()[0])
    if "failure" in report:
        raise RuntimeError(f"the glTF validator could not read {path}: {report['failure']}")
    return report["issues"]


def assert_valid(path: str | os.PathLike) -> dict:
    """Assert the validator finds no error in ``path``; returns its report."""
    issues = validate(path)
    errors = [f"{m['code']} at {m.get('pointer', '?')}: {m['message']}" for m in issues["messages"]
              if m["severity"] == 0]
    assert issues["numErrors"] == 0, f"{Path(path).name}: {issues['numErrors']} validator errors: {errors[:10]}"
    return issues
