"""What the commands share: the error type, skeleton loading, solver options, units in messages, output paths."""

from __future__ import annotations

import argparse
import math
from collections.abc import Sequence
from pathlib import Path

import gsik
from gsik.errors import GsikError
from gsik.io.bvh import read_bvh
from gsik.io.bvh_skeleton import import_bvh
from gsik.io.urdf_skeleton import skeleton_from_urdf
from gsik.solver import PAPER_METHOD

PROG = "gsik"


class CommandError(GsikError):
    """A command cannot run as asked (conflicting options, an unwritable folder); exit code 2."""


def load_any_skeleton(spec: str):
    """A bundled skeleton by name, a skeleton YAML file, a URDF robot (``.urdf``), a BVH clip's skeleton or a glTF
    character's (``.glb``/``.gltf``)."""
    suffix = Path(spec).suffix.lower()
    if suffix in (".glb", ".gltf"):
        from gsik.io.gltf import read_character

        return read_character(spec).skeleton
    if suffix == ".urdf":
        return skeleton_from_urdf(spec)
    if suffix == ".bvh":
        return import_bvh(read_bvh(spec), source=spec).skeleton
    return gsik.load_skeleton(spec)


def settings_overrides(args: argparse.Namespace) -> dict:
    """Solver settings the options change (``--sweeps``, ``--paper``)."""
    out = {}
    if getattr(args, "sweeps", None) is not None:
        out["sweeps"] = args.sweeps
    if getattr(args, "paper", False):
        out.update(PAPER_METHOD)
    return out


def mm(x: float) -> str:
    """A length [m] as millimetres for a report."""
    return f"{x * 1e3:.3f} mm"


def deg(x: float) -> str:
    """An angle [rad] as degrees for a report."""
    return f"{math.degrees(x):.3f} deg"


def make_dir(path: str) -> Path:
    """The folder ``path``, created with its parents if needed."""
    p = Path(path)
    try:
        p.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CommandError(f"cannot create folder {path!r}: {exc.strerror or exc}") from None
    return p


def check_out(path: str, suffixes: Sequence[str], what: str) -> None:
    """``--out`` ends in one of ``suffixes`` and its folder exists: checked before any work is done."""
    if Path(path).suffix.lower() not in suffixes:
        raise CommandError(f"--out {path!r}: {what} files end in {' or '.join(suffixes)}")
    parent = Path(path).resolve().parent
    if not parent.is_dir():
        raise CommandError(f"--out {path!r}: folder {str(parent)!r} does not exist")


def split_names(values: Sequence[str] | None) -> list[str] | None:
    """Names given as several arguments and/or comma lists, or ``None`` for none."""
    if not values:
        return None
    return [n.strip() for v in values for n in v.split(",") if n.strip()]
