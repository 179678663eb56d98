"""Shared fixtures for the solver tests (NumPy only: no display needed)."""

from __future__ import annotations

import numpy as np
import pytest

import gsik


@pytest.fixture(scope="session")
def biped() -> gsik.Skeleton:
    return gsik.load_skeleton("biped")


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


@pytest.fixture(scope="session")
def blender_character(tmp_path_factory):
    """``make(spec) -> Path`` of the glTF character Blender made for a ``blender.gltf_characters.Spec``, made once
    per test session (skips where bpy is missing)."""
    from blender.gltf_characters import make_character

    folder = tmp_path_factory.mktemp("blender_characters")
    return lambda spec: make_character(spec, folder)
