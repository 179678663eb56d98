"""A glTF file's JSON and buffers, read within limits: ``.glb`` or ``.gltf`` with external or data-URI buffers.

Every size is checked before memory is given to it: the file against :data:`MAX_FILE_BYTES`, a buffer's declared
``byteLength`` against :data:`MAX_BUFFER_BYTES` and against the bytes actually there, a data URI's length before it
is decoded. External URIs must name a file inside the glTF file's own folder.
"""

from __future__ import annotations

import base64
import binascii
import os
import struct
import urllib.parse
import warnings
from typing import NamedTuple

from gsik.errors import GltfError, show_value
from gsik.io.files import read_bounded

#: Largest glTF or GLB file read [bytes].
MAX_FILE_BYTES = 512 * 1024 * 1024
#: Largest buffer (declared or actual) [bytes]; all buffers together are bounded by the same figure.
MAX_BUFFER_BYTES = 512 * 1024 * 1024
#: Largest JSON part (a .gltf file, or a GLB's JSON chunk) [bytes]: parsing it is the slow step.
MAX_JSON_BYTES = 64 * 1024 * 1024
#: Most entries of any top-level array (nodes, meshes, accessors ...).
MAX_ITEMS = 100_000

_GLB_MAGIC = b"glTF"
_DATA_PREFIX = "data:"


class LoadedFile(NamedTuple):
    """The parsed JSON (a ``pygltflib.GLTF2``) and the bytes of each buffer."""

    document: object
    buffers: tuple[bytes, ...]


def gltf_library():
    """The ``pygltflib`` module, or a :class:`GltfError` saying how to install it (the ``gltf`` extra)."""
    try:
        import pygltflib
    except ImportError:
        raise GltfError("reading and writing glTF needs pygltflib: pip install 'gsik[gltf]'") from None
    return pygltflib


def load_gltf_file(path: str | os.PathLike) -> LoadedFile:
    """The JSON document and buffers of ``path`` (``.glb`` or ``.gltf``), bounded and checked.

    Raises:
        GltfError: not glTF, malformed JSON or GLB chunks, a buffer that is missing, too large, shorter than
            declared, or outside the file's folder.
        GsikFileError: the file cannot be read.
    """
    data = read_bounded(path, "glTF file", MAX_FILE_BYTES)
    where = show_value(os.fspath(path), 240)
    document, glb_blob = _parse(data, where)
    _check_counts(document, where)
    folder = os.path.dirname(os.path.abspath(os.fspath(path)))
    buffers = tuple(_buffer_bytes(document, i, glb_blob, folder, where) for i in range(len(document.buffers)))
    return LoadedFile(document, buffers)


def _parse(data: bytes, where: str) -> tuple[object, bytes | None]:
    """``(document, GLB binary chunk or None)`` of a file's bytes."""
    pygltflib = gltf_library()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            if data[:4] == _GLB_MAGIC:
                _check_glb_header(data, where)
                _check_json_size(struct.unpack_from("<I", data, 12)[0], where)
                document = pygltflib.GLTF2.load_from_bytes(data)
                blob = document.binary_blob() if document is not None else None
            else:
                _check_json_size(len(data), where)
                document, blob = pygltflib.GLTF2.from_json(data.decode("utf-8"), infer_missing=True), None
    except GltfError:
        raise
    except (ValueError, TypeError, KeyError, AttributeError, RecursionError, struct.error, UnicodeError) as exc:
        raise GltfError(f"{where}: not a glTF file ({type(exc).__name__}: {show_value(str(exc))})") from None
    if document is None or not isinstance(getattr(document, "nodes", None), list):
        raise GltfError(f"{where}: not a glTF file (no JSON chunk)")
    return document, blob


def _check_json_size(size: int, where: str) -> None:
    if size > MAX_JSON_BYTES:
        raise GltfError(f"{where}: {size:,} bytes of JSON; gsik reads at most {MAX_JSON_BYTES:,}")


