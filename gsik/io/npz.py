"""Bounded ``.npz`` reading: every member checked against declared sizes and shapes before one byte is inflated.

An ``.npz`` is a zip archive of ``.npy`` arrays. ``numpy.load`` trusts it: a 1.5 MB archive can inflate to
gigabytes, hold hundreds of unused members, or declare an array of 10**12 floats that is allocated before the data
is found missing. :func:`read_npz_members` reads one through :func:`gsik.io.files.read_bounded` and checks, in this
order, each step before the next costs anything:

1. the archive's end record: at most :data:`MAX_MEMBERS` members and a small central directory, no ZIP64 (so
   ``zipfile`` itself never builds a million entries);
2. every member's name (only the expected ``<key>.npy``, each once), compression (stored or deflate), declared
   uncompressed size (each, and all together, within :data:`MAX_NPZ_UNCOMPRESSED`);
3. every member's ``.npy`` header: a plain dtype of the kind expected (no objects, no structured, complex or date
   types), the number of dimensions expected, and ``shape x itemsize`` within the member's declared size;
4. only then its data, read to exactly that many bytes.

Every refusal is the caller's :class:`~gsik.errors.GsikError` subclass naming the file, the member and the limit.
"""

from __future__ import annotations

import io
import os
import struct
import zipfile
from collections.abc import Mapping
from typing import NamedTuple

import numpy as np
from numpy.lib import format as npy_format

from gsik.errors import GsikError, choices, show_value
from gsik.io.files import MAX_PATH_CHARS, read_bounded

#: Largest ``.npz`` file read [bytes].
MAX_NPZ_BYTES = 64 * 1024 * 1024

#: Most bytes all members may inflate to, together [bytes].
MAX_NPZ_UNCOMPRESSED = 64 * 1024 * 1024

#: Most members an archive may list (whether or not the reader expects them).
MAX_MEMBERS = 64

#: Largest central directory [bytes]: :data:`MAX_MEMBERS` entries with names of up to a few hundred characters.
MAX_DIRECTORY_BYTES = 64 * 1024

_END = struct.Struct("<4s4H2LH")  # end of central directory record
_END_SIGNATURE, _ZIP64_LOCATOR = b"PK\x05\x06", b"PK\x06\x07"
_METHODS = (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED)
_MAX_HEADER = 4096  # an .npy header of a plain dtype takes well under this [bytes]


class Member(NamedTuple):
    """What a member ``<key>.npy`` must hold.

    Attributes:
        kinds: Accepted ``dtype.kind`` letters (``"f"`` float, ``"iu"`` integers, ``"U"`` text).
        ndim: Its number of dimensions (0 for a scalar).
    """

    kinds: str
    ndim: int


def read_npz_members(path: str | os.PathLike, what: str, members: Mapping[str, Member],
                     error: type[GsikError]) -> dict[str, np.ndarray]:
    """The arrays of the ``.npz`` file ``path`` whose member names are keys of ``members``, bounded as the module
    docstring says; members may be missing (the caller says which it needs), unexpected ones are refused.

    Args:
        path: The archive.
        what: What it is, for messages (``"pose prior"``).
        members: ``key`` -> :class:`Member` for every member allowed (stored as ``<key>.npy``).
        error: The error raised for a malformed or out-of-bounds archive.

    Returns:
        ``key`` -> array, for every member present.

    Raises:
        GsikFileError: the file cannot be read, is not a regular file or is larger than :data:`MAX_NPZ_BYTES`.
        error: anything else, naming the file, the member and the bound.
    """
    source = os.fspath(path)
    source = source if len(source) <= MAX_PATH_CHARS else show_value(source, MAX_PATH_CHARS)
    data = read_bounded(path, what, MAX_NPZ_BYTES)
    _check_end_record(data, source, what, error)
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as archive:
            infos = _checked_infos(archive.infolist(), members, source, what, error)
            return {key: _read_member(archive, info, members[key], source, error) for key, info in infos.items()}
    except GsikError:
        raise
    except (zipfile.BadZipFile, zipfile.LargeZipFile, EOFError, NotImplementedError, RuntimeError, ValueError,
            OSError, struct.error) as exc:
        raise error(f"{source}: not a valid {what} archive: {show_value(str(exc) or type(exc).__name__)}") from None


def _check_end_record(data: bytes, source: str, what: str, error: type[GsikError]) -> None:
    """The archive's end record lists at most :data:`MAX_MEMBERS` members in a small directory, without ZIP64."""
    at = data.rfind(_END_SIGNATURE, max(0, len(data) - _END.size - 0xFFFF))
    if at < 0 or len(data) - at < _END.size:
        raise error(f"{source}: not a {what} file: not a .npz (zip) archive")
    _, _, _, _, n_members, directory_bytes, _, _ = _END.unpack_from(data, at)
    if at >= 20 and data[at - 20:at - 16] == _ZIP64_LOCATOR:
        raise error(f"{source}: not a {what} file: a ZIP64 archive (a .npz of gsik is a plain zip archive)")
    if n_members > MAX_MEMBERS:
        raise error(f"{source}: the archive lists {n_members:,} members; the limit is {MAX_MEMBERS}")
    if directory_bytes > MAX_DIRECTORY_BYTES:
        raise error(f"{source}: the archive's directory is {directory_bytes:,} bytes; the limit is "
                    f"{MAX_DIRECTORY_BYTES:,}")


