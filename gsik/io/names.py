"""Names made unique: one rule for every format that invents names (End Sites, link sites, added effectors)."""

from __future__ import annotations

from collections.abc import Container


#: A joint's name where its file's would be an effector's (``{}`` the file's name): a glTF node ``head``.
RENAMED_JOINT = "{}_joint"


def unique_name(base: str, taken: Container[str]) -> str:
    """``base`` if it is free, else ``base2``, ``base3`` ... (the first free one); ``taken`` is not changed."""
    name, k = base, 2
    while name in taken:
        name, k = f"{base}{k}", k + 1
    return name


__all__ = ["RENAMED_JOINT", "unique_name"]
