"""Names older gsik wrote in pose files, read as today's (the file format is unchanged).

Before every glTF character's effectors were named like the biped's, a character whose file names a joint like an
effector (Unreal's ``head``, ``pelvis``) got the effector site ``<name>_site`` and kept the joint's name; today the
site is ``<name>`` and the joint ``<name>_joint`` (:data:`gsik.io.names.RENAMED_JOINT`). A name the skeleton lacks
is read as its renamed form when the skeleton has that, so such files still open; nothing valid is renamed.
"""

from __future__ import annotations

from collections.abc import Collection

from gsik.io.names import RENAMED_JOINT

_OLD_SITE = "{}_site"


def _renamed(given, valid: Collection[str], new_name) -> object:
    """``given`` (a mapping, else returned as is) with each key not in ``valid`` whose ``new_name(key)`` is in
    ``valid`` and not given renamed to it, in order."""
    if not isinstance(given, dict) or all(k in valid for k in given):
        return given
    out = {}
    for key, value in given.items():
        new = new_name(key) if isinstance(key, str) and key not in valid else None
        out[new if new in valid and new not in given else key] = value
    return out


def _old_site(key: str) -> str | None:
    suffix = _OLD_SITE.format("")
    return key[: -len(suffix)] if key.endswith(suffix) else None


def _old_dof(key: str) -> str:
    joint, dot, axis = key.rpartition(".")
    return f"{RENAMED_JOINT.format(joint)}{dot}{axis}"


def targets(given, effectors: Collection[str]) -> object:
    """A ``targets`` mapping with ``<effector>_site`` keys read as ``<effector>``."""
    return _renamed(given, effectors, _old_site)


def joints(given, dof_names: Collection[str]) -> object:
    """A ``joints`` mapping with ``<joint>.<axis>`` keys read as ``<joint>_joint.<axis>``."""
    return _renamed(given, dof_names, _old_dof)


def dof_list(given, dof_names: Collection[str]) -> object:
    """A clip's ``dofs`` list with old DOF names read as today's (see :func:`joints`)."""
    if not isinstance(given, list):
        return given
    return list(joints(dict.fromkeys(given), dof_names)) if len(set(given)) == len(given) else given
