"""Read a glTF file into :class:`~gsik.io.gltf.model.GltfFile`: nodes, skins and meshes, each checked."""

from __future__ import annotations

import os

import numpy as np

from gsik.errors import GltfError, show_value
from gsik.io.gltf.accessors import read_accessor
from gsik.io.gltf.axes import trs_from_matrix
from gsik.io.gltf.load import load_gltf_file
from gsik.io.gltf.model import GltfFile, GltfMesh, GltfNode, GltfPrimitive, GltfSkin, frozen_array

#: How far a vertex's skin weights may sum from 1 (glTF asks for 1; 8-bit weights round to within 4/255).
WEIGHT_SUM_TOLERANCE = 0.02
_TRIANGLES = 4


def read_gltf(path: str | os.PathLike) -> GltfFile:
    """Read a ``.glb`` or ``.gltf`` file (external or data-URI buffers) within gsik's limits.

    Raises:
        GltfError: a malformed or unsafe file (see :mod:`gsik.io.gltf.load`), a cycle or a node with two parents,
            an index out of range, a skin's weights that do not sum to one, a joint index past its skin.
        GsikFileError: the file or a buffer file cannot be read.
    """
    loaded = load_gltf_file(path)
    where = show_value(os.fspath(path), 240)
    doc = loaded.document
    nodes = _nodes(doc, where)
    skins = tuple(_skin(doc, loaded.buffers, k, len(nodes), where) for k in range(len(doc.skins or [])))
    meshes = tuple(_mesh(doc, loaded.buffers, k, where) for k in range(len(doc.meshes or [])))
    file = GltfFile(os.fspath(path), nodes, skins, meshes, doc, loaded.buffers)
    _check_skinned_meshes(file, where)
    return file


def _parents(doc, where: str) -> list[int]:
    """Parent index per node; refuses a child out of range, a node with two parents and a cycle."""
    n = len(doc.nodes)
    parent = [-1] * n
    for i, node in enumerate(doc.nodes):
        for c in node.children or []:
            if not isinstance(c, int) or isinstance(c, bool) or not 0 <= c < n:
                raise GltfError(f"{where}: nodes[{i}].children holds {show_value(c)}, not a node (0..{n - 1})")
            if parent[c] != -1 or c == i:
                raise GltfError(f"{where}: node {c} is a child twice (of nodes {parent[c]} and {i}): the nodes "
                                "must form a tree")
            parent[c] = i
    for i in range(n):  # a walk up longer than n nodes has met a cycle
        seen, j = 0, i
        while j != -1:
            j, seen = parent[j], seen + 1
            if seen > n:
                raise GltfError(f"{where}: the nodes' children form a cycle through node {i}")
    return parent


