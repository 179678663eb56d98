"""Write a posed or animated character as glTF: the input file with its joints moved, everything else kept.

A one-frame motion is written as the pose itself (the skin joints' node transforms); a longer one as a glTF
animation (``animation=True`` forces it for one frame): one rotation channel per joint that moves or differs from
its rest, a translation channel for each joint whose parent is not a joint (the hips), linear interpolation, the
nodes left at rest. Meshes, materials, names, extra nodes, other animations and extensions are the input's.
``.glb`` gets one binary buffer; ``.gltf`` gets its buffer embedded as a data URI.
"""

from __future__ import annotations

import base64
import copy
import os
import struct

import numpy as np

from gsik.anim.motion import Motion
from gsik.errors import GltfError, show_value
from gsik.io.files import atomic_write_bytes
from gsik.io.gltf.character import Character
from gsik.io.gltf.load import gltf_library
from gsik.io.gltf.pose import NodeTracks, node_tracks

#: A joint whose rotation stays within this of its rest over the motion gets no channel (quaternion distance,
#: about half the angle [rad]).
STILL = 1e-7
_FLOAT, _ARRAY_BUFFER = 5126, 34962


class BlobBuilder:
    """One binary buffer under construction: the input's buffers first, then new accessors appended."""

    def __init__(self, document, buffers: tuple[bytes, ...]) -> None:
        self.document = document
        self.blob = bytearray()
        starts = []
        for data in buffers:
            self._align()
            starts.append(len(self.blob))
            self.blob += data
        for view in document.bufferViews or []:
            view.byteOffset = (view.byteOffset or 0) + starts[view.buffer]
            view.buffer = 0

    def _align(self) -> None:
        self.blob += b"\0" * (-len(self.blob) % 4)

    def add(self, values: np.ndarray, kind: str, *, bounds: bool = False, target: int | None = None,
            component: int = _FLOAT) -> int:
        """Append ``values`` (count, width) as a new accessor of ``kind`` (``"VEC3"`` ...); returns its index."""
        pygltflib = gltf_library()
        dtype = {_FLOAT: np.float32, 5123: np.uint16, 5125: np.uint32, 5121: np.uint8}[component]
        data = np.ascontiguousarray(values, dtype=dtype)
        self._align()
        view = pygltflib.BufferView(buffer=0, byteOffset=len(self.blob), byteLength=data.nbytes, target=target)
        self.blob += data.tobytes()
        self.document.bufferViews.append(view)
        rows = data.reshape(len(data), -1)
        accessor = pygltflib.Accessor(bufferView=len(self.document.bufferViews) - 1, componentType=component,
                                      count=len(data), type=kind)
        if bounds:
            accessor.min = rows.min(axis=0).astype(float).tolist()
            accessor.max = rows.max(axis=0).astype(float).tolist()
        self.document.accessors.append(accessor)
        return len(self.document.accessors) - 1

    def finish(self) -> None:
        """Make the document's buffers the one blob."""
        pygltflib = gltf_library()
        self._align()
        self.document.buffers = [pygltflib.Buffer(byteLength=len(self.blob))]


def posed_document(character: Character, motion: Motion, *, animation: bool | None = None,
                   name: str = "gsik") -> tuple[object, bytes]:
    """``(document, binary buffer)``: a copy of the character's file with ``motion`` on it (see the module).

    Raises:
        GltfError: an empty motion, or one that lacks a DOF of the character.
    """
    if not isinstance(motion, Motion) or motion.n_frames == 0:
        raise GltfError("a glTF export needs a gsik.anim.motion.Motion with at least one frame")
    document = copy.deepcopy(character.file.document)
    for field in ("accessors", "bufferViews", "animations", "nodes"):
        if getattr(document, field) is None:
            setattr(document, field, [])
    blob = BlobBuilder(document, character.file.buffers)
    tracks = node_tracks(character, motion)
    if motion.n_frames == 1 and not animation:
        _set_nodes(document, tracks, 0)
    else:
        _add_animation(document, blob, tracks, character, name)
    blob.finish()
    return document, bytes(blob.blob)


