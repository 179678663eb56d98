"""The skinned body's mesh (gsik_studio.skinned_body.SkinnedMesh): the biped's mannequin goes through the same
skinning as a character, written in place into float32 arrays, and only when the pose moved it. No window."""

from __future__ import annotations

import numpy as np
import pytest

import gsik
from gsik.io.gltf import character_from_skeleton
from gsik.io.gltf.binding import skin_binding
from gsik.mannequin import mannequin_mesh
from gsik.skinning import skinned
from gsik_studio.model.characters import body_character
from gsik_studio.skinned_body import SkinnedMesh


def _pose(sk, q):
    solver = gsik.Solver(sk)
    solver.set_q(q)
    return solver.world_positions(), solver.world_rotations()


def _world(P, R):
    W = np.zeros((len(P), 4, 4))
    W[:, :3, :3], W[:, :3, 3], W[:, 3, 3] = R, P, 1.0
    return W


@pytest.fixture(scope="module")
def biped():
    return gsik.load_skeleton("biped")


def test_the_biped_body_is_its_mannequin_as_export_gltf_writes_it(biped):
    character = body_character(biped)
    assert character.skeleton is biped
    binding = skin_binding(character)
    assert binding.n_vertices == len(mannequin_mesh(biped).points) > 1000
    assert np.all(binding.weights[:, 0] == 1.0)  # rigid solids: one joint per vertex
    np.testing.assert_array_equal(binding.positions, skin_binding(character_from_skeleton(biped)).positions)


def test_the_mesh_is_skinned_in_place_in_float32_and_only_when_the_pose_moved_it(biped):
    mesh = SkinnedMesh(skin_binding(body_character(biped)))
    pd = mesh.polydata
    points, normals = pd.GetPoints(), pd.GetPointData().GetArray("Normals")
    assert pd.points.dtype == np.float32 and pd.point_data["Normals"].dtype == np.float32
    q = np.random.default_rng(2).uniform(biped.lower, biped.upper)
    P, R = _pose(biped, q)
    assert mesh.update(P, R)
    expected_points, expected_normals = skinned(mesh.binding, _world(P, R))
    np.testing.assert_allclose(pd.points, expected_points, atol=1e-5)
    np.testing.assert_allclose(pd.point_data["Normals"], expected_normals, atol=1e-5)
    assert pd.GetPoints() is points and pd.GetPointData().GetArray("Normals") is normals  # the same VTK arrays
    stamp = (points.GetMTime(), normals.GetMTime())
    assert not mesh.update(P.copy(), R.copy())  # the same pose: nothing written, nothing for VTK to upload
    assert (points.GetMTime(), normals.GetMTime()) == stamp
    P2, R2 = _pose(biped, biped.rest)
    assert mesh.update(P2, R2)
    assert points.GetMTime() > stamp[0] and normals.GetMTime() > stamp[1]
    np.testing.assert_allclose(pd.points, skinned(mesh.binding, _world(P2, R2))[0], atol=1e-5)


def test_carriers_are_the_frames_that_move_vertices(biped):
    mesh = SkinnedMesh(skin_binding(body_character(biped)))
    assert set(mesh.carriers) == set(mannequin_mesh(biped).carrier)