def _trs(node, i: int, where: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(translation, rotation (x, y, z, w), scale)`` of a node, from its TRS or its matrix."""
    if node.matrix is not None and any(v is not None for v in (node.translation, node.rotation, node.scale)):
        raise GltfError(f"{where}: nodes[{i}] has both a matrix and TRS properties")
    if node.matrix is not None:
        M = _finite(node.matrix, (16,), f"nodes[{i}].matrix", where).reshape(4, 4).T  # column-major
        return trs_from_matrix(M, f"{where}: nodes[{i}].matrix")
    t = _finite(node.translation if node.translation is not None else [0, 0, 0], (3,), f"nodes[{i}].translation",
                where)
    r = _finite(node.rotation if node.rotation is not None else [0, 0, 0, 1], (4,), f"nodes[{i}].rotation", where)
    s = _finite(node.scale if node.scale is not None else [1, 1, 1], (3,), f"nodes[{i}].scale", where)
    norm = float(np.linalg.norm(r))
    if abs(norm - 1.0) > 1e-3:
        raise GltfError(f"{where}: nodes[{i}].rotation {show_value(r.tolist())} is not a unit quaternion")
    return t, r / norm, s


def _finite(values, shape: tuple[int, ...], field: str, where: str) -> np.ndarray:
    try:
        a = np.array(values, dtype=float)
    except (TypeError, ValueError):
        a = None
    if a is None or a.shape != shape or not np.all(np.isfinite(a)):
        raise GltfError(f"{where}: {field} must be {shape[0]} finite numbers, got {show_value(values)}")
    return a


def _index(value, n: int, field: str, where: str) -> int:
    if value is None:
        return -1
    if not isinstance(value, int) or isinstance(value, bool) or not 0 <= value < n:
        raise GltfError(f"{where}: {field} is {show_value(value)}, not one of the file's {n}")
    return value


def _nodes(doc, where: str) -> tuple[GltfNode, ...]:
    parent = _parents(doc, where)
    nodes = []
    for i, node in enumerate(doc.nodes):
        t, r, s = _trs(node, i, where)
        name = node.name if isinstance(node.name, str) and node.name else f"node{i}"
        mesh = _index(node.mesh, len(doc.meshes or []), f"nodes[{i}].mesh", where)
        skin = _index(node.skin, len(doc.skins or []), f"nodes[{i}].skin", where)
        nodes.append(GltfNode(name, parent[i], frozen_array(t), frozen_array(r), frozen_array(s), mesh, skin))
    return tuple(nodes)


def _skin(doc, buffers, k: int, n_nodes: int, where: str) -> GltfSkin:
    skin = doc.skins[k]
    joints = tuple(_index(j, n_nodes, f"skins[{k}].joints", where) for j in (skin.joints or []))
    if not joints:
        raise GltfError(f"{where}: skins[{k}] has no joints")
    if len(set(joints)) != len(joints):
        raise GltfError(f"{where}: skins[{k}] lists a joint twice")
    if skin.inverseBindMatrices is None:
        ibm = np.tile(np.eye(4), (len(joints), 1, 1))
    else:
        raw = read_accessor(doc, buffers, skin.inverseBindMatrices, f"skins[{k}].inverseBindMatrices")
        if raw.shape != (len(joints), 16):
            raise GltfError(f"{where}: skins[{k}].inverseBindMatrices holds {raw.shape[0]} matrices of "
                            f"{raw.shape[1]} numbers for {len(joints)} joints (one MAT4 each)")
        ibm = raw.astype(float).reshape(-1, 4, 4).transpose(0, 2, 1)
        if not np.all(np.isfinite(ibm)):
            raise GltfError(f"{where}: skins[{k}].inverseBindMatrices holds numbers that are not finite")
    return GltfSkin(skin.name or f"skin{k}", joints, frozen_array(ibm))


def _mesh(doc, buffers, k: int, where: str) -> GltfMesh:
    mesh = doc.meshes[k]
    prims = tuple(_primitive(doc, buffers, p, f"meshes[{k}].primitives[{m}]", where)
                  for m, p in enumerate(mesh.primitives or []))
    return GltfMesh(mesh.name or f"mesh{k}", prims)


def _attribute(doc, buffers, attrs, name: str, what: str, where: str) -> np.ndarray | None:
    index = getattr(attrs, name, None)
    return None if index is None else read_accessor(doc, buffers, index, f"{where}: {what}.{name}")


def _primitive(doc, buffers, prim, what: str, where: str) -> GltfPrimitive:
    attrs = prim.attributes
    positions = _attribute(doc, buffers, attrs, "POSITION", what, where)
    if positions is None or positions.shape[1] != 3:
        raise GltfError(f"{where}: {what} has no POSITION of VEC3")
    n = len(positions)
    normals = _attribute(doc, buffers, attrs, "NORMAL", what, where)
    if normals is not None and normals.shape != (n, 3):
        raise GltfError(f"{where}: {what}.NORMAL must have one VEC3 per vertex ({n})")
    triangles = _triangles(doc, buffers, prim, n, what, where)
    joints, weights = _influences(doc, buffers, attrs, n, what, where)
    material = _index(prim.material, len(doc.materials or []), f"{what}.material", where)
    colors = _attribute(doc, buffers, attrs, "COLOR_0", what, where)
    if colors is not None and (len(colors) != n or colors.shape[1] not in (3, 4)):
        raise GltfError(f"{where}: {what}.COLOR_0 must have one VEC3 or VEC4 per vertex ({n})")
    return GltfPrimitive(frozen_array(positions), None if normals is None else frozen_array(normals),
                         frozen_array(triangles, np.int64), joints, weights, _base_color(doc, material), material,
                         None if colors is None else frozen_array(np.clip(colors[:, :3], 0.0, 1.0)))


def _triangles(doc, buffers, prim, n: int, what: str, where: str) -> np.ndarray:
    mode = _TRIANGLES if prim.mode is None else prim.mode
    if mode != _TRIANGLES:
        return np.zeros((0, 3), dtype=np.int64)  # points, lines, strips: kept in the file, not drawn
    if prim.indices is None:
        index = np.arange(n - n % 3)
    else:
        index = read_accessor(doc, buffers, prim.indices, f"{where}: {what}.indices").ravel().astype(np.int64)
    if index.size and (index.min() < 0 or index.max() >= n):
        raise GltfError(f"{where}: {what}.indices reach vertex {int(index.max())}; the primitive has {n}")
    return index[: index.size - index.size % 3].reshape(-1, 3)


def _influences(doc, buffers, attrs, n: int, what: str, where: str) -> tuple[np.ndarray | None, np.ndarray | None]:
    """``(joints, weights)`` (n, 4k) of every JOINTS_i / WEIGHTS_i set, weights summing to 1 per vertex."""
    joints, weights = [], []
    for set_index in range(8):
        j = _attribute(doc, buffers, attrs, f"JOINTS_{set_index}", what, where)
        w = _attribute(doc, buffers, attrs, f"WEIGHTS_{set_index}", what, where)
        if j is None and w is None:
            break
        if j is None or w is None or j.shape != (n, 4) or w.shape != (n, 4):
            raise GltfError(f"{where}: {what}: JOINTS_{set_index} and WEIGHTS_{set_index} must both be VEC4, one "
                            f"per vertex ({n})")
        joints.append(j.astype(np.int64))
        weights.append(w.astype(float))
    if not joints:
        return None, None
    J, W = np.concatenate(joints, axis=1), np.concatenate(weights, axis=1)
    sums = W.sum(axis=1)
    bad = np.flatnonzero(~(np.abs(sums - 1.0) <= WEIGHT_SUM_TOLERANCE) | np.any(W < 0, axis=1))
    if bad.size:
        v = int(bad[0])
        raise GltfError(f"{where}: {what}: the skin weights of {bad.size:,} vertices do not sum to 1 (vertex {v}: "
                        f"{show_value(W[v].tolist())}, sum {sums[v]:.4g})")
    return frozen_array(J, np.int64), frozen_array(W / sums[:, None])


def _base_color(doc, material: int) -> np.ndarray:
    """RGBA base colour factor of ``material`` (white for none)."""
    color = [1.0, 1.0, 1.0, 1.0]
    if material >= 0:
        pbr = doc.materials[material].pbrMetallicRoughness
        factor = getattr(pbr, "baseColorFactor", None) if pbr is not None else None
        if factor is not None:
            try:
                color = [float(np.clip(float(c), 0.0, 1.0)) for c in factor][:4]
            except (TypeError, ValueError):
                pass
    return frozen_array(color if len(color) == 4 else [1.0, 1.0, 1.0, 1.0])


def _check_skinned_meshes(file: GltfFile, where: str) -> None:
    """A skinned mesh's joint indices must lie inside its skin."""
    for i, node in enumerate(file.nodes):
        if node.mesh < 0 or node.skin < 0:
            continue
        n_joints = len(file.skins[node.skin].joints)
        for p in file.meshes[node.mesh].primitives:
            if p.joints is not None and p.joints.size and int(p.joints.max()) >= n_joints:
                raise GltfError(f"{where}: node {node.name!r}: mesh {file.meshes[node.mesh].name!r} uses joint "
                                f"{int(p.joints.max())} of skin {file.skins[node.skin].name!r}, which has "
                                f"{n_joints}")
