"""Bones from the tree's shape, where names fail (placeholder until the structural reader lands)."""

from __future__ import annotations

from gsik.humanoid.chains import Found


def bones_by_structure(rig, labels, found) -> dict[str, Found]:
    """Canonical bone -> joint from the rig's branches; nothing yet."""
    return {}
