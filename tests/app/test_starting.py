"""The start-up clock the window benchmark reads: silent unless asked for."""

from __future__ import annotations

import time

from gsik_studio.starting import TIMES_VARIABLE, mark


def test_mark_prints_the_stage_and_the_time_only_when_asked(monkeypatch, capsys):
    monkeypatch.delenv(TIMES_VARIABLE, raising=False)
    mark("view")
    assert capsys.readouterr().err == ""
    monkeypatch.setenv(TIMES_VARIABLE, "1")
    before = time.time()
    mark("start window")
    line = capsys.readouterr().err
    assert line.startswith("gsik-studio-time start window ") and line.endswith("\n")
    assert before - 0.01 <= float(line.split()[-1]) <= time.time() + 0.01
