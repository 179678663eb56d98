"""Reading URDF's XML elements: namespaced tags, single children, link references and number attributes.

Every reader raises :class:`~gsik.errors.UrdfError` naming the element, the attribute and the bad text.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET

import numpy as np

from gsik.errors import UrdfError

_NUMBER_RE = re.compile(r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?")


def local_tag(tag: str) -> str:
    """Tag without an XML namespace (``{ns}robot`` -> ``robot``)."""
    return tag.rsplit("}", 1)[-1] if isinstance(tag, str) else ""


def children(elem: ET.Element, tag: str) -> list[ET.Element]:
    """``elem``'s direct children with local tag ``tag``, in document order."""
    return [c for c in elem if local_tag(c.tag) == tag]


def number(token: str, where: str) -> float:
    """``token`` as a finite float; ``where`` names the place in the error message."""
    try:
        value = float(token)
    except ValueError:
        raise UrdfError(f"{where}: non-numeric value {token!r}") from None
    if not np.isfinite(value):
        raise UrdfError(f"{where}: non-finite value {token!r}")
    if not _NUMBER_RE.fullmatch(token):  # float() also takes "1_0" and " 1 "
        raise UrdfError(f"{where}: non-numeric value {token!r}")
    return value


def vector_attr(elem: ET.Element | None, attr: str, default: tuple[float, ...], where: str) -> np.ndarray:
    """A 3-number attribute like ``xyz="0 0 0.1"``; ``default`` when element or attribute is missing."""
    if elem is None or elem.get(attr) is None:
        return np.array(default, dtype=float)
    text = elem.get(attr)
    where = f"{where} {attr}={text!r}"
    tokens = text.split()
    if len(tokens) != 3:
        raise UrdfError(f"{where}: expected 3 numbers, found {len(tokens)}")
    return np.array([number(t, where) for t in tokens])


def scalar_attr(elem: ET.Element, attr: str, where: str) -> float:
    """One-number attribute ``attr`` of ``elem`` (missing reads as empty and is refused)."""
    text = elem.get(attr, "")
    return number(text.strip(), f"{where} {attr}={text!r}")


def only_child(elem: ET.Element, tag: str, where: str) -> ET.Element | None:
    """``elem``'s single ``<tag>`` child, ``None`` when absent; two or more are refused."""
    found = children(elem, tag)
    if len(found) > 1:
        raise UrdfError(f"{where} has {len(found)} <{tag}> elements; expected at most one")
    return found[0] if found else None


def link_ref(joint: ET.Element, tag: str, where: str, links: set[str]) -> str:
    """The link named by ``joint``'s ``<parent link=...>`` or ``<child link=...>``, one of ``links``."""
    elem = only_child(joint, tag, where)
    if elem is None or not elem.get("link"):
        raise UrdfError(f"{where} has no <{tag} link=...>")
    name = elem.get("link")
    if name not in links:
        raise UrdfError(f"{where} references unknown link {name!r} as {tag}")
    return name
