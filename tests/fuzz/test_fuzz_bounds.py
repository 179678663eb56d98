"""Bombs stay small: every hostile file is refused within ~200 MB and ~2 s of CPU, measured in a fresh process."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent

#: Bounds of the issue: far above what a refusal costs (a few MB, milliseconds), far below a bomb that went off.
MAX_MEMORY_MB = 200
MAX_CPU_S = 2.0


def test_every_bomb_is_refused_within_memory_and_time_bounds():
    code = f"import sys; sys.path.insert(0, {str(HERE)!r}); import fuzzing; fuzzing.print_bomb_figures()"
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300,
                         env={**os.environ, "PYTHONWARNINGS": "ignore"})
    assert run.returncode == 0, run.stderr[-2000:]
    figures = json.loads(run.stdout.strip().splitlines()[-1])
    for bomb in figures["bombs"]:
        assert bomb["outcome"].split(":")[0].endswith("Error"), bomb  # refused, as a GsikError
        assert bomb["cpu_s"] < MAX_CPU_S, bomb
        assert bomb["traced_peak_mb"] < MAX_MEMORY_MB, bomb
    assert figures["rss_growth_mb"] < MAX_MEMORY_MB, figures
