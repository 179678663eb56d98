"""Retargeting a BVH clip onto the biped (issue 12): name heuristics, mapping files, a round trip, a real clip."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gsik import load_skeleton
from gsik.anim.motion import Motion
from gsik.anim.retarget import Retargeter, best_rotations, widened
from gsik.anim.retarget_map import read_mapping, resolve_mapping, skeleton_bones
from gsik.errors import RetargetError
from gsik.humanoid import Rig
from gsik.io.bvh import BvhClip, read_bvh
from gsik.io.bvh_skeleton import motion_to_bvh

DATA = Path(__file__).resolve().parents[1] / "data"
REAL_CLIP = next((p / "shared" / "mocap" / "mocap_bvhtools_test.bvh" for p in Path(__file__).resolve().parents[3:5]
                  if (p / "shared" / "mocap").is_dir()), Path("../shared/mocap/mocap_bvhtools_test.bvh"))
#: The biped's own names the heuristics do not know (its shoulders are not a rig's clavicles).
BIPED_EXTRA = {"left_shoulder": "left_shoulder", "right_shoulder": "right_shoulder", "atlas": "atlas",
               "waist": "waist"}


def _chain_rig(names: list[str]) -> Rig:
    """A rig whose joints hang one below the other (each 10 units down), names as given."""
    return Rig(tuple(names), tuple(range(-1, len(names) - 1)), [[0.0, -10.0 * k, 0.0] for k in range(len(names))])


def _legs_and_neck(left: tuple[str, str, str], right: tuple[str, str, str]) -> Rig:
    """Hips, a spine-neck-head chain and two legs named as given."""
    names = ["Hips", "Spine", "Neck", "Head", *left, *right]
    parents = [-1, 0, 1, 2, 0, 4, 5, 0, 7, 8]
    rest = [[0, 0, 0], [0, 10, 0], [0, 50, 0], [0, 60, 0], [10, 0, 0], [10, -45, 0], [10, -90, 0],
            [-10, 0, 0], [-10, -45, 0], [-10, -90, 0]]
    return Rig(tuple(names), tuple(parents), rest)


def test_clip_joints_map_to_biped_frames_through_the_humanoid_recognition():
    rig = _legs_and_neck(("mixamorig:LeftUpLeg", "mixamorig:LeftLeg", "mixamorig:LeftFoot"),
                         ("Thigh_R", "r_calf", "foot_r"))
    got = resolve_mapping(rig, skeleton_bones(load_skeleton("biped")))
    assert got == {"pelvis": "Hips", "waist": "Spine", "neck": "Neck", "atlas": "Head",
                   "left_hip": "mixamorig:LeftUpLeg", "left_knee": "mixamorig:LeftLeg",
                   "left_ankle": "mixamorig:LeftFoot",
                   "right_hip": "Thigh_R", "right_knee": "r_calf", "right_ankle": "foot_r"}


def test_a_mapping_file_overrides_the_heuristics_and_bad_names_are_refused(tmp_path):
    path = tmp_path / "map.yaml"
    rig = _legs_and_neck(("LeftUpLeg", "Genou", "LeftFoot"), ("RightUpLeg", "RightLeg", "RightFoot"))
    frames = skeleton_bones(load_skeleton("biped"))
    for key in ("left_knee", "leftLowerLeg"):  # an old file's biped frame, or the canonical bone
        path.write_text(f"format: 1\nmap:\n  {key}: Genou\n")
        assert resolve_mapping(rig, frames, read_mapping(path))["left_knee"] == "Genou"
    with pytest.raises(RetargetError, match="'left_kne'.*valid: .*'left_knee'"):
        resolve_mapping(rig, frames, {"left_kne": "LeftLeg"})
    with pytest.raises(RetargetError, match="'Knee'.*not in the clip.*'Genou'"):
        resolve_mapping(rig, frames, {"left_knee": "Knee"})
    path.write_text("left_knee: Genou\n")
    with pytest.raises(RetargetError, match="needs a 'map:'"):
        read_mapping(path)


def test_a_rig_without_the_legs_the_retargeting_needs_is_refused_with_their_names():
    clip = read_bvh(DATA / "mixamo_zyx_crlf.bvh")
    with pytest.raises(RetargetError, match="'rightUpperLeg', 'rightLowerLeg', 'rightFoot'.*mapping file"):
        Retargeter(load_skeleton("biped"), clip)


def test_best_rotations_turn_rest_directions_onto_turned_ones():
    rng = np.random.default_rng(0)
    rest = rng.normal(size=(3, 3))
    from gsik.rotations import matrix_from_rotvec
    R = np.stack([matrix_from_rotvec(v) for v in rng.normal(size=(5, 3))])
    got = best_rotations(rest, np.einsum("nij,mj->nmi", R, rest))
    np.testing.assert_allclose(got, R, atol=1e-9)
    one = best_rotations(rest[:1], np.einsum("nij,j->ni", R, rest[0])[:, None])
    np.testing.assert_allclose(np.einsum("nij,j->ni", one, rest[0]), np.einsum("nij,j->ni", R, rest[0]), atol=1e-9)


def _biped_clip(n: int = 40) -> tuple[BvhClip, Motion]:
    """A biped motion (knees, elbows, hips, waist and neck swinging) exported as a y-up BVH clip."""
    sk = load_skeleton("biped")
    t = np.linspace(0.0, 1.0, n)[:, None]
    mid = 0.5 * (sk.lower + sk.upper)
    q = sk.rest + 0.3 * np.sin(2 * np.pi * t + np.arange(sk.n_dofs)) * (mid - sk.rest + 0.3 * (sk.upper - sk.lower))
    q = np.clip(q, sk.lower + 0.05, sk.upper - 0.05)
    W = np.broadcast_to(np.eye(4), (n, 4, 4)).copy()
    W[:, :3, 3] = [0.1, 0.2, 1.0]
    motion = Motion(sk, q, ("pelvis",) * n, W, 1 / 30)
    return motion_to_bvh(motion, up="y"), motion


def test_a_biped_clip_retargets_onto_the_biped_joint_for_joint():
    clip, motion = _biped_clip()
    rt = Retargeter(load_skeleton("biped"), clip, BIPED_EXTRA)
    assert rt.up == "y" and abs(rt.scale - 0.01) < 1e-9  # cm, same legs
    r = rt.retarget(clip)
    assert r.unmapped_frames == () and "head" in r.unmapped_clip
    want, got = motion.positions(), r.motion.positions()
    joints = [motion.skeleton.frame_of(j) for j in motion.skeleton.joint_names]
    # A few warm-started steps per frame: within a centimetre of the clip's own biped, not exactly on it (this
    # random clip's fastest frame leaves the lowest-priority shoulder, and its elbow, up to 10.2 mm behind with the
    # solver's settling of issue 16; 12 steps a frame close it, at up to twice the cost on every clip).
    assert np.abs(got[1:, joints] - want[1:, joints]).max() < 1.1e-2  # metres
    assert np.median(np.abs(got[1:, joints] - want[1:, joints])) < 1e-4
    assert r.errors[1:].max() < 1.1e-2
    # The first frame starts from the rest pose: with the human ranges of motion (issue 18) its prioritised steps
    # stall 8.7 mm from this clip's first pose at a shoulder, the lowest-priority target (the next frames,
    # warm-started, converge).
    assert np.abs(got[0, joints] - want[0, joints]).max() < 1e-2 and r.errors[0].max() < 1e-2


@pytest.mark.skipif(not REAL_CLIP.exists(), reason=f"the real clip {REAL_CLIP} is not beside the repository")
def test_a_real_clip_maps_every_biped_frame_and_keeps_its_joints():
    full = read_bvh(REAL_CLIP)
    clip = BvhClip(full.joints, full.frame_time, full.motion[:40])
    r = Retargeter(load_skeleton("biped"), clip).retarget(clip)
    assert r.unmapped_frames == ("head_top",)  # the clip's head End Site has no length
    assert set(r.unmapped_clip) >= {"LeftShoulder", "RightShoulder", "Spine1", "Spine2"}
    table = {row[0]: row for row in r.error_table()}
    for frame in ("left_ankle", "right_ankle", "left_hand", "right_hand", "atlas"):  # priority 0
        assert table[frame][3] < 1.0, table[frame]  # p95 [mm]
    for frame in ("left_knee", "right_knee", "left_elbow", "right_elbow"):
        assert table[frame][3] < 40.0, table[frame]


def test_gsik_retarget_writes_a_biped_clip_and_reports_every_mapped_joint(tmp_path):
    import io

    from gsik.cli import main
    from gsik.io.bvh import write_bvh

    clip, _ = _biped_clip(10)
    src, out, mapping = tmp_path / "clip.bvh", tmp_path / "biped.bvh", tmp_path / "map.yaml"
    write_bvh(src, clip)
    mapping.write_text("format: 1\nmap:\n" + "".join(f"  {k}: {v}\n" for k, v in BIPED_EXTRA.items()))
    text = io.StringIO()
    assert main(["retarget", str(src), "--map", str(mapping), "--out", str(out)], out=text) == 0, text.getvalue()
    report = text.getvalue()
    assert "left_knee" in report and "biped frames not mapped: none" in report and "clip joints not used:" in report
    written = read_bvh(out)
    assert written.n_frames == 10 and {"hips", "left_knee", "right_elbow"} <= {j.name for j in written.joints}
    text = io.StringIO()
    assert main(["retarget", str(src), "--out", str(tmp_path / "x.txt")], out=text) == 2


def test_the_limit_margin_never_widens_a_ball_joint_past_half_a_turn():
    """A shoulder raised past 180 deg is the same arm lowered the other way: a copy of poses the range holds,
    where a warm-started solve got trapped (CMU 001_14's arms overhead); hinges keep their limits."""
    sk = load_skeleton("biped")
    wide = widened(sk, np.radians(30))
    assert np.all(wide.upper <= np.maximum(sk.upper, np.pi)) and np.all(wide.lower >= np.minimum(sk.lower, -np.pi))
    d = sk.dof_names.index("right_shoulder.x")
    assert wide.upper[d] == pytest.approx(np.pi) and wide.lower[d] == pytest.approx(sk.lower[d] - np.radians(30))
    knee = sk.dof_names.index("left_knee.x")
    assert (wide.lower[knee], wide.upper[knee]) == (sk.lower[knee], sk.upper[knee])


def test_a_frame_the_warm_start_cannot_reach_is_solved_again_from_the_rest_pose(monkeypatch):
    """With no warm-started steps at all, every frame after the first stays at the first one's pose, far from
    the moving clip; each is then solved again from the rest pose (as 001_14's arms, wound overhead past what the
    next frames could undo, are) and lands within the check's 2% of the height."""
    import gsik.anim.retarget as retarget_module

    clip, _ = _biped_clip()
    monkeypatch.setattr(retarget_module, "STEPS_PER_FRAME", 0)
    r = Retargeter(load_skeleton("biped"), clip, BIPED_EXTRA).retarget(clip)
    assert np.percentile(r.errors, 95, axis=0).max() < 0.02 * r.height
    monkeypatch.setattr(retarget_module, "COLD_START_FRACTION", np.inf)  # the retry off: the frames stay behind
    stuck = Retargeter(load_skeleton("biped"), clip, BIPED_EXTRA).retarget(clip)
    assert np.percentile(stuck.errors, 95, axis=0).max() > 0.02 * stuck.height
