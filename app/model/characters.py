"""Skinned glTF characters in the studio's model: open one as a document, export a document as glTF.

Plain Python. A character's skeleton is an ordinary gsik skeleton, so a document on it is an ordinary
:class:`~gsik_studio.model.document.Document`; what only a character has (its file, meshes and skin) is kept here,
found again by the skeleton (:func:`character_of`), so the body view can skin its meshes and Export glTF can
write the file back with everything else kept.
"""

from __future__ import annotations

import os
import weakref

import gsik
from gsik.io.gltf import Character, character_from_skeleton, read_character, write_gltf
from gsik_studio.model.document import Document

#: File name endings read as glTF characters.
CHARACTER_SUFFIXES = (".glb", ".gltf")

_characters: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def is_character_file(path: str | os.PathLike) -> bool:
    return os.fspath(path).lower().endswith(CHARACTER_SUFFIXES)


def open_character(path: str | os.PathLike) -> Character:
    """Read a skinned glTF character and remember it for its skeleton.

    Raises:
        GsikError: a bad file, no skin, not a humanoid (nothing changes in any document).
    """
    character = read_character(path)
    _characters[character.skeleton] = character
    return character


def character_of(skeleton: gsik.Skeleton) -> Character | None:
    """The character ``skeleton`` was read from, or ``None`` (a YAML, URDF or BVH skeleton)."""
    return _characters.get(skeleton)


def read_skeleton(path: str | os.PathLike) -> gsik.Skeleton:
    """A character's skeleton (remembered, see :func:`open_character`) for a ``.glb``/``.gltf`` path, else
    :func:`gsik_studio.model.transfer.read_skeleton`'s (YAML, URDF).

    Raises:
        GsikError: the file cannot be read or is not a valid skeleton or character.
    """
    from gsik_studio.model.transfer import read_skeleton as read_other

    return open_character(path).skeleton if is_character_file(path) else read_other(path)


def character_document(path: str | os.PathLike) -> Document:
    """A new document on the character of ``path``, standing at the file's rest pose."""
    return Document(open_character(path).skeleton)


def body_character(skeleton: gsik.Skeleton) -> Character:
    """The character whose skinned body the studio draws and Export glTF writes: the one ``skeleton`` was read from,
    else ``skeleton`` with its mannequin as the skinned mesh (:func:`gsik.io.gltf.character_from_skeleton`)."""
    return character_of(skeleton) or character_from_skeleton(skeleton)


def export_gltf(doc: Document, path: str | os.PathLike) -> str:
    """Write the document's clip, else its keys, else its pose as glTF, on its character (everything else of the
    file kept) or, for a skeleton that is no character, on its mannequin body; returns what was written.

    Raises:
        GsikError: nothing was written (an existing file is unchanged).
    """
    from gsik_studio.model.transfer import export_source

    what, motion = export_source(doc)
    write_gltf(path, body_character(doc.skeleton), motion)
    return what
