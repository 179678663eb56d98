"""Hostile files of every class the bounded readers refuse, made small: the bombs are declared, never materialised.

Each :class:`Case` is a file (written by :func:`make_cases` into a folder), the reader it is handed to, and what the
refusal must say (the bound and its limit). The tests (``test_hostile_files.py``) and the benchmark
(``benchmarks/bench_hostile.py``) share them.
"""

from __future__ import annotations

import io
import os
import struct
import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple

import numpy as np

import gsik

#: A chain of two joints and an End Site, six root channels and three on the chest.
BVH_HEAD = """HIERARCHY
ROOT hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT chest
  {
    OFFSET 0 10 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 0 10 0
    }
  }
}
MOTION
"""


class Case(NamedTuple):
    """One hostile file: ``name``, the ``reader`` it is given to (a key of :func:`readers`), its ``path`` and a
    part of the refusal's message (``expect``)."""

    name: str
    reader: str
    path: str
    expect: str


def readers() -> dict[str, Callable[[str], object]]:
    """Every file reader of gsik, by name."""
    from gsik.anim.retarget_map import read_mapping
    from gsik.io.bvh import read_bvh
    from gsik.io.pose import read_pose_document
    from gsik.io.urdf import read_urdf
    from gsik.prior import read_prior
    from gsik.prior_mixture import read_mixture
    return {"pose": read_pose_document, "skeleton": gsik.load_skeleton, "bvh": read_bvh, "urdf": read_urdf,
            "map": read_mapping, "prior": read_prior, "mixture": read_mixture}


def refusal(reader: str, path: str) -> BaseException | None:
    """What reading ``path`` with ``reader`` raised (``None`` when it was read)."""
    try:
        readers()[reader](path)
    except BaseException as exc:  # noqa: BLE001 - the caller checks it is a GsikError
        return exc
    return None


# -- files that are not regular files, and regular files past a size limit ----------------------------------

def special_cases(folder: Path) -> list[Case]:
    """A FIFO, devices and a folder through every reader: refused by ``stat`` before a byte is read."""
    fifo = folder / "fifo"
    if not fifo.exists():
        os.mkfifo(fifo)
    kinds = [(str(fifo), "a FIFO"), ("/dev/zero", "a character device"), ("/dev/urandom", "a character device"),
             (str(folder), "a folder")]
    return [Case(f"{os.path.basename(p)} as {r}", r, p, f"not a regular file ({kind})")
            for p, kind in kinds for r in readers()]


def oversize_cases(folder: Path) -> list[Case]:
    """A sparse file one byte past each reader's limit (no disk used): refused by its size alone."""
    from gsik.io.bvh.limits import MAX_BVH_BYTES
    from gsik.io.npz import MAX_NPZ_BYTES
    from gsik.io.urdf import MAX_URDF_BYTES
    from gsik.io.yaml_safe import MAX_BYTES
    limits = {"pose": MAX_BYTES, "skeleton": MAX_BYTES, "map": MAX_BYTES, "bvh": MAX_BVH_BYTES,
              "urdf": MAX_URDF_BYTES, "prior": MAX_NPZ_BYTES}
    out = []
    for reader, limit in limits.items():
        path = folder / f"big_{reader}.{'yaml' if limit == MAX_BYTES else reader}"
        with open(path, "wb") as f:
            f.truncate(limit + 1)
        out.append(Case(f"{limit + 1:,}-byte {reader}", reader, str(path), f"the limit is {limit:,} bytes"))
    return out


# -- .npz archives -------------------------------------------------------------------------------------------

def _npy(array: np.ndarray) -> bytes:
    buffer = io.BytesIO()
    np.lib.format.write_array(buffer, np.asarray(array), allow_pickle=False)
    return buffer.getvalue()


def _npy_declaring(shape: tuple, descr: str = "<f8", data: bytes = b"\0" * 80) -> bytes:
    """An ``.npy`` whose header declares ``shape`` of ``descr`` over only ``data``."""
    header = repr({"descr": descr, "fortran_order": False, "shape": shape}).encode()
    header += b" " * (63 - (len(header) + 10) % 64) + b"\n"
    return b"\x93NUMPY\x01\x00" + struct.pack("<H", len(header)) + header + data


def _zip(members: dict[str, bytes], method: int = zipfile.ZIP_STORED) -> bytes:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", method) as z:
        for name, data in members.items():
            z.writestr(name, data)
    return buffer.getvalue()


def prior_members(n: int = 3, **replace) -> dict[str, bytes]:
    """The members of a valid format-1 prior over ``n`` DOFs, some replaced by raw ``.npy`` bytes or arrays."""
    arrays = {"format": 1, "skeleton": "s", "dof_names": [f"d{i}" for i in range(n)], "mean": np.zeros(n),
              "covariance": np.eye(n), "n_frames": 10, "shrinkage": 0.1, "source": ""}
    out = {f"{k}.npy": _npy(np.asarray(v)) for k, v in arrays.items()}
    for k, v in replace.items():
        out[f"{k}.npy"] = v if isinstance(v, bytes) else _npy(np.asarray(v))
    return out


