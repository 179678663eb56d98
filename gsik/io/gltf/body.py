"""Any gsik skeleton as a skinned glTF character: one node per joint, its mannequin (:mod:`gsik.mannequin`) as the mesh.

The nodes are the skeleton's joints (names kept, joint 0 the scene's root), at the skeleton's rest pose, which is
the bind pose; every mannequin vertex is bound with weight 1 to the joint that carries its solid, its colour a
vertex colour. The file is made in memory and returned as a :class:`~gsik.io.gltf.character.Character`, so posing
and writing it is the same path as for a character read from a file; the studio draws the biped's body from it
through the same skinning as a character's (``gsik_studio.skinned_body``).
"""

from __future__ import annotations

from types import MappingProxyType

import numpy as np

from gsik.io.gltf.axes import GSIK_FROM_GLTF, gltf_from_gsik, xyzw_from_matrix
from gsik.io.gltf.character import Character
from gsik.io.gltf.load import gltf_library
from gsik.io.gltf.model import GltfFile, GltfMesh, GltfNode, GltfPrimitive, GltfSkin, frozen_array
from gsik.io.gltf.write import BlobBuilder
from gsik.mannequin import mannequin_mesh
from gsik.skeleton import Skeleton

_UNSIGNED_SHORT = 5123
#: The material's base colour: white, since glTF multiplies it with the vertex colours (COLOR_0), which carry
#: the mannequin's clay and the left side's tint.
_BASE_COLOR = (1.0, 1.0, 1.0, 1.0)


def _joint_of_frames(sk: Skeleton) -> np.ndarray:
    """(n_frames,) the joint each frame moves with: the nearest joint end frame at or above it."""
    end_of = {int(f): j for j, f in enumerate(sk.joint_frame)}
    out = np.zeros(sk.n_frames, dtype=np.int64)
    for f in range(sk.n_frames):
        a = f
        while a >= 0 and a not in end_of:
            a = int(sk.frame_parent[a])
        out[f] = end_of.get(a, 0)
    return out


def character_from_skeleton(sk: Skeleton) -> Character:
    """``sk`` with its mannequin body as a skinned glTF character (see the module); a skeleton without segments
    gets the skin alone."""
    pygltflib = gltf_library()
    frames = sk.frame_transforms(sk.rest)
    world = gltf_from_gsik(frames[sk.joint_frame])  # (n_joints, 4, 4) file axes, the bind pose
    nodes, gltf_nodes = _joint_nodes(sk, world)
    n = len(nodes)
    document = pygltflib.GLTF2(asset=pygltflib.Asset(generator="gsik", version="2.0"), scene=0,
                               scenes=[pygltflib.Scene(name=sk.name, nodes=[0])], nodes=gltf_nodes)
    blob = BlobBuilder(document, ())
    inverse_bind = np.linalg.inv(world)
    document.skins = [pygltflib.Skin(name=sk.name, joints=list(range(n)), inverseBindMatrices=blob.add(
        inverse_bind.transpose(0, 2, 1).reshape(n, 16), "MAT4"))]
    meshes = _add_body(sk, frames, blob, nodes)
    blob.finish()
    file = GltfFile("<memory>", tuple(nodes), (GltfSkin(sk.name, tuple(range(n)), frozen_array(inverse_bind)),),
                    meshes, document, (bytes(blob.blob),))
    rest_world = np.concatenate([world, np.tile(np.eye(4), (len(nodes) - n, 1, 1))])
    rest_world.flags.writeable = False
    effectors = MappingProxyType({e: e for e in sk.effector_sites})
    return Character(file, sk, 0, tuple(range(n)), None, effectors, MappingProxyType({}), rest_world,
                     np.array(sk.rest))


