"""Shared BVH test material: the base file (its line numbers are used by the malformed cases), line edits,
and independent rotation matrices."""

from __future__ import annotations

from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parents[1] / "data"

# Line numbers of this text are used by the malformed-file cases below.
BASE = """\
HIERARCHY
ROOT Hips
{
\tOFFSET 0 0 0
\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
\tJOINT Chest
\t{
\t\tOFFSET 0 1 0
\t\tCHANNELS 3 Zrotation Xrotation Yrotation
\t\tEnd Site
\t\t{
\t\t\tOFFSET 0 0.5 0
\t\t}
\t}
}
MOTION
Frames: 2
Frame Time: 0.04
0 1 0 10 20 30 1 2 3
0 1 0 11 21 31 4 5 6
"""


def lines_of(text: str = BASE) -> list[str]:
    return text.split("\n")


def replace_line(n: int, new: str, text: str = BASE) -> str:
    """``text`` with 1-based line ``n`` replaced by ``new``."""
    lines = lines_of(text)
    lines[n - 1] = new
    return "\n".join(lines)


def delete_line(n: int, text: str = BASE) -> str:
    lines = lines_of(text)
    del lines[n - 1]
    return "\n".join(lines)


def insert_line(n: int, new: str, text: str = BASE) -> str:
    """``text`` with ``new`` inserted so that it becomes line ``n``."""
    lines = lines_of(text)
    lines.insert(n - 1, new)
    return "\n".join(lines)


# Independent rotation matrices (degrees) to check the module against.
def rx(d: float) -> np.ndarray:
    c, s = np.cos(np.radians(d)), np.sin(np.radians(d))
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def ry(d: float) -> np.ndarray:
    c, s = np.cos(np.radians(d)), np.sin(np.radians(d))
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rz(d: float) -> np.ndarray:
    c, s = np.cos(np.radians(d)), np.sin(np.radians(d))
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


AXIS_MATRIX = {"X": rx, "Y": ry, "Z": rz}
