"""Retargeting from any humanoid onto any humanoid skeleton (issue 17, item 2): ``--onto``, A onto T, chain by
chain at the target's own lengths."""

from __future__ import annotations

import io
import sys
from pathlib import Path

import numpy as np
import pytest

from gsik.anim.retarget import Retargeter
from gsik.errors import RetargetError
from gsik.io.bvh import read_bvh, write_bvh
from gsik.io.bvh_skeleton import import_bvh
from gsik.io.urdf_skeleton import skeleton_from_urdf

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "humanoid"))
from humanoid_rigs import CONVENTIONS, build, clip_of, wave_motion  # noqa: E402

MIXAMO = CONVENTIONS[0]
UNITY = next(c for c in CONVENTIONS if c.name == "unity_vrm")
#: Bones whose direction (to the next bone of the chain) the target must follow: upper -> lower -> end.
CHAINS = [(a, b) for s in ("left", "right") for a, b in ((f"{s}UpperArm", f"{s}LowerArm"),
                                                       (f"{s}LowerArm", f"{s}Hand"),
                                                       (f"{s}UpperLeg", f"{s}LowerLeg"),
                                                       (f"{s}LowerLeg", f"{s}Foot"))]


def _source(frames: int = 12):
    """A Mixamo-named T-pose rig, every joint swinging by 10 degrees."""
    t = build(MIXAMO, a_pose=False)
    return t, clip_of(t.rig, wave_motion(frames, t.clip.motion.shape[1], t.rig.rest_positions[0], 10.0))


def _directions(positions: np.ndarray, index: dict[str, int], bones: dict[str, str]) -> np.ndarray:
    """(n_frames, len(CHAINS), 3) unit directions of each chain bone."""
    d = np.stack([positions[:, index[bones[b]]] - positions[:, index[bones[a]]] for a, b in CHAINS], axis=1)
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def test_a_t_pose_clip_drives_an_a_pose_skeleton_of_other_names_bone_for_bone():
    src, clip = _source()
    target = build(UNITY, a_pose=True, up="z")
    skeleton = import_bvh(target.clip).skeleton
    rt = Retargeter(skeleton, clip)
    r = rt.retarget(clip)
    assert rt.mapping["LeftUpperArm"] == "mixamorig:LeftArm" and rt.mapping["RightLowerLeg"] == "mixamorig:RightLeg"
    assert r.errors.max() < 0.002  # metres: every mapped joint on its target
    from gsik.anim.retarget import clip_world_positions

    want = _directions(clip_world_positions(clip, rt.up), {n: k for k, n in enumerate(src.rig.names)}, src.expect)
    got_positions = np.stack([r.motion.frames(i)[1] for i in range(r.motion.n_frames)])
    frame_index = {n: skeleton.frame_of(n) for n in skeleton.target_names}
    got = _directions(got_positions, frame_index, target.expect)
    assert np.degrees(np.arccos(np.clip(np.sum(want * got, axis=-1), -1, 1))).max() < 1.0


def test_bones_keep_the_targets_own_lengths():
    _, clip = _source()
    body = {"LowerArm": (40, 148, 0), "Hand": (75, 148, 0)}  # shorter upper arm, longer forearm than the clip's
    target = build(UNITY, body=body)
    skeleton = import_bvh(target.clip).skeleton
    r = Retargeter(skeleton, clip).retarget(clip)
    p = np.stack([r.motion.frames(i)[1] for i in range(r.motion.n_frames)])
    upper = np.linalg.norm(p[:, skeleton.frame_of("LeftLowerArm")] - p[:, skeleton.frame_of("LeftUpperArm")], axis=1)
    scale = 0.01  # the BVH is in centimetres
    np.testing.assert_allclose(upper, 23.0 * scale, rtol=1e-6)


def test_gsik_retarget_onto_a_bvh_skeleton_writes_its_joints(tmp_path):
    from gsik.cli import main

    _, clip = _source(6)
    src, skel, out = tmp_path / "clip.bvh", tmp_path / "character.bvh", tmp_path / "out.bvh"
    write_bvh(src, clip)
    write_bvh(skel, build(UNITY, a_pose=True).clip)
    text = io.StringIO()
    assert main(["retarget", str(src), "--onto", str(skel), "--out", str(out)], out=text) == 0, text.getvalue()
    assert "LeftLowerArm" in text.getvalue()
    written = read_bvh(out)
    assert written.n_frames == 6 and {"LeftUpperArm", "RightFoot", "Head"} <= {j.name for j in written.joints}


def test_a_target_that_is_no_humanoid_is_refused_naming_what_is_missing():
    _, clip = _source(2)
    urdf = Path(__file__).resolve().parents[1] / "data" / "two_link_arm.urdf"
    with pytest.raises(RetargetError, match="is no humanoid gsik can retarget onto.*no joint found for"):
        Retargeter(skeleton_from_urdf(urdf), clip)


def test_the_limit_margin_widens_ball_joints_only_and_lets_a_deep_bend_through():
    from gsik import load_skeleton
    from gsik.anim.retarget import widened

    biped = load_skeleton("biped")
    wide = widened(biped, 0.5)
    hinge = [biped.dof_index(n) for n in ("left_knee.x", "right_elbow.x")]
    ball = [biped.dof_index(n) for n in ("waist.x", "left_hip.z", "neck.y", "right_ankle.x")]
    np.testing.assert_array_equal(wide.lower[hinge], biped.lower[hinge])
    np.testing.assert_allclose(wide.upper[ball] - biped.upper[ball], 0.5)
    t = build(UNITY)
    motion = np.zeros((8, t.clip.motion.shape[1]))
    motion[:, :3] = t.rig.rest_positions[0]
    spine = [k for k, j in enumerate(t.clip.joints) if j.name == "Spine"][0]
    column = sum(len(j.channels) for j in t.clip.joints[:spine]) + 2  # Spine's Xrotation (ZYX): bend forward
    motion[:, column] = np.linspace(0.0, 75.0, 8)  # degrees: past the biped's waist range
    clip = clip_of(t.rig, motion)
    tight = Retargeter(biped, clip).retarget(clip)
    loose = Retargeter(biped, clip, limit_margin=np.radians(30.0)).retarget(clip)
    assert loose.errors.max() < 0.005 < tight.errors.max()