def _joint_nodes(sk: Skeleton, world: np.ndarray) -> tuple[list[GltfNode], list]:
    """One node per joint at its bind transform ``world`` (n_joints, 4, 4): as plain data and as glTF JSON."""
    pygltflib = gltf_library()
    parents = [int(p) for p in sk.joint_parent]
    nodes, gltf_nodes = [], []
    for j, name in enumerate(sk.joint_names):
        local = world[j] if parents[j] < 0 else np.linalg.inv(world[parents[j]]) @ world[j]
        t, r = local[:3, 3], xyzw_from_matrix(local[:3, :3])
        children = [k for k, p in enumerate(parents) if p == j]
        nodes.append(GltfNode(name, parents[j], frozen_array(t), frozen_array(r), frozen_array(np.ones(3))))
        gltf_nodes.append(pygltflib.Node(name=name, translation=t.tolist(), rotation=r.tolist(),
                                         children=children or None))
    return nodes, gltf_nodes


def _add_body(sk: Skeleton, frames: np.ndarray, blob: BlobBuilder, nodes: list[GltfNode]) -> tuple[GltfMesh, ...]:
    """The mannequin's mesh, material and mesh node added to ``blob``'s document (none for no segments)."""
    pygltflib = gltf_library()
    body = mannequin_mesh(sk)
    if not len(body.points):
        return ()
    document = blob.document
    primitive, data = _body_primitive(sk, body, frames, blob)
    document.materials = [pygltflib.Material(name="mannequin", pbrMetallicRoughness=pygltflib.PbrMetallicRoughness(
        baseColorFactor=list(_BASE_COLOR), metallicFactor=0.0, roughnessFactor=0.8))]
    document.meshes = [pygltflib.Mesh(name=f"{sk.name}_body", primitives=[primitive])]
    document.nodes.append(pygltflib.Node(name=f"{sk.name}_body", mesh=0, skin=0))
    document.scenes[0].nodes.append(len(document.nodes) - 1)
    nodes.append(GltfNode(f"{sk.name}_body", -1, frozen_array(np.zeros(3)), frozen_array([0.0, 0.0, 0.0, 1.0]),
                          frozen_array(np.ones(3)), 0, 0))
    return (GltfMesh(f"{sk.name}_body", (data,)),)


def _body_primitive(sk: Skeleton, body, frames: np.ndarray, blob: BlobBuilder) -> tuple[object, GltfPrimitive]:
    """The mannequin ``body`` as a glTF primitive (accessors added to ``blob``) and as plain data."""
    pygltflib = gltf_library()
    R, t = frames[body.carrier, :3, :3], frames[body.carrier, :3, 3]  # (n_vertices, 3, 3), (n_vertices, 3)
    # World (gsik axes) at the bind pose, then the file's axes: p_file = C^T p_world.
    positions = (np.einsum("vij,vj->vi", R, body.points) + t) @ GSIK_FROM_GLTF
    normals = np.einsum("vij,vj->vi", R, body.normals) @ GSIK_FROM_GLTF
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    joints = np.zeros((len(positions), 4), dtype=np.uint16)
    joints[:, 0] = _joint_of_frames(sk)[body.carrier]
    weights = np.zeros((len(positions), 4))
    weights[:, 0] = 1.0
    attributes = pygltflib.Attributes(
        POSITION=blob.add(positions, "VEC3", bounds=True, target=34962),
        NORMAL=blob.add(normals, "VEC3", target=34962),
        JOINTS_0=blob.add(joints, "VEC4", target=34962, component=_UNSIGNED_SHORT),
        WEIGHTS_0=blob.add(weights, "VEC4", target=34962),
        COLOR_0=blob.add(body.colors, "VEC3", target=34962))
    indices = blob.add(body.triangles.reshape(-1, 1), "SCALAR", target=34963, component=5125)
    primitive = pygltflib.Primitive(attributes=attributes, indices=indices, material=0)
    data = GltfPrimitive(frozen_array(positions), frozen_array(normals), frozen_array(body.triangles, np.int64),
                         frozen_array(joints, np.int64), frozen_array(weights), frozen_array(_BASE_COLOR), 0,
                         frozen_array(body.colors))
    return primitive, data