def _set_nodes(document, tracks: NodeTracks, frame: int) -> None:
    """The joints' nodes given frame ``frame``'s transforms (a node's matrix becomes its TRS)."""
    for k, node in enumerate(tracks.nodes):
        n = document.nodes[node]
        if n.matrix is not None:
            from gsik.io.gltf.axes import trs_from_matrix

            _, _, n.scale = trs_from_matrix(np.array(n.matrix, dtype=float).reshape(4, 4).T, "node matrix")
            n.scale, n.matrix = [float(v) for v in n.scale], None
        n.translation = [float(v) for v in tracks.translation[frame, k]]
        n.rotation = [float(v) for v in tracks.rotation[frame, k]]


def _add_animation(document, blob: BlobBuilder, tracks: NodeTracks, character: Character, name: str) -> None:
    pygltflib = gltf_library()
    rest = character.file.nodes
    times = blob.add(tracks.times[:, None], "SCALAR", bounds=True)
    channels, samplers = [], []

    def channel(node: int, path: str, values: np.ndarray, kind: str) -> None:
        samplers.append(pygltflib.AnimationSampler(input=times, output=blob.add(values, kind),
                                                   interpolation="LINEAR"))
        channels.append(pygltflib.AnimationChannel(sampler=len(samplers) - 1,
                                                   target=pygltflib.AnimationChannelTarget(node=node, path=path)))

    joints = set(tracks.nodes)
    for k, node in enumerate(tracks.nodes):
        r = tracks.rotation[:, k]
        rest_r = np.asarray(rest[node].rotation)
        off_rest = np.minimum(np.linalg.norm(r - rest_r, axis=1), np.linalg.norm(r + rest_r, axis=1))
        if off_rest.max() > STILL:
            channel(node, "rotation", r, "VEC4")
        if rest[node].parent not in joints:
            channel(node, "translation", tracks.translation[:, k], "VEC3")
    document.animations.append(pygltflib.Animation(name=name, channels=channels, samplers=samplers))


def gltf_bytes(document, blob: bytes, path: str | os.PathLike) -> bytes:
    """The file's bytes: GLB for a ``.glb`` path, glTF JSON with the buffer as a data URI otherwise."""
    document.buffers[0].byteLength = len(blob)
    if os.fspath(path).lower().endswith(".glb"):
        document.buffers[0].uri = None
        return _glb(document, blob)
    document.buffers[0].uri = "data:application/octet-stream;base64," + base64.b64encode(blob).decode("ascii")
    return document.gltf_to_json().encode("utf-8")


def _glb(document, blob: bytes) -> bytes:
    """A GLB container: header, JSON chunk (space padded), BIN chunk (zero padded)."""
    text = document.to_json(separators=(",", ":"), allow_nan=False).encode("utf-8")
    text += b" " * (-len(text) % 4)
    blob += b"\0" * (-len(blob) % 4)
    length = 12 + 8 + len(text) + 8 + len(blob)
    return b"".join([b"glTF", struct.pack("<II", 2, length), struct.pack("<I", len(text)), b"JSON", text,
                     struct.pack("<I", len(blob)), b"BIN\0", blob])


def write_gltf(path: str | os.PathLike, character: Character, motion: Motion, *, animation: bool | None = None,
               name: str = "gsik") -> None:
    """Write ``character`` posed or animated by ``motion`` to ``path`` (``.glb`` or ``.gltf``), atomically.

    Args:
        path: The output; a failed write leaves an existing file untouched.
        character: The character (:func:`~gsik.io.gltf.read_character`, or a skeleton's own body).
        motion: Its pose (one frame) or animation.
        animation: Write one frame as an animation too; ``None``/``False`` writes a single frame as the pose.
        name: The animation's name.

    Raises:
        GltfError: a bad motion or path ending.
        GsikFileError: the file cannot be written.
    """
    if not os.fspath(path).lower().endswith((".glb", ".gltf")):
        raise GltfError(f"cannot write {show_value(os.fspath(path), 240)}: a glTF file ends in .glb or .gltf")
    document, blob = posed_document(character, motion, animation=animation, name=name)
    atomic_write_bytes(path, gltf_bytes(document, blob, path))