def _checked_infos(infos: list[zipfile.ZipInfo], members: Mapping[str, Member], source: str, what: str,
                   error: type[GsikError]) -> dict[str, zipfile.ZipInfo]:
    """``key`` -> entry, each entry checked by name, method and declared size, before any is inflated."""
    if len(infos) > MAX_MEMBERS:
        raise error(f"{source}: the archive lists {len(infos):,} members; the limit is {MAX_MEMBERS}")
    out: dict[str, zipfile.ZipInfo] = {}
    total = 0
    for info in infos:
        key = info.filename[:-4] if info.filename.endswith(".npy") else None
        if key not in members:
            raise error(f"{source}: unexpected member {show_value(info.filename)} in a {what}; members: "
                        f"{choices(f'{k}.npy' for k in members)}")
        if key in out:
            raise error(f"{source}: member {info.filename!r} is listed twice")
        if info.compress_type not in _METHODS or info.flag_bits & 0x1:
            raise error(f"{source}: member {info.filename!r} is encrypted or compressed with method "
                        f"{info.compress_type}; a .npz is stored or deflated")
        total += info.file_size
        if total > MAX_NPZ_UNCOMPRESSED:
            raise error(f"{source}: members declare more than {MAX_NPZ_UNCOMPRESSED:,} bytes uncompressed "
                        f"(at {info.filename!r}: {info.file_size:,}); the limit is {MAX_NPZ_UNCOMPRESSED:,}")
        out[key] = info
    return out


def _read_member(archive: zipfile.ZipFile, info: zipfile.ZipInfo, member: Member, source: str,
                 error: type[GsikError]) -> np.ndarray:
    """One member's array: its ``.npy`` header checked against ``member`` and its declared size, then its data."""
    where = f"{source}: member {info.filename!r}"
    with archive.open(info) as f:
        dtype, shape, fortran, header_bytes = _read_header(f, where, error)
        _check_array(dtype, shape, member, where, error)
        nbytes = int(np.prod(shape, dtype=object)) * dtype.itemsize
        if header_bytes + nbytes != info.file_size:
            raise error(f"{where}: its header declares {shape} of {dtype} ({nbytes:,} bytes) but the member holds "
                        f"{info.file_size - header_bytes:,} bytes of data")
        data = f.read(nbytes)
    if len(data) != nbytes:
        raise error(f"{where}: truncated: {len(data):,} of {nbytes:,} bytes")
    return np.frombuffer(data, dtype=dtype).reshape(shape, order="F" if fortran else "C")


def _read_header(f, where: str, error: type[GsikError]) -> tuple[np.dtype, tuple[int, ...], bool, int]:
    """``(dtype, shape, fortran_order, header length [bytes])`` of an ``.npy`` stream, nothing allocated."""
    try:
        version = npy_format.read_magic(f)
        read = {(1, 0): npy_format.read_array_header_1_0, (2, 0): npy_format.read_array_header_2_0}.get(version)
        if read is None:
            raise ValueError(f"unsupported .npy version {version}")
        shape, fortran, dtype = read(f, max_header_size=_MAX_HEADER)
    except (ValueError, TypeError, SyntaxError, EOFError) as exc:
        raise error(f"{where}: not an .npy array: {show_value(str(exc))}") from None
    return dtype, shape, bool(fortran), f.tell()


def _check_array(dtype: np.dtype, shape: tuple[int, ...], member: Member, where: str,
                 error: type[GsikError]) -> None:
    """A plain dtype of an accepted kind, the expected number of dimensions."""
    if dtype.fields is not None or dtype.subdtype is not None or dtype.kind not in member.kinds:
        raise error(f"{where}: holds {dtype.str!r} values; expected {_kind_names(member.kinds)}")
    if len(shape) != member.ndim:
        raise error(f"{where}: has shape {shape}; expected {member.ndim} dimension{'s' * (member.ndim != 1)}")


def _kind_names(kinds: str) -> str:
    names = {"f": "floats", "i": "integers", "u": "unsigned integers", "U": "text"}
    return " or ".join(names.get(k, k) for k in kinds)


def npz_bytes(arrays: Mapping[str, np.ndarray]) -> bytes:
    """``arrays`` as the bytes of an uncompressed ``.npz`` archive (``numpy.savez``), never pickled."""
    buffer = io.BytesIO()
    np.savez(buffer, **{k: np.asarray(v) for k, v in arrays.items()})
    return buffer.getvalue()
