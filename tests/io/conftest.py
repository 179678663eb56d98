"""The Blender-made glTF characters, made once per test session (tests/io/gltf_characters.py)."""

from __future__ import annotations

import pytest
from gltf_characters import Spec, make_character


@pytest.fixture(scope="session")
def blender_character(tmp_path_factory):
    """``make(spec) -> Path`` of the file Blender made for a :class:`gltf_characters.Spec` (cached per session)."""
    folder = tmp_path_factory.mktemp("blender_characters")

    def make(spec: Spec):
        return make_character(spec, folder)

    return make
