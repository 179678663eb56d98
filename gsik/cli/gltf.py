"""``gsik export-gltf``: a pose file (its pose, keys or clip) or a BVH clip as a glTF character."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TextIO

import numpy as np

from gsik.anim.motion import Motion
from gsik.cli.common import CommandError, check_out, load_any_skeleton
from gsik.io.bvh import read_bvh
from gsik.io.bvh_skeleton import import_bvh
from gsik.io.gltf import Character, character_from_skeleton, read_character, write_gltf
from gsik.io.pose import pose_from_document, read_pose_document
from gsik.io.pose.model import PoseRead

CHARACTER_ENDINGS = (".glb", ".gltf")


def add_command(add) -> None:
    """Register ``export-gltf`` with the parser's ``add(name, help, description)``."""
    p = add("export-gltf", "write a pose, its keys or clip, or a BVH clip as a glTF character (.glb/.gltf)",
            "Write a pose file's pose (or its keys or clip as an animation) or a BVH clip as glTF 2.0: on "
            "--character (a skinned .glb/.gltf, everything else of it kept; a clip of another rig is retargeted "
            "onto it first), else on the pose's or clip's own skeleton with its mannequin body as a skinned mesh.")
    p.add_argument("input", metavar="POSE.yaml|CLIP.bvh", help="a pose file or a BVH clip")
    p.add_argument("--character", metavar="CHARACTER.glb", help="the character to pose (a skinned glTF file)")
    p.add_argument("--out", metavar="OUT.glb", required=True, help="the glTF file to write (.glb or .gltf)")
    p.add_argument("--animation", action="store_true", help="write a single pose as a one-frame animation too")
    p.set_defaults(run=cmd_export_gltf)


def cmd_export_gltf(args: argparse.Namespace, out: TextIO) -> int:
    check_out(args.out, CHARACTER_ENDINGS, "glTF")
    if Path(args.input).suffix.lower() == ".bvh":
        character, motion, what = _from_clip(args)
    else:
        character, motion, what = _from_pose_file(args)
    write_gltf(args.out, character, motion, animation=args.animation)
    out.write(f"wrote {args.out}: {what} on {character.skeleton.name!r} ({character.file.n_vertices:,} vertices)\n")
    return 0


def _from_clip(args: argparse.Namespace) -> tuple[Character, Motion, str]:
    """The clip on its own skeleton, on a character of the same rig, or retargeted onto a character of another."""
    clip = read_bvh(args.input)
    imported = import_bvh(clip)
    motion = imported.motion
    if args.character is None:
        return character_from_skeleton(imported.skeleton), motion, f"{motion.n_frames} frames"
    character = read_character(args.character)
    if all(d in imported.skeleton.dof_names for d in character.skeleton.dof_names):
        return character, motion, f"{motion.n_frames} frames"
    from gsik.anim.retarget import Retargeter

    done = Retargeter(character.skeleton, clip, name=Path(args.input).name).retarget(clip)
    return character, done.motion, f"{done.motion.n_frames} frames retargeted"


def _from_pose_file(args: argparse.Namespace) -> tuple[Character, Motion, str]:
    doc = read_pose_document(args.input)
    spec = args.character or doc.skeleton
    if spec is None:
        raise CommandError(f"{args.input}: cannot tell its skeleton (no 'skeleton:' field); give --character")
    if Path(spec).suffix.lower() in CHARACTER_ENDINGS:
        character = read_character(spec)
    else:
        character = character_from_skeleton(load_any_skeleton(spec))
    read = pose_from_document(doc, character.skeleton)
    return (character, *_motion(read, character))


def _motion(read: PoseRead, character: Character) -> tuple[Motion, str]:
    """The clip, else the keys (each key a frame at its time), else the pose."""
    sk = character.skeleton
    if read.clip is not None:
        return read.clip.motion, f"clip {read.clip.name!r}, {read.clip.motion.n_frames} frames"
    if read.keys is not None and len(read.keys.keys) > 1:
        return _keys_motion(read, sk), f"{len(read.keys.keys)} keys"
    pose = read.pose
    return Motion(sk, pose.q(sk)[None], (pose.root,), pose.world_from_root[None], 1.0 / 30.0), "the pose"


def _keys_motion(read: PoseRead, sk) -> Motion:
    """Every frame of the key range, angles linear between keys (the glTF animation interpolates the same way)."""
    frames = np.array([f for f, _ in read.keys.keys], dtype=float)
    q = np.array([p.q(sk) for _, p in read.keys.keys])
    first = read.keys.keys[0][1]
    every = np.arange(int(frames[0]), int(frames[-1]) + 1)
    angles = np.stack([np.interp(every, frames, q[:, d]) for d in range(sk.n_dofs)], axis=1)
    W = np.broadcast_to(first.world_from_root, (len(every), 4, 4))
    return Motion(sk, angles, (first.root,) * len(every), W, 1.0 / read.keys.fps)