def _declared_size(data: bytes, member: str, size: int) -> bytes:
    """``data`` (a zip) with ``member``'s uncompressed size set to ``size`` in its local and central headers."""
    out = bytearray(data)
    name = member.encode()
    for signature, offset in ((b"PK\x03\x04", 22), (b"PK\x01\x02", 24)):
        at = out.find(signature)
        while at >= 0:
            name_at = at + (30 if signature == b"PK\x03\x04" else 46)
            if out[name_at:name_at + len(name)] == name:
                struct.pack_into("<L", out, at + offset, size)
            at = out.find(signature, at + 4)
    return bytes(out)


def _inflating(size: int) -> bytes:
    """A deflated member of ``size`` zero bytes (a real bomb: ``size`` / 1000 on disk), as a whole zip."""
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as z:
        with z.open("mean.npy", "w") as m:
            chunk = b"\0" * (1 << 20)
            for _ in range(size >> 20):
                m.write(chunk)
    return buffer.getvalue()


def npz_cases(folder: Path) -> list[Case]:
    """Prior archives: bombs by declared size, by member count, by declared shape; wrong types and layouts."""
    from gsik.io.npz import MAX_MEMBERS, MAX_NPZ_UNCOMPRESSED
    valid = _zip(prior_members())
    many = _zip({**prior_members(), **{f"x{i}.npy": b"" for i in range(300)}})
    files = {
        "declared_10GB.npz": (_declared_size(valid, "mean.npy", 0xFFFFFFF0), f"the limit is {MAX_NPZ_UNCOMPRESSED:,}"),
        "inflates_200MB.npz": (_inflating(200 << 20), f"the limit is {MAX_NPZ_UNCOMPRESSED:,}"),
        "300_members.npz": (many, f"lists 308 members; the limit is {MAX_MEMBERS}"),
        "unexpected.npz": (_zip({**prior_members(), "payload.npy": _npy(np.zeros(1))}), "unexpected member"),
        "shape_1e12.npz": (_zip(prior_members(mean=_npy_declaring((10**12,)))), "(1000000000000,) of float64"),
        "object.npz": (_zip(prior_members(mean=_npy_declaring((3,), "|O"))), "'|O' values; expected floats"),
        "structured.npz": (_zip(prior_members(mean=np.zeros(3, dtype=[("a", "f8")]))), "expected floats"),
        "complex_mean.npz": (_zip(prior_members(mean=np.zeros(3, dtype=complex))), "'<c16' values"),
        "datetime_mean.npz": (_zip(prior_members(mean=np.zeros(3, dtype="datetime64[D]"))), "'<M8[D]' values"),
        "string_mean.npz": (_zip(prior_members(mean=np.array(["a", "b", "c"]))), "expected floats"),
        "format_text.npz": (_zip(prior_members(format="1")), "member 'format.npy': holds '<U1' values"),
        "format_1.9.npz": (_zip(prior_members(format=1.9)), "member 'format.npy': holds '<f8' values"),
        "format_vector.npz": (_zip(prior_members(format=[1, 1])), "member 'format.npy': has shape (2,)"),
        "n_frames_words.npz": (_zip(prior_members(n_frames="ten")), "member 'n_frames.npy': holds '<U3'"),
        "covariance_4x4.npz": (_zip(prior_members(covariance=np.eye(4))), "covariance has shape (4, 4) for 3 DOF"),
        "shrinkage_nan.npz": (_zip(prior_members(shrinkage=np.nan)), "shrinkage must be in [0, 1], got nan"),
        "bzip2.npz": (_zip(prior_members(), zipfile.ZIP_BZIP2), "compressed with method 12"),
        "plain.npy": (_npy(np.zeros(3)), "not a .npz (zip) archive"),
        "empty.npz": (b"", "not a .npz (zip) archive"),
        "truncated.npz": (valid[: len(valid) // 2], "not a .npz (zip) archive"),
    }
    out = []
    for name, (data, expect) in files.items():
        (folder / name).write_bytes(data)
        out.append(Case(name, "prior", str(folder / name), expect))
    out.append(Case("300_members.npz as mixture", "mixture", str(folder / "300_members.npz"), "the limit is"))
    return out


# -- text formats: counts past their bounds in a few bytes ------------------------------------------------------

def _star(n: int, frames: int = 1, channels: str = "0") -> str:
    """A root with ``n`` children of ``channels`` each, declaring ``frames`` (and giving none past the first)."""
    joints = "".join(f"  JOINT j{i}\n  {{\n    OFFSET 0 1 0\n    CHANNELS {channels}\n  }}\n" for i in range(n))
    return f"HIERARCHY\nROOT r\n{{\n  OFFSET 0 0 0\n  CHANNELS 0\n{joints}}}\nMOTION\nFrames: {frames}\n" \
           "Frame Time: 0.01\n\n"


def _deep(n: int) -> str:
    opened = "".join(f"JOINT j{i}\n{{\nOFFSET 0 1 0\nCHANNELS 0\n" for i in range(n))
    return f"HIERARCHY\nROOT r\n{{\nOFFSET 0 0 0\nCHANNELS 0\n{opened}{'}' * (n + 1)}\nMOTION\nFrames: 1\n" \
           "Frame Time: 0.01\n\n"


def _urdf_chain(n: int) -> str:
    links = "".join(f'<link name="l{i}"/>' for i in range(n + 1))
    joints = "".join(f'<joint name="j{i}" type="continuous"><parent link="l{i}"/><child link="l{i + 1}"/></joint>'
                     for i in range(n))
    return f'<robot name="r">{links}{joints}</robot>'


def text_cases(folder: Path) -> list[Case]:
    """BVH frame, channel, joint and depth counts, URDF link counts and nesting, map-file fields, past bounds."""
    from gsik.io.bvh.limits import MAX_BVH_DEPTH, MAX_BVH_FRAMES, MAX_BVH_JOINTS, MAX_BVH_VALUES
    from gsik.io.urdf import MAX_URDF_ELEMENTS, MAX_XML_DEPTH
    files = {
        "frames_999999999.bvh": ("bvh", BVH_HEAD + "Frames: 999999999\nFrame Time: 0.03\n",
                                 f"Frames: 999,999,999: the limit is {MAX_BVH_FRAMES:,} frames"),
        "no_channels_3M.bvh": ("bvh", "HIERARCHY\nROOT a\n{\n OFFSET 0 0 0\n CHANNELS 0\n}\nMOTION\n"
                                      "Frames: 3000000\nFrame Time: 0.01\n", f"the limit is {MAX_BVH_FRAMES:,}"),
        "values.bvh": ("bvh", _star(50, 200_000, "3 Zrotation Xrotation Yrotation"),
                       f"Frames: 200,000 x (150 channels + 51 joints) = 40,200,000 values; the limit is "
                       f"{MAX_BVH_VALUES:,}"),
        "star.bvh": ("bvh", _star(MAX_BVH_JOINTS + 1), f"the limit is {MAX_BVH_JOINTS:,}"),
        "deep.bvh": ("bvh", _deep(MAX_BVH_DEPTH + 1), f"depth {MAX_BVH_DEPTH + 1:,}; the limit is {MAX_BVH_DEPTH:,}"),
        "frame_time.bvh": ("bvh", BVH_HEAD + "Frames: 1\nFrame Time: 5e-324\n" + "0 " * 9 + "\n",
                           "Frame Time 5e-324: must be from 0.0001 to 1000 seconds"),
        "links.urdf": ("urdf", _urdf_chain(MAX_URDF_ELEMENTS + 1), f"<link> elements; the limit is "
                                                                   f"{MAX_URDF_ELEMENTS:,}"),
        "nested.urdf": ("urdf", '<robot name="r">' + "<a>" * 100_000 + "</a>" * 100_000 + "</robot>",
                        f"nested deeper than {MAX_XML_DEPTH}"),
        "banana_map.yaml": ("map", "format: banana\nmap:\n  neck: Neck\n", ":1: format: 'banana'; the mapping format"),
        "unknown_key_map.yaml": ("map", "map:\n  neck: Neck\nmpa: {}\n", ":3: unknown key 'mpa'"),
    }
    out = []
    for name, (reader, text, expect) in files.items():
        (folder / name).write_text(text)
        out.append(Case(name, reader, str(folder / name), expect))
    return out


def make_cases(folder: str | os.PathLike) -> list[Case]:
    """Every hostile file, written into ``folder``."""
    folder = Path(folder)
    return special_cases(folder) + oversize_cases(folder) + npz_cases(folder) + text_cases(folder)


# -- degenerate but well-formed rigs: for retarget, learn-prior and track -------------------------------------

def human_bvh(offset: str = "10", frames: int = 20, root_position: str = "0 90 0") -> str:
    """A nine-joint human rig (hips, spine, neck, head, both legs), ``offset`` on every bone, standing still."""
    def chain(names: list[str], direction: str) -> str:
        if not names:
            return f"End Site\n{{\nOFFSET {direction}\n}}\n"
        return f"JOINT {names[0]}\n{{\nOFFSET {direction}\nCHANNELS 3 Zrotation Xrotation Yrotation\n" \
               f"{chain(names[1:], direction)}}}\n"
    up, down = f"0 {offset} 0", f"0 -{offset} 0"
    body = chain(["Spine", "Neck", "Head"], up) + chain(["LeftUpLeg", "LeftLeg", "LeftFoot"], down).replace(
        f"OFFSET {down}\nCHANNELS", f"OFFSET {offset} 0 0\nCHANNELS", 1) + chain(
        ["RightUpLeg", "RightLeg", "RightFoot"], down).replace(f"OFFSET {down}\nCHANNELS", f"OFFSET -{offset} 0 0\n"
                                                                                             "CHANNELS", 1)
    row = root_position + " 0 0 0" + " 0 0 0" * 9
    return (f"HIERARCHY\nROOT Hips\n{{\nOFFSET 0 0 0\nCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation "
            f"Yrotation\n{body}}}\nMOTION\nFrames: {frames}\nFrame Time: 0.0333\n" + (row + "\n") * frames)
