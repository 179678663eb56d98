"""glTF 2.0 skinned characters: read them as gsik skeletons, write them posed or animated.

The steps, each its own module, as Blender's glTF I/O splits them (a reader returns data, a writer takes data):

* :func:`read_gltf` (:mod:`.read`, :mod:`.load`, :mod:`.accessors`): a ``.glb`` or ``.gltf`` file (external or
  data-URI buffers) into a plain :class:`GltfFile` (nodes, skins, meshes with vertices, normals, joint indices and
  weights, inverse bind matrices, base colours), bounded in size and checked;
* :func:`character_from_file` / :func:`read_character` (:mod:`.character`): the skin as a posable gsik skeleton,
  recognised as a humanoid (conventions there);
* :func:`character_from_skeleton` (:mod:`.body`): any gsik skeleton with its mannequin body as a skinned character;
* :func:`write_gltf` (:mod:`.write`, :mod:`.pose`): a pose or a motion on a character, written atomically.

Errors are :class:`~gsik.errors.GltfError` (a malformed, unsafe or non-skinned file) or the humanoid
recognition's ``HumanoidError``.
"""

from gsik.io.gltf.body import character_from_skeleton
from gsik.io.gltf.character import Character, character_from_file, read_character
from gsik.io.gltf.model import GltfFile, GltfMesh, GltfNode, GltfPrimitive, GltfSkin
from gsik.io.gltf.read import read_gltf
from gsik.io.gltf.write import posed_document, write_gltf

__all__ = [
    "Character",
    "GltfFile",
    "GltfMesh",
    "GltfNode",
    "GltfPrimitive",
    "GltfSkin",
    "character_from_file",
    "character_from_skeleton",
    "posed_document",
    "read_character",
    "read_gltf",
    "write_gltf",
]
