"""``gsik track`` (issue 9): joints as targets, the input's conventions kept, every joint's error, folders."""

from __future__ import annotations

import io
import shutil
from pathlib import Path

import numpy as np
import pytest

from gsik.cli import main
from gsik.io.bvh import bvh_forward_kinematics, read_bvh

DATA = Path(__file__).resolve().parents[1] / "data"


def run(*argv: str) -> tuple[int, str]:
    out = io.StringIO()
    code = main(list(argv), out=out)
    return code, out.getvalue()


def assert_same_conventions(got, want) -> None:
    """Same joints (names, End Sites, OFFSETs, channels), frame time and frame count."""
    assert got.joints == want.joints
    assert got.frame_time == want.frame_time and got.n_frames == want.n_frames


def test_track_keeps_a_namespaced_rig_and_takes_its_joints_as_targets(tmp_path):
    clip_path = DATA / "mixamo_zyx_crlf.bvh"
    out = tmp_path / "solved.bvh"
    code, text = run("track", str(clip_path), "--effectors", "mixamorig:LeftLeg,mixamorig:Head",
                     "--position-only", "mixamorig:LeftLeg", "--out", str(out))
    assert code == 0, text
    assert "tracked mixamorig:LeftLeg, mixamorig:Head with root mixamorig:Hips" in text
    clip, solved = read_bvh(clip_path), read_bvh(out)
    assert_same_conventions(solved, clip)
    np.testing.assert_allclose(bvh_forward_kinematics(solved)[1], bvh_forward_kinematics(clip)[1], atol=0.01)
    # Stripped names for the options; the file keeps the rig's names.
    code, text = run("track", str(clip_path), "--strip-namespace", "--effectors", "LeftLeg", "--out", str(out))
    assert code == 0 and "tracked LeftLeg" in text
    assert read_bvh(out).names == clip.names


def test_track_keeps_a_metre_clip_in_metres_unless_asked(tmp_path):
    clip_path = DATA / "blender_chain_zyx_m.bvh"
    clip = read_bvh(clip_path)
    kept, changed = tmp_path / "kept.bvh", tmp_path / "cm.bvh"
    assert run("track", str(clip_path), "--out", str(kept))[0] == 0
    assert_same_conventions(read_bvh(kept), clip)
    np.testing.assert_allclose(read_bvh(kept).motion, clip.motion, atol=1e-6)
    assert run("track", str(clip_path), "--units", "cm", "--out", str(changed))[0] == 0
    cm = read_bvh(changed)
    assert cm.frame_time == clip.frame_time and cm.n_frames == clip.n_frames
    size = lambda c: np.ptp(bvh_forward_kinematics(c)[1][0], axis=0).max()  # noqa: E731
    assert size(cm) == pytest.approx(100 * size(clip), rel=1e-6)


def test_track_prints_every_joints_error_and_the_up_axis_note(tmp_path):
    code, text = run("track", str(DATA / "up_misleading_first_frame.bvh"), "--effectors", "LeftHand_end")
    assert code == 0, text
    assert "up axis: y up: over 30 frames the body is" in text
    assert "worst untracked joint: " in text and "% of the body height" in text
    table = text.split("every joint and site against the clip")[1]
    for name in ("Hips", "Spine", "LeftArm", "LeftHand", "LeftLeg", "LeftFoot", "LeftFoot_end"):
        assert f" {name} " in table
    assert "* LeftHand_end" in table


def test_track_wrap_angles_on_request(tmp_path):
    clip_path = DATA / "wrap_channel.bvh"
    continuous, wrapped = tmp_path / "continuous.bvh", tmp_path / "wrapped.bvh"
    assert run("track", str(clip_path), "--out", str(continuous))[0] == 0
    assert run("track", str(clip_path), "--wrap-angles", "--out", str(wrapped))[0] == 0
    spine = read_bvh(clip_path).channel_index("Spine").start + 1
    c, w = read_bvh(continuous).motion[:, spine], read_bvh(wrapped).motion[:, spine]
    assert np.abs(np.diff(c)).max() < 15 and np.abs(c).max() > 180
    assert np.abs(w).max() <= 180 and np.abs(np.diff(w)).max() > 300
    np.testing.assert_allclose(np.remainder(c - w + 180, 360) - 180, 0.0, atol=1e-6)


def test_track_priority_pole_and_their_errors(capsys):
    clip = str(DATA / "walk_zxy.bvh")
    code, text = run("track", clip, "--effectors", "LeftForeArm_end,RightLeg_end", "--pole", "RightLeg",
                     "--priority", "LeftForeArm_end=1")
    assert code == 0, text
    assert "tracked LeftForeArm_end, RightLeg_end, RightLeg" in text
    assert run("track", clip, "--priority", "Head_end")[0] == 2
    assert "--priority 'Head_end': expected NAME=LEVEL" in capsys.readouterr().err
    assert run("track", clip, "--pole", "RightLeg")[0] == 2
    assert "--pole needs --effectors" in capsys.readouterr().err
    assert run("track", clip, "--effectors", "Head_end", "--priority", "Nose=1")[0] == 2
    assert "priorities name 'Nose', which is not tracked" in capsys.readouterr().err


def test_track_a_folder_in_worker_processes_with_one_table(tmp_path):
    clips = tmp_path / "clips"
    clips.mkdir()
    for name in ("walk_zxy.bvh", "blender_chain_zyx_m.bvh", "wrap_channel.bvh"):
        shutil.copy(DATA / name, clips / name)
    (clips / "broken.bvh").write_text("HIERARCHY\nROOT Hips\n")
    out = tmp_path / "solved"
    code, text = run("track", str(clips), "--out", str(out), "--workers", "2", "--no-progress")
    assert code == 4  # one clip could not be read: the others are written, the exit code says some failed
    lines = text.splitlines()
    assert lines[0].startswith("clip") and "worst joint (p95)" in lines[0]
    assert [line.split()[0] for line in lines[2:6]] == ["blender_chain_zyx_m.bvh", "broken.bvh",
                                                        "walk_zxy.bvh", "wrap_channel.bvh"]
    assert "broken.bvh" in lines[3] and "error:" in lines[3]
    assert "1 of 4 clips failed; wrote 3 files" in text
    for name in ("walk_zxy.bvh", "blender_chain_zyx_m.bvh", "wrap_channel.bvh"):
        assert_same_conventions(read_bvh(out / name), read_bvh(DATA / name))
    assert run("track", str(clips), "--out", str(tmp_path / "x.bvh"))[0] == 2


def test_track_does_not_write_frames_that_are_not_rotations_unless_forced(tmp_path, monkeypatch, capsys):
    import gsik.cli.track as track
    from gsik.anim.retarget_check import RotationCheck

    monkeypatch.setattr(track, "rotation_check", lambda motion: RotationCheck(0.5, "LeftLeg", 2))
    out = tmp_path / "solved.bvh"
    code, _ = run("track", str(DATA / "walk_zxy.bvh"), "--out", str(out), "--no-progress")
    assert code == 3 and not out.exists()
    assert "frame LeftLeg is not a rotation at clip frame 2" in capsys.readouterr().err
    code, _ = run("track", str(DATA / "walk_zxy.bvh"), "--out", str(out), "--no-progress", "--force")
    assert code == 0 and out.exists()
