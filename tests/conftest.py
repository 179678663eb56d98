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
