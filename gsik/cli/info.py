"""``gsik info``: a skeleton as plain data (``--json``) or as readable text."""

from __future__ import annotations

import argparse
import json
import math
from typing import TextIO

from gsik.cli.common import load_any_skeleton
from gsik.skeleton import Skeleton


def skeleton_info(sk: Skeleton) -> dict:
    """The skeleton as plain data (what ``gsik info --json`` prints)."""
    return {"name": sk.name, "source": sk.source, "root": sk.root, "n_joints": sk.n_joints, "n_dofs": sk.n_dofs,
            "joints": _joints(sk), "dofs": _dofs(sk), "effectors": list(sk.effector_sites), "sites": _sites(sk),
            "segments": _segments(sk)}


def _dofs(sk: Skeleton) -> list[dict]:
    joint_of_dof = {d: name for j, name in enumerate(sk.joint_names) for d in sk.joint_dofs[j]}
    return [{
        "name": name, "joint": joint_of_dof.get(d),
        "axis": [float(v) for v in sk.frame_axis[sk.dof_frame[d]]],
        "lower": float(sk.lower[d]), "upper": float(sk.upper[d]), "rest": float(sk.rest[d]),
        "lower_deg": math.degrees(sk.lower[d]), "upper_deg": math.degrees(sk.upper[d]),
        "rest_deg": math.degrees(sk.rest[d]),
    } for d, name in enumerate(sk.dof_names)]


def _joints(sk: Skeleton) -> list[dict]:
    return [{"name": name,
             "parent": None if sk.joint_parent[j] < 0 else sk.joint_names[sk.joint_parent[j]],
             "dofs": [sk.dof_names[d] for d in sk.joint_dofs[j]]}
            for j, name in enumerate(sk.joint_names)]


def _sites(sk: Skeleton) -> list[dict]:
    effectors = set(sk.effector_sites)
    return [{"name": name, "parent": sk.frame_names[sk.frame_parent[f]], "effector": name in effectors}
            for name, f in zip(sk.site_names, sk.site_frame)]


def _segments(sk: Skeleton) -> list[dict]:
    """Each segment from its start to its ends, named by joint or site (a joint's rotations are ``joint.x``)."""
    owner = dict(enumerate(sk.frame_names))
    owner.update({int(f): name for name, f in zip(sk.joint_names, sk.joint_frame)})
    bones_of: dict[int, list[int]] = {s: [] for s in range(len(sk.segment_names))}
    for b, s in enumerate(sk.bone_segment):
        bones_of[int(s)].append(b)
    out = []
    for s, name in enumerate(sk.segment_names):
        bones = bones_of[s]
        start = owner[int(sk.bone_frames[bones[0], 0])] if bones else None
        out.append({"name": name, "from": start, "to": [owner[int(sk.bone_frames[b, 1])] for b in bones]})
    return out


def format_info(info: dict) -> str:
    """:func:`skeleton_info` as readable text."""
    lines = [f"skeleton {info['name']}  ({info['source']})",
             f"{info['n_joints']} joints, {info['n_dofs']} degrees of freedom, {len(info['sites'])} sites, "
             f"{len(info['segments'])} segments",
             f"IK root: {info['root']}",
             f"effectors ({len(info['effectors'])}): {', '.join(info['effectors']) or '-'}",
             "", "joints:", *_joint_lines(info["joints"]),
             "", "degrees of freedom (limits and rest: degrees, then radians):", *_dof_lines(info["dofs"]),
             "", "sites (* = effector):"]
    lines += [f"  {'*' if s['effector'] else ' '} {s['name']}  on {s['parent']}" for s in info["sites"]]
    lines += ["", "segments:"]
    lines += [f"  {s['name']}: {s['from']} -> {', '.join(s['to'])}" for s in info["segments"]]
    return "\n".join(lines)


def _joint_lines(joints: list[dict]) -> list[str]:
    w = max((len(j["name"]) for j in joints), default=4)
    lines = []
    for j in joints:
        parent = j["parent"] or "(top)"
        dofs = f"{len(j['dofs'])} DOF" if j["dofs"] else "fixed"
        lines.append(f"  {j['name']:<{w}}  parent {parent:<{w}}  {dofs}")
    return lines


def _dof_lines(dofs: list[dict]) -> list[str]:
    w = max((len(d["name"]) for d in dofs), default=4)
    lines = [f"  {'dof':<{w}}  {'lower':>8} {'upper':>8} {'rest':>8}   {'lower':>8} {'upper':>8} {'rest':>8}"]
    lines += [f"  {d['name']:<{w}}  {d['lower_deg']:8.1f} {d['upper_deg']:8.1f} {d['rest_deg']:8.1f}   "
              f"{d['lower']:8.4f} {d['upper']:8.4f} {d['rest']:8.4f}" for d in dofs]
    return lines


def cmd_info(args: argparse.Namespace, out: TextIO) -> int:
    info = skeleton_info(load_any_skeleton(args.skeleton))
    if args.json:
        json.dump(info, out, indent=2)
        out.write("\n")
    else:
        out.write(format_info(info) + "\n")
    return 0
