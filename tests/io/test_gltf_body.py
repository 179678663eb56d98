"""A skeleton's mannequin as a skinned glTF body (gsik.io.gltf.body): the same solids the studio draws, at any pose."""

from __future__ import annotations

import numpy as np
import pytest

import gsik
from gsik.io.gltf import character_from_skeleton
from gsik.io.gltf.binding import skin_binding
from gsik.mannequin import mannequin_mesh
from gsik.skinning import skinned


def _world(solver) -> np.ndarray:
    """(n_frames, 4, 4) the solver's world transforms of every frame."""
    P, R = solver.world_positions(), solver.world_rotations()
    W = np.zeros((len(P), 4, 4))
    W[:, :3, :3], W[:, :3, 3], W[:, 3, 3] = R, P, 1.0
    return W


@pytest.mark.parametrize("name", ["biped", "humanoid"])
@pytest.mark.parametrize("root", ["right_foot", "left_foot"])
def test_the_skinned_mannequin_is_each_solid_rigid_on_its_carrier_at_any_pose(name, root):
    sk = gsik.load_skeleton(name)
    body = mannequin_mesh(sk)
    binding = skin_binding(character_from_skeleton(sk))
    solver = gsik.Solver(sk)
    solver.set_root(root)
    rng = np.random.default_rng(7)
    for q in (sk.rest, rng.uniform(sk.lower, sk.upper), rng.uniform(sk.lower, sk.upper)):
        solver.set_q(q)
        W = _world(solver)
        points, normals = skinned(binding, W)
        R, P = W[body.carrier, :3, :3], W[body.carrier, :3, 3]
        np.testing.assert_allclose(points, np.einsum("vij,vj->vi", R, body.points) + P, atol=1e-9)
        np.testing.assert_allclose(normals, np.einsum("vij,vj->vi", R, body.normals), atol=1e-9)


def test_the_mannequin_keeps_its_colours_through_the_file():
    """The vertex colours carry the clay and the left side's tint; the material's base colour (which glTF
    multiplies with them) is white, so a glTF viewer and the studio show the same colours."""
    sk = gsik.load_skeleton("biped")
    character = character_from_skeleton(sk)
    np.testing.assert_allclose(skin_binding(character).colors, mannequin_mesh(sk).colors)
    factor = character.file.document.materials[0].pbrMetallicRoughness.baseColorFactor
    assert factor == [1.0, 1.0, 1.0, 1.0]
    assert len({tuple(c) for c in mannequin_mesh(sk).colors}) == 2  # clay, and the left side tinted
