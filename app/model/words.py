"""Skeleton names in words, for what people read (undo texts, titles): ``right_shoulder.y`` -> ``right shoulder (y)``.

Plain Python (the widgets' :func:`gsik_studio.widgets.nice` is the same rule for labels).
"""

from __future__ import annotations


def words(name: str) -> str:
    """A joint, site or effector name in words: ``"left_hand"`` -> ``"left hand"``."""
    return name.replace("_", " ")


def dof_words(dof_name: str) -> str:
    """A DOF name ``"<joint>.<axis>"`` in words: ``"right_shoulder.y"`` -> ``"right shoulder (y)"``.

    A name without an axis part (a URDF joint's single DOF) is just its words.
    """
    joint, dot, axis = dof_name.rpartition(".")
    return f"{words(joint)} ({axis})" if dot and joint else words(dof_name)


def names_words(names) -> str:
    """Several names in words, comma-separated: ``("head", "left_hand")`` -> ``"head, left hand"``."""
    return ", ".join(words(n) for n in names)