def _check_glb_header(data: bytes, where: str) -> None:
    """The GLB header's length must be the file's, and each chunk must lie inside it."""
    if len(data) < 20:
        raise GltfError(f"{where}: a GLB file of {len(data)} bytes is too short for its header")
    version, length = struct.unpack_from("<II", data, 4)
    if version != 2:
        raise GltfError(f"{where}: GLB version {version}; gsik reads version 2")
    if length != len(data):
        raise GltfError(f"{where}: the GLB header says {length:,} bytes, the file has {len(data):,}")
    index = 12
    while index < length:
        if index + 8 > length:
            raise GltfError(f"{where}: a GLB chunk header at byte {index} runs past the end of the file")
        chunk = struct.unpack_from("<I", data, index)[0]
        if index + 8 + chunk > length:
            raise GltfError(f"{where}: a GLB chunk of {chunk:,} bytes at byte {index} runs past the end of the file")
        index += 8 + chunk


def _check_counts(document, where: str) -> None:
    for field in ("nodes", "meshes", "accessors", "bufferViews", "buffers", "skins", "materials", "animations"):
        items = getattr(document, field, None) or []
        if len(items) > MAX_ITEMS:
            raise GltfError(f"{where}: {len(items):,} {field}; gsik reads at most {MAX_ITEMS:,}")


def _buffer_bytes(document, i: int, glb_blob: bytes | None, folder: str, where: str) -> bytes:
    """The bytes of buffer ``i``: the GLB chunk, a data URI or a file next to the glTF file."""
    buffer = document.buffers[i]
    declared = buffer.byteLength
    what = f"{where}: buffers[{i}]"
    if not isinstance(declared, int) or isinstance(declared, bool) or declared < 0:
        raise GltfError(f"{what}.byteLength must be an integer >= 0, got {show_value(declared)}")
    if declared > MAX_BUFFER_BYTES:
        raise GltfError(f"{what} declares {declared:,} bytes; gsik reads at most {MAX_BUFFER_BYTES:,}")
    uri = buffer.uri
    if uri is None:
        if glb_blob is None:
            raise GltfError(f"{what} has no uri and the file has no GLB binary chunk")
        data = glb_blob
    elif not isinstance(uri, str):
        raise GltfError(f"{what}.uri must be a string, got {show_value(uri)}")
    elif uri.startswith(_DATA_PREFIX):
        data = _data_uri(uri, declared, what)
    else:
        data = _external(uri, folder, what)
    if len(data) < declared:
        raise GltfError(f"{what} declares {declared:,} bytes but holds {len(data):,}")
    return bytes(data[:declared])


def _data_uri(uri: str, declared: int, what: str) -> bytes:
    """A base64 data URI decoded, refused before decoding when it would be larger than declared."""
    head, _, payload = uri.partition(",")
    if not head.endswith(";base64"):
        raise GltfError(f"{what}: a data URI must be base64 ({show_value(head)})")
    if len(payload) > 4 * (declared // 3 + 2) + 4:
        raise GltfError(f"{what}: its data URI holds {len(payload):,} characters, more than the {declared:,} bytes "
                        "it declares")
    try:
        return base64.b64decode(payload, validate=True)
    except (binascii.Error, ValueError):
        raise GltfError(f"{what}: its data URI is not valid base64") from None


def _external(uri: str, folder: str, what: str) -> bytes:
    """The bytes of a relative URI inside ``folder``: no scheme, no absolute path, no way out of the folder."""
    parsed = urllib.parse.urlsplit(uri)
    if parsed.scheme or parsed.netloc or uri.startswith(("/", "\\")):
        raise GltfError(f"{what}: uri {show_value(uri)} is not a relative file name (gsik reads buffers from the "
                        "glTF file's own folder only)")
    target = os.path.realpath(os.path.join(folder, urllib.parse.unquote(parsed.path)))
    if os.path.commonpath([target, os.path.realpath(folder)]) != os.path.realpath(folder):
        raise GltfError(f"{what}: uri {show_value(uri)} points outside the glTF file's folder")
    return read_bounded(target, f"{what}: buffer file", MAX_BUFFER_BYTES)
